"""Frozen-Φ chains in lock-step: each chain is the exact sampler, whatever shares its block."""

from __future__ import annotations

import numpy as np
import pytest
from naive import (
    NaiveModel, count_topics, ml_topics_naive, neighbour_colouring_naive, neighbourhood, start_chain_naive,
    sweep_chain_naive,
)

from curiosity_cli.maps.cell_grid import SquareGrid
from curiosity_cli.errors import ParameterError
from curiosity_cli.topics._chain_kernels import neighbour_colouring
from curiosity_cli.topics.chains import FrozenChains, sweep_order
from curiosity_cli.topics.model import TopicModel
from curiosity_cli.topics.neighbours import stream_neighbours

K, V = 5, 30


def small_map(rows=3, cols=4, seed=0):
    """(words, cells, table): 0 to 9 words per cell (some cells empty), 4 neighbours."""
    rng = np.random.default_rng(seed)
    table = SquareGrid(rows * 4, cols * 4, 4).neighbour_table(4)
    sizes = rng.integers(0, 10, rows * cols)
    cells = np.repeat(np.arange(rows * cols), sizes)
    return rng.integers(0, V, cells.size), cells, table


def chains_of(words, cells, table, alpha=0.1, beta=0.1, n_topics=K) -> FrozenChains:
    return FrozenChains(words, cells, table, n_topics=n_topics, vocabulary_size=V, alpha=alpha, beta=beta)


def twin_of(words, cells, table, phi) -> NaiveModel:
    """A frozen twin holding every cell of the table (empty ones too), as the chains do."""
    n_cells = table.shape[0]
    return NaiveModel(
        n_topics=np.shape(phi)[1], vocabulary_size=V, table=np.asarray(table), alpha=0.1, beta=0.1, key=0, counter=0,
        words={c: words[cells == c].astype(np.int64) for c in range(n_cells)},
        topics={c: np.zeros(np.count_nonzero(cells == c), np.int64) for c in range(n_cells)},
        order=list(range(n_cells)), times=list(range(n_cells)), frozen=np.asarray(phi, np.int64),
    )


def twin_swept(words, cells, table, phi, seed, placed, sweeps) -> NaiveModel:
    """One chain's naive twin after its start and ``sweeps`` sweeps (the chains' streams)."""
    twin = twin_of(words, cells, table, phi)
    start_chain_naive(twin, seed, placed)
    for s in range(sweeps):
        sweep_chain_naive(twin, table.shape[0] + s)
    return twin


def twin_topics(twin: NaiveModel) -> np.ndarray:
    return np.concatenate([twin.topics[c] for c in sorted(twin.topics)])


def test_every_chain_of_a_block_is_its_naive_twin_draw_for_draw():
    words, cells, table = small_map()
    rng = np.random.default_rng(1)
    phis = [rng.integers(0, 6, (V, K)) for _ in range(3)]
    later = [rng.integers(0, 6, (V, K)) for _ in range(3)]
    seeds, placed = [11, 2**64 - 1, 5], [False, True, False]
    chains = chains_of(words, cells, table)
    chains.start(phis, seeds, placed)
    chains.sweep(2)
    chains.switch(later)
    chains.sweep(1)
    for r in range(3):
        twin = twin_swept(words, cells, table, phis[r], seeds[r], placed[r], 2)
        twin.frozen = later[r]
        sweep_chain_naive(twin, table.shape[0] + 2)
        np.testing.assert_array_equal(chains.topics()[:, r], twin_topics(twin))
        np.testing.assert_array_equal(chains.ml_topics()[:, r], ml_topics_naive(twin, sorted(twin.topics)))


def test_chains_with_allowed_topics_are_their_naive_twins_and_stay_inside_them():
    """A labelling reading's mask (``allowed``): each chain is its twin whose eq. 5 weights are 0 outside the mask,
    in the sweeps and the ML labels, and after a sweep every word is at a topic it may take; a chain given None is
    the unmasked chain."""
    words, cells, table = small_map()
    rng = np.random.default_rng(4)
    phis = [rng.integers(0, 6, (V, K)) for _ in range(3)]
    masks = []
    for _ in range(2):
        mask = rng.random((V, K)) < 0.4
        mask[np.arange(V), rng.integers(0, K, V)] = True
        masks.append(mask)
    seeds, placed = [3, 8, 3], [True, False, False]
    chains = chains_of(words, cells, table)
    chains.start(phis, seeds, placed, [masks[0], masks[1], None])
    chains.sweep(2)
    unmasked = chains_of(words, cells, table)
    unmasked.start(phis[2:], seeds[2:], placed[2:])
    unmasked.sweep(2)
    np.testing.assert_array_equal(chains.topics()[:, 2], unmasked.topics()[:, 0])
    for r, mask in enumerate(masks):
        twin = twin_of(words, cells, table, phis[r])
        twin.allowed = mask
        start_chain_naive(twin, seeds[r], placed[r])
        for s in range(2):
            sweep_chain_naive(twin, table.shape[0] + s)
        topics = chains.topics()[:, r]
        np.testing.assert_array_equal(topics, twin_topics(twin))
        np.testing.assert_array_equal(chains.ml_topics()[:, r], ml_topics_naive(twin, sorted(twin.topics)))
        assert mask[words, topics].all() and mask[words, chains.ml_topics()[:, r]].all()


def test_a_word_allowed_no_topic_is_refused():
    words, cells, table = small_map()
    mask = np.ones((V, K), bool)
    mask[7] = False
    with pytest.raises(ParameterError, match="allowed: chain 0 allows no topic to word 7"):
        chains_of(words, cells, table).start([np.ones((V, K), int)], [0], allowed=[mask])
    with pytest.raises(ParameterError, match=r"allowed: chain 0 is int64 of shape \(30, 5\), expected bool"):
        chains_of(words, cells, table).start([np.ones((V, K), int)], [0], allowed=[np.ones((V, K), int)])


@pytest.mark.slow
@pytest.mark.parametrize("n_topics", [8, 13, 24, 127])
def test_the_draw_over_many_topics_is_the_twins(n_topics):
    """The sweep searches the running sums eight topics at a time and stops once every chain is past its
    target: K a multiple of 8 and not, up to the most the kernel holds, each chain its naive twin's."""
    words, cells, table = small_map(rows=4, cols=4, seed=n_topics)
    rng = np.random.default_rng(n_topics)
    # a few heavy topics per word and many light ones, so that the chains' draws fall far apart
    phis = [rng.integers(0, 3, (V, n_topics)) * rng.integers(0, 2, (V, n_topics)) ** 3 * 40 for _ in range(9)]
    seeds, placed = list(range(40, 49)), [r % 3 == 0 for r in range(9)]
    chains = chains_of(words, cells, table, n_topics=n_topics)
    chains.start(phis, seeds, placed)
    chains.sweep(2)
    for r in range(9):
        twin = twin_swept(words, cells, table, phis[r], seeds[r], placed[r], 2)
        np.testing.assert_array_equal(chains.topics()[:, r], twin_topics(twin))
        _, _, ncz = count_topics(twin)
        np.testing.assert_array_equal(chains.counts()[0][:, :, r], ncz)


@pytest.mark.parametrize(
    "table",
    [
        SquareGrid(7, 9).neighbour_table(), SquareGrid(1, 6).neighbour_table(), SquareGrid(4, 4).neighbour_table(0),
        stream_neighbours(SquareGrid(3, 4), 5), np.array([[1, 2], [0, 2], [0, 1]], np.int32), np.array([[-1]], np.int32),
    ],
    ids=["grid", "row", "lda", "stream", "triangle", "one cell"],
)
def test_the_colouring_matches_its_twin_and_no_neighbours_share_a_colour(table):
    colour = neighbour_colouring(table)
    np.testing.assert_array_equal(colour, neighbour_colouring_naive(table))
    for c in range(table.shape[0]):
        assert all(colour[d] != colour[c] for d in table[c] if d >= 0)
    order, starts = sweep_order(table)
    np.testing.assert_array_equal(np.sort(order), np.arange(table.shape[0]))
    for c in range(starts.size - 1):
        part = order[starts[c] : starts[c + 1]]
        assert (colour[part] == c).all() and (np.diff(part) > 0).all()


def test_a_grid_is_swept_as_a_checkerboard_and_a_triangle_in_three_colours():
    rows, cols = 5, 6
    colour = neighbour_colouring(SquareGrid(rows, cols).neighbour_table())
    np.testing.assert_array_equal(colour, (np.arange(rows)[:, None] + np.arange(cols)).ravel() % 2)
    _, starts = sweep_order(np.array([[1, 2], [0, 2], [0, 1]], np.int32))
    np.testing.assert_array_equal(starts, [0, 1, 2, 3])


def test_the_counts_follow_the_topics():
    words, cells, table = small_map(seed=3)
    chains = chains_of(words, cells, table)
    chains.start([np.ones((V, K), int)] * 2, [0, 1], [True, False])
    chains.sweep(3)
    for r in range(2):
        twin = twin_of(words, cells, table, np.ones((V, K)))
        at = 0
        for c in sorted(twin.topics):
            n = twin.words[c].size
            twin.topics[c] = chains.topics()[at : at + n, r].astype(np.int64)
            at += n
        _, _, ncz = count_topics(twin)
        np.testing.assert_array_equal(chains.counts()[0][:, :, r], ncz)
        around = np.array([neighbourhood(twin, ncz, c) for c in range(table.shape[0])])
        np.testing.assert_array_equal(chains.counts()[1][:, :, r], around)


def test_the_uniform_start_is_the_models_restart():
    words, cells, table = small_map(seed=2)
    phi = np.random.default_rng(0).integers(0, 4, (V, K))
    model = TopicModel(K, V, table, alpha=0.1, beta=0.1, seed=0, frozen_counts=phi)
    for c in range(table.shape[0]):
        model.add_cell(c, words[cells == c])
    model.restart(77)
    chains = chains_of(words, cells, table)
    chains.start([phi], [77])
    np.testing.assert_array_equal(chains.topics()[:, 0], model.topics())


@pytest.mark.parametrize("others", [0, 2, 15])
def test_a_chain_does_not_depend_on_the_chains_beside_it(others):
    words, cells, table = small_map(seed=4)
    rng = np.random.default_rng(others)
    phi, other_phis = rng.integers(0, 6, (V, K)), [rng.integers(0, 6, (V, K)) for _ in range(others)]
    alone = chains_of(words, cells, table)
    alone.start([phi], [9], [True])
    alone.sweep(3)
    block = chains_of(words, cells, table)
    where = others // 2
    block.start(
        [*other_phis[:where], phi, *other_phis[where:]], [*range(100, 100 + where), 9, *range(200, 200 + others - where)],
        [False] * where + [True] + [False] * (others - where),
    )
    block.sweep(2)
    block.keep([where])  # the others dropped half-way: the chain goes on as before
    block.sweep(1)
    np.testing.assert_array_equal(block.topics()[:, 0], alone.topics()[:, 0])
    np.testing.assert_array_equal(block.ml_topics()[:, 0], alone.ml_topics()[:, 0])


@pytest.mark.slow
def test_lock_step_marginals_match_the_exact_single_chain_sampler():
    """Per-word topic frequencies of 8 lock-step chains against 8 chains of the model's own
    frozen sampler (another draw order and summation, the same distribution), next to the
    gap between two independent sets of exact chains: the lock-step gap must be of that size.

    With 3000 sweeps per chain, the largest gap over the 640 word-topic pairs was 0.0155
    between the exact sets and 0.0159 against lock-step (seeds as below); lock-step
    chains with α = 0.6 instead of 0.5 were 0.031 off, and fail.
    """
    rng = np.random.default_rng(5)
    table = SquareGrid(16, 16, 4).neighbour_table(4)  # 4 x 4 cells
    cells = np.repeat(np.arange(16), 10)
    words = np.where(cells % 4 < 2, rng.integers(0, 15, cells.size), rng.integers(15, 30, cells.size))
    phi = rng.integers(0, 20, (V, 4))
    sweeps, burn = 3000, 100

    def frequencies(chain_topics: list[np.ndarray]) -> np.ndarray:
        counts = np.zeros((words.size, 4))
        for topics in chain_topics:
            counts[np.arange(words.size), topics] += 1
        return counts / len(chain_topics)

    chains = FrozenChains(words, cells, table, n_topics=4, vocabulary_size=V, alpha=0.5, beta=0.1)
    chains.start([phi] * 8, list(range(8)))
    chains.sweep(burn)
    samples = []
    for _ in range(sweeps):
        chains.sweep(1)
        samples += list(chains.topics().T)
    lock_step = frequencies(samples)

    def exact(first_seed: int) -> np.ndarray:
        samples = []
        for seed in range(first_seed, first_seed + 8):
            model = TopicModel(4, V, table, alpha=0.5, beta=0.1, seed=seed, frozen_counts=phi)
            for c in range(16):
                model.add_cell(c, words[cells == c])
            model.refine_batch(burn)
            for _ in range(sweeps):
                model.refine_batch(1)
                samples.append(model.topics().astype(np.int64))
        return frequencies(samples)

    reference = exact(100)
    exact_gap = np.abs(exact(200) - reference).max()
    lock_step_gap = np.abs(lock_step - reference).max()
    assert lock_step_gap < 1.5 * exact_gap, (lock_step_gap, exact_gap)
    assert lock_step_gap < 0.05


def test_bad_arguments_are_named():
    words, cells, table = small_map()
    chains = chains_of(words, cells, table)
    with pytest.raises(ParameterError, match=r"sweep: no chains yet; start\(\) them first"):
        chains.sweep(1)
    with pytest.raises(ParameterError, match=r"phis: chain 1 has shape \(3, 5\), expected \(V, K\) = \(30, 5\)"):
        chains.start([np.zeros((V, K), int), np.zeros((3, K), int)], [0, 1])
    with pytest.raises(ParameterError, match=r"seeds: got 1, expected one per chain \(2\)"):
        chains.start([np.zeros((V, K), int)] * 2, [0])
    with pytest.raises(ParameterError, match=r"cells: must be non-decreasing"):
        chains_of(words, cells[::-1], table)
    with pytest.raises(ParameterError, match=r"words: values must be in 0..29"):
        chains_of(words + V, cells, table)
