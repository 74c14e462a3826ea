#!/usr/bin/env python3
"""Make the embedded map ``geonrw-essen`` in ``data/maps/`` from its GeoNRW source tile.

``geonrw-essen`` is a 992 x 992 crop of the GeoNRW tile ``essen_360_5693``: a real 1 m
aerial photograph of forest crossed by roads, with land-cover labels that GeoNRW
rasterised from official map data (not drawn on these pixels). The recipe, the pinned
source commit and the SHA-256 of each source file are in
``scripts/embedded_maps/geonrw_essen.py``; licence and attribution in data/README.md.

The two source files are in the public GitHub repository
``aniketqxp/carbon-sequestration-index`` (folder ``geonrw_samples/``), which neither CI nor
a user's machine can reach, so the map is committed and this script is run by hand with
``--source`` naming either a git clone or mirror of that repository (the files are read
from the pinned commit with ``git show``), or a folder holding the two files. Each file is
checked against its SHA-256 before use.

Examples
--------
Make the map, or check the committed one against a fresh build::

    git clone https://github.com/aniketqxp/carbon-sequestration-index /tmp/csi
    python scripts/make_geonrw_map.py --source /tmp/csi
    python scripts/make_geonrw_map.py --source /tmp/csi --check
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from curiosity_cli.errors import CuriosityError, DatasetError
from curiosity_cli.files import display_path

from embedded_maps.geonrw_essen import NAME, SOURCE_COMMIT, SOURCE_FILES, SOURCE_FOLDER, build_geonrw_essen
from embedded_maps.map_files import compare_maps, write_map_files

DEFAULT_OUT_DIR = Path(__file__).resolve().parent.parent / "data" / "maps"
SCRIPT = "scripts/make_geonrw_map.py"


def parse_args(argv: list[str] | None) -> argparse.Namespace:
    """Parse the command line (see the module docstring)."""
    parser = argparse.ArgumentParser(
        prog="make_geonrw_map.py",
        description=f"Make the embedded map {NAME} (image.png, labels.png, legend.yaml) from its GeoNRW tile.",
    )
    parser.add_argument(
        "--source",
        type=Path,
        required=True,
        metavar="PATH",
        help=f"a git clone or mirror of the source repository (read at commit {SOURCE_COMMIT[:7]}), "
        f"or a folder holding {' and '.join(SOURCE_FILES)}",
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
        help="make the map in a temporary folder and compare it with the one in --out; exit 1 if it differs",
    )
    return parser.parse_args(argv)


def read_sources(source: Path) -> dict[str, bytes]:
    """The bytes of the source files, from a folder holding them or from a git repository at the pinned commit.

    Raises
    ------
    DatasetError
        A file is in neither place.
    """
    if all((source / filename).is_file() for filename in SOURCE_FILES):
        return {filename: (source / filename).read_bytes() for filename in SOURCE_FILES}
    sources = {}
    for filename in SOURCE_FILES:
        spec = f"{SOURCE_COMMIT}:{SOURCE_FOLDER}/{filename}"
        try:
            result = subprocess.run(["git", "-C", str(source), "show", spec], capture_output=True, check=False)
        except OSError as exc:
            raise DatasetError(f"cannot run git to read {spec} from {source}: {exc}") from exc
        if result.returncode != 0:
            message = result.stderr.decode(errors="replace").strip().splitlines()
            raise DatasetError(
                f"{source} holds neither {filename} nor a git repository with {spec}"
                + (f" (git: {message[-1]})" if message else "")
            )
        sources[filename] = result.stdout
    return sources


def main(argv: list[str] | None = None) -> int:
    """Run the command line; return the exit code."""
    args = parse_args(argv)
    try:
        start = time.perf_counter()
        image, labels, legend = build_geonrw_essen(read_sources(args.source))
        if args.check:
            with tempfile.TemporaryDirectory(prefix="curiosity-maps-") as tmp:
                write_map_files(NAME, Path(tmp), image, labels, legend, SCRIPT)
                problem = compare_maps(NAME, Path(tmp), args.out)
            print(f"{NAME}: {'identical' if problem is None else 'differs: ' + problem}", flush=True)
            return 0 if problem is None else 1
        fractions = write_map_files(NAME, args.out, image, labels, legend, SCRIPT)
        shares = ", ".join(f"{k} {100 * v:.1f}%" for k, v in fractions.items())
        print(f"{NAME}: {time.perf_counter() - start:.1f} s -> {display_path(args.out / NAME)} ({shares})", flush=True)
        return 0
    except CuriosityError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main())
