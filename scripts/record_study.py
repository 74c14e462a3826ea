"""Record a finished study's tables in ``studies/`` (:mod:`curiosity_cli.study.record`), for a study run without ``--record``.

``curiosity reproduce CONFIG --record studies/NAME`` records each combination as it
finishes; this does the same afterwards for every finished combination folder
``specification-NAME_seed-S`` of a study's results (``results/<study>-sweep/``): its
tables, ``config.yaml``, ``provenance.yaml``, ``maps.csv`` and ``record.yaml`` go to
``studies/<study>/seed-S/NAME/``, with ``runs.csv`` (each run's path and Φ_p digests). A
combination already recorded is left as it is, and its runs are checked against the
record's: one computed again that explored other runs is named, and the exit code is 1
(a folder recorded before ``runs.csv`` was kept cannot be checked, and is counted). One
whose tables are not a current set (unfinished, or edited) is named and skipped.

    python scripts/record_study.py results/multiverse-sweep studies/multiverse
    python scripts/record_study.py --smoke     # a tiny study made in a temporary folder, recorded there: seconds
"""

from __future__ import annotations

import argparse
import re
import sys
import tempfile
from pathlib import Path

from curiosity_cli.errors import CuriosityError
from curiosity_cli.study.record import RUNS, keep_experiment, same_runs

COMBINATION = re.compile(r"^specification-(?P<specification>.+)_seed-(?P<seed>\d+)$")
#: --smoke's study: one combination, two walkers of two restarts of 10 steps on the smallest map, one sweep.
SMOKE = [
    "datasets=[rare-patches]", "explore.weight_functions=[random-walk, topic-perplexity]", "explore.restarts=2",
    "explore.path_length=10", "explore.checkpoints=[10]", "label.sweeps=1", "label.batch_sweeps=1",
]


def record_study(results: Path, record: Path) -> int:
    """Record every finished combination of ``results`` in ``record`` (module docstring); return the exit code."""
    recorded, kept, unchecked, skipped, differ = 0, 0, 0, [], []
    for folder in sorted(p for p in results.iterdir() if p.is_dir()):
        match = COMBINATION.match(folder.name)
        if match is None:
            continue
        target = record / f"seed-{match['seed']}" / match["specification"]
        try:
            if target.is_dir():
                kept += 1
                if not (target / RUNS).is_file():
                    unchecked += 1
                elif (difference := same_runs(target, folder)) is not None:
                    differ.append(f"{folder.name}: {difference}")
                continue
            keep_experiment(folder, target)
        except CuriosityError as exc:
            skipped.append(f"{folder.name}: {exc}")
            continue
        recorded += 1
    print(
        f"recorded {recorded} combinations in {record} ({kept} were recorded already: "
        f"{kept - unchecked - len(differ)} explored the recorded runs, {unchecked} recorded without runs to check)"
    )
    for line in skipped:
        print(f"skipped {line}", file=sys.stderr)
    for line in differ:
        print(f"not the recorded runs: {line}", file=sys.stderr)
    return 1 if differ else 0


def smoke_study(folder: Path) -> Path:
    """A study's results folder in ``folder``: one combination explored, labelled and evaluated (:data:`SMOKE`)."""
    from curiosity_cli import api

    results = folder / "smoke-sweep"
    experiment = api.explore(
        "quick", overrides=[*SMOKE, "name=specification-default_seed-0"], results_dir=results, jobs=1
    ).folder
    api.label(experiment, jobs=1)
    api.evaluate(experiment)
    return results


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("results", type=Path, nargs="?", help="a study's results folder, e.g. results/multiverse-sweep")
    parser.add_argument("record", type=Path, nargs="?", help="where to keep its tables, e.g. studies/multiverse")
    parser.add_argument("--smoke", action="store_true", help="a tiny study recorded in a temporary folder, seconds "
                        "(what tests/test_scripts.py runs)")
    args = parser.parse_args()
    if args.smoke:
        with tempfile.TemporaryDirectory() as tmp:
            return record_study(smoke_study(Path(tmp)), Path(tmp) / "record")
    if args.record is None:
        parser.error("expected a study's results folder and where to keep its tables")
    return record_study(args.results, args.record)


if __name__ == "__main__":
    sys.exit(main())
