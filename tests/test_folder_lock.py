"""One process at a time in an experiment folder: a second is refused in one line, a killed holder frees it."""

from __future__ import annotations

import os
import signal
import subprocess
import sys

import pytest
from experiments import small_experiment
from typer.testing import CliRunner

from curiosity_cli.cli import app
from curiosity_cli.experiment.lock import FolderInUseError, working_in

runner = CliRunner()

HOLD = """
import sys, time
from curiosity_cli.experiment.lock import working_in
with working_in(sys.argv[1], "label"):
    print("held", flush=True)
    time.sleep(60)
"""


@pytest.mark.skipif(sys.platform == "win32", reason="no fcntl: no lock")
def test_a_second_label_is_refused_while_another_process_works_and_a_killed_one_frees_the_folder(own_map, tmp_path):
    config, folder = small_experiment(own_map, tmp_path)
    holder = subprocess.Popen([sys.executable, "-c", HOLD, str(folder)], stdout=subprocess.PIPE, text=True)
    try:
        assert holder.stdout.readline().strip() == "held"
        result = runner.invoke(app, ["label", str(folder), "--jobs", "1"])
        assert result.exit_code == 1 and "Traceback" not in result.stderr
        (line,) = result.stderr.strip().splitlines()
        assert line.startswith(f"Error: {folder}: another process works in this experiment (`curiosity label`, "
                               f"process {holder.pid}, since ")
        assert not (folder / "labels").exists()  # it did nothing, not even its clean-up
    finally:
        os.kill(holder.pid, signal.SIGKILL)
        holder.wait()
        holder.stdout.close()
    with working_in(folder, "label"):  # the kernel freed the lock of the killed process
        with working_in(folder, "evaluate"):  # and one process may hold it twice (reproduce runs every stage)
            pass


def test_a_folder_held_here_is_free_again_afterwards_and_a_missing_one_is_not_made(tmp_path):
    with working_in(tmp_path, "explore"):
        pass
    with working_in(tmp_path, "label"):
        assert (tmp_path / ".lock").is_file()
    with working_in(tmp_path / "missing", "label"):
        pass
    assert not (tmp_path / "missing").exists()
    assert issubclass(FolderInUseError, Exception)
