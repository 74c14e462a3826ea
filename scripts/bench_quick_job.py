"""Time the quick job (``curiosity reproduce --quick``) of one commit against another's, interleaved.

Each repeat runs the reference commit's quick job and the candidate's, alternating which
goes first (ABBA), each in a fresh results folder, with the same word stores and fetched
map (the user cache) and each version's numba cache (a warm-up run of each compiles its
kernels first, untimed). Prints every run's seconds and the stages of its REPORT.md, then
the medians side by side and their ratio.

    python scripts/bench_quick_job.py --reference b845e5f              # against HEAD, 2 repeats, --jobs 2 here
    python scripts/bench_quick_job.py --reference HEAD~3 --candidate HEAD --repeats 3 --jobs 16

Both commits are checked out with ``git worktree`` into a temporary folder (so edits to
this checkout while it runs change nothing) and imported ahead of this checkout's
installed package (``PYTHONPATH``), with this checkout's virtual environment.
"""

from __future__ import annotations

import argparse
import os
import re
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def run_quick(code: Path, jobs: int, results: Path) -> tuple[float, dict]:
    """Seconds of one quick job, with ``code`` first on the path, and its REPORT.md stages.

    Its cache folder is its own, holding links to the word stores of the user cache: no run
    extracts words again, and none takes the labels an earlier run computed (shared items).
    """
    from curiosity_cli.paths import DEFAULT_CACHE

    cache = results / "cache"
    cache.mkdir(parents=True)
    for store in DEFAULT_CACHE.glob("*.npz"):
        (cache / store.name).symlink_to(store)
    env = dict(os.environ)
    env["PYTHONPATH"] = str(code) + os.pathsep + env.get("PYTHONPATH", "")
    command = [sys.executable, "-c", "import sys; from curiosity_cli.cli import main; sys.argv[0] = 'curiosity'; main()",
               "reproduce", "--quick", "--jobs", str(jobs), "--results-dir", str(results), "--cache-dir", str(cache)]
    began = time.perf_counter()
    subprocess.run(command, check=True, env=env, cwd=code, stdout=subprocess.DEVNULL)
    seconds = time.perf_counter() - began
    report = next(results.glob("*/REPORT.md")).read_text()
    stages = dict(re.findall(r"^\| ([a-z ]+) \| (\d+) \|$", report[report.index("## Time"):], re.M))
    return seconds, stages


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--reference", required=True, help="the commit to compare with")
    parser.add_argument("--candidate", default="HEAD", help="the commit to time against it (default HEAD)")
    parser.add_argument("--repeats", type=int, default=2)
    parser.add_argument("--jobs", type=int, default=os.cpu_count())
    args = parser.parse_args()
    commits = [subprocess.run(["git", "rev-parse", "--short", rev], cwd=ROOT, check=True, capture_output=True,
                              text=True).stdout.strip() for rev in (args.reference, args.candidate)]
    with tempfile.TemporaryDirectory() as tmp:
        versions = {}
        try:
            for role, commit in zip(("reference", "candidate"), commits):
                versions[f"{role} {commit}"] = Path(tmp) / role
                subprocess.run(["git", "worktree", "add", "--detach", str(Path(tmp) / role), commit], cwd=ROOT,
                               check=True, capture_output=True)
            for code in versions.values():  # compile each version's kernels, untimed
                run_quick(code, args.jobs, Path(tempfile.mkdtemp(dir=tmp)))
            times = {name: [] for name in versions}
            for repeat in range(args.repeats):
                order = list(versions) if repeat % 2 == 0 else list(versions)[::-1]
                for name in order:
                    seconds, stages = run_quick(versions[name], args.jobs, Path(tempfile.mkdtemp(dir=tmp)))
                    times[name].append(seconds)
                    print(f"{name:<22} {seconds:6.1f} s   " + ", ".join(f"{k} {v}" for k, v in stages.items()), flush=True)
        finally:
            for code in versions.values():
                subprocess.run(["git", "worktree", "remove", "--force", str(code)], cwd=ROOT, check=False)
    medians = {name: statistics.median(values) for name, values in times.items()}
    (ref_name, ref), (new_name, new) = medians.items()
    print(f"\nquick job, --jobs {args.jobs}, medians of {args.repeats}: {ref_name} {ref:.1f} s, {new_name} {new:.1f} s, "
          f"ratio {new / ref:.2f}")


if __name__ == "__main__":
    main()
