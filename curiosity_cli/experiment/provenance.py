"""Where a result came from: package version, git commit, library versions, command line.

Every output folder gets one of these beside its resolved config, so a number in a
table can be traced to the code that made it.
"""

from __future__ import annotations

import platform
import subprocess
import sys
from datetime import datetime, timezone
from pathlib import Path

from curiosity_cli import __version__
#: The source checkout the package runs from, if it runs from one (an editable install).
_CHECKOUT = Path(__file__).resolve().parents[2]


def git_commit() -> tuple[str, bool]:
    """``(commit, dirty)`` of the source checkout the package runs from; ``("unknown", False)``
    for an installed wheel, whose folder may sit inside some other repository."""
    if not (_CHECKOUT / ".git").exists() or not (_CHECKOUT / "pyproject.toml").is_file():
        return "unknown", False
    try:
        commit = subprocess.run(
            ["git", "-C", str(_CHECKOUT), "rev-parse", "HEAD"], capture_output=True, text=True, timeout=10
        )
        status = subprocess.run(
            ["git", "-C", str(_CHECKOUT), "status", "--porcelain", "--untracked-files=no"],
            capture_output=True, text=True, timeout=10,
        )
    except (OSError, subprocess.TimeoutExpired):
        return "unknown", False
    if commit.returncode != 0:
        return "unknown", False
    return commit.stdout.strip(), bool(status.stdout.strip())


def provenance(seed: int) -> dict:
    """The facts a results folder records about the run that wrote it."""
    import numba
    import numpy

    commit, dirty = git_commit()
    return {
        "seed": seed,
        "curiosity": __version__,
        "git_commit": commit,
        "git_dirty": dirty,
        "python": platform.python_version(),
        "numpy": numpy.__version__,
        "numba": numba.__version__,
        "platform": platform.platform(),
        "command": " ".join(["curiosity", *sys.argv[1:]]),
        "started": datetime.now(timezone.utc).isoformat(timespec="seconds"),
    }
