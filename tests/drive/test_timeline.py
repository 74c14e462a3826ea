"""The replay timeline's rule for a surprising frame: it must stand out from the mission, not merely be the highest."""

from __future__ import annotations

import numpy as np
import pytest

from curiosity_cli.drive.timeline import (
    MIN_SPREAD,
    OUTLIER_MADS,
    SURPRISING,
    surprise_threshold,
    surprising,
    timeline_figure,
)

FRAMES = 400


def plateau(seed: int = 0) -> np.ndarray:
    """A steady view's perplexity: 4.3 with 2 % noise (as scripts/check_drive_surprise.py's frames read)."""
    return 4.3 * (1 + 0.02 * np.random.default_rng(seed).standard_normal(FRAMES))


def series(perplexity: np.ndarray, refined: np.ndarray | None = None) -> dict:
    n = len(perplexity)
    return {
        "frame": np.arange(n), "time": 1.7e9 + 0.25 * np.arange(n), "perplexity": perplexity, "score": perplexity,
        "refined": np.ones(n, bool) if refined is None else refined, "clock": "bag", "fell_back": False,
    }


@pytest.mark.parametrize("seed", range(5))
def test_a_plateau_marks_nothing(seed):
    # before, its six highest frames were shown as the most surprising, 2 % above the floor
    assert surprising(plateau(seed)) == []


def test_a_flat_series_marks_nothing_not_even_a_hair_above_it():
    flat = np.full(FRAMES, 2.0)
    assert surprising(flat) == []
    flat[100] = 2.0 * (1 + OUTLIER_MADS * MIN_SPREAD) * 0.99  # all others equal: no spread, but under the least one
    assert surprising(flat) == []
    flat[200] = 2.0 * (1 + OUTLIER_MADS * MIN_SPREAD) * 1.01
    assert surprising(flat) == [200]


def test_a_clear_outlier_is_marked():
    perplexity = plateau()
    perplexity[250] *= 2
    assert surprising(perplexity) == [250]
    median = np.median(perplexity)
    assert surprise_threshold(perplexity) == pytest.approx(median + OUTLIER_MADS * np.median(np.abs(perplexity - median)))


def test_at_most_six_are_marked_the_highest_and_peaks_apart():
    perplexity = plateau()
    peaks = np.arange(10, FRAMES, 40)  # ten outliers, far apart
    perplexity[peaks] = 10 + np.arange(peaks.size)
    perplexity[peaks[-1] + 1] = 30  # beside the highest-but-this: one peak, not two
    assert len(surprising(perplexity)) == SURPRISING
    assert surprising(perplexity) == sorted([peaks[-1] + 1, *peaks[-6:-1]])


def test_a_frame_never_refined_is_never_marked_nor_counted_in_the_rule():
    perplexity = plateau()
    refined = np.ones(FRAMES, bool)
    perplexity[50], refined[50] = 500.0, False  # its words kept their random topics: not a discovery
    perplexity[300] *= 2
    assert surprising(perplexity, eligible=refined) == [300]
    assert surprise_threshold(perplexity, refined) == surprise_threshold(np.delete(perplexity, 50))
    assert surprise_threshold(perplexity, np.zeros(FRAMES, bool)) == np.inf


def test_the_figure_draws_the_rule_and_says_when_no_frame_stands_out():
    figure = timeline_figure(series(plateau()), {}, "a steady view")
    strip, surprise, _ = figure.axes
    (line,) = [line for line in surprise.get_lines() if line.get_linestyle() == "--"]
    assert line.get_ydata()[0] == pytest.approx(surprise_threshold(plateau()))
    (entry,) = surprise.get_legend().get_texts()
    assert entry.get_text() == (
        f"surprising above the median + {OUTLIER_MADS} median absolute deviations (at least 10% above it)"
    )
    assert [t.get_text() for t in strip.texts] == [
        f"no frame stands out: none above the median + {OUTLIER_MADS} median absolute deviations (at least 10% above it)"
    ]
    outlier = plateau()
    outlier[250] *= 2
    image = np.zeros((12, 16, 3), np.uint8)
    strip, surprise, _ = timeline_figure(series(outlier), {250: image}, "a discovery").axes
    assert len(strip.texts) == 0 and len(strip.artists) == 1
