"""The CUDA labelling kernels against the CPU kernels, byte for byte: run as a script.

``python tests/topics/cuda_cases.py CASE`` runs one case (:data:`CASES`) on both devices
and exits 0 when topics, counts, neighbourhood sums and ML topics are identical, printing
the first difference otherwise. ``tests/topics/test_chains_cuda.py`` runs it under numba's
CUDA simulator (``NUMBA_ENABLE_CUDASIM=1``, set before numba is imported, hence a
process of its own); ``scripts/device_check.sh`` runs it on a real GPU.
"""

from __future__ import annotations

import sys

import numpy as np

from curiosity_cli.maps.cell_grid import SquareGrid
from curiosity_cli.topics.chains import FrozenChains

K, V = 5, 30


def tiny_map(rows: int, cols: int, seed: int, most_words: int = 6):
    """(words, cells, table): 0 to ``most_words - 1`` words per cell (some cells without words), 4 neighbours."""
    rng = np.random.default_rng(seed)
    table = SquareGrid(rows * 4, cols * 4, 4).neighbour_table(4)
    sizes = rng.integers(0, most_words, rows * cols)
    sizes[0] = 0  # a cell without words, always
    cells = np.repeat(np.arange(rows * cols), sizes)
    return rng.integers(0, V, cells.size), cells, table


def one_cell_map():
    return np.array([3, 3, 7, 0, 29]), np.zeros(5, int), np.array([[-1, -1, -1, -1]], np.int32)


def allowed_topics(rng, n_chains: int) -> list:
    """Every other chain's topics allowed per word (a labelling reading's): about half of them, one at least; the
    rest None (all)."""
    masks = []
    for r in range(n_chains):
        mask = rng.random((V, K)) < 0.5
        mask[np.arange(V), rng.integers(0, K, V)] = True
        masks.append(mask if r % 2 else None)
    return masks


def run(device: str, words, cells, table, n_chains: int, seed: int) -> list[tuple[str, np.ndarray]]:
    """Start, sweep, switch, keep and sweep ``n_chains`` chains on ``device``; every state along the way."""
    rng = np.random.default_rng(seed)
    phis = [rng.integers(0, 6, (V, K)) for _ in range(n_chains)]
    later = [rng.integers(0, 6, (V, K)) for _ in range(n_chains)]
    chains = FrozenChains(words, cells, table, n_topics=K, vocabulary_size=V, alpha=0.1, beta=0.1, device=device)
    chains.start(
        phis, [seed * 100 + r for r in range(n_chains)], [r % 3 == 1 for r in range(n_chains)],
        allowed_topics(rng, n_chains),
    )
    states = []

    def record(step: str) -> None:
        ncz, ng = chains.counts()
        states.extend([(f"{step} topics", chains.topics()), (f"{step} ncz", ncz), (f"{step} ng", ng),
                       (f"{step} ml_topics", chains.ml_topics())])

    record("start")
    chains.sweep(2)
    record("2 sweeps")
    chains.switch(later, allowed_topics(rng, n_chains))
    chains.sweep(1)
    record("switched")
    if n_chains > 1:
        chains.keep(list(range(n_chains - 1, -1, -2)))
        chains.sweep(1)
        record("kept")
    return states


CASES = {
    "tiny map, 3 chains": (lambda: tiny_map(3, 4, 0), 3),
    "tiny map, 10 chains": (lambda: tiny_map(2, 3, 1), 10),
    "one cell, 2 chains": (one_cell_map, 2),
    "one word per cell at most, 9 chains": (lambda: tiny_map(3, 3, 2, most_words=2), 9),
}


def compare(case: str) -> str | None:
    """None when both devices gave the same bytes in ``case``; else the first difference, in words."""
    build, n_chains = CASES[case]
    words, cells, table = build()
    cpu = run("cpu", words, cells, table, n_chains, seed=len(case))
    gpu = run("cuda", words, cells, table, n_chains, seed=len(case))
    for (name, a), (_, b) in zip(cpu, gpu):
        if a.dtype != b.dtype or a.shape != b.shape:
            return f"{name}: {a.dtype}{a.shape} on the CPU, {b.dtype}{b.shape} on the GPU"
        if a.tobytes() != b.tobytes():
            where = tuple(int(i) for i in np.argwhere(a != b)[0])
            return f"{name}: {np.count_nonzero(a != b)} of {a.size} differ, first at {where}: CPU {a[where]}, GPU {b[where]}"
    return None


if __name__ == "__main__":
    failed = False
    for case in sys.argv[1:] or list(CASES):
        difference = compare(case)
        print(f"{case}: {'the same bytes' if difference is None else difference}", flush=True)
        failed |= difference is not None
    sys.exit(1 if failed else 0)
