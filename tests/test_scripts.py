"""Every top-level script under scripts/ runs its smoke mode, so a changed API breaks a test, not a script.

A script's ``--smoke`` runs the code it always runs, on tiny inputs (the smallest shipped map,
a few steps and sweeps), in seconds, and exits 0. The benchmarks and studies print and never
assert, so what is checked is that each runs to its end: its exit code and its last words.
A script that cannot run here says why in :data:`NOT_SMOKED`.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

SCRIPTS = Path(__file__).resolve().parents[1] / "scripts"
#: Each script smoked, and words its smoke run prints at its end.
SMOKED = {
    "bench_batch_threads.py": "colours",
    "bench_drive.py": "ACK: VEL written",
    "bench_explore.py": "topic-perplexity",
    "bench_extract.py": "issue #3's budget",
    "bench_gibbs.py": "synthetic: a/c = ",  # tomotopy, its reference, comes with the test extra (the bench extra)
    "bench_label.py": "goal: lock-step",
    # without a GPU the label benchmarks run their CPU side, and device_compare.py the CPU against itself: the
    # CUDA kernels run under numba's simulator in tests/topics/test_chains_cuda.py, on tiny maps, as a shipped
    # map's 300,000 words would take the simulator many minutes
    "bench_label_devices.py": "CPU / CUDA",
    "bench_label_profile.py": "of the stage's wall time",
    "bench_long_mission.py": "timeline:",
    "bench_pipeline.py": "batch reference, 1 sweeps",
    "bench_replay.py": "frames/s, ratio",  # HEAD against itself, each in a `git worktree` of the repository's .git
    "bench_scaleout.py": "overhead per task",
    "bench_study_reuse.py": "--reuse",
    "check_drive_surprise.py": "target <= 1.5: met",
    "check_revisits.py": "passes: ",
    "check_dose_response.py": "slope of mean_recall per rare class seen",
    "compare_mi.py": "outside the noise:",
    "device_compare.py": "the same bytes on both devices",
    "make_maps.py": "rare-patches: identical",
    "null_reference.py": "one walker 50 % worse",
    "plan_hypotheses.py": "scale: {aerial-mosaic: ",
    "record_study.py": "recorded 1 combinations",
    "study_batch_sampler.py": "verdict:",
    "study_budget.py": "by word samples per step",
    "study_frozen_cost.py": "fit:",
    "study_label_sweeps.py": "doubling:",
    "study_screening.py": "rost",
    "validate_measures.py": "validation-frozen.png",
}
#: The smoke runs of a few seconds, in the quick tier; the others start numba's kernels, OpenCV, Dask or a drive
#: in processes of their own and are marked slow.
QUICK = {"compare_mi.py", "make_maps.py", "null_reference.py", "plan_hypotheses.py"}
#: Each script not smoked, and why.
NOT_SMOKED = {
    "bench_chain_kernel.py": "it checks out a reference commit with `git worktree` (the repository's own .git) and "
    "compiles each version's kernels in a numba cache of its own: minutes",
    "bench_quick_job.py": "it checks out two commits with `git worktree` (the repository's own .git) and runs the "
    "quick job, which fetches zurich-zh17, four times: many minutes and a download",
    "device_check.sh": "the check on a GPU machine, run there by hand (issue 33); the scripts it runs are smoked "
    "here, and its `--small` runs its CPU parts in minutes",
    "make_geonrw_map.py": "its source tile is in a GitHub repository that neither CI nor a user's machine can reach "
    "(tests/maps/test_make_maps.py checks the legend it writes)",
    "prepare_device.sh": "it downloads a numba-cuda wheel with pip and fetches zurich-zh17: the network",
}


def test_every_script_is_smoked_or_says_why_not():
    scripts = sorted(p.name for p in SCRIPTS.iterdir() if p.suffix in (".py", ".sh"))
    assert scripts == sorted([*SMOKED, *NOT_SMOKED])
    assert not set(SMOKED) & set(NOT_SMOKED)


@pytest.fixture(scope="module")
def environment(tmp_path_factory) -> dict:
    """The scripts' environment: a user cache of their own (the smallest map's words extracted once for all), the
    kernels compiled in the real one, results in a temporary folder, figures without a display."""
    from curiosity_cli._numba import cache_dir

    folder = tmp_path_factory.mktemp("scripts")
    return {
        **os.environ, "CURIOSITY_CACHE": str(folder / "cache"), "NUMBA_CACHE_DIR": str(cache_dir()),
        "CURIOSITY_RESULTS": str(folder / "results"), "MPLBACKEND": "Agg",
    }


@pytest.mark.parametrize(
    "script",
    [pytest.param(name, marks=[] if name in QUICK else [pytest.mark.slow]) for name in SMOKED],
)
def test_the_smoke_mode_runs_to_its_end(script, environment, tmp_path):
    done = subprocess.run(
        [sys.executable, str(SCRIPTS / script), "--smoke"], env=environment, cwd=tmp_path, capture_output=True,
        text=True, timeout=600,
    )
    assert done.returncode == 0, done.stdout + done.stderr
    assert SMOKED[script] in done.stdout, done.stdout


@pytest.mark.parametrize(
    "script, arguments, code, says",
    [  # the hostile round of issue 64: tracebacks, or an answer from nothing
        ("plan_hypotheses.py", ["--smoke", "--alpha", "2"], 2, "--alpha: got 2.0, expected a one-sided level"),
        ("plan_hypotheses.py", ["--smoke", "--alpha", "nan"], 2, "--alpha: got nan"),
        ("plan_hypotheses.py", ["--smoke", "--against", "nope"], 1, "Error: --against: got 'nope', expected one of human"),
        ("plan_hypotheses.py", ["--smoke", "--path-length", "7"], 1, "at 7 steps (--path-length)"),
        ("plan_hypotheses.py", ["--smoke", "--comparators", "topic-perplexity"], 1, "is the walker itself"),
        ("check_revisits.py", ["--seeds", "0"], 2, "--seeds, --jobs: got 0 and 2, expected at least 1 each"),
        ("check_revisits.py", ["--jobs", "0"], 2, "--seeds, --jobs: got 5 and 0"),
        ("check_revisits.py", ["--maps", "planted-disjoint"], 2, "invalid choice: 'planted-disjoint'"),
        ("check_revisits.py", ["--set", "drive.surprise=nope", "--seeds", "1"], 1, "Error: overrides: drive.surprise: got 'nope'"),
        ("bench_replay.py", ["--reference", "nosuchcommit"], 2, "'nosuchcommit' is not a commit of "),
        ("bench_replay.py", ["--skip", "-3", "--frames", "2"], 2, "--skip must be at least 0"),
    ],
)
def test_a_script_s_bad_arguments_are_one_line(script, arguments, code, says, environment, tmp_path):
    done = subprocess.run(
        [sys.executable, str(SCRIPTS / script), *arguments], env=environment, cwd=tmp_path, capture_output=True,
        text=True, timeout=120,
    )
    assert done.returncode == code and "Traceback" not in done.stderr, done.stderr
    assert says in done.stderr, done.stderr
