"""Where the tool reads and writes: the one table of its folders.

| what | default | overridden by |
| --- | --- | --- |
| experiment folders | ``./results`` | ``--results-dir``, ``$CURIOSITY_RESULTS`` |
| the user cache: word stores (``stores/``), fetched maps (``sources/``), compiled kernels (``numba-*/``) | ``$XDG_CACHE_HOME/curiosity``, else ``~/.cache/curiosity`` | ``$CURIOSITY_CACHE``; word stores also ``--cache-dir`` |
| shipped configs and data | inside the installed package (:data:`SHIPPED_CONFIGS`, :data:`SHIPPED_DATA`) | never written |

The defaults of ``results_dir`` and ``cache_dir`` are read from the environment when this
module is imported; the user cache's other folders (fetched maps, kernels) when used.
"""

from __future__ import annotations

import os
from importlib import resources
from pathlib import Path


def _environment_folder(variable: str, default: Path) -> Path:
    value = os.environ.get(variable)
    return Path(value).expanduser() if value else default


def user_cache() -> Path:
    """The user's cache of downloads and derived data: ``$CURIOSITY_CACHE``, else
    ``$XDG_CACHE_HOME/curiosity``, else ``~/.cache/curiosity``.

    Nothing there is committed or shared; deleting it costs only downloads and recomputing.
    """
    return _environment_folder(
        "CURIOSITY_CACHE", Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "curiosity"
    )


#: Where experiment folders go unless ``results_dir`` says otherwise.
DEFAULT_RESULTS = _environment_folder("CURIOSITY_RESULTS", Path("results"))
#: Where word stores are cached unless ``cache_dir`` says otherwise.
DEFAULT_CACHE = user_cache() / "stores"
#: The shipped configs (the repository's ``configs/``) and data (its ``data/``), wherever the package is installed.
SHIPPED_CONFIGS = Path(str(resources.files("curiosity_cli.shipped.configs")))
SHIPPED_DATA = Path(str(resources.files("curiosity_cli.shipped.data")))


def experiment_root(results_dir: Path, name: str) -> Path:
    """Where the experiment ``name`` lives: ``results_dir/<name>``."""
    return Path(results_dir) / name
