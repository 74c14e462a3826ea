"""Benchmark labelling's chains on each device: the CPU lock-step kernel against the CUDA kernel.

Z_p is frozen-Φ Gibbs sampling of every word of a map by R chains in lock-step
(:class:`~curiosity_cli.topics.chains.FrozenChains`). The CPU kernel (one core; the
reference) and the CUDA kernels (one GPU) run the same sweep with the same bytes; this
times both in one process on the same machine.

For each R of --chains: real Φ_p from --runs topic-perplexity runs of --steps steps on
--map (explored here, the paper's settings), the chains taking them in turn. Each device
gets one untimed sweep, then the devices are interleaved in every repeat; printed:
nanoseconds per word-sample per chain, median of --repeats, and the ratio CPU / CUDA.
Without numba-cuda or a GPU the CUDA column says why and only the CPU is timed.

    python scripts/bench_label_devices.py                   # zurich-zh17, R = 16, 64, 256
    python scripts/bench_label_devices.py --json out.json   # the table as JSON too
    python scripts/bench_label_devices.py --smoke           # the smallest map, R = 2, one sweep: seconds

Prints and never asserts: timings depend on the machine.
"""

from __future__ import annotations

import argparse
import json
import statistics
import time

from bench_label import setup  # the same maps and Φ_p as the CPU benchmark (this script's folder is on the path)

from curiosity_cli.label.sampling import map_chains
from curiosity_cli.topics.devices import cuda_missing

CHAINS = (16, 64, 256)



def time_devices(config, store, phis, chains: int, devices: list[str], sweeps: int, repeats: int) -> dict:
    """Seconds per word-sample per chain on each device, one list per device."""
    n = store.words.size
    blocks = {}
    for device in devices:
        block = map_chains(store, config.model, device)
        block.start([phis[i % len(phis)] for i in range(chains)], list(range(chains)))
        block.sweep(1)  # compiles, and warms the caches
        blocks[device] = block
    times = {device: [] for device in devices}
    for _ in range(repeats):
        for device, block in blocks.items():
            began = time.perf_counter()
            block.sweep(sweeps)  # the CUDA sweep synchronises before it returns
            times[device].append((time.perf_counter() - began) / (sweeps * n * chains))
    return times


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--map", default="zurich-zh17")
    parser.add_argument("--chains", type=int, nargs="+", default=list(CHAINS))
    parser.add_argument("--runs", type=int, default=4, help="runs whose Φ_p the chains take in turn")
    parser.add_argument("--steps", type=int, default=80)
    parser.add_argument("--sweeps", type=int, default=1, help="sweeps per timing")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--json", help="also write the table to this file")
    parser.add_argument("--smoke", action="store_true", help="tiny inputs, seconds (what tests/test_scripts.py runs)")
    args = parser.parse_args()
    if args.smoke:
        args.map, args.chains, args.runs, args.steps, args.repeats = "rare-patches", [2], 1, 3, 1

    missing = cuda_missing()
    devices = ["cpu"] if missing else ["cpu", "cuda"]
    config, store, phis = setup(args.map, args.runs, args.steps)
    print(f"{args.map}: {store.words.size:,} words, {store.n_cells:,} cells; Φ_p of {args.runs} topic-perplexity runs "
          f"at {args.steps} steps, K = {config.model.topics}; ns per word-sample per chain, median of "
          f"{args.repeats} x {args.sweeps} sweeps (CPU: one core)", flush=True)
    if missing:
        print(f"  CUDA: not timed: {missing}", flush=True)
    print(f"  {'chains R':>8} {'CPU':>9} {'CUDA':>9} {'CPU / CUDA':>11}", flush=True)
    rows = []
    for chains in args.chains:
        times = time_devices(config, store, phis, chains, devices, args.sweeps, args.repeats)
        ns = {device: statistics.median(values) * 1e9 for device, values in times.items()}
        row = {"chains": chains, "cpu_ns": ns["cpu"], "cuda_ns": ns.get("cuda")}
        rows.append(row)
        cuda = f"{ns['cuda']:9.3f}" if "cuda" in ns else f"{'-':>9}"
        ratio = f"{ns['cpu'] / ns['cuda']:10.1f}x" if "cuda" in ns else f"{'-':>11}"
        print(f"  {chains:>8} {ns['cpu']:9.2f} {cuda} {ratio}", flush=True)
    if args.json:
        with open(args.json, "w") as handle:
            json.dump({"map": args.map, "words": int(store.words.size), "cuda_missing": missing, "rows": rows}, handle, indent=1)


if __name__ == "__main__":
    main()
