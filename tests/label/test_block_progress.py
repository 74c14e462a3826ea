"""A label block's chain sweeps counted while it runs: written by its worker, read by the stage, each sweep once."""

from __future__ import annotations

import time

from curiosity_cli.label import block_progress
from curiosity_cli.label.block_progress import BlockProgress, SweepCounter


def test_a_blocks_sweeps_count_while_it_runs_and_its_end_tops_them_up_each_once(monkeypatch):
    monkeypatch.setattr(block_progress, "EVERY", 0.01)
    done = []
    with BlockProgress({"label-a/b/restart-000+1": 40, "batch-a": 8}, lambda: done.append(1), local=True) as progress:
        counter = SweepCounter(progress.path("label-a/b/restart-000+1"))
        for _ in range(5):
            counter(3)  # 3 chains swept
            time.sleep(0.03)
        deadline = time.monotonic() + 5
        while len(done) < 15 and time.monotonic() < deadline:
            time.sleep(0.01)
        assert len(done) == 15  # read from the worker's file before the block ended
        progress.ended("label-a/b/restart-000+1")
        assert len(done) == 40  # the rest of its planned sweeps, once
        counter(3)  # a late write after its end is not counted again
        time.sleep(0.05)
        assert len(done) == 40
        progress.ended("batch-a")
        assert len(done) == 48
        folder = progress.path("batch-a").rsplit("/", 1)[0]
    assert not __import__("os").path.exists(folder)  # the files go with the stage


def test_without_a_display_or_shared_files_nothing_is_written():
    assert BlockProgress({"k": 1}, None, local=True).path("k") is None
    assert BlockProgress({"k": 1}, lambda: None, local=False).path("k") is None  # a cluster's workers: counted at the end
    counter = SweepCounter(None)
    counter(4)
    assert counter.done == 4


def test_progress_folders_a_killed_labelling_left_are_removed_and_a_live_one_s_kept(tmp_path, monkeypatch):
    """Issue 64: SIGKILL during labelling left an empty curiosity-label-progress-* folder in TMPDIR."""
    import os
    import tempfile

    from curiosity_cli.label.block_progress import remove_orphans

    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    dead = tmp_path / "curiosity-label-progress-999999999-abc"  # above any process id Linux gives
    live = tmp_path / f"curiosity-label-progress-{os.getpid()}-def"
    older = tmp_path / "curiosity-label-progress-ghi"  # named before names held a process id: left alone
    for folder in (dead, live, older):
        folder.mkdir()
    assert remove_orphans() == 1
    assert not dead.exists() and live.is_dir() and older.is_dir()
