"""Where the tool reads and writes by default: the one table of default folders."""

from __future__ import annotations

from pathlib import Path

#: Where experiment folders go unless ``results_dir`` says otherwise.
DEFAULT_RESULTS = Path("results")
#: Where word stores are cached unless ``cache_dir`` says otherwise.
DEFAULT_CACHE = DEFAULT_RESULTS / "cache"


def experiment_root(results_dir: Path, name: str) -> Path:
    """Where the experiment ``name`` lives: ``results_dir/<name>``."""
    return Path(results_dir) / name
