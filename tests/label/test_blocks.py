"""Cutting a stage's chains into blocks: every chain once, every worker busy to the end."""

from __future__ import annotations

import pytest

from curiosity_cli.label.blocks import _block_cost, _makespan, dealing_order, plan_blocks

#: The paper grid (3 maps x 4 walkers x 20 restarts, restart 0 checked: 84 chains a map) and the quick job's map.
PAPER = [[2] * 4 + [1] * 76] * 3
QUICK = [[2] * 7 + [1] * 63]


def fixed_blocks(counts, most=16):
    """The plan before: blocks filled to ``most`` chains in order."""
    out, size = [], most
    for index, count in enumerate(counts):
        if size + count > most:
            out.append([])
            size = 0
        out[-1].append(index)
        size += count
    return out


def finish(grid, plan, workers):
    return _makespan([_block_cost(sum(c[i] for i in b), 8) for c, blocks in zip(grid, plan) for b in blocks], workers)


@pytest.mark.parametrize("grid", [PAPER, QUICK, [[1] * 5, [2, 1], []]], ids=["paper", "quick", "small"])
@pytest.mark.parametrize("workers", [1, 2, 16])
def test_every_chain_is_planned_once_and_no_later_than_full_blocks_in_order(grid, workers):
    plan = plan_blocks(grid, workers, lanes=8, most=16)
    assert len(plan) == len(grid)
    for counts, blocks in zip(grid, plan):
        assert sorted(i for block in blocks for i in block) == list(range(len(counts)))
        assert all(block == sorted(block) and block for block in blocks)
    before = [fixed_blocks(counts) for counts in grid]
    assert finish(grid, plan, workers) <= finish(grid, before, workers)


def test_sixteen_workers_label_the_paper_grid_in_one_round():
    plan = plan_blocks(PAPER, 16, lanes=8, most=16)
    n_blocks = sum(len(blocks) for blocks in plan)
    assert n_blocks <= 16  # before: 18 blocks of up to 16, a second round of two on 16 workers
    assert finish(PAPER, plan, 16) < finish(PAPER, [fixed_blocks(c) for c in PAPER], 16)


def test_two_workers_take_one_block_each_of_the_quick_job():
    plan = plan_blocks(QUICK, 2, lanes=8, most=16)
    assert len(plan[0]) == 2  # before: 5 blocks, so one worker had 3 to the other's 2
    held = [-(-sum(QUICK[0][i] for i in block) // 8) for block in plan[0]]
    assert held[0] == held[1]  # the two workers finish together


def test_one_worker_keeps_blocks_of_two_vectors():
    plan = plan_blocks(QUICK, 1, lanes=8, most=16)
    assert all(9 <= sum(QUICK[0][i] for i in block) <= 16 for block in plan[0])


def test_a_gpu_takes_each_map_whole_and_small_blocks_stay_small():
    assert plan_blocks([[1, 2], [1], []], 4, lanes=8, most=None) == [[[0, 1]], [[0]], []]
    assert plan_blocks([[1, 1, 2]], 2, lanes=8, most=1) == [[[0], [1], [2]]]


def test_a_map_of_more_words_gets_no_larger_blocks_and_the_grid_finishes_sooner():
    words = [1_123_410, 1_073_645, 1_660_656]  # the paper grid's maps: aerial-mosaic, sentinel-coast, reef-mosaic

    def weighted_finish(plan):
        costs = [_block_cost(sum(c[i] for i in b), 8) * n for c, blocks, n in zip(PAPER, plan, words) for b in blocks]
        return _makespan(costs, 16)

    plan = plan_blocks(PAPER, 16, lanes=8, most=16, words=words)
    largest = [max(sum(c[i] for i in b) for b in blocks) for c, blocks in zip(PAPER, plan)]
    assert largest[2] <= min(largest[:2])
    assert weighted_finish(plan) < weighted_finish(plan_blocks(PAPER, 16, lanes=8, most=16))


def test_blocks_are_dealt_costliest_first_as_the_plan_assumes():
    # map 1 has 1.5 times the words; a block of 4 chains is held as 8, at 1.45 times the cost per chain:
    # costs 16 x 3 = 48, 8 x 1.45 x 3 = 34.8, 16 x 2 = 32, 8 x 1.45 x 2 = 23.2; in map order they were 32, 23.2, 48, 34.8
    counts = [[1] * 20, [1] * 20]
    plan = [[list(range(16)), list(range(16, 20))], [list(range(16)), list(range(16, 20))]]
    assert dealing_order(plan, counts, lanes=8, words=[2, 3]) == [(1, 0), (1, 1), (0, 0), (0, 1)]
    assert dealing_order(plan, counts, lanes=8) == [(0, 0), (1, 0), (0, 1), (1, 1)]  # ties in plan order
