"""The reliability cases' shared experiment: explored, labelled and evaluated once per test process, copied per case."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest
from cli_cases import EXPERIMENT, EXPLORE, LABEL, run_cli
from small_maps import grid_yaml, write_own_map


@pytest.fixture(scope="session")
def experiment(tmp_path_factory) -> Path:
    """A folder holding the own map, ``grid.yaml`` and ``results/grid`` explored, labelled and evaluated.

    Made once for every module that breaks it: no case writes here (``work`` is a copy, and a case that edits the
    map copies it first), so a case cannot see another's fault.
    """
    root = tmp_path_factory.mktemp("experiment")
    grid_yaml(write_own_map(root), root)
    for args in (EXPLORE, LABEL, ["evaluate", EXPERIMENT]):
        outcome = run_cli(args, cwd=root)
        assert outcome.code == 0, outcome.output
    return root


@pytest.fixture
def work(experiment: Path, tmp_path: Path) -> Path:
    """A copy of the experiment's config and results to break (the map stays where the config names it)."""
    shutil.copy(experiment / "grid.yaml", tmp_path)
    shutil.copytree(experiment / "results", tmp_path / "results")
    (tmp_path / "a-file").write_text("not a folder\n")
    return tmp_path
