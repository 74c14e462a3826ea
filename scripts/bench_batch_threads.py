"""The batch reference's sweeps on 1 to many threads: this checkout beside a reference checkout, interleaved.

Each measurement is a fresh process that computes one map's batch reference as the
label stage does (``label.sampling.batch_labels``: SWEEPS batch sweeps and the
log-likelihood trace after each) on THREADS threads, after one untimed sweep that
compiles, and prints its seconds. The versions take turns within each repeat; the table
gives medians and the reference's time over this checkout's (above 1: faster now).

``--colours`` adds this checkout with the word-topic counts synchronised once per colour
of the cell colouring instead of every 1/16 of the cells (``batch_sweeps._PHASES = 1``):
the approximate parallel sweep of issue 42 (its answer: ``scripts/study_batch_sampler.py``).

    git archive REF | tar -x -C /tmp/ref      # the reference's source, once
    python scripts/bench_batch_threads.py --reference /tmp/ref --maps reef-mosaic --threads 1 2 --repeats 3
    python scripts/bench_batch_threads.py --smoke    # one sweep of the smallest map, both versions: seconds

Prints and never asserts: timings depend on the machine.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent.parent


def worker(name: str, sweeps: int, threads: int, colours: bool) -> None:
    """Print the seconds of one map's batch reference (module docstring) in this process."""
    import time

    from curiosity_cli.config import load_config
    from curiosity_cli.experiment.maps import prepare_stores
    from curiosity_cli.label.sampling import batch_labels
    from curiosity_cli.paths import DEFAULT_CACHE
    from curiosity_cli.words.store import load_store

    if colours:
        from curiosity_cli.topics import batch_sweeps

        batch_sweeps._PHASES = 1
    config = load_config("quick", overrides=[f"datasets=[{name}]"])
    store = load_store(next(iter(prepare_stores(config, DEFAULT_CACHE).values())).path)
    batch_labels(store, config.model, sweeps=1, seed=1, threads=threads)  # compiled
    began = time.perf_counter()
    batch_labels(store, config.model, sweeps=sweeps, seed=1, threads=threads)
    print(f"{time.perf_counter() - began:.4f}")


def measure(source: Path, name: str, sweeps: int, threads: int, colours: bool) -> float:
    """Seconds of one measurement in a fresh process that imports ``curiosity_cli`` from ``source``."""
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(filter(None, [str(source), os.environ.get("PYTHONPATH")]))}
    command = [sys.executable, __file__, "--worker", name, str(sweeps), str(threads)] + ["--colours"] * colours
    out = subprocess.run(command, env=env, capture_output=True, text=True, cwd=source)
    if out.returncode:
        raise SystemExit(f"{source}: {out.stderr.strip().splitlines()[-1] if out.stderr.strip() else out.returncode}")
    return float(out.stdout.split()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--reference", type=Path, help="a checkout of the reference commit (its root)")
    parser.add_argument("--maps", nargs="+", default=["reef-mosaic"])
    parser.add_argument("--sweeps", type=int, default=20)
    parser.add_argument("--threads", type=int, nargs="+", default=[1, 2])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--colours", action="store_true", help="also counts synchronised once per colour")
    parser.add_argument("--smoke", action="store_true", help="tiny inputs, seconds (what tests/test_scripts.py runs)")
    parser.add_argument("--worker", nargs=3, metavar=("MAP", "SWEEPS", "THREADS"), help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.smoke:
        args.maps, args.sweeps, args.threads, args.repeats, args.colours = ["rare-patches"], 1, [1], 1, True
    if args.worker:
        worker(args.worker[0], int(args.worker[1]), int(args.worker[2]), args.colours)
        return
    versions = {"this checkout": (HERE, False)}
    if args.reference:
        versions = {"reference": (args.reference.resolve(), False), **versions}
    if args.colours:
        versions["colours"] = (HERE, True)
    print(f"logical CPUs {os.cpu_count()}; {args.sweeps} sweeps and their trace, median of {args.repeats}")
    for name in args.maps:
        print(f"\n{name}")
        print("threads  " + "  ".join(f"{v:>14}" for v in versions) + ("   reference / this" if args.reference else ""))
        for threads in args.threads:
            seconds = {v: [] for v in versions}
            for _ in range(args.repeats):
                for version, (source, colours) in versions.items():
                    seconds[version].append(measure(source, name, args.sweeps, threads, colours))
            medians = {v: statistics.median(s) for v, s in seconds.items()}
            line = f"{threads:>7}  " + "  ".join(f"{medians[v]:>12.2f} s" for v in versions)
            if args.reference:
                line += f"   {medians['reference'] / medians['this checkout']:.2f}x"
            print(line, flush=True)


if __name__ == "__main__":
    main()
