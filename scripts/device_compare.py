"""Label a small experiment on the CPU and on a CUDA GPU, and compare the label files byte for byte.

1. Explore a small experiment (--map, --restarts per paper weight function, --steps,
   short label schedules) into --out; label it with ``label.device=cpu``; copy it with
   its batch references and label the copy with ``label.device=cuda``.
2. Compare every label file (and example map) of the two: the files' bytes, and for each
   array the first element that differs.
3. If any differ, find out where the devices part: the same chains (the map's, real Φ_p
   of the runs) swept one sweep at a time on both devices from one start, the first
   sweep whose topics differ, and in it the first word in sweep order (colour, cell,
   word, chain) that differs, with the counts it saw on each device and its draw redone
   here in float32 (numpy: one rounding per operation, never fused) and in float64: a
   draw that differs where the random target sits within a float32 rounding of a running
   sum names a rounding (a fused or reordered float32 operation); a far one, the state
   (counts or random bits) the GPU drew from.

    python scripts/device_compare.py --out /tmp/compare                 # a few minutes on a GPU machine
    python scripts/device_compare.py --out /tmp/compare --diagnose     # step 3 even if the files agree
    python scripts/device_compare.py --out /tmp/compare --reading unseen-topic   # labelled under a masked reading
    python scripts/device_compare.py --smoke     # the CPU against itself, tiny, in a temporary folder: seconds

Exits 0 when every file is the same bytes, 1 when some differ, 2 when there is no GPU.
"""

from __future__ import annotations

import argparse
import json
import shutil
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from curiosity_cli import api
from curiosity_cli.config import LABEL_READINGS
from curiosity_cli.topics.devices import cuda_missing

WEIGHTS = ["random-walk", "stochastic-coverage", "word-perplexity", "topic-perplexity"]


def explore(out: Path, args) -> Path:
    overrides = [
        f"datasets=[{args.map}]", f"explore.restarts={args.restarts}", f"explore.path_length={args.steps}",
        f"explore.checkpoints={[c for c in (10, 20, 40, 80, 160) if c < args.steps] + [args.steps]}",
        f"explore.weight_functions={WEIGHTS}", "name=device-compare", f"label.sweeps={args.sweeps}",
        f"label.warm_sweeps={args.warm_sweeps}", f"label.batch_sweeps={args.batch_sweeps}",
        f"label.reading={args.reading}",
    ]
    return api.explore("quick", overrides=overrides, results_dir=out, jobs=args.jobs).folder


def label_files(folder: Path) -> list[Path]:
    return sorted(p.relative_to(folder) for p in (folder / "labels").rglob("*.npz"))


def compare_files(a: Path, b: Path) -> list[str]:
    """A line per label file or array that differs between folders ``a`` and ``b``."""
    lines = []
    names = label_files(a)
    if names != label_files(b):
        lines.append(f"different label files: {sorted(set(names) ^ set(label_files(b)))[:5]}")
    for name in names:
        if not (b / name).is_file() or (a / name).read_bytes() == (b / name).read_bytes():
            continue
        with np.load(a / name) as x, np.load(b / name) as y:
            differ = []
            for key in sorted(set(x.files) | set(y.files)):
                if key not in x.files or key not in y.files:
                    differ.append(f"{key}: only on one device")
                    continue
                u, v = x[key], y[key]
                if key == "meta":
                    if json.loads(str(u)) != json.loads(str(v)):
                        differ.append(f"meta: {str(u)[:200]} / {str(v)[:200]}")
                    continue
                if u.shape != v.shape or u.tobytes() != v.tobytes():
                    if u.shape != v.shape:
                        differ.append(f"{key}: shape {u.shape} / {v.shape}")
                    else:
                        where = tuple(int(i) for i in np.argwhere(u != v)[0])
                        differ.append(f"{key}: {np.count_nonzero(u != v)} of {u.size} differ, first at {where}: "
                                      f"CPU {u[where]}, GPU {v[where]}")
        lines.append(f"{name}: " + ("; ".join(differ) if differ else "same arrays, different file bytes (zip)"))
    return lines


def diagnose(folder: Path, args) -> None:
    """Step 3 (module docstring): where the CPU's and the GPU's sweeps part."""
    from curiosity_cli.label.sampling import map_chains
    from curiosity_cli.experiment.saved_config import load_saved_config
    from curiosity_cli.explore.runs import read_run
    from curiosity_cli.explore.walker import SparseCounts
    from curiosity_cli.words.extract import extract_words
    from curiosity_cli.maps.map_data import load_map

    config = load_saved_config(folder)
    store = extract_words(load_map(args.map), config.words).store
    runs = sorted((folder / "runs").rglob("run.json"))[: args.diagnose_chains]
    phis = []
    for path in runs:
        run = read_run(path.parent)
        phis.append(SparseCounts.of(run.phi(run.meta["checkpoints"][-1])).dense())
    cpu, gpu = (map_chains(store, config.model, device) for device in args.devices)
    seeds = list(range(len(phis)))
    for chains in (cpu, gpu):
        chains.start(phis, seeds)
    for name, u, v in (("start topics", cpu.topics(), gpu.topics()),):
        if u.tobytes() != v.tobytes():
            print(f"  {name} differ already (the start is the CPU's on both: a copy to or from the GPU is wrong)")
            return
    for sweep in range(args.diagnose_sweeps):
        before_cpu, before_gpu = cpu.counts(), gpu.counts()
        topics_before = cpu.topics()
        cpu.sweep(1)
        gpu.sweep(1)
        u, v = cpu.topics(), gpu.topics()
        counts_cpu, counts_gpu = cpu.counts(), gpu.counts()
        if u.tobytes() == v.tobytes():
            if any(a.tobytes() != b.tobytes() for a, b in zip(counts_cpu, counts_gpu)):
                print(f"  sweep {sweep}: the same topics but different counts: the GPU's count update (settle or "
                      "atomics) is wrong")
                return
            print(f"  sweep {sweep}: the same topics and counts", flush=True)
            continue
        _explain(store, config, cpu, phis, sweep, topics_before, before_cpu, before_gpu, u, v)
        return
    print(f"  {args.diagnose_sweeps} sweeps of {len(phis)} chains: the same bytes on both devices")


def _explain(store, config, cpu, phis, sweep, topics_before, before_cpu, before_gpu, u, v) -> None:
    """The first differing word in sweep order, and its draw redone in float32 and float64."""
    from curiosity_cli.topics._rng import mix, next_state, stream_start, unit32

    order, starts = cpu._order, cpu._colour_starts
    first, count = cpu._cell_first, cpu._cell_count
    rank = np.empty(order.size, np.int64)
    rank[order] = np.arange(order.size)
    word_cells = np.repeat(np.arange(first.size), count)
    wrong = np.argwhere(u != v)
    # sweep order: by the cell's place in the order, then the word's index
    key = rank[word_cells[wrong[:, 0]]] * (u.shape[0] + 1) + wrong[:, 0]
    i, r = (int(x) for x in wrong[np.argmin(key)])
    cell = int(word_cells[i])
    colour = int(np.searchsorted(starts, rank[cell], side="right") - 1)
    print(f"  sweep {sweep}: {np.count_nonzero(u != v)} of {u.size} topics differ; the first in sweep order: word {i} "
          f"(cell {cell}, colour {colour}, chain {r}): CPU topic {u[i, r]}, GPU {v[i, r]}")
    same_ng = before_cpu[1][cell, :, r].tobytes() == before_gpu[1][cell, :, r].tobytes()
    print(f"  its cell's neighbourhood sums before the sweep: {'the same' if same_ng else 'DIFFERENT'} on both devices")
    # redo the cell on the CPU's state, in numpy, up to word i: its sums as the colours before it left them
    k_topics = config.model.topics
    alpha32 = np.float32(config.model.alpha)
    counts = np.asarray(phis[r], np.int64)
    inv = (1.0 / (counts.sum(axis=0) + store.vocabulary_size * config.model.beta)).astype(np.float32)
    phiw = (counts.astype(np.float32) + np.float32(config.model.beta)) * inv
    sums = np.zeros(k_topics, np.int64)
    for d in [cell, *(int(d) for d in cpu._table[cell] if d >= 0)]:
        swept = np.searchsorted(starts, rank[d], side="right") - 1 < colour
        words_of_d = slice(int(first[d]), int(first[d] + count[d]))
        sums += np.bincount((u if swept else topics_before)[words_of_d, r].astype(np.int64), minlength=k_topics)
    state = stream_start(mix(np.uint64(r)), np.uint64(first.size + sweep), cell)
    for j in range(int(first[cell]), i + 1):
        w = store.words[j]
        old = int(topics_before[j, r])
        sums[old] -= 1
        weights = phiw[w] * (sums.astype(np.float32) + alpha32)  # float32, one rounding each
        running = np.zeros(k_topics, np.float32)
        total = np.float32(0)
        for k in range(k_topics):
            total = np.float32(total + weights[k])
            running[k] = total
        state, bits = next_state(np.uint64(state))
        target = np.float32(unit32(np.uint64(bits)) * total)
        new = int(np.count_nonzero(running <= target))
        if j < i:
            sums[int(u[j, r])] += 1
            continue
        exact = np.cumsum(phiw[w].astype(np.float64) * (sums + float(config.model.alpha)))
        gap = np.min(np.abs(running.astype(np.float64) - float(target)))
        print(f"  redone in numpy float32: topic {new} (the CPU's {u[i, r]}); target {float(target):.9g} of total "
              f"{float(total):.9g}; nearest running sum {gap:.3g} away ({gap / max(float(total), 1e-30):.3g} of the total, "
              f"float32 rounding is {np.finfo(np.float32).eps:.3g}); float64 total {exact[-1]:.12g}")
        if gap <= 4 * np.finfo(np.float32).eps * float(total):
            print("  => the target sits within float32 roundings of a running sum: the GPU rounded a float32 sum or "
                  "product differently (a fused multiply-add, or another order of the sums over topics)")
        else:
            print("  => the draw is far from any boundary: the GPU drew from another state (its random bits or the "
                  "counts it read), not a rounding")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", type=Path, help="the experiment and its two labelled copies go here (required)")
    parser.add_argument("--map", default="aerial-mosaic")
    parser.add_argument("--restarts", type=int, default=3)
    parser.add_argument("--steps", type=int, default=40)
    parser.add_argument("--sweeps", type=int, default=16)
    parser.add_argument("--warm-sweeps", type=int, default=4)
    parser.add_argument("--batch-sweeps", type=int, default=20)
    parser.add_argument("--jobs", type=int, default=None)
    parser.add_argument("--reading", default="frozen", choices=LABEL_READINGS,
                        help="how Z_p is labelled (label.reading): the masked readings take a per-chain topic mask")
    parser.add_argument("--diagnose", action="store_true", help="step 3 even if the files agree")
    parser.add_argument("--diagnose-chains", type=int, default=8)
    parser.add_argument("--diagnose-sweeps", type=int, default=3)
    parser.add_argument("--devices", nargs=2, default=["cpu", "cuda"], help="the two devices (cpu cpu: a check of this script)")
    parser.add_argument("--smoke", action="store_true",
                        help="the CPU against itself on tiny inputs with step 3, in a temporary folder, seconds "
                        "(what tests/test_scripts.py runs)")
    args = parser.parse_args()
    if args.smoke:
        args.devices, args.map, args.restarts, args.steps, args.jobs = ["cpu", "cpu"], "rare-patches", 1, 10, 1
        args.diagnose = True
        args.sweeps = args.warm_sweeps = args.batch_sweeps = args.diagnose_chains = args.diagnose_sweeps = 1
        with tempfile.TemporaryDirectory() as tmp:
            args.out = Path(tmp)
            sys.exit(compare(args))
    if args.out is None:
        parser.error("the following argument is required: --out")
    missing = cuda_missing() if "cuda" in args.devices else None
    if missing:
        print(f"device_compare: no GPU to compare with: {missing}")
        sys.exit(2)
    sys.exit(compare(args))


def compare(args) -> int:
    """Steps 1 to 3 (module docstring) into ``args.out``; the exit code."""
    began = time.perf_counter()
    folder = explore(args.out / "results", args)
    print(f"explored {folder} in {time.perf_counter() - began:.0f} s", flush=True)
    on = {}
    for side, device in enumerate(args.devices):
        copy = args.out / f"{side}-{device}" / folder.name
        if copy.exists():
            shutil.rmtree(copy)
        source = on.get(0, folder)
        shutil.copytree(source, copy, ignore=shutil.ignore_patterns("labels"))  # the CPU's batch references reused
        began = time.perf_counter()
        done = api.label(copy, overrides=[f"label.device={device}"], jobs=args.jobs, reuse=False)  # computed on each device
        print(f"labelled {done['labelled']} runs on {device} in {time.perf_counter() - began:.1f} s", flush=True)
        on[side] = copy
    files = label_files(on[0])
    lines = compare_files(on[0], on[1])
    print(f"{len(files)} label files and example maps compared: "
          + ("every one the same bytes on both devices" if not lines else f"{len(lines)} differ"))
    for line in lines[:20]:
        print(f"  {line}")
    if lines or args.diagnose:
        print("where the devices part" + (" (the frozen reading's chains, without the reading's masks)"
                                          if args.reading != "frozen" else "") + ":", flush=True)
        diagnose(on[0], args)
    return 1 if lines else 0


if __name__ == "__main__":
    main()
