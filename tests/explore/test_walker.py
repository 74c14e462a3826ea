"""One exploration run: its records agree with each other and with the paper's rules."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from small_maps import small_config, synthetic_store, two_region_store
from test_weights import potential_naive

from curiosity_cli.errors import ParameterError
from curiosity_cli.explore import weights
from curiosity_cli.explore.walker import explore


def run(store, weight_function="topic-perplexity", start=9, seed=(1,), truth=None, **explore_settings):
    config = small_config(**explore_settings)
    return explore(store, weight_function, start, model=config.model, settings=config.explore, seed=seed, truth=truth)


def two_region_truth() -> np.ndarray:
    """(48, 2) bool: the classes present in each cell of :func:`two_region_store`, its two halves."""
    right = np.zeros((6, 8), bool)
    right[:, 4:] = True
    return np.stack([~right.ravel(), right.ravel()], axis=1)


@pytest.mark.parametrize("name", [n for n in weights.WEIGHT_FUNCTIONS if n not in weights.CEILINGS])
def test_paths_step_between_4_neighbours_and_never_leave_the_map(name):
    e = run(two_region_store(), name, path_length=40, checkpoints=(40,), truth=two_region_truth())
    rows, cols = np.divmod(e.path, 8)
    assert ((rows >= 0) & (rows < 6) & (cols >= 0) & (cols < 8)).all()
    assert (np.abs(np.diff(rows)) + np.abs(np.diff(cols)) == 1).all()


def test_the_same_seed_gives_the_same_run_and_another_seed_another():
    a, b, c = (run(two_region_store(), seed=s) for s in ((1,), (1,), (2,)))
    for field in dataclasses.fields(a):
        if field.name != "checkpoints":
            np.testing.assert_array_equal(getattr(a, field.name), getattr(b, field.name))
    for length in a.checkpoints:
        np.testing.assert_array_equal(a.checkpoints[length].dense(), b.checkpoints[length].dense())
    assert not np.array_equal(a.path, c.path)


def test_checkpoints_hold_the_words_of_the_path_so_far():
    store = two_region_store()
    e = run(store)
    assert sorted(e.checkpoints) == [10, 30]
    for length, counts in e.checkpoints.items():
        phi = counts.dense()
        assert phi.shape == (store.vocabulary_size, 8)
        seen = np.unique(e.path[:length])
        words = np.concatenate([store.cell_words(c) for c in seen])
        np.testing.assert_array_equal(phi.sum(axis=1), np.bincount(words, minlength=phi.shape[0]))


def test_step_records_agree_with_the_path_and_the_formulas():
    e = run(two_region_store(), "word-perplexity")
    first = [cell not in e.path[:step] for step, cell in enumerate(e.path)]
    np.testing.assert_array_equal(e.first_visit, first)
    assert (e.words_sampled >= 5000).all()
    assert np.isfinite(e.log_likelihood).all() and (e.log_likelihood < 0).all()
    for step in range(e.path.size - 1):
        here = e.candidate_step == step
        chosen = e.candidate_cell[here & e.chosen]
        assert chosen.tolist() == [e.path[step + 1]]
        visits = {int(c): int(n) for c, n in zip(*np.unique(e.path[: step + 1], return_counts=True))}
        if e.boxed_in[step]:  # the limit of eq. 8: each neighbour's own visit count
            expected = [visits[int(g)] for g in e.candidate_cell[here]]
        else:
            expected = [potential_naive(int(g), visits, 8) for g in e.candidate_cell[here]]
        np.testing.assert_allclose(e.coverage[here], expected, rtol=1e-12)
    np.testing.assert_allclose(e.weight, e.word_perplexity / e.coverage, rtol=1e-15)
    assert (e.word_perplexity >= 1).all() and (e.topic_perplexity >= 1).all()
    assert e.path.size - 1 == len(np.unique(e.candidate_step)), "the last step scores no move"


@pytest.mark.parametrize("name", ["stochastic-coverage", "word-perplexity", "topic-perplexity"])
def test_the_papers_repulsion_never_steps_back_while_an_unvisited_neighbour_is_open(name):
    # eq. 8 evaluated naively on the path: a visited neighbour has d = 0, so weight 0
    store = two_region_store()
    e = run(store, name, path_length=80, checkpoints=(80,))
    table = store.grid.neighbour_table()
    boxed = 0
    for step in range(e.path.size - 1):
        seen = set(e.path[: step + 1].tolist())
        neighbours = [g for g in table[e.path[step]].tolist() if g >= 0]
        open_cells = [g for g in neighbours if g not in seen]
        if open_cells:
            assert e.path[step + 1] in open_cells, step
            assert not e.boxed_in[step]
        else:
            assert e.boxed_in[step]
            boxed += 1
    assert e.boxed_in.sum() == boxed and not e.fallback.any()
    assert boxed > 0, "80 steps on 48 cells must get boxed in at times"


def test_boxed_in_steps_prefer_the_least_visited_neighbour():
    # a 1 x 3 corridor: from the middle both ends are visited once more each time round,
    # so the limit rule is 1 / visits; stochastic coverage from cell 1 after 0, 1, 2, 1
    store = synthetic_store(np.zeros((1, 3), int))
    e = run(store, "stochastic-coverage", start=0, path_length=40, checkpoints=(40,))
    assert e.path[:3].tolist() == [0, 1, 2]
    assert e.boxed_in[2:-1].all()
    # from the middle the end visited less is preferred: the visit counts never differ by more than a few
    counts = np.bincount(e.path, minlength=3)
    assert abs(int(counts[0]) - int(counts[2])) <= 3


@pytest.mark.parametrize("reading", ["clamp", "others"])
def test_the_other_readings_of_eq_8_step_back_and_count_boxed_in_steps_alike(reading):
    # under the clamp or with a candidate's own visits left out, a visited neighbour keeps a
    # weight, so the walker steps back while unvisited cells are open; the literal reading
    # never does (test above). A step with every neighbour visited is boxed in under each.
    store = two_region_store()
    table = store.grid.neighbour_table()
    revisits = []
    for coverage in ("literal", reading):
        e = run(store, "stochastic-coverage", path_length=40, checkpoints=(40,), coverage=coverage)
        revisits.append(int((~e.first_visit).sum()))
        every_visited = [
            all(g in e.path[: step + 1] for g in table[e.path[step]] if g >= 0) for step in range(e.path.size - 1)
        ]
        np.testing.assert_array_equal(e.boxed_in[:-1], every_visited)
        assert not e.fallback.any()
    assert revisits[1] > revisits[0], revisits


def test_each_reading_scores_the_coverage_potential_of_its_own_sum():
    for reading in ("clamp", "others"):
        e = run(two_region_store(), "stochastic-coverage", path_length=30, checkpoints=(30,), coverage=reading)
        for step in range(e.path.size - 1):
            here = e.candidate_step == step
            visits = {int(c): int(n) for c, n in zip(*np.unique(e.path[: step + 1], return_counts=True))}
            expected = [potential_naive(int(g), visits, 8, reading, 0.25) for g in e.candidate_cell[here]]
            np.testing.assert_allclose(e.coverage[here], expected, rtol=1e-12)


@pytest.mark.parametrize("name", ["lawnmower", "scattered-cells", "compact-block"])
def test_a_planned_walker_observes_its_plan_and_scores_nothing(name):
    store = two_region_store()
    e = run(store, name, start=9, path_length=100, checkpoints=(10, 100))
    plan = weights.WEIGHT_FUNCTIONS[name]
    if name != "scattered-cells":  # deterministic: the plan from the start cell alone
        np.testing.assert_array_equal(e.path, plan.cells(9, store.grid, 100, np.random.default_rng(0)))
    assert e.candidate_cell.size == 0 and not e.fallback.any() and not e.boxed_in.any()
    np.testing.assert_array_equal(e.first_visit, [c not in e.path[:i] for i, c in enumerate(e.path)])
    assert len(np.unique(e.path)) == 48, "100 steps of a plan cover all 48 cells"
    again = run(store, name, start=9, path_length=100, checkpoints=(10, 100))
    np.testing.assert_array_equal(e.path, again.path)


def test_a_wall_clock_budget_refines_until_the_time_is_up():
    e = run(two_region_store(), path_length=5, checkpoints=(5,), step_seconds=0.01)
    assert (e.words_sampled > 0).all()


def test_bad_arguments_name_the_parameter():
    config = small_config()
    kwargs = dict(model=config.model, settings=config.explore, seed=0)
    with pytest.raises(ParameterError, match="weight_function: got 'curious', expected one of random-walk"):
        explore(two_region_store(), "curious", 0, **kwargs)
    with pytest.raises(ParameterError, match=r"start_cell: got 48, expected 0 \.\. 47"):
        explore(two_region_store(), "random-walk", 48, **kwargs)
    with pytest.raises(ParameterError, match="single cell"):
        explore(synthetic_store(np.zeros((1, 1), int)), "random-walk", 0, **kwargs)


def test_a_weight_function_giving_negative_weights_is_refused(monkeypatch):
    monkeypatch.setitem(weights.WEIGHT_FUNCTIONS, "broken", lambda c: -np.ones(c.cells.size))
    with pytest.raises(ParameterError, match="weight function 'broken': returned .* expected 4 weights >= 0"):
        run(two_region_store(), "broken")


def test_a_weight_function_added_to_the_registry_drives_the_walker(monkeypatch):
    # always the last candidate: right when it exists, so the walker ends at the right edge
    def rightmost(c):
        w = np.zeros(c.cells.size)
        w[-1] = 1.0
        return w

    monkeypatch.setitem(weights.WEIGHT_FUNCTIONS, "rightmost", rightmost)
    e = run(two_region_store(), "rightmost", start=8, path_length=5, checkpoints=(5,))
    assert e.path.tolist() == [8, 9, 10, 11, 12]


@pytest.mark.slow
def test_topic_perplexity_walkers_linger_on_a_rare_stripe_more_than_coverage_walkers():
    # a uniform 24 x 24 map crossed by a one-cell-wide stripe of other words (column 12);
    # 32 paired restarts from start cells within 6 columns of the stripe, 100 steps each.
    # Measured with the paper's repulsion: 0.15 of topic-perplexity steps on or beside the
    # stripe against 0.12 for stochastic coverage (paired difference 0.030, standard error
    # 0.015; 48 restarts: 0.031 and 0.014). With the clamp reading (min_d2 = 0.25), which lets a
    # walker step back onto the stripe, it was 0.22 against 0.13.
    regions = np.zeros((24, 24), int)
    regions[:, 12] = 1
    store = synthetic_store(regions)
    near = {}
    for name in ("stochastic-coverage", "topic-perplexity"):
        near[name] = []
        for restart in range(32):
            rng = np.random.default_rng(restart)
            start = int(rng.integers(0, 24)) * 24 + int(rng.integers(6, 19))
            e = run(store, name, start, seed=(restart,), path_length=100, checkpoints=(100,), samples_per_step=20000)
            near[name].append(np.mean(np.abs(e.path % 24 - 12) <= 1))
    coverage, topic = np.mean(near["stochastic-coverage"]), np.mean(near["topic-perplexity"])
    assert topic > coverage + 0.01, (topic, coverage)


def test_an_oracle_with_no_new_class_in_reach_walks_stochastic_coverage_s_walk_on_its_streams():
    store, one_class = two_region_store(), np.ones((48, 1), bool)
    coverage = run(store, "stochastic-coverage", path_length=30, checkpoints=(30,))
    for name in ("oracle-0.1", "oracle-0.3"):
        oracle = run(store, name, path_length=30, checkpoints=(30,), truth=one_class)
        np.testing.assert_array_equal(oracle.path, coverage.path)
        np.testing.assert_array_equal(oracle.weight, coverage.weight)
        np.testing.assert_array_equal(oracle.checkpoints[30].dense(), coverage.checkpoints[30].dense())
    with pytest.raises(ParameterError, match="^truth: expected the classes present in each of the map's 48 cells"):
        run(store, "oracle-0.2", truth=None)


def test_an_oracle_moves_to_a_new_class_with_its_chance_and_otherwise_as_its_base_walker():
    from curiosity_cli.explore.walker import _oracle_move

    candidates = weights.Candidates(
        cells=np.arange(4), coverage=np.array([1.0, 2.0, 4.0, np.inf]), word_perplexity=np.ones(4),
        topic_perplexity=np.ones(4),
    )
    new = np.array([[False, False], [False, True], [False, False], [True, True]])
    base = weights.stochastic_coverage_weights(candidates)
    draws, overrides = 4000, 0
    rng, own, twin = (np.random.default_rng(s) for s in (1, 2, 1))
    for _ in range(draws):
        expected = int(twin.choice(4, p=base / base.sum()))  # the base walker's draw, from the same move stream
        weights_used, choice, fell_back = _oracle_move(weights.Oracle(0.3), candidates, new, rng, own)
        assert not fell_back
        if weights_used.tolist() == [0.0, 1.0, 0.0, 1.0]:
            overrides += 1
            assert choice in (1, 3), "uniform among the candidates holding a class new to the path"
        else:
            np.testing.assert_array_equal(weights_used, base)
            assert choice == expected
    # 0.3 of the steps, within a binomial 99.9 % band (about +- 0.024)
    assert abs(overrides / draws - 0.3) < 3.3 * np.sqrt(0.3 * 0.7 / draws)
    none_new = _oracle_move(weights.Oracle(1.0), candidates, np.zeros((4, 2), bool), rng, own)
    np.testing.assert_array_equal(none_new[0], base)


def test_the_sham_weighs_each_candidate_by_its_stand_in_s_score_steering_as_hard_as_topic_perplexity(monkeypatch):
    from curiosity_cli.explore import walker

    # a score that names its cell: the sham's weights then say which cell stood in for each candidate
    monkeypatch.setattr(walker, "_perplexities", lambda model, store, cells, settings: cells + 2.0)
    seed, store = (3,), two_region_store()
    sham = run(store, "sham", seed=seed, path_length=40, checkpoints=(40,))
    stand_in = weights.Sham().stand_ins(store.grid, np.random.default_rng(np.random.SeedSequence(seed).spawn(3)[2]))
    steps = 0
    for step in np.unique(sham.candidate_step):
        at = sham.candidate_step == step
        cells, coverage, weight = sham.candidate_cell[at], sham.coverage[at], sham.weight[at]
        open_ = np.isfinite(coverage)
        if open_.sum() < 2:
            continue
        # weight * U is the stand-in's score to one power on every open candidate
        exponents = np.log(weight[open_] * coverage[open_]) / np.log(stand_in[cells[open_]] + 2.0)
        np.testing.assert_allclose(exponents, exponents[0], rtol=1e-9)
        candidates = weights.Candidates(cells, coverage, np.ones(cells.size), cells + 2.0)
        assert distance(weight, candidates) == pytest.approx(
            distance(weights.topic_perplexity_weights(candidates), candidates), abs=1e-9
        )
        steps += 1
    assert steps >= 20


def distance(weight: np.ndarray, candidates) -> float:
    """A step's total-variation distance from stochastic coverage's, as steering.csv measures it."""
    from curiosity_cli.explore.walker import move_probabilities

    coverage_only = move_probabilities(weights.stochastic_coverage_weights(candidates))[0]
    return 0.5 * float(np.abs(move_probabilities(weight)[0] - coverage_only).sum())


def test_the_sham_s_translation_moves_every_cell_by_one_offset_at_least_a_quarter_of_the_map_away():
    grid, rng = two_region_store().grid, np.random.default_rng(0)  # 6 x 8 cells: 2 cells or more
    for _ in range(50):
        stand_in = weights.Sham().stand_ins(grid, rng)
        assert np.array_equal(np.sort(stand_in), np.arange(grid.n_cells)), "a permutation of the cells"
        (dr, dc), = {((t // 8 - c // 8) % 6, (t % 8 - c % 8) % 8) for c, t in enumerate(stand_in)}
        assert np.hypot(min(dr, 6 - dr), min(dc, 8 - dc)) >= 2
