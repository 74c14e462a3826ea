#!/usr/bin/env bash
# Fill .device/ (git-ignored) with what scripts/device_check.sh needs on a bare GPU machine
# that reaches no network: the user cache (CURIOSITY_CACHE) with the fetched zurich-zh17 map
# and the word stores of the maps the check uses, and a numba-cuda wheel for Python 3.12 in
# case the machine's own numba-cuda does not import. Run here, from anywhere:
#
#     scripts/prepare_device.sh            # then carry .device (see scripts/device_check.sh)
#
# It prints the folder's size, which must stay well under the 64 MiB a device call carries.
set -euo pipefail
cd "$(dirname "$0")/.."
PY=${PYTHON:-.venv/bin/python}
[ -x "$PY" ] || PY=python3
rm -rf .device
mkdir -p .device/wheels .device/cache/maps
export CURIOSITY_CACHE=$PWD/.device/cache
# the fetched map, from this machine's user cache when it is there (else extract fetches it)
mine=${XDG_CACHE_HOME:-$HOME/.cache}/curiosity/maps/zurich-zh17
[ -d "$mine" ] && cp -r "$mine" .device/cache/maps/
# word stores at the paper's settings: zurich-zh17 (the benchmark), the embedded maps (the grid, the comparison)
for map in zurich-zh17 aerial-mosaic sentinel-coast reef-mosaic; do
    "$PY" -m curiosity_cli extract "$map" >/dev/null
done
rm -rf .device/cache/numba-*   # compiled for this machine's processor, not the device's
"$PY" -m pip download -q --no-deps --only-binary=:all: --python-version 3.12 --implementation cp \
    --platform manylinux_2_28_x86_64 --platform manylinux_2_24_x86_64 -d .device/wheels "numba-cuda==0.30.4"
du -sh .device .device/*
