"""TopicModel: count invariants, realtime picking, frozen Φ, randomness, validation."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from naive import neighbour_table_problem_naive, recount

from curiosity_cli.maps.cell_grid import SquareGrid
from curiosity_cli.errors import ParameterError
from curiosity_cli.topics import TopicModel, stream_neighbours, take_snapshot
from curiosity_cli.topics._gibbs_kernels import distance2_colouring
from curiosity_cli.topics.batch_sweeps import batch_phases
from curiosity_cli.topics.neighbours import check_neighbours


def build(seed=0, rows=4, cols=5, spatial=4, n_topics=6, vocabulary=15, words_per_cell=(0, 12), model_seed=None, **kw):
    """A model with random words in every cell; ``seed`` draws the words and seeds the model."""
    rng = np.random.default_rng(seed)
    model_seed = seed if model_seed is None else model_seed
    table = SquareGrid(rows, cols).neighbour_table(spatial)
    model = TopicModel(n_topics, vocabulary, table, alpha=0.2, beta=0.1, seed=model_seed, **kw)
    for cell in rng.permutation(rows * cols):
        model.add_cell(int(cell), rng.integers(0, vocabulary, rng.integers(*words_per_cell)))
    return model


def assert_consistent(model: TopicModel):
    """Counts non-negative, totals equal the word count, every cached count equals a recount."""
    counts = recount(model)
    assert model.topic_word_counts().min(initial=0) >= 0
    assert model.cell_topic_counts().min(initial=0) >= 0
    if not model.frozen:
        assert model.topic_totals().sum() == model.n_words
        np.testing.assert_array_equal(model.topic_word_counts(), counts["nwk"])
        np.testing.assert_array_equal(model.topic_totals(), counts["nk"])
    assert model.cell_topic_counts().sum() == model.n_words
    np.testing.assert_array_equal(model.cell_topic_counts(), counts["ncz"])
    np.testing.assert_array_equal(model.neighbourhood_counts(), counts["ng"])
    # the cached normaliser is exactly the one recomputed from the totals
    expected = (1.0 / (model.topic_totals() + model.vocabulary_size * model.beta)).astype(np.float32)
    np.testing.assert_array_equal(model._inv[: model.n_topics], expected)
    assert not model._inv[model.n_topics :].any()


def assert_same_state(a: TopicModel, b: TopicModel):
    sa, sb = take_snapshot(a), take_snapshot(b)
    for field in dataclasses.fields(sa):
        x, y = getattr(sa, field.name), getattr(sb, field.name)
        if isinstance(x, np.ndarray):
            assert x.dtype == y.dtype, field.name
            np.testing.assert_array_equal(x, y, err_msg=field.name)
        else:
            assert x == y, field.name


# --- invariants on random problems ----------------------------------------------------

operations = st.lists(
    st.one_of(
        st.tuples(st.just("cells"), st.integers(0, 2**16)),
        st.tuples(st.just("batch"), st.integers(1, 2)),
        st.tuples(st.just("realtime"), st.floats(0, 1)),
        st.tuples(st.just("add"), st.integers(0, 2**16)),
        st.tuples(st.just("remove"), st.integers(0, 2**16)),
        st.tuples(st.just("grow"), st.integers(1, 2)),
    ),
    max_size=6,
)


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    seed=st.integers(0, 2**32),
    rows=st.integers(1, 4),
    cols=st.integers(1, 4),
    spatial=st.sampled_from([0, 4]),
    n_topics=st.integers(1, 10),
    vocabulary=st.integers(1, 9),
    frozen=st.booleans(),
    ops=operations,
)
def test_counts_stay_consistent_through_any_sequence_of_operations(
    seed, rows, cols, spatial, n_topics, vocabulary, frozen, ops
):
    rng = np.random.default_rng(seed)
    frozen_counts = rng.integers(0, 4, (vocabulary, n_topics)) if frozen else None
    model = TopicModel(
        n_topics, vocabulary, SquareGrid(rows, cols).neighbour_table(spatial), alpha=0.5, beta=0.3, seed=seed,
        frozen_counts=frozen_counts,
    )
    pending = list(rng.permutation(rows * cols))
    model.add_cell(int(pending.pop()), rng.integers(0, vocabulary, rng.integers(0, 6)))
    assert_consistent(model)
    for op, arg in ops:
        if op == "add" and pending:
            model.add_cell(int(pending.pop()), rng.integers(0, vocabulary, arg % 7))
        elif op == "cells":
            observed = model.observed_cells()
            model.refine_cells(np.random.default_rng(arg).choice(observed, size=3))
        elif op == "batch":
            model.refine_batch(1, threads=arg)
        elif op == "realtime":
            model.refine_realtime(5, eta=arg)
        elif op == "remove" and model.n_observed > 1:
            gone = np.random.default_rng(arg).choice(model.observed_cells(), size=1)
            model.remove_cells(gone)
            pending.append(int(gone[0]))
        elif op == "grow":
            rows += arg  # new rows below the grid: the old bottom row gains neighbours
            pending += list(range(model.n_cells, rows * cols))
            model.grow(SquareGrid(rows, cols).neighbour_table(spatial))
        assert_consistent(model)
        if frozen:
            np.testing.assert_array_equal(model.topic_word_counts(), frozen_counts)


def test_state_accessors_are_in_store_order_and_copies():
    model = TopicModel(3, 10, SquareGrid(2, 2).neighbour_table(), alpha=0.1, beta=0.1, seed=0)
    model.add_cell(3, [5, 6])
    model.add_cell(0, [1])
    model.add_cell(2, [])
    np.testing.assert_array_equal(model.observed_cells(), [3, 0, 2])
    np.testing.assert_array_equal(model.observation_times(), [0, 1, 2])
    assert model.n_words == 3 and model.n_observed == 3
    assert model.is_observed(2) and not model.is_observed(1)
    topics = model.topics()
    assert topics.dtype == np.int8 and topics.shape == (3,)
    np.testing.assert_array_equal(topics, np.concatenate([model.topics([0]), model.topics([3])]))
    np.testing.assert_array_equal(model.cell_words(3), [5, 6])
    model.topic_word_counts()[:] = 99  # a copy: the model is untouched
    assert_consistent(model)


def test_topic_labels_use_the_smallest_integer_type():
    assert TopicModel(127, 5, SquareGrid(1, 1).neighbour_table(), alpha=1, beta=1, seed=0).topic_dtype == np.int8
    wide = TopicModel(200, 5, SquareGrid(1, 2).neighbour_table(), alpha=1, beta=1, seed=0)
    assert wide.topic_dtype == np.int16
    wide.add_cell(0, [0, 1, 2, 3, 4] * 20)
    wide.add_cell(1, [4] * 30)
    wide.refine_cells([0, 1])
    assert wide.topics().max() < 200
    assert_consistent(wide)


def test_phi_is_normalised_counts():
    model = build(1)
    model.refine_batch(2)
    phi = model.phi()
    assert phi.shape == (model.vocabulary_size, model.n_topics)
    np.testing.assert_allclose(phi.sum(axis=0), 1.0, rtol=1e-12)
    expected = (model.topic_word_counts() + 0.1) / (model.topic_totals() + 15 * 0.1)
    np.testing.assert_allclose(phi, expected, rtol=1e-15)


def test_ml_topics_default_to_every_observed_cell_in_cell_order():
    model = build(2)
    model.refine_batch(3)
    cells = np.arange(model.n_cells)
    np.testing.assert_array_equal(model.ml_topics(), model.ml_topics(cells))
    assert model.ml_topics().shape == (model.n_words,)
    assert model.ml_topics([]).shape == (0,)


def test_log_likelihood_rises_as_the_sampler_fits_clustered_words():
    # two kinds of cells with disjoint words: refinement should separate them
    rng = np.random.default_rng(3)
    model = TopicModel(2, 20, SquareGrid(4, 4).neighbour_table(), alpha=0.1, beta=0.1, seed=3)
    for cell in range(16):
        base = 0 if cell % 4 < 2 else 10
        model.add_cell(cell, base + rng.integers(0, 10, 30))
    start = model.log_likelihood()
    model.refine_batch(30)
    assert model.log_likelihood() > start + 0.3
    assert TopicModel(2, 20, SquareGrid(4, 4).neighbour_table(), alpha=0.1, beta=0.1, seed=3).log_likelihood() == 0.0


@pytest.mark.parametrize("threads", [1, 3])
def test_a_traced_batch_gives_the_log_likelihood_after_each_sweep_and_the_same_topics(threads, monkeypatch):
    from curiosity_cli.topics import batch_sweeps

    def clustered():
        rng = np.random.default_rng(3)
        model = TopicModel(4, 20, SquareGrid(5, 8).neighbour_table(), alpha=0.1, beta=0.1, seed=3)
        for cell in range(40):
            model.add_cell(cell, (0 if cell % 8 < 4 else 10) + rng.integers(0, 10, 30))
        return model

    whole = clustered().log_likelihood()  # one run of cells
    # 40 cells summed in 5 runs of 8, which the threads share
    monkeypatch.setattr(batch_sweeps, "_LIKELIHOOD_CELLS", 8)
    assert clustered().log_likelihood() == pytest.approx(whole, rel=1e-12)
    one_by_one = clustered()
    after_each = []
    for _ in range(5):
        one_by_one.refine_batch(1, threads=threads)
        after_each.append(one_by_one.log_likelihood())
    traced = clustered()
    assert traced.refine_batch(5, threads=threads, trace=True).tolist() == after_each
    np.testing.assert_array_equal(traced.ml_topics(), one_by_one.ml_topics())
    assert clustered().refine_batch(2) is None


def test_a_frozen_models_batch_is_not_traced():
    model = TopicModel(
        2, 20, SquareGrid(4, 4).neighbour_table(), alpha=0.1, beta=0.1, seed=3, frozen_counts=np.ones((20, 2), np.int32),
    )
    model.add_cell(0, [1, 2, 3])
    with pytest.raises(ParameterError, match="^trace: "):
        model.refine_batch(1, trace=True)


# --- realtime refinement --------------------------------------------------------------


@pytest.mark.parametrize("eta", [0.2, 0.5, 0.9])
def test_realtime_refines_the_newest_observation_with_probability_eta(eta):
    # earlier cells hold one word each, the newest none: every pick spends one unit of
    # the budget, words sampled = earlier picks, and each pick advances the counter
    model = TopicModel(4, 5, SquareGrid(1, 50).neighbour_table(0), alpha=0.1, beta=0.1, seed=4)
    for cell in range(49):
        model.add_cell(cell, [cell % 5])
    model.add_cell(49, [])
    before = model.full_state()["counter"]
    done = model.refine_realtime(20_000, eta=eta)
    picks = model.full_state()["counter"] - before - 1
    assert picks == 20_000
    # binomial standard error with 20,000 picks is at most 0.0036
    assert (picks - done) / picks == pytest.approx(eta, abs=0.02)


def test_realtime_picks_earlier_observations_uniformly():
    # earlier cells of 1, 100 and 10,000 words and an empty newest one: with eta = 0 and
    # a budget of 1, each call makes one pick, and the words sampled say which cell
    model = TopicModel(2, 3, SquareGrid(1, 4).neighbour_table(0), alpha=0.1, beta=0.1, seed=5)
    sizes = [1, 100, 10_000]
    for cell, size in enumerate(sizes):
        model.add_cell(cell, np.zeros(size, int))
    model.add_cell(3, [])
    counts = np.zeros(3, int)
    for _ in range(300):
        counts[sizes.index(model.refine_realtime(1, eta=0.0))] += 1
    # uniform: 100 each, standard deviation about 8
    assert np.all(np.abs(counts - 100) < 40)


def test_realtime_respects_the_budget():
    model = build(6, words_per_cell=(5, 10))
    largest = max(len(model.cell_words(c)) for c in model.observed_cells())
    for budget in [1, 7, 100, 1000]:
        done = model.refine_realtime(budget, eta=0.5)
        assert budget <= done < budget + largest
    assert model.refine_realtime(0, eta=0.5) == 0


def test_realtime_ends_even_when_no_reachable_cell_has_words():
    model = TopicModel(3, 5, SquareGrid(1, 3).neighbour_table(), alpha=0.1, beta=0.1, seed=0)
    assert model.refine_realtime(10, eta=0.5) == 0
    model.add_cell(0, [1, 2])
    model.add_cell(1, [])
    counter = model.full_state()["counter"]
    assert model.refine_realtime(10, eta=1.0) == 0  # only the empty newest cell is picked
    assert model.full_state()["counter"] == counter + 11  # ten empty picks spent the budget
    assert model.refine_realtime(10, eta=0.0) >= 10
    # a vanishing chance of picking the only cell with words still ends
    model = TopicModel(3, 5, SquareGrid(1, 3).neighbour_table(), alpha=0.1, beta=0.1, seed=0)
    model.add_cell(0, [])
    model.add_cell(1, [1, 2])
    assert model.refine_realtime(1000, eta=5e-324) == 0


def test_realtime_refines_every_cell_of_the_picked_time():
    model = TopicModel(3, 5, stream_neighbours(SquareGrid(2, 2), 2), alpha=0.1, beta=0.1, seed=0)
    for cell in range(8):
        model.add_cell(cell, [cell % 5] * (cell + 1), time=cell // 4)
    # eta = 1 picks the newest time only: cells 4..7 with 5 + 6 + 7 + 8 words
    assert model.refine_realtime(1, eta=1.0) == 26


# --- frozen Φ -------------------------------------------------------------------------


def test_frozen_refinement_leaves_word_topic_counts_unchanged_and_labels_a_map():
    learned = build(7)
    learned.refine_batch(5)
    counts = learned.topic_word_counts()
    whole = TopicModel(
        learned.n_topics, learned.vocabulary_size, SquareGrid(4, 5).neighbour_table(), alpha=0.2, beta=0.1, seed=70,
        frozen_counts=counts,
    )
    assert whole.frozen
    for cell in range(20):
        whole.add_cell(cell, learned.cell_words(cell))
    np.testing.assert_array_equal(whole.topic_word_counts(), counts)
    whole.refine_batch(3, threads=2)
    whole.refine_cells([0, 1, 2])
    whole.refine_realtime(50, eta=0.5)
    np.testing.assert_array_equal(whole.topic_word_counts(), counts)
    np.testing.assert_array_equal(whole.topic_totals(), counts.sum(axis=0))
    np.testing.assert_array_equal(whole.phi(), learned.phi())
    assert whole.ml_topics().shape == (whole.n_words,)
    assert_consistent(whole)


# --- randomness -----------------------------------------------------------------------


def run(seed, threads=1, model_seed=None):
    model = build(seed, model_seed=model_seed)
    model.refine_batch(2, threads=threads)
    model.refine_realtime(100, eta=0.5)
    model.refine_cells([1, 2, 3])
    return model


def test_same_seed_same_state_on_any_thread_count_and_different_seed_differs():
    assert_same_state(run(8), run(8))
    assert_same_state(run(8, threads=1), run(8, threads=2))
    a, b = run(8), run(8, model_seed=9)  # same words, another seed
    np.testing.assert_array_equal(a.topic_word_counts().sum(axis=1), b.topic_word_counts().sum(axis=1))
    assert not np.array_equal(a.topics(), b.topics())


@pytest.mark.parametrize("spatial", [0, 4])
def test_batch_phases_cover_the_cells_once_in_sixteenths_of_independent_cells(spatial):
    model = build(3, rows=9, cols=11, spatial=spatial)  # 99 cells: phases of at most 7
    phases = batch_phases(np.sort(model.observed_cells()).astype(np.int64), distance2_colouring(model.neighbours))
    cells = np.concatenate(phases)
    np.testing.assert_array_equal(np.sort(cells), np.arange(99))
    assert max(phase.size for phase in phases) <= 7
    if spatial == 0:
        # one colour: 15 runs of 7 or 6 cells, the longer ones first
        assert [phase.size for phase in phases] == [7] * 9 + [6] * 6
    table = model.neighbours
    for phase in phases:
        # no two cells of a phase within graph distance 2
        for c in phase:
            near = {int(d) for d in table[c] if d >= 0}
            near |= {int(e) for d in list(near) for e in table[d] if e >= 0}
            near.discard(int(c))
            assert not near & set(phase.tolist())


@pytest.mark.parametrize("frozen", [False, True])
def test_batch_is_the_same_on_any_number_of_threads_with_many_cells_per_phase(frozen):
    kw = dict(frozen_counts=np.arange(15 * 6).reshape(15, 6) % 7) if frozen else {}
    states = []
    for threads in (1, 2, 3, 5):
        model = build(4, rows=12, cols=12, **kw)  # 144 cells: phases of up to 9
        model.refine_batch(3, threads=threads)
        assert_consistent(model)
        states.append(model)
    for other in states[1:]:
        assert_same_state(states[0], other)


def test_batch_on_a_single_observed_cell_is_the_same_on_two_threads():
    models = []
    for threads in (1, 2):
        model = TopicModel(3, 5, SquareGrid(2, 2).neighbour_table(), alpha=0.1, beta=0.1, seed=1)
        model.add_cell(2, [0, 1, 1, 4, 4, 4])
        model.refine_batch(4, threads=threads)
        assert_consistent(model)
        models.append(model)
    assert_same_state(*models)


# --- validation -----------------------------------------------------------------------


@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        ({"n_topics": 0}, "n_topics"),
        ({"n_topics": 2.5}, "n_topics"),
        ({"vocabulary_size": 0}, "vocabulary_size"),
        ({"alpha": 0.0}, "alpha"),
        ({"alpha": float("nan")}, "alpha"),
        ({"beta": -1}, "beta"),
        ({"beta": "0.1"}, "beta"),
        ({"seed": -1}, "seed"),
        ({"seed": 2**64}, "seed"),
        ({"neighbours": np.zeros((0, 4), int)}, "neighbours"),
        ({"neighbours": np.array([[1], [-1]])}, "neighbours"),
        ({"neighbours": np.array([[0]])}, "neighbours"),
        ({"neighbours": np.array([[1, 1], [0, -1]])}, "neighbours"),
        ({"neighbours": np.array([[5]])}, "neighbours"),
        ({"neighbours": np.array([[1.0], [0.0]])}, "neighbours"),
        ({"vocabulary_hashes": 5}, "vocabulary_hashes"),
        ({"vocabulary_hashes": {"orb": 1}}, "vocabulary_hashes"),
        ({"frozen_counts": np.zeros((3, 3), int)}, "frozen_counts"),
        ({"frozen_counts": -np.ones((10, 4), int)}, "frozen_counts"),
        ({"frozen_counts": np.zeros((10, 4))}, "frozen_counts"),
    ],
)
def test_constructor_names_the_bad_parameter(kwargs, name):
    arguments = {"n_topics": 4, "vocabulary_size": 10, "neighbours": SquareGrid(2, 2).neighbour_table()}
    arguments.update(alpha=0.1, beta=0.1, seed=0)
    arguments.update(kwargs)
    positional = [arguments.pop(k) for k in ("n_topics", "vocabulary_size", "neighbours")]
    with pytest.raises(ParameterError, match=rf"^{name}:"):
        TopicModel(*positional, **arguments)


def test_methods_name_the_bad_parameter():
    model = TopicModel(4, 10, SquareGrid(2, 2).neighbour_table(), alpha=0.1, beta=0.1, seed=0)
    model.add_cell(0, [1, 2])
    cases = [
        (lambda: model.add_cell(0, [1]), "cell"),
        (lambda: model.add_cell(4, [1]), "cell"),
        (lambda: model.add_cell(1, [10]), "words"),
        (lambda: model.add_cell(1, [-1]), "words"),
        (lambda: model.add_cell(1, [[1]]), "words"),
        (lambda: model.add_cell(1, [0.5]), "words"),
        (lambda: model.add_cell(1, [1], time=-3), "time"),
        (lambda: model.refine_cells([1]), "cells"),
        (lambda: model.refine_cells([7]), "cells"),
        (lambda: model.refine_batch(-1), "sweeps"),
        (lambda: model.refine_batch(1, threads=0), "threads"),
        (lambda: model.refine_realtime(-5, eta=0.5), "word_budget"),
        (lambda: model.refine_realtime(5, eta=1.5), "eta"),
        (lambda: model.ml_topics([3]), "cells"),
        (lambda: model.cell_words(2), "cell"),
    ]
    for call, name in cases:
        with pytest.raises(ParameterError, match=rf"^{name}:"):
            call()
    model.add_cell(1, [3], time=5)
    with pytest.raises(ParameterError, match="^time:"):
        model.add_cell(2, [3], time=4)
    assert_consistent(model)


# --- neighbour tables -----------------------------------------------------------------


def test_grid_neighbours_columns_are_up_down_left_right():
    table = SquareGrid(2, 3).neighbour_table()
    assert table.dtype == np.int32 and table.shape == (6, 4)
    np.testing.assert_array_equal(table[0], [-1, 3, -1, 1])
    np.testing.assert_array_equal(table[4], [1, -1, 3, 5])
    assert SquareGrid(3, 3).neighbour_table(spatial=0).shape == (9, 0)
    check_neighbours(SquareGrid(5, 7).neighbour_table())


def test_stream_neighbours_add_previous_and_next_frame():
    table = stream_neighbours(SquareGrid(2, 2), 3)
    assert table.shape == (12, 6)
    np.testing.assert_array_equal(table[5], [-1, 7, 4, -1, 1, 9])
    np.testing.assert_array_equal(
        stream_neighbours(SquareGrid(2, 2), 3, temporal=0)[:4], SquareGrid(2, 2).neighbour_table()
    )
    np.testing.assert_array_equal(stream_neighbours(SquareGrid(1, 1), 2, spatial=0), [[-1, 1], [0, -1]])
    check_neighbours(stream_neighbours(SquareGrid(3, 4), 5))


@settings(max_examples=200, deadline=None)
@given(seed=st.integers(0, 2**32), n_cells=st.integers(1, 7), width=st.integers(0, 4), damage=st.integers(0, 3))
def test_neighbour_tables_are_checked_as_their_sorted_edges_say(seed, n_cells, width, damage):
    rng = np.random.default_rng(seed)
    if damage == 0 and width:  # a random symmetric graph: each edge listed in both rows, where there is room
        table = np.full((n_cells, width), -1)
        for a, b in rng.permutation([(a, b) for a in range(n_cells) for b in range(a + 1, n_cells)]).reshape(-1, 2):
            free_a, free_b = np.flatnonzero(table[a] < 0), np.flatnonzero(table[b] < 0)
            if free_a.size and free_b.size and rng.random() < 0.6:
                table[a, rng.choice(free_a)], table[b, rng.choice(free_b)] = b, a
    else:  # anything: self-loops, repeats and one-way links drawn at random
        table = rng.integers(-1, n_cells, (n_cells, width))
    problem = neighbour_table_problem_naive(table)
    if problem is None:
        np.testing.assert_array_equal(check_neighbours(table), table)
    else:
        with pytest.raises(ParameterError) as info:
            check_neighbours(table)
        assert str(info.value) == problem


def test_a_ring_of_frames_links_the_last_frame_to_the_first():
    ring = stream_neighbours(SquareGrid(2, 2), 3, ring=True)
    np.testing.assert_array_equal(ring[1], [-1, 3, 0, -1, 9, 5])  # frame 0's previous is frame 2
    np.testing.assert_array_equal(ring[9], [-1, 11, 8, -1, 5, 1])  # frame 2's next is frame 0
    np.testing.assert_array_equal(ring[4:8], stream_neighbours(SquareGrid(2, 2), 3)[4:8])
    check_neighbours(ring)


@pytest.mark.parametrize(
    ("call", "name"),
    [
        (lambda: SquareGrid(0, 3), "rows"),
        (lambda: SquareGrid(3, -1), "cols"),
        (lambda: SquareGrid(3, 3).neighbour_table(spatial=6), "spatial"),
        (lambda: stream_neighbours(SquareGrid(2, 2), 0), "n_frames"),
        (lambda: stream_neighbours(SquareGrid(2, 2), 2, ring=True), "n_frames"),
        (lambda: stream_neighbours(SquareGrid(2, 2), 2, temporal=1), "temporal"),
        (lambda: stream_neighbours(SquareGrid(2, 2), 2, spatial=True), "spatial"),
    ],
)
def test_neighbour_tables_name_the_bad_parameter(call, name):
    with pytest.raises(ParameterError, match=rf"^{name}:"):
        call()


@pytest.mark.parametrize("frozen", [False, True])
def test_set_topics_puts_every_word_there_and_recounts(frozen):
    model = build(seed=3)
    if frozen:
        model = build(seed=3, frozen_counts=np.random.default_rng(0).integers(0, 4, (15, 6)))
    topics = np.random.default_rng(1).integers(0, 6, model.n_words)
    model.set_topics(topics)
    np.testing.assert_array_equal(model.topics(), topics)
    assert_consistent(model)
    model.refine_batch(2)  # a chain from there keeps its counts exact
    assert_consistent(model)
    with pytest.raises(ParameterError, match=r"topics: got 1 \.\. 6, expected 0 \.\. 5"):
        model.set_topics(np.where(topics == 0, 6, topics))
    with pytest.raises(ParameterError, match=rf"topics: got int64 of shape \(3,\), expected \({model.n_words},\) integers"):
        model.set_topics(topics[:3])
