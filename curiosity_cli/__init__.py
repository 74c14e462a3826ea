"""curiosity: curiosity-driven exploration experiments on map mosaics (Girdhar & Dudek).

From Python: ``from curiosity_cli import api as cur`` (:mod:`curiosity_cli.api`).
"""

from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("curiosity")
except PackageNotFoundError:  # running from a source tree that was never installed
    __version__ = "0+unknown"
