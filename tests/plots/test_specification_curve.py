"""The specification-curve figure: a point per row in the table's order, a dot per choice it used."""

from __future__ import annotations

import numpy as np
import pandas as pd
from matplotlib.collections import PathCollection

from curiosity_cli.plots.specification_curve import specification_curve_figure


def test_points_follow_the_table_and_the_dots_mark_each_rows_map_and_values():
    table = pd.DataFrame({
        "label": ["clamp", "default", "clamp", "default"],
        "dataset": ["a", "a", "b", "b"],
        "ratio": [0.9, 1.0, 1.1, 1.3],
        "ratio_ci_low": [0.8, 0.9, 1.0, 1.2],
        "ratio_ci_high": [1.0, 1.1, 1.2, 1.4],
        "null_no_rw_median": [0.96, 0.97, 0.95, 0.96],
        "null_no_rw_low": [0.85, 0.88, 0.84, 0.86],
        "null_no_rw_high": [1.05, 1.06, 1.04, 1.07],
        "beats_all": [False, False, True, True],
        "p_each_holm": [1.0, 1.0, 0.2, 0.01],
        "paper_map": ["Montreal1", "Montreal1", "Montreal2", "Montreal2"],
        "paper_ratio": [1.51, 1.51, 1.20, 1.20],
    })
    choices = {"default": {"explore.coverage": "literal", "model.beta": "0.1"},
               "clamp": {"explore.coverage": "clamp", "model.beta": "0.1"}}
    fig = specification_curve_figure(table, choices, label="label", datasets=["b", "a"])
    top, dots = fig.axes[:2]
    assert [t.get_text() for t in dots.get_yticklabels()] == [
        "map: b", "map: a", "explore.coverage: literal", "explore.coverage: clamp", "model.beta: 0.1",
    ]
    assert [t.get_text() for t in dots.get_xticklabels()] == table["label"].tolist()
    # each dot is one scatter of one point: used ones big, others small
    used = sorted(
        (int(x), int(y)) for c in dots.collections for (x, y), size in zip(c.get_offsets(), c.get_sizes()) if size > 10
    )
    expected = sorted([(0, 1), (0, 3), (0, 4), (1, 1), (1, 2), (1, 4), (2, 0), (2, 3), (2, 4), (3, 0), (3, 2), (3, 4)])
    assert used == expected
    scatters = [c for c in top.collections if isinstance(c, PathCollection)]
    nulls, points = scatters[0], np.concatenate([c.get_offsets() for c in scatters[1:]])
    assert sorted(map(tuple, points.tolist())) == [(0, 0.9), (1, 1.0), (2, 1.1), (3, 1.3)]
    # filled where the lead holds after Holm's correction, tinted where only uncorrected, hollow elsewhere
    faces = {tuple(xy): tuple(np.round(c.get_facecolor()[0], 2)) for c in scatters[1:] for xy in c.get_offsets().tolist()}
    assert faces[(3, 1.3)][3] == 1.0 and faces[(3, 1.3)][:3] != (1.0, 1.0, 1.0)
    assert faces[(2, 1.1)][3] == 0.3
    assert faces[(0, 0.9)] == faces[(1, 1.0)] == (1.0, 1.0, 1.0, 1.0)
    # behind each point its null reference (the random walk left out): a band from low to high, the median marked
    assert nulls.get_offsets().tolist() == [[0, 0.96], [1, 0.97], [2, 0.95], [3, 0.96]]
    bands = [(round(b.get_x() + b.get_width() / 2, 6), round(b.get_y(), 6), round(b.get_y() + b.get_height(), 6))
             for b in top.patches]
    assert bands == [(0, 0.85, 1.05), (1, 0.88, 1.06), (2, 0.84, 1.04), (3, 0.86, 1.07)]
    paper_lines = sorted(round(line.get_ydata()[0], 2) for line in top.get_lines() if line.get_linestyle() == "--")
    assert paper_lines == [1.2, 1.51]
    assert sorted(t.get_text() for t in top.texts) == ["Montreal1 (paper): 1.51", "Montreal2 (paper): 1.20"]
