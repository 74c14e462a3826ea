"""Which measures see a planted effect and ignore a sham (issue 58): the validation table and figure.

Pools the ``mi.csv`` of evaluated experiments that ran stochastic coverage beside the
validation walkers (configs/validation.yaml and validation-sham.yaml; a run two of them
share is taken once, and only when both give it the same values), apart for each labelling
reading the experiments were labelled under (``label.reading``), and writes ``validation.csv``
(a ``reading`` column first) and a figure per reading, ``validation-READING.png``/``.pdf``, to
--out (:mod:`curiosity_cli.evaluate.validation` says what passes). Prints, per reading and map,
each measure that passed and each that did not, with the oracles' leads, the sham's rate and
where topic perplexity sits on the oracles' scale.

    curiosity reproduce validation && curiosity reproduce validation-sham
    python scripts/validate_measures.py results/validation results/validation-sham --out results/validation-table
    # another reading: label copies of the same runs under it (docs/GUIDE.md, "Validating the measures")
    curiosity label results-unseen/validation --set label.reading=unseen-topic && curiosity evaluate results-unseen/validation
    python scripts/validate_measures.py results/validation* results-unseen/validation* --out results/validation-table
    python scripts/validate_measures.py --smoke     # a tiny generated map, every validation walker, seconds
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

from curiosity_cli.errors import CuriosityError
from curiosity_cli.evaluate.validation import ORACLES, pooled_readings, readings_table

#: --smoke's experiment: a tiny generated map, stochastic coverage and every validation walker, 10 restarts of
#: 10 steps, one sweep.
SMOKE = [
    "explore.weight_functions=[stochastic-coverage, oracle-0.1, oracle-0.2, oracle-0.3, sham]", "explore.restarts=10",
    "explore.path_length=10", "explore.checkpoints=[10]", "label.sweeps=1", "label.batch_sweeps=1", "model.topics=8",
    "explore.samples_per_step=500",
]


def validate(folders: list[Path], out: Path, length: int) -> int:
    """Write the table and figures of ``folders`` to ``out`` and print what passed; returns the exit code."""
    from curiosity_cli.plots.validation import validation_figure

    table = readings_table(pooled_readings(folders), length)
    out.mkdir(parents=True, exist_ok=True)
    table.to_csv(out / "validation.csv", index=False)
    figures = [
        validation_figure(block, out / f"validation-{reading}")[0] for reading, block in table.groupby("reading", sort=False)
    ]
    top = f"lead_{max(ORACLES.values()):g}"
    for (reading, dataset), block in table.groupby(["reading", "dataset"], sort=False):
        print(
            f"\n{dataset}, labelled {reading}: {int(block['validated'].sum())} of {len(block)} measures validated "
            f"at {length} steps"
        )
        for _, row in block.iterrows():
            status = "passes" if row["validated"] else ("graded, sham undecided" if row["graded"] else "fails")
            print(
                f"  {row['measure']:<18} {row['against']:<6} {status:<23} {top} {row[top]:+.4f} "
                f"(slope p {row['slope_p']:.3g}, top p {row['top_p']:.3g}); sham rate {row['sham_rate']:.3f} "
                f"[{row['sham_rate_low']:.3f}, {row['sham_rate_high']:.3f}] of {row['sham_replications']}; "
                f"topic perplexity {row['ours_lead']:+.4f} [{row['ours_low']:+.4f}, {row['ours_high']:+.4f}], "
                f"P equivalent {row['ours_p_equivalent']:.2f}"
            )
    print(f"\nwrote {out / 'validation.csv'} and {', '.join(map(str, figures))}")
    return 0


def smoke(folder: Path) -> Path:
    """A tiny generated map explored, labelled and evaluated in ``folder``; returns the experiment folder."""
    import yaml

    from curiosity_cli import api

    (folder / "tiny.yaml").write_text(yaml.safe_dump({
        "name": "tiny-planted", "cell_width": 8, "word_stride": 2, "licence": "CC0",
        "generate": {"seed": 1, "rows": 8, "cols": 10, "vocabulary": 60, "support": 10, "beta": 1.0,
                     "background_topics": 2, "rare_topics": 2, "patches_per_topic": 2, "patch_cells": 1,
                     "patch_gap": 1, "overlap": 0.0},
    }))
    overrides = [*SMOKE, f"datasets=[{folder / 'tiny.yaml'}]", "name=smoke"]
    experiment = api.explore("quick", overrides=overrides, results_dir=folder, cache_dir=folder / "cache", jobs=1).folder
    api.label(experiment, jobs=1, cache_dir=folder / "cache")
    api.evaluate(experiment, cache_dir=folder / "cache")
    return experiment


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("folders", type=Path, nargs="*", help="evaluated experiment folders, e.g. results/validation")
    parser.add_argument("--out", type=Path, help="where validation.csv and the figure go (default: beside the first)")
    parser.add_argument("--length", type=int, default=80, help="the path length read (default 80)")
    parser.add_argument("--smoke", action="store_true", help="a tiny generated map, seconds (tests/test_scripts.py)")
    args = parser.parse_args()
    try:
        if args.smoke:
            with tempfile.TemporaryDirectory() as tmp:
                return validate([smoke(Path(tmp))], Path(tmp) / "table", 10)
        if not args.folders:
            parser.error("expected one or more evaluated experiment folders")
        return validate(args.folders, args.out or args.folders[0].parent / "validation-table", args.length)
    except CuriosityError as exc:
        print(f"Error: {exc}", file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main())
