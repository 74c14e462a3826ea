#!/usr/bin/env bash
# The check on a GPU machine (issue 33), in one run of about 8 minutes, from the repository root.
#
# Here, first:   scripts/prepare_device.sh          (fills the git-ignored .device/, ~10 MB)
# There:         bash scripts/device_check.sh       (carry: [".device"]; $OUT receives the logs)
# Here, a check: bash scripts/device_check.sh --small   (no GPU: the CPU parts on tiny settings)
#
# Parts, each with its own time limit, each printing its own error and the script going on:
#   0. the machine: GPU, Python, numpy, numba, numba-cuda (the carried wheel if the machine's
#      does not import); the CUDA kernels against the CPU kernels, byte for byte, on tiny maps
#   a. scripts/bench_label_devices.py: ns per word-sample per chain, CPU vs CUDA, R = 16, 64, 256
#   b. scripts/device_compare.py: a small experiment labelled on both devices, label files
#      compared byte for byte, and where the devices part if they do not agree; under the
#      frozen reading and the two masked ones (unseen-topic, used-topics)
#   d. the machine's cores (lscpu) and scripts/bench_batch_threads.py: the batch reference's sweeps on
#      1, 4 and 16 threads, beside the reference checkout in .device/ref when there is one
#   c. the paper grid (bench_pipeline.py --full-grid --grid-only --grids paper --jobs 16) with
#      --device cuda, then CPU only, each stage timed, the label stage's timeline from its
#      files (batch references, first and last label file) and its profile (bench_label_profile.py
#      --folder): in the time left (DEVICE_CHECK_SECONDS)
# DEVICE_CHECK_SKIP names parts to leave out: a (the benchmark, when its kernels did not change), b (the comparison),
# d (the threads), gpu-grid (part c on the CPU only), cpu-grid (part c on the GPU only); e.g. DEVICE_CHECK_SKIP=a,b.
set -u
cd "$(dirname "$0")/.."
small=0
[ "${1:-}" = "--small" ] && small=1
export PYTHONPATH=$PWD${PYTHONPATH:+:$PYTHONPATH}
export CURIOSITY_CACHE=$PWD/.device/cache PYTHONUNBUFFERED=1 MPLBACKEND=Agg
OUT=${OUT:-$PWD/.device/out}
mkdir -p "$OUT"
PY=${PYTHON:-python3}
[ -x .venv/bin/python ] && [ -z "${PYTHON:-}" ] && [ $small = 1 ] && PY=.venv/bin/python
started=$(date +%s)
budget=${DEVICE_CHECK_SECONDS:-$([ $small = 1 ] && echo 900 || echo 450)}
left() { echo $(( budget - ($(date +%s) - started) )); }
# the time limit of a part: its own cap, or what is left less a reserve
limit() { local l; l=$(( $(left) - ${2:-10} )); [ "$l" -gt "$1" ] && l=$1; [ "$l" -lt 1 ] && l=1; echo $l; }
part() { echo; echo "=== $1 ($(left) s left) ==="; }
summary=()

exec > >(tee -a "$OUT/device_check.log") 2>&1

part "0. the machine"
# the shipped configs and data are package resources that pyproject.toml maps from configs/ and
# data/; on a bare machine (no install: its setuptools may be too old for pyproject.toml, and
# nothing can be fetched) this copy of the checkout links them into place instead
if ! "$PY" -c "import curiosity_cli.paths" 2>/dev/null; then
    echo "curiosity is not installed here: linking configs/ and data/ in as curiosity_cli.shipped's packages"
    for tree in . .device/ref; do
        [ -d $tree/curiosity_cli ] || continue
        ln -sfn ../../configs $tree/curiosity_cli/shipped/configs && ln -sfn ../../data $tree/curiosity_cli/shipped/data
        touch $tree/configs/__init__.py $tree/data/__init__.py
    done
fi
"$PY" -c "import curiosity_cli.paths as p; print('curiosity: configs at', p.SHIPPED_CONFIGS)" 2>&1 | tail -1
nvidia-smi -L 2>&1 || echo "no nvidia-smi"
"$PY" -c "import sys, numpy, numba; print('python', sys.version.split()[0], '| numpy', numpy.__version__, '| numba', numba.__version__)"
"$PY" -c "import importlib.metadata as m; print('numba-cuda', m.version('numba-cuda'))" 2>&1 | tail -1
missing=$("$PY" -c "from curiosity_cli.topics.devices import cuda_missing; print(cuda_missing() or '')" 2>&1 | tail -1)
if [[ "$missing" == *numba-cuda* ]] && ls .device/wheels/*.whl >/dev/null 2>&1; then
    echo "the machine's numba-cuda does not import ($missing); installing the carried wheel"
    "$PY" -m pip install -q --no-index --no-deps --no-compile --target /tmp/site .device/wheels/*.whl \
        && export PYTHONPATH=/tmp/site:$PYTHONPATH
    missing=$("$PY" -c "from curiosity_cli.topics.devices import cuda_missing; print(cuda_missing() or '')" 2>&1 | tail -1)
fi
if [ -n "$missing" ]; then
    gpu=0; echo "no GPU to label on: $missing"; summary+=("GPU: none ($missing)")
else
    gpu=1; summary+=("GPU: $(nvidia-smi -L 2>/dev/null | head -1)")
    if timeout "$(limit 120)" "$PY" tests/topics/cuda_cases.py; then
        summary+=("0. tiny maps, CUDA vs CPU kernels: the same bytes")
    else
        summary+=("0. tiny maps, CUDA vs CPU kernels: DIFFERENT or failed (exit $?; see the log)")
    fi
fi

skip=${DEVICE_CHECK_SKIP:-}
part "a. benchmark: CPU lock-step vs CUDA, ns per word-sample per chain"
if [[ ",$skip," == *,a,* ]]; then summary+=("a. benchmark: skipped (DEVICE_CHECK_SKIP)")
elif [ $small = 1 ]; then bench=(--map aerial-mosaic --chains 8 16 --runs 2 --steps 10 --repeats 1)
else bench=(--chains 16 64 256 --repeats 3); fi
if [[ ",$skip," == *,a,* ]]; then :
elif timeout "$(limit 170 240)" "$PY" scripts/bench_label_devices.py "${bench[@]}" --json "$OUT/bench.json"; then
    summary+=("a. benchmark: $OUT/bench.json")
else
    summary+=("a. benchmark: failed or timed out (exit $?)")
fi

part "b. a small experiment labelled on both devices, label files compared"
if [ $gpu = 1 ]; then compare=(--devices cpu cuda); else compare=(--devices cpu cpu); echo "(no GPU: cpu against cpu, a check of the script)"; fi
if [ $small = 1 ]; then compare+=(--restarts 1 --steps 20 --sweeps 2 --warm-sweeps 1 --batch-sweeps 2 --jobs 2 --diagnose --diagnose-chains 2 --diagnose-sweeps 1)
else compare+=(--restarts 3 --steps 40 --jobs 16); fi
# the frozen reading, then the two that give each chain a topic mask (unseen-topic with one topic more)
for reading in frozen unseen-topic used-topics; do
    rm -rf /tmp/device-compare
    echo "--- label.reading=$reading"
    if [[ ",$skip," == *,b,* ]]; then status=skipped
    else timeout "$(limit 150 60)" "$PY" scripts/device_compare.py --out /tmp/device-compare --reading $reading "${compare[@]}"
        status=$?; fi
    case $status in
        skipped) summary+=("b. label files ($reading): skipped (DEVICE_CHECK_SKIP)");;
        0) summary+=("b. label files ($reading) ${compare[1]} vs ${compare[2]}: the same bytes");;
        1) summary+=("b. label files ($reading) ${compare[1]} vs ${compare[2]}: DIFFERENT (the log says where)");;
        *) summary+=("b. label files ($reading): failed or timed out (exit $status)");;
    esac
done

part "d. the machine's cores, and the batch reference's sweeps on 1 to 16 threads"
lscpu | grep -E "^(Model name|CPU\(s\)|Thread\(s\) per core|Core\(s\) per socket|Socket\(s\)|L3)" || echo "no lscpu"
threads=(1 4 16); [ $small = 1 ] && threads=(1 2)
reference=(); [ -d .device/ref/curiosity_cli ] && reference=(--reference .device/ref)
if [[ ",$skip," == *,d,* ]]; then summary+=("d. threads: skipped (DEVICE_CHECK_SKIP)")
elif timeout "$(limit 150 240)" "$PY" scripts/bench_batch_threads.py "${reference[@]}" --maps reef-mosaic --threads "${threads[@]}" \
        --repeats 1 --sweeps 20 --colours; then
    summary+=("d. batch sweeps on threads: in the log")
else
    summary+=("d. batch sweeps on threads: failed or timed out (exit $?)")
fi

part "c. the paper grid, --jobs 16, each stage timed (in the time left)"
jobs=$(nproc); [ "$jobs" -gt 16 ] && jobs=16
devices=(); [ $gpu = 1 ] && [[ ",$skip," != *,gpu-grid,* ]] && devices=(cuda)
[[ ",$skip," != *,cpu-grid,* ]] && devices+=(cpu)
for device in "${devices[@]}"; do
    t=$(limit 600 5)
    if [ "$t" -lt 60 ]; then summary+=("c. paper grid on $device: not run, $t s left"); continue; fi
    echo "--- label.device=$device, $t s at most"
    if [ $small = 1 ]; then
        tmp=$(mktemp -d)
        timeout "$t" "$PY" -m curiosity_cli reproduce quick --results-dir "$tmp" --jobs 2 --no-reuse --set "datasets=[aerial-mosaic]" \
            --set explore.restarts=2 --set explore.path_length=20 --set "explore.checkpoints=[10,20]" \
            --set label.sweeps=2 --set label.warm_sweeps=1 --set label.batch_sweeps=2 --set label.device=$device \
            > "$OUT/grid_$device.log" 2>&1
        status=$?
        grep -A12 "## Time" "$tmp"/quick/REPORT.md 2>/dev/null
        rm -rf "$tmp"
    else
        tmp=$(mktemp -d)
        timeout "$t" "$PY" scripts/bench_pipeline.py --full-grid --grid-only --grids paper --jobs "$jobs" --device "$device" \
            --results-dir "$tmp" > "$OUT/grid_$device.log" 2>&1
        status=$?
        tail -25 "$OUT/grid_$device.log"
        "$PY" - "$tmp" <<'PY'
import json, sys
from pathlib import Path
import numpy as np
folder = next(Path(sys.argv[1]).glob("*/config.yaml")).parent
def times(pattern):
    return sorted(p.stat().st_mtime for p in folder.glob(pattern))
runs, labels = times("runs/**/run.json"), times("labels/*/*/restart-*.npz")
t0 = runs[0] if runs else 0
print(f"label stage from its files ({folder.name}), seconds after the first run.json:")
print(f"  runs explored: last at {runs[-1] - t0:.0f}" if runs else "  no runs")
for batch in sorted(folder.glob("batch/*.npz")):
    with np.load(batch) as npz:
        print(f"  batch {batch.stem}: written at {batch.stat().st_mtime - t0:.0f}, {json.loads(str(npz['meta']))['seconds']:.1f} s of sweeps")
if labels:
    print(f"  label files: {len(labels)}, first at {labels[0] - t0:.0f}, last at {labels[-1] - t0:.0f}")
PY
        "$PY" scripts/bench_label_profile.py --folder "$(dirname "$(ls "$tmp"/*/config.yaml | head -1)")"
        rm -rf "$tmp"
    fi
    if [ $status = 0 ]; then summary+=("c. paper grid on $device: $(grep -m1 'min end to end' "$OUT/grid_$device.log" | sed 's/.*: //')")
    else summary+=("c. paper grid on $device: failed or timed out (exit $status; $OUT/grid_$device.log)"); tail -5 "$OUT/grid_$device.log"; fi
done

part "summary ($(( $(date +%s) - started )) s)"
for line in "${summary[@]}"; do echo "  $line"; done
[ -f "$OUT/bench.json" ] && "$PY" -c "
import json; d = json.load(open('$OUT/bench.json'))
for r in d['rows']:
    c = r['cuda_ns']; print(f\"  R = {r['chains']:>3}: CPU {r['cpu_ns']:.2f} ns, CUDA {'-' if c is None else f'{c:.3f}'} ns\" + ('' if c is None else f\", {r['cpu_ns'] / c:.0f}x\"))
"
exit 0
