"""Benchmark the lock-step labelling kernel against a reference commit's, interleaved, on the same inputs.

The CPU's frozen-Φ sweep (:class:`~curiosity_cli.topics.chains.FrozenChains`, the kernels of
``topics/_chain_kernels.py``) of this working tree and of --ref (a commit, checked out with
``git worktree add`` into a temporary folder, removed afterwards; this checkout's branch is
never touched). Each variant runs in its own process (its own package, its own numba cache)
on the same map's words and the same real Φ_p (--runs topic-perplexity runs of --steps
steps, explored once by the working tree and kept in --inputs), R = --chains chains taking
them in turn, the seeds 0 .. R - 1. Each process compiles and sweeps once untimed; then
every round times --sweeps sweeps of each variant in turn, the order alternating from round
to round. Printed: nanoseconds per word-sample per chain, the median (and the range) of
--rounds, by the wall clock and by the sweeping thread's CPU time (on a machine shared with
other work the second moves less), the ratio reference / variant (above 1: faster than the
reference), and whether every variant's topics and counts are the reference's, byte for
byte, after the same sweeps. --ids adds each version given the word ids as int32 instead of
the store's own unsigned type (FrozenChains makes an int32 copy of either).

    python scripts/bench_chain_kernel.py                              # aerial-mosaic, R = 16, against HEAD
    python scripts/bench_chain_kernel.py --ref 9949bef --ids          # also each variant given int32 word ids

Prints and never asserts: timings depend on the machine (run it beside a reference, as here).
"""

from __future__ import annotations

import argparse
import hashlib
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent


def build_inputs(path: Path, name: str, runs: int, steps: int) -> None:
    """The map's words, cells and neighbour table and ``runs`` real Φ_p, saved to ``path`` (npz)."""
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from bench_label import setup  # the same maps and Φ_p as the other label benchmarks

    config, store, phis = setup(name, runs, steps)
    table = store.grid.neighbour_table(config.model.spatial_neighbours)
    np.savez(
        path, words=store.words, cells=np.repeat(np.arange(store.n_cells), store.words_per_cell()), table=table,
        phis=np.stack(phis), n_topics=config.model.topics, vocabulary_size=store.vocabulary_size,
        alpha=config.model.alpha, beta=config.model.beta,
    )


def worker(inputs: Path, chains: int, int32_ids: bool) -> None:
    """Hold a started block of chains and answer ``sweep N`` (seconds), ``digest`` and ``quit`` on stdin."""
    from curiosity_cli.topics.chains import FrozenChains

    data = np.load(inputs)
    words = data["words"].astype(np.int32) if int32_ids else data["words"]
    block = FrozenChains(
        words, data["cells"], data["table"], n_topics=int(data["n_topics"]),
        vocabulary_size=int(data["vocabulary_size"]),
        alpha=float(data["alpha"]), beta=float(data["beta"]),
    )
    phis = data["phis"]
    block.start([phis[r % len(phis)] for r in range(chains)], list(range(chains)))
    block.sweep(1)  # compiles (or loads the cache) and warms the caches
    print("ready", block.n_words, flush=True)
    for line in sys.stdin:
        command = line.split()
        if command[0] == "sweep":
            began, began_cpu = time.perf_counter(), time.thread_time()
            block.sweep(int(command[1]))
            print(time.perf_counter() - began, time.thread_time() - began_cpu, flush=True)
        elif command[0] == "digest":
            digest = hashlib.sha256()
            for array in (block.topics(), *block.counts()):
                digest.update(np.ascontiguousarray(array).tobytes())
            print(digest.hexdigest(), flush=True)
        else:
            return


class Variant:
    """One worker process: a package tree and how it is given the word ids."""

    def __init__(self, label: str, tree: Path, inputs: Path, chains: int, int32_ids: bool):
        self.label = label
        env = {**os.environ, "PYTHONPATH": str(tree)}
        command = [sys.executable, str(Path(__file__).resolve()), "--worker", "--inputs", str(inputs),
                   "--chains", str(chains)] + (["--int32-worker"] if int32_ids else [])
        self.process = subprocess.Popen(command, stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True, env=env,
                                        cwd=tempfile.gettempdir())
        self.times: list[float] = []  # wall seconds per word-sample per chain
        self.cpu: list[float] = []  # the sweeping thread's CPU seconds, the same unit

    def ask(self, line: str) -> str:
        self.process.stdin.write(line + "\n")
        self.process.stdin.flush()
        return self.process.stdout.readline().strip()

    def ready(self) -> int:
        answer = self.process.stdout.readline().split()
        if not answer or answer[0] != "ready":
            raise SystemExit(f"{self.label}: the worker failed (its error is above)")
        return int(answer[1])

    def close(self) -> None:
        if self.process.poll() is None:
            self.process.stdin.write("quit\n")
            self.process.stdin.close()
        self.process.wait()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--ref", default="HEAD", help="the reference commit")
    parser.add_argument("--map", default="aerial-mosaic")
    parser.add_argument("--chains", type=int, default=16)
    parser.add_argument("--runs", type=int, default=4, help="runs whose Φ_p the chains take in turn")
    parser.add_argument("--steps", type=int, default=80)
    parser.add_argument("--sweeps", type=int, default=2, help="sweeps per timing")
    parser.add_argument("--rounds", type=int, default=7)
    parser.add_argument("--ids", action="store_true", help="also time each variant given int32 word ids")
    parser.add_argument("--inputs", type=Path, help="the inputs' npz (default: in the temporary folder, made once)")
    parser.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    parser.add_argument("--int32-worker", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.worker:
        worker(args.inputs, args.chains, args.int32_worker)
        return

    inputs = args.inputs or Path(tempfile.gettempdir()) / f"bench_chain_kernel-{args.map}-{args.runs}x{args.steps}.npz"
    if not inputs.exists():
        print(f"exploring {args.runs} runs of {args.steps} steps on {args.map} for Φ_p -> {inputs}", flush=True)
        build_inputs(inputs, args.map, args.runs, args.steps)
    ref = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "--short", args.ref], capture_output=True, text=True,
                         check=True).stdout.strip()
    tree = Path(tempfile.mkdtemp(prefix=f"bench-ref-{ref}-"))
    subprocess.run(["git", "-C", str(ROOT), "worktree", "add", "--detach", "-q", str(tree), ref], check=True)
    variants = []
    try:
        plans = [(f"reference {ref}", tree, False), ("working tree", ROOT, False)]
        if args.ids:
            plans += [(f"reference {ref}, int32 ids", tree, True), ("working tree, int32 ids", ROOT, True)]
        variants = [Variant(label, where, inputs, args.chains, int32) for label, where, int32 in plans]
        n_words = [v.ready() for v in variants][0]  # the workers compile side by side, then wait
        samples = args.sweeps * n_words * args.chains
        for round_ in range(args.rounds):
            for v in variants if round_ % 2 == 0 else variants[::-1]:
                wall, cpu = map(float, v.ask(f"sweep {args.sweeps}").split())
                v.times.append(wall / samples)
                v.cpu.append(cpu / samples)
        digests = [v.ask("digest") for v in variants]
    finally:
        for v in variants:
            v.close()
        subprocess.run(["git", "-C", str(ROOT), "worktree", "remove", "--force", str(tree)], check=False)

    data = np.load(inputs)
    print(f"\n{args.map}: {n_words:,} words, V = {int(data['vocabulary_size'])}, K = {int(data['n_topics'])}, "
          f"R = {args.chains}, Φ_p of {args.runs} topic-perplexity runs at {args.steps} steps; word ids "
          f"{data['words'].dtype} as the store holds them unless said")
    print(f"ns per word-sample per chain, median (min, max) of {args.rounds} interleaved rounds x {args.sweeps} "
          f"sweeps, wall and the sweeping thread's CPU time; ratio: reference / this; same bytes: topics and counts "
          f"after {1 + args.rounds * args.sweeps} sweeps")
    print(f"  {'variant':<30} {'wall':>22} {'ratio':>6}   {'CPU':>22} {'ratio':>6}  same bytes")
    for v, digest in zip(variants, digests):
        cells = []
        for mine, reference in ((v.times, variants[0].times), (v.cpu, variants[0].cpu)):
            median = statistics.median(mine)
            cells.append(f"{median * 1e9:6.2f} ({min(mine) * 1e9:6.2f}, {max(mine) * 1e9:6.2f}) "
                         f"{statistics.median(reference) / median:5.2f}x")
        print(f"  {v.label:<30} {cells[0]}   {cells[1]}  {'yes' if digest == digests[0] else 'NO'}")


if __name__ == "__main__":
    main()
