"""The drive's readings of surprise: each against a plain recomputation, the one named by drive.surprise steering,
and the four-laps check of revisits and a change (scripts/check_revisits.py) giving what the guide reports."""

from __future__ import annotations

import dataclasses
import importlib.util
import math
from pathlib import Path

import numpy as np
import pytest

from curiosity_cli.config import CONFIG_DIR, DRIVE_SURPRISES, load_config
from curiosity_cli.drive.curiosity import cell_perplexity
from curiosity_cli.drive.pipeline import CuriosityPipeline
from curiosity_cli.drive.stream import StreamModel
from curiosity_cli.drive.surprise import RECENT_FRAMES, add_and_score, predicted_mix
from curiosity_cli.errors import ParameterError

K, V, GRID = 6, 40, (2, 3)


def stream(memory=None) -> StreamModel:
    return StreamModel(K, V, GRID, memory=memory, spatial=4, temporal=2, alpha=0.1, beta=0.1, newest_share=0.5,
                       budget=300, seed=1)


def frames(n: int, seed: int = 0) -> list[list[np.ndarray]]:
    rng = np.random.default_rng(seed)
    return [[rng.integers(0, V, rng.integers(0, 9)) for _ in range(6)] for _ in range(n)]


def naive_readings(model: StreamModel, cell_words) -> dict:
    """Every reading by plain loops over the model's counts, before and after adding the frame."""
    m = model.model
    alpha, beta = m.alpha, m.beta
    before = model.frame_cells()
    if before is None:
        mix = np.full((6, K), 1 / K)
    else:
        ng = m.neighbourhood_counts()
        mix = np.array([[(ng[c, k] + alpha) / (ng[c].sum() + K * alpha) for k in range(K)] for c in before])
    nwk, nk = m.topic_word_counts(), m.topic_totals()
    predictive = []
    for c, words in enumerate(cell_words):
        logs = [math.log(sum(mix[c, k] * (nwk[w, k] + beta) / (nk[k] + V * beta) for k in range(K))) for w in words]
        predictive.append(math.exp(-sum(logs) / len(logs)) if logs else 1.0)
    counts = model.add_frame(cell_words)
    cells = model.frame_cells()
    ng = m.neighbourhood_counts()
    ncz = m.cell_topic_counts()
    recent = sum(ncz[model.frame_cells(back)].sum(axis=0) for back in range(min(RECENT_FRAMES, model.frames_in_memory)))
    bayesian = []
    for row, c in enumerate(cells):
        post = [(ng[c, k] + alpha) / (ng[c].sum() + K * alpha) for k in range(K)]
        bayesian.append(sum(p * math.log2(p / mix[row, k]) for k, p in enumerate(post)))
    return {
        "paper": cell_perplexity(counts, m.topic_totals(), alpha), "predictive": np.array(predictive),
        "recent": cell_perplexity(counts, recent, alpha), "bayesian": np.array(bayesian),
    }


@pytest.mark.parametrize("memory", [None, 4])
def test_each_reading_is_its_plain_recomputation_frame_after_frame(memory):
    fast, slow = stream(memory), stream(memory)
    for cell_words in frames(30):
        got = add_and_score(fast, cell_words, DRIVE_SURPRISES, 0.1)
        want = naive_readings(slow, cell_words)
        for reading in DRIVE_SURPRISES:
            assert got[reading] == pytest.approx(want[reading], rel=1e-9, abs=1e-12), reading
    assert np.array_equal(fast.topic_totals(), slow.topic_totals()), "scoring changes nothing of the model"


def test_before_the_first_frame_the_predicted_mix_is_uniform_and_a_cell_without_words_is_not_surprising():
    model = stream()
    assert np.array_equal(predicted_mix(model), np.full((6, K), 1 / K))
    got = add_and_score(model, [np.array([], np.int64)] * 6, DRIVE_SURPRISES, 0.1)
    assert (got["paper"] == 1).all() and (got["predictive"] == 1).all() and (got["recent"] == 1).all()
    with pytest.raises(ParameterError, match=r"readings: got \['novelty'\], expected some of paper, predictive"):
        add_and_score(model, frames(1)[0], ["novelty"], 0.1)


def test_the_reading_drive_surprise_names_steers_and_the_others_ride_along():
    config = load_config(CONFIG_DIR / "paper-grid.yaml")
    rng = np.random.default_rng(2)
    pictures = [rng.integers(0, 256, (96, 128, 3), dtype=np.uint8) for _ in range(4)]
    paper = CuriosityPipeline(config, seed=0)
    predictive = CuriosityPipeline(
        dataclasses.replace(config, drive=dataclasses.replace(config.drive, surprise="predictive")), seed=0,
        readings=("paper",),
    )
    for picture in pictures:
        a, b = paper.process(picture), predictive.process(picture)
        assert set(a.surprises) == {"paper"} and set(b.surprises) == {"predictive", "paper"}
        assert np.array_equal(a.perplexity, a.surprises["paper"]) and np.array_equal(b.perplexity, b.surprises["predictive"])
        # the same model either way (scoring does not touch it): the paper's reading rides along unchanged
        assert np.array_equal(b.surprises["paper"], a.perplexity)


def _check_revisits():
    path = Path(__file__).resolve().parents[2] / "scripts" / "check_revisits.py"
    spec = importlib.util.spec_from_file_location("check_revisits", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.mark.slow
def test_four_laps_the_paper_s_surprise_grows_on_familiar_ground_the_predictive_falls_and_none_passes():
    """What docs/GUIDE.md reports ("Revisiting and change detection"), on a short loop: 30 frames a lap."""
    check = _check_revisits()
    result = check.run(("quick", [], "aerial-mosaic", 30, 0))
    verdicts = {reading: check.verdict(result, reading, 30) for reading in DRIVE_SURPRISES}
    assert verdicts["paper"]["medians"][3] > verdicts["paper"]["medians"][0]
    assert verdicts["predictive"]["fall"] <= check.FALL
    # the change's first frame stands out under the predictive reading; the frames after it are predicted by it
    first = result["marked"][0]
    assert result["series"]["predictive"][first] == result["series"]["predictive"][60:90].max()
    assert not any(v["passes"] for v in verdicts.values())
