"""Record a finished study's tables in ``studies/`` (:mod:`curiosity_cli.study.record`), for a study run without ``--record``.

``curiosity reproduce CONFIG --record studies/NAME`` records each combination as it
finishes; this does the same afterwards for every finished combination folder
``specification-NAME_seed-S`` of a study's results (``results/<study>-sweep/``): its
tables, ``config.yaml``, ``provenance.yaml``, ``maps.csv`` and ``record.yaml`` go to
``studies/<study>/seed-S/NAME/``. A combination already recorded is left as it is; one
whose tables are not a current set (unfinished, or edited) is named and skipped.

    python scripts/record_study.py results/multiverse-sweep studies/multiverse
"""

from __future__ import annotations

import argparse
import re
import sys
from pathlib import Path

from curiosity_cli.errors import CuriosityError
from curiosity_cli.study.record import keep_experiment

COMBINATION = re.compile(r"^specification-(?P<specification>.+)_seed-(?P<seed>\d+)$")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("results", type=Path, help="a study's results folder, e.g. results/multiverse-sweep")
    parser.add_argument("record", type=Path, help="where to keep its tables, e.g. studies/multiverse")
    args = parser.parse_args()
    recorded, kept, skipped = 0, 0, []
    for folder in sorted(p for p in args.results.iterdir() if p.is_dir()):
        match = COMBINATION.match(folder.name)
        if match is None:
            continue
        target = args.record / f"seed-{match['seed']}" / match["specification"]
        if target.is_dir():
            kept += 1
            continue
        try:
            keep_experiment(folder, target)
        except CuriosityError as exc:
            skipped.append(f"{folder.name}: {exc}")
            continue
        recorded += 1
    print(f"recorded {recorded} combinations in {args.record} ({kept} were recorded already)")
    for line in skipped:
        print(f"skipped {line}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
