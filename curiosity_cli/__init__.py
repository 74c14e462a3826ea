"""curiosity: curiosity-driven exploration experiments on map mosaics (Girdhar & Dudek).

From Python: ``from curiosity_cli import api as cur`` (:mod:`curiosity_cli.api`).
"""

from importlib.metadata import PackageNotFoundError, version

#: The name it is installed under (``pip install curiosity-cli``): ``curiosity`` on the package index is another
#: project's. The command stays ``curiosity`` and the package ``curiosity_cli``.
DISTRIBUTION = "curiosity-cli"

try:
    __version__ = version(DISTRIBUTION)
except PackageNotFoundError:  # running from a source tree that was never installed
    __version__ = "0+unknown"
