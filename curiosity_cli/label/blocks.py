"""The plan of a label stage's blocks: a map's runs cut into blocks of chains that advance
in lock-step in one task, sized so that every worker finishes together, as early as it can."""

from __future__ import annotations

from collections.abc import Sequence

#: A block's time per chain held against a block of two vectors' worth or more: one
#: vector's worth of chains hides less latency (21.3 against 14.8 ns a word-sample at 8
#: and 16 chains, ``docs/PERFORMANCE.md``).
_ONE_VECTOR_COST = 1.45


def plan_blocks(
    chain_counts: Sequence[Sequence[int]], workers: int, *, lanes: int, most: int | None, words: Sequence[int] | None = None,
) -> list[list[list[int]]]:
    """Cut each map's runs into blocks of chains so that ``workers`` workers finish together, as early as they can.

    A block's chains advance in lock-step in one task and are held in multiples of
    ``lanes`` (a block of 17 chains costs what 24 do). Blocks of one size ``s`` (a
    multiple of ``lanes``, up to ``3 * most``) are tried, each map's runs cut either into
    blocks filled to ``s`` in order or into ``ceil(chains / s)`` blocks of nearly equal
    chains; the blocks are dealt largest first to the least busy worker, and the plan whose
    last worker finishes first wins (ties: the smaller blocks). A block costs its chains
    held times its map's words. So 252 chains of three maps of equal words on 16 workers
    are 12 blocks of 21 (one round) rather than 18 of 16 (a second round of 2), and 77
    chains on 2 workers are 2 blocks rather than 5; with the paper grid's words (reef-mosaic
    1.5 times the others'), 15 blocks of 16 and three of 4, reef-mosaic's first.

    Parameters
    ----------
    chain_counts : sequence of sequences of int
        Per map, each run's chains, in order (a run's chains stay in one block).
    workers : int
        Tasks that run at once.
    lanes : int
        Chains are held in multiples of this.
    most : int or None
        The block size past which the time per chain stops falling (below ``lanes``:
        blocks of that size); None: every map's runs in one block (a GPU).
    words : sequence of int, optional
        Per map, its words: a chain's sweeps cost in proportion (default: the same for every map).

    Returns
    -------
    list of list of list of int
        Per map, its blocks, each the indices of its runs in order; every run in exactly one.
        Submit them in :func:`dealing_order`: the plan assumes a worker that frees takes
        the costliest block left.
    """
    if most is None:
        return [[list(range(len(counts)))] if len(counts) else [] for counts in chain_counts]
    best = None
    words = [1] * len(chain_counts) if words is None else words
    sizes = [most] if most < lanes else range(lanes, 3 * most + 1, lanes)  # below a vector: as asked (tests)
    for size in sizes:
        for cut in (_full_blocks, _even_blocks):
            plan = [cut(counts, size) for counts in chain_counts]
            costs = [
                _block_cost(sum(counts[i] for i in block), lanes) * n_words
                for counts, blocks, n_words in zip(chain_counts, plan, words) for block in blocks
            ]
            finish = _makespan(costs, workers)
            if best is None or finish < best[0] - 1e-9:
                best = (finish, plan)
    return best[1]


def dealing_order(
    plan: list[list[list[int]]], chain_counts: Sequence[Sequence[int]], *, lanes: int, words: Sequence[int] | None = None,
) -> list[tuple[int, int]]:
    """The ``(map, block)`` indices of a :func:`plan_blocks` plan, costliest block first (ties: in plan order).

    The order the plan's makespan assumes: on a pool whose free worker takes the next
    task submitted, the costliest blocks start first and the cheap ones fill in at the end.
    In map order instead, the paper grid's reef-mosaic blocks (its words 1.5 times the
    others') started when the first blocks finished, and the label stage on 16 cores took
    184 s where its plan needed about 130.
    """
    words = [1] * len(chain_counts) if words is None else words
    costs = {
        (m, b): _block_cost(sum(chain_counts[m][i] for i in block), lanes) * words[m]
        for m, blocks in enumerate(plan) for b, block in enumerate(blocks)
    }
    return sorted(costs, key=lambda index: -costs[index])


def _full_blocks(counts: Sequence[int], size: int) -> list[list[int]]:
    """Runs cut in order into blocks filled to ``size`` chains (a run's chains together), the last one what is left."""
    blocks, filled = [], size
    for index, count in enumerate(counts):
        if filled + count > size and (filled > 0 or not blocks):
            blocks.append([])
            filled = 0
        blocks[-1].append(index)
        filled += count
    return blocks


def _even_blocks(counts: Sequence[int], size: int) -> list[list[int]]:
    """Runs cut into ``ceil(total / size)`` blocks in order, each near its even share of the chains."""
    total = sum(counts)
    if total == 0:
        return []
    n_blocks = -(-total // size)
    blocks, done = [[] for _ in range(n_blocks)], 0
    for index, count in enumerate(counts):
        # the block whose even share holds this run's middle chain
        blocks[min(n_blocks - 1, int((done + count / 2) * n_blocks / total))].append(index)
        done += count
    return [block for block in blocks if block]


def _block_cost(chains: int, lanes: int) -> float:
    held = -(-chains // lanes) * lanes
    return held * (_ONE_VECTOR_COST if held == lanes else 1.0)


def _makespan(costs: list[float], workers: int) -> float:
    """When the last of ``workers`` finishes, each block taken, largest first, by the first free worker."""
    loads = [0.0] * max(1, workers)
    for cost in sorted(costs, reverse=True):
        loads[loads.index(min(loads))] += cost
    return max(loads)
