"""The real CLI in a subprocess, and what a bad input or fault must and must not do.

Reliability cases (issue 16) run ``python -m curiosity_cli ...`` in a fresh process, as a
user would, and check the contract of the house: the exit code, exactly one ``Error:``
line naming the file or option, no traceback and no raw warning, and nothing written
outside the folders the command owns.
"""

from __future__ import annotations

import os
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

#: The experiment the reliability cases break (``tests/reliability/conftest.py``), and its commands.
EXPERIMENT = "results/grid"
# two worker processes: a worker's error must come back as one line too
FAST_LABELS = ["--jobs", "2", "--set", "label.sweeps=2", "--set", "label.batch_sweeps=5"]
LABEL = ["label", EXPERIMENT, *FAST_LABELS]
EXPLORE = ["explore", "grid.yaml", "--jobs", "2"]


@dataclass(frozen=True)
class Outcome:
    """What one command did: its exit code and its two streams."""

    code: int
    stdout: str
    stderr: str

    @property
    def output(self) -> str:
        return self.stdout + self.stderr


def run_cli(args: list[str], *, cwd: Path, env: dict | None = None, timeout: float = 300, stdin: str | None = None) -> Outcome:
    """Run ``curiosity ARGS`` in a subprocess from ``cwd``; the environment gets ``env`` on top.

    The user cache is ``cwd/results/cache``, so a case's word stores are its own and travel
    with a copied experiment; the compiled kernels stay in the real user cache (compiled once).
    """
    from curiosity_cli._numba import cache_dir

    isolated = {"CURIOSITY_CACHE": str(Path(cwd) / "results" / "cache"), "NUMBA_CACHE_DIR": str(cache_dir())}
    full_env = {**os.environ, "PYTHONWARNINGS": "default", **isolated, **(env or {})}
    done = subprocess.run(
        [sys.executable, "-m", "curiosity_cli", *map(str, args)], cwd=cwd, env=full_env, capture_output=True,
        text=True, timeout=timeout, input=stdin,
    )
    return Outcome(done.returncode, done.stdout, done.stderr)


def assert_clean_error(outcome: Outcome, *names: str, code: int = 1) -> str:
    """One ``Error:`` line naming each of ``names``, exit ``code``, no traceback; returns the line.

    For usage errors (``code=2``) click prints its own box; the line checked is then the
    one holding ``Error``.
    """
    assert outcome.code == code, f"exit {outcome.code}, expected {code}:\n{outcome.output}"
    assert "Traceback" not in outcome.output, outcome.output
    assert "Warning:" not in outcome.output, outcome.output
    errors = [line for line in outcome.stderr.splitlines() if "Error" in line]
    assert len(errors) == 1, f"expected one Error line:\n{outcome.stderr}"
    line = errors[0] if code != 2 else outcome.stderr
    for name in names:
        assert name in line, f"{name!r} not in {line!r}"
    return errors[0]


def files_under(root: Path) -> set[Path]:
    """Every file and folder below ``root`` (to compare before and after a command)."""
    return set(Path(root).rglob("*"))


def assert_written_only_inside(before: set[Path], after: set[Path], *allowed: Path) -> None:
    """Every path that appeared is inside one of ``allowed``."""
    new = after - before
    outside = [p for p in new if not any(p == a or a in p.parents for a in map(Path, allowed))]
    assert not outside, f"written outside {[str(a) for a in allowed]}: {sorted(map(str, outside))[:5]}"
