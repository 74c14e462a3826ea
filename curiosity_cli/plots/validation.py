"""The validation figure (issue 58): each measure's lead of the oracles over stochastic coverage as P grows,
beside the sham's and topic perplexity's, one panel per measure and map."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from curiosity_cli.evaluate.validation import ORACLES


def validation_figure(table, stem: Path) -> list[Path]:
    """Draw :func:`~curiosity_cli.evaluate.validation.validation_table`'s rows against the truth (``human``) and
    against no labelling (``words``): a row of panels per measure, a column per map; returns the PNG and PDF.

    Each panel: the oracles' mean lead at P with its 95 % interval (0 at P = 0, where an oracle is stochastic
    coverage), topic perplexity's lead and interval as a band, the sham's mean lead as a cross at P = 0; the
    title says whether the measure passed there (the criteria in the table).
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from curiosity_cli.plots.figures import save_figure

    rows = table[table["against"].isin(["human", "words"])]
    measures = list(dict.fromkeys(zip(rows["measure"], rows["against"])))
    datasets = list(dict.fromkeys(rows["dataset"]))
    shares = np.array([0.0, *ORACLES.values()])
    fig, axes = plt.subplots(
        len(measures), len(datasets), figsize=(3.2 * len(datasets), 2.3 * len(measures)), squeeze=False,
        layout="constrained",
    )
    for i, (measure, against) in enumerate(measures):
        for j, dataset in enumerate(datasets):
            ax = axes[i, j]
            match = rows[(rows["measure"] == measure) & (rows["against"] == against) & (rows["dataset"] == dataset)]
            if match.empty:
                ax.set_axis_off()
                continue
            row = match.iloc[0]
            lead = np.array([0.0, *(row[f"lead_{p:g}"] for p in ORACLES.values())])
            low = np.array([0.0, *(row[f"lead_{p:g}_low"] for p in ORACLES.values())])
            high = np.array([0.0, *(row[f"lead_{p:g}_high"] for p in ORACLES.values())])
            ax.axhline(0, color="0.6", lw=0.8)
            ax.errorbar(shares, lead, yerr=[lead - low, high - lead], color="tab:green", marker="o", ms=3,
                        capsize=2, label="oracle-P")
            if np.isfinite(row["ours_lead"]):
                ax.axhspan(row["ours_low"], row["ours_high"], color="tab:red", alpha=0.15, lw=0)
                ax.axhline(row["ours_lead"], color="tab:red", lw=1, ls="--", label="topic perplexity")
            if np.isfinite(row["sham_lead"]):
                ax.plot([0], [row["sham_lead"]], marker="x", color="0.2", ls="", label="sham")
            verdict = "passes" if row["validated"] else ("graded; sham undecided" if row["graded"] else "fails")
            ax.set_title(f"{dataset}: {verdict}", fontsize=8)
            ax.tick_params(labelsize=7)
            if j == 0:
                ax.set_ylabel(f"{measure}\n({'truth' if against == 'human' else 'no labels'}) lead", fontsize=7)
            if i == len(measures) - 1:
                ax.set_xlabel("P (oracle's chance of a new class)", fontsize=7)
    axes[0, 0].legend(fontsize=6, loc="upper left")
    fig.suptitle("Lead over stochastic coverage (up: better; a time: sooner)", fontsize=8)
    paths = save_figure(fig, stem)
    plt.close(fig)
    return paths
