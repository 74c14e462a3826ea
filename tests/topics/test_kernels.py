"""Every topic-model kernel against its slow twin in tests/naive.py, bit for bit."""

from __future__ import annotations

import numpy as np
import pytest
from naive import (
    NaiveModel,
    Stream,
    add_cell_naive,
    add_words_naive,
    below,
    distance2_colouring_naive,
    lane_draw,
    lda_gibbs_naive,
    log_likelihood_naive,
    mix,
    ml_topics_naive,
    recount,
    refine_batch_naive,
    refine_cells_naive,
    refine_realtime_naive,
    restart_naive,
    unit32,
    unit64,
)

from curiosity_cli.maps.cell_grid import SquareGrid
from curiosity_cli.errors import ParameterError
from curiosity_cli.topics import _rng
from curiosity_cli.topics._gibbs_kernels import distance2_colouring
from curiosity_cli.topics._sampler import lane_draw as lane_draw_kernel
from curiosity_cli.topics import model as model_module
from curiosity_cli.topics.model import TopicModel
from curiosity_cli.topics.neighbours import stream_neighbours


def small_model(seed, *, rows=3, cols=4, spatial=4, n_topics=5, vocabulary=12, observed=0.75, frozen=None):
    """A model over a small grid with most cells observed, some of them empty."""
    rng = np.random.default_rng(seed)
    model = TopicModel(
        n_topics, vocabulary, SquareGrid(rows, cols).neighbour_table(spatial), alpha=0.3, beta=0.2, seed=seed, frozen_counts=frozen
    )
    for cell in rng.permutation(rows * cols)[: max(1, int(observed * rows * cols))]:
        model.add_cell(int(cell), rng.integers(0, vocabulary, rng.integers(0, 9)))
    return model


def assert_matches(model: TopicModel, twin: NaiveModel):
    """Same topics in every cell, same random state, and counts that match a recount."""
    assert [int(c) for c in model.observed_cells()] == twin.order
    for cell in twin.order:
        np.testing.assert_array_equal(model.topics([cell]), twin.topics[cell], err_msg=f"cell {cell}")
    assert model.full_state()["counter"] == twin.counter
    counts = recount(model)
    np.testing.assert_array_equal(model.topic_word_counts(), counts["nwk"])
    np.testing.assert_array_equal(model.topic_totals(), counts["nk"])
    np.testing.assert_array_equal(model.cell_topic_counts(), counts["ncz"])
    np.testing.assert_array_equal(model.neighbourhood_counts(), counts["ng"])


# --- random numbers -------------------------------------------------------------------


def test_rng_matches_twin():
    for seed, counter, cell in [(0, 0, 0), (1, 5, 7), (2**64 - 1, 2**63, 12345)]:
        key = mix(seed)
        assert int(_rng.mix(np.uint64(seed))) == key
        kernel_state = _rng.stream_start(np.uint64(key), np.uint64(counter), cell)
        twin = Stream(key, counter, cell)
        assert int(kernel_state) == twin.state
        for _ in range(20):
            # numba hands uint64 back as Python ints; pass them in as uint64 again
            kernel_state, bits = _rng.next_state(np.uint64(kernel_state))
            assert int(bits) == twin.bits()
            bits = np.uint64(bits)
            assert _rng.unit32(bits) == unit32(int(bits))
            assert _rng.unit64(bits) == unit64(int(bits))
            assert 0 <= _rng.below(bits, 7) < 7


@pytest.mark.parametrize("n_topics", [1, 3, 8, 13, 64])
def test_lane_draw_matches_twin(n_topics):
    rng = np.random.default_rng(n_topics)
    padded = -(-n_topics // 8) * 8
    stream = Stream(99, 0, n_topics)
    for trial in range(300):
        p = np.zeros(padded, np.float32)
        p[:n_topics] = rng.random(n_topics, dtype=np.float32) ** 4
        if trial % 3 == 0:
            p[:n_topics][rng.random(n_topics) < 0.5] = 0  # zero-mass topics are never drawn
            p[rng.integers(n_topics)] = np.float32(1e-3)
        bits = stream.bits()
        got = lane_draw_kernel(p, np.uint64(bits))
        assert got == lane_draw(p, bits)
        assert p[got] > 0


def test_lane_draw_takes_last_positive_topic_when_the_target_rounds_past_the_total():
    # u close to 1 times a total summed in another order than the running sums: must not
    # fall off the end nor return a zero-mass topic
    p = np.zeros(16, np.float32)
    p[[1, 9, 3]] = [np.float32(1.0), np.float32(3e-8), np.float32(1e-8)]
    all_ones = 2**64 - 1
    assert lane_draw_kernel(p, np.uint64(all_ones)) == lane_draw(p, all_ones)
    assert p[lane_draw_kernel(p, np.uint64(all_ones))] > 0


# --- initial topics and refinement ----------------------------------------------------


@pytest.mark.parametrize("spatial", [4, 0])
def test_add_cell_matches_twin(spatial):
    rng = np.random.default_rng(1)
    model = TopicModel(6, 10, SquareGrid(3, 3).neighbour_table(spatial), alpha=0.5, beta=0.1, seed=11)
    twin = NaiveModel.of(model)
    for cell in rng.permutation(9):
        words = rng.integers(0, 10, rng.integers(0, 12))
        model.add_cell(int(cell), words)
        add_cell_naive(twin, int(cell), words)
        assert_matches(model, twin)


@pytest.mark.parametrize(("seed", "spatial"), [(0, 4), (1, 4), (2, 0), (3, 4)])
def test_refine_cells_matches_twin(seed, spatial):
    model = small_model(seed, spatial=spatial)
    twin = NaiveModel.of(model)
    cells = list(model.observed_cells()) * 2  # each cell twice: every listing has its own stream
    model.refine_cells(cells)
    refine_cells_naive(twin, cells)
    assert_matches(model, twin)


def test_refine_cells_without_neighbours_is_plain_collapsed_lda():
    model = small_model(4, rows=4, cols=4, spatial=0, n_topics=4, vocabulary=9, observed=1.0)
    state = NaiveModel.of(model)
    cells = [int(c) for c in model.observed_cells()]
    docs = [state.words[c] for c in cells]
    topics = [state.topics[c].copy() for c in cells]
    streams = [Stream(state.key, state.counter + j, c) for j, c in enumerate(cells)]
    model.refine_cells(cells)
    lda_gibbs_naive(docs, topics, 4, 9, model.alpha, model.beta, streams)
    for cell, zs in zip(cells, topics):
        np.testing.assert_array_equal(model.topics([cell]), zs)


# Batch twins run on grids of more than 16 observed cells: a phase holds at most
# ceil(observed / 16) cells, so smaller models would have one cell per phase and test
# neither the stale counts of a phase nor threads sharing one.
BATCH_GRID = dict(rows=8, cols=9, observed=0.9)  # 64 cells: phases of up to 4


@pytest.mark.parametrize("batch", [False, True])
def test_refinement_with_more_than_eight_topics_matches_twin(batch):
    # K = 13 pads to 16 columns: two blocks per lane, three lanes with padding
    model = small_model(5, n_topics=13, vocabulary=20, **(BATCH_GRID if batch else {}))
    twin = NaiveModel.of(model)
    if batch:
        model.refine_batch(2, threads=2)
        refine_batch_naive(twin, 2)
    else:
        model.refine_cells(model.observed_cells())
        refine_cells_naive(twin, list(model.observed_cells()))
    assert_matches(model, twin)


@pytest.mark.parametrize("threads", [1, 2, 3])
@pytest.mark.parametrize(("seed", "spatial"), [(6, 4), (7, 0)])
def test_refine_batch_matches_twin(seed, spatial, threads):
    model = small_model(seed, spatial=spatial, **BATCH_GRID)
    twin = NaiveModel.of(model)
    model.refine_batch(2, threads=threads)
    refine_batch_naive(twin, 2)
    assert_matches(model, twin)


def test_refine_batch_with_many_repeated_words_in_a_cell_matches_twin():
    # three word ids: every cell repeats words, so a cell's own changes to a word's
    # counts must show when the same word comes round again within the phase, and no
    # other cell's changes of the phase may
    model = small_model(14, n_topics=4, vocabulary=3, **{**BATCH_GRID, "observed": 1.0})
    twin = NaiveModel.of(model)
    model.refine_batch(3, threads=2)
    refine_batch_naive(twin, 3)
    assert_matches(model, twin)


def test_refine_batch_on_a_stream_table_matches_twin():
    rng = np.random.default_rng(8)
    model = TopicModel(4, 8, stream_neighbours(SquareGrid(2, 3), 8), alpha=0.3, beta=0.2, seed=8)
    for frame in range(8):
        for cell in range(frame * 6, frame * 6 + 6):
            model.add_cell(cell, rng.integers(0, 8, rng.integers(0, 6)), time=frame)
    twin = NaiveModel.of(model)
    model.refine_batch(2, threads=2)
    refine_batch_naive(twin, 2)
    assert_matches(model, twin)


@pytest.mark.parametrize("eta", [0.0, 0.5, 1.0])
def test_refine_realtime_matches_twin(eta):
    model = small_model(9)
    twin = NaiveModel.of(model)
    done = model.refine_realtime(40, eta=eta)
    assert done >= 40
    twin_done, _, _ = refine_realtime_naive(twin, 40, eta)
    assert done == twin_done
    assert_matches(model, twin)


def frames_model(seed: int, *, fewest_words: int, spacing: int) -> TopicModel:
    """A stream model of 4 frames of 2 x 2 cells, each with ``fewest_words`` to 4 words, observed
    every ``spacing`` time steps."""
    rng = np.random.default_rng(seed)
    model = TopicModel(5, 10, stream_neighbours(SquareGrid(2, 2), 4), alpha=0.3, beta=0.2, seed=seed)
    for frame in range(4):
        for cell in range(frame * 4, frame * 4 + 4):
            model.add_cell(cell, rng.integers(0, 10, rng.integers(fewest_words, 5)), time=spacing * frame)
    return model


def test_refine_realtime_with_observation_times_matches_twin():
    model = frames_model(10, fewest_words=1, spacing=2)
    twin = NaiveModel.of(model)
    done, newest = model.refine_realtime(60, eta=0.4, return_newest=True)
    twin_done, _, twin_newest = refine_realtime_naive(twin, 60, 0.4)
    assert (done, newest) == (twin_done, twin_newest) and 0 < newest < done
    assert_matches(model, twin)


@pytest.mark.parametrize("picks", ["uniform", "recent"])
def test_refine_realtime_cut_into_pieces_matches_twin(monkeypatch, picks):
    # a large budget goes to the kernel in pieces, so that a signal can stop it; each piece
    # resumes the last one's picks: the same as one call, which the twin is
    monkeypatch.setattr(model_module, "RESPONSIVE_SAMPLES", 3)
    model = frames_model(12, fewest_words=0, spacing=1)
    twin = NaiveModel.of(model)
    done, newest = model.refine_realtime(200, eta=0.3, picks=picks, return_newest=True)
    twin_done, _, twin_newest = refine_realtime_naive(twin, 200, 0.3, picks)
    assert (done, newest) == (twin_done, twin_newest) and 0 < newest < done
    assert_matches(model, twin)


# --- frozen word-topic counts ---------------------------------------------------------


def frozen_model(seed, spatial=4, **grid):
    rng = np.random.default_rng(seed)
    frozen = rng.integers(0, 5, (12, 5))
    return small_model(seed, spatial=spatial, frozen=frozen, **grid), frozen


@pytest.mark.parametrize("spatial", [4, 0])
def test_frozen_refine_cells_matches_twin(spatial):
    model, frozen = frozen_model(11, spatial)
    twin = NaiveModel.of(model)
    np.testing.assert_array_equal(twin.frozen, frozen)
    model.refine_cells(model.observed_cells())
    refine_cells_naive(twin, list(model.observed_cells()))
    assert_matches(model, twin)


@pytest.mark.slow
@pytest.mark.parametrize("threads", [1, 2])
def test_frozen_sweeps_over_runs_of_one_word_id_match_twin(threads):
    """Cells sorted by word id, as word stores are: long runs of one word id in a cell."""
    rows, cols = BATCH_GRID["rows"], BATCH_GRID["cols"]
    rng = np.random.default_rng(17)
    model = TopicModel(5, 12, SquareGrid(rows, cols).neighbour_table(4), alpha=0.3, beta=0.2, seed=17,
                       frozen_counts=rng.integers(0, 5, (12, 5)))
    for cell in range(rows * cols):
        model.add_cell(cell, np.sort(rng.integers(0, 3, rng.integers(0, 15))))
    twin = NaiveModel.of(model)
    model.refine_batch(3, threads=threads)
    refine_batch_naive(twin, 3)
    assert_matches(model, twin)


@pytest.mark.parametrize("threads", [1, 2])
def test_frozen_refine_batch_matches_twin(threads):
    model, _ = frozen_model(12, **BATCH_GRID)
    twin = NaiveModel.of(model)
    model.refine_batch(3, threads=threads)
    refine_batch_naive(twin, 3)
    assert_matches(model, twin)


@pytest.mark.parametrize("frozen", [False, True])
def test_restart_matches_twin_and_a_fresh_model(frozen):
    model = frozen_model(14)[0] if frozen else small_model(14)
    model.refine_batch(2)
    model.restart(99)
    twin = NaiveModel.of(model)
    before = NaiveModel.of(small_model(14, frozen=twin.frozen) if frozen else small_model(14))
    restart_naive(before, 99)
    assert twin.topics.keys() == before.topics.keys()
    for c in twin.topics:
        np.testing.assert_array_equal(twin.topics[c], before.topics[c])
    assert (twin.counter, twin.key) == (before.counter, before.key)
    assert_matches(model, twin)  # the cached counts agree with the redrawn topics


# --- ML topics and log-likelihood -----------------------------------------------------


@pytest.mark.parametrize("frozen", [False, True])
def test_ml_topics_and_log_likelihood_match_twins(frozen):
    model = frozen_model(13)[0] if frozen else small_model(13)
    model.refine_batch(3)
    twin = NaiveModel.of(model)
    cells = sorted(twin.order)
    np.testing.assert_array_equal(model.ml_topics(), ml_topics_naive(twin, cells))
    np.testing.assert_array_equal(model.ml_topics(cells[::-1]), ml_topics_naive(twin, cells[::-1]))
    assert model.log_likelihood() == pytest.approx(log_likelihood_naive(twin), rel=1e-12)


# --- colouring ------------------------------------------------------------------------


@pytest.mark.parametrize(
    "table",
    [
        SquareGrid(7, 9).neighbour_table(), SquareGrid(1, 6).neighbour_table(), SquareGrid(4, 4).neighbour_table(0),
        stream_neighbours(SquareGrid(3, 4), 5),
    ],
    ids=["grid", "row", "lda", "stream"],
)
def test_distance2_colouring_matches_twin_and_separates_interacting_cells(table):
    colour = distance2_colouring(table)
    np.testing.assert_array_equal(colour, distance2_colouring_naive(table))
    for c in range(table.shape[0]):
        near = {d for d in table[c] if d >= 0}
        near |= {e for d in list(near) for e in table[d] if e >= 0}
        near.discard(c)
        assert all(colour[d] != colour[c] for d in near)


def test_grid_colouring_uses_few_colours():
    # 5 is the minimum for a 4-neighbour grid ((row + 2 col) mod 5 achieves it)
    assert distance2_colouring(SquareGrid(64, 64).neighbour_table()).max() + 1 <= 8


# --- readings of the exploration: revisits add words again, refinement picks recent observations ------


def test_add_words_to_an_observed_cell_matches_twin():
    rng = np.random.default_rng(21)
    model = TopicModel(5, 12, SquareGrid(3, 4).neighbour_table(), alpha=0.3, beta=0.2, seed=21)
    for t, cell in enumerate([5, 6, 0, 2, 11]):
        model.add_cell(cell, rng.integers(0, 12, rng.integers(0, 6)), time=t)
    model.add_cell(7, [], time=5)  # an empty cell after the others: its first word index must move too
    twin = NaiveModel.of(model)
    for t, cell in [(6, 6), (7, 5), (8, 7), (9, 6)]:  # in the middle, first, the empty one, again
        words = rng.integers(0, 12, 4)
        model.add_words(cell, words, time=t)
        add_words_naive(twin, cell, words, t)
        assert_matches(model, twin)
        np.testing.assert_array_equal(model.cell_words(cell), twin.words[cell])
        assert list(model.observation_times()) == twin.times
    assert model.n_words == sum(len(w) for w in twin.words.values())
    model.refine_realtime(200, eta=0.5)
    refine_realtime_naive(twin, 200, 0.5)
    assert_matches(model, twin)


def test_add_words_needs_an_observed_cell():
    model = small_model(3, observed=0.25)
    unobserved = next(c for c in range(12) if not model.is_observed(c))
    with pytest.raises(ParameterError, match=f"^cell: cell {unobserved} is not in the model yet"):
        model.add_words(unobserved, [1, 2])


@pytest.mark.parametrize("picks", ["recent", "recent-64-ours"])
@pytest.mark.parametrize("eta", [0.0, 0.5, 1.0])
def test_recent_refinement_picks_match_twin(eta, picks):
    rng = np.random.default_rng(12)
    model = TopicModel(5, 10, SquareGrid(10, 10).neighbour_table(), alpha=0.3, beta=0.2, seed=12)
    for t, cell in enumerate(rng.permutation(100)[:80]):
        model.add_cell(int(cell), rng.integers(0, 10, rng.integers(1, 4)), time=t)
    twin = NaiveModel.of(model)
    done, newest = model.refine_realtime(500, eta=eta, picks=picks, return_newest=True)
    assert (done, newest) == tuple(refine_realtime_naive(twin, 500, eta, picks)[::2])
    assert_matches(model, twin)
    if eta == 1.0 and picks == "recent":
        assert newest == done  # every pick is the last observation, as the authors' refinery with one cell a step


@pytest.mark.parametrize("window", [1, 64])
def test_recent_picks_follow_the_stated_probabilities(window):
    # 100 observation times, one word each: count which time each pick refines through the
    # twin's picker (the kernel matches the twin above). With eta = 0.5, P(time t) is
    # 0.5 / window for each of the newest `window` (recent: 1; recent-64-ours: 64) plus
    # 0.5 * ((t + 1)^2 - t^2) / 100^2 from Beta(2, 1).
    n_times, n_picks = 100, 200_000
    picker = Stream(mix(5), 0, 100)
    counts = np.zeros(n_times)
    for _ in range(n_picks):
        newest = unit64(picker.bits()) < 0.5
        bits = picker.bits()
        if newest:
            t = n_times - window + below(bits, window)
        else:
            t = min(int(np.floor(unit64(bits) ** 0.5 * n_times)), n_times - 1)
        counts[t] += 1
    t = np.arange(n_times)
    expected = 0.5 * ((t + 1) ** 2 - t**2) / n_times**2 + np.where(t >= n_times - window, 0.5 / window, 0.0)
    assert expected.sum() == pytest.approx(1.0)
    # chi-square goodness of fit, 99 degrees of freedom: 148.2 is the 0.1 % critical value
    chi2 = ((counts - n_picks * expected) ** 2 / (n_picks * expected)).sum()
    assert chi2 < 148.2, chi2
    # and recent times are refined more often than old ones, as the authors' refinery intends
    assert counts[-10:].sum() > 5 * counts[:10].sum()


def test_refinement_picks_are_checked():
    with pytest.raises(ParameterError, match="^picks: got 'newest', expected one of uniform, recent, recent-64-ours$"):
        small_model(1).refine_realtime(10, eta=0.5, picks="newest")
