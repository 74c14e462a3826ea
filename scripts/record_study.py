"""Copy a study's small tables into ``studies/`` so that they are kept in the repository (issue 43).

A study takes longer than one sitting on a 2-core machine, and ``results/`` is not kept.
For every finished combination folder ``specification-NAME_seed-S`` of a study's results
(``results/<study>-sweep/``), this copies the tables its numbers are read from, and what
says how they were made, to ``studies/<study>/seed-S/NAME/``: ``mi.csv``,
``steering.csv``, ``mechanism.csv`` (the per-run tables pooling reads), ``config.yaml``
(the resolved settings: a later study refuses tables made otherwise),
``provenance.yaml`` (commit, versions, command) and ``maps.csv``. Runs and label files
are not copied. A combination without all of them (unfinished) is skipped and named.

Pooling recorded seeds with computed ones inside ``curiosity reproduce`` is not built yet;
what is recorded is the data it will read.

    python scripts/record_study.py results/multiverse-sweep studies/multiverse
"""

from __future__ import annotations

import argparse
import re
import shutil
import sys
from pathlib import Path

TABLES = ("mi.csv", "steering.csv", "mechanism.csv", "config.yaml", "provenance.yaml", "maps.csv")
COMBINATION = re.compile(r"^specification-(?P<specification>.+)_seed-(?P<seed>\d+)$")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("results", type=Path, help="a study's results folder, e.g. results/multiverse-sweep")
    parser.add_argument("record", type=Path, help="where to keep its tables, e.g. studies/multiverse")
    args = parser.parse_args()
    recorded, skipped = 0, []
    for folder in sorted(p for p in args.results.iterdir() if p.is_dir()):
        match = COMBINATION.match(folder.name)
        if match is None:
            continue
        missing = [name for name in TABLES if not (folder / name).is_file()]
        if missing:
            skipped.append(f"{folder.name} (no {', '.join(missing)})")
            continue
        target = args.record / f"seed-{match['seed']}" / match["specification"]
        target.mkdir(parents=True, exist_ok=True)
        for name in TABLES:
            shutil.copyfile(folder / name, target / name)
        recorded += 1
    print(f"recorded {recorded} combinations in {args.record}")
    for line in skipped:
        print(f"skipped {line}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
