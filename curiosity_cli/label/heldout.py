"""How well a path's model Φ_p predicts the map's words it did not see: held-out log-likelihood by document completion.

Each map's words are split once into an observed half and a held-out half
(:func:`map_split`): in each cell with ``n`` words, ``floor(n / 2)`` of them drawn at
random are held out (none of a cell with one word), from a seed that depends only on the
experiment's seed and the map, so every walker and restart of a map is scored on the same
words and their scores are paired.

Per run, a frozen-Φ Gibbs chain over the observed words only
(:func:`~curiosity_cli.label.sampling.map_chains` with ``kept``), with the labeller's
model (K, α, β, the neighbourhood) and sweeps, Φ frozen to Φ_p at each checkpoint
(:func:`~curiosity_cli.label.sampling.advance_chains`), seeded from the run's seed
(:data:`~curiosity_cli.seeds.HELDOUT_CHAIN_TAG`); a block's runs advance in lock-step,
each depending only on its own run. After a checkpoint's sweeps, each held-out word
``w`` of cell ``c`` scores (:func:`word_log2`)::

    θ_ck = (n_Gc,k + α) / (Σ_k n_Gc,k + K α)       n_Gc: the topics of the observed words of c and its neighbours
    φ_k(w) = (Φ_p[w, k] + β) / (n_k + V β)           n_k = Σ_w Φ_p[w, k]
    log2 Σ_k θ_ck φ_k(w)

θ_c is the labeller's prior of a word of ``c`` (eq. 5's ``n_G + α``) from the chain's
last state, one draw. :func:`heldout_sums` adds the scores over every held-out word and over
those in a cell the path had not visited by the checkpoint (whose words Φ_p does not
hold), in the store's order, so a sum does not depend on which runs share a block.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence

import numpy as np

from curiosity_cli.config import ModelConfig
from curiosity_cli.label.sampling import advance_chains, map_chains
from curiosity_cli.words.store import WordStore


def map_split(store: WordStore, experiment_seed: int, name: str) -> np.ndarray:
    """(N,) bool ndarray: the words of map ``name``'s ``store`` held out, drawn from the experiment's seed and the
    map's name only (:data:`~curiosity_cli.seeds.SPLIT_TAG`)."""
    from curiosity_cli.seeds import SPLIT_TAG, name_key

    return split_words(store.word_cells(), np.random.SeedSequence((experiment_seed, name_key(name), SPLIT_TAG)))


def split_words(word_cells: np.ndarray, seed: np.random.SeedSequence) -> np.ndarray:
    """Hold out ``floor(n / 2)`` of the ``n`` words of each cell, drawn uniformly without replacement.

    Parameters
    ----------
    word_cells : (N,) int ndarray
        Each word's cell, non-decreasing (words grouped by cell, as a store holds them).
    seed : numpy.random.SeedSequence

    Returns
    -------
    (N,) bool ndarray
        True for a held-out word.
    """
    word_cells = np.asarray(word_cells, np.int64)
    keys = np.random.default_rng(seed).random(word_cells.size)
    order = np.lexsort((keys, word_cells))  # each cell's words by their random key
    counts = np.bincount(word_cells)
    rank = np.empty(word_cells.size, np.int64)
    rank[order] = np.arange(word_cells.size) - np.repeat(np.cumsum(counts) - counts, counts)
    return rank < (counts // 2)[word_cells]


def heldout_chains(
    store: WordStore, model: ModelConfig, held: np.ndarray, paths: Sequence[Sequence[np.ndarray]], seeds: Sequence[int],
    *, sweeps: int, warm_sweeps: int | None, device: str = "cpu",
) -> Iterator[tuple[int, list[int], list[np.ndarray]]]:
    """The held-out words' scores under each path's model at each of its checkpoints, the chains in lock-step.

    Parameters
    ----------
    store : WordStore
    model : ModelConfig
        K, α, β and the neighbourhood.
    held : (N,) bool ndarray
        The held-out words (:func:`map_split`); the chains run over the others.
    paths : sequence of sequences of (V, K) int ndarrays
        Each path's Φ_p at its checkpoints, shortest path first.
    seeds : sequence of int
        One per path.
    sweeps, warm_sweeps : int
        As :func:`~curiosity_cli.label.sampling.label_paths`'s.
    device : str
        Where the chains run (the same bytes on each).

    Yields
    ------
    j : int
        The checkpoint.
    chains : list of int
        The paths that have a ``j``-th checkpoint, in order.
    scores : list of (H,) float64 ndarrays
        Per path of ``chains``, :func:`word_log2` of each held-out word, in the store's order.
    """
    words, cells = store.words[held], store.word_cells()[held]
    chains = map_chains(store, model, device, kept=~held)
    for j, active in advance_chains(chains, paths, seeds, sweeps=sweeps, warm_sweeps=warm_sweeps):
        _, around = chains.counts()
        yield j, active, [
            word_log2(around[:, :, r], paths[c][j], words, cells, model.alpha, model.beta)
            for r, c in enumerate(active)
        ]


def word_log2(
    around: np.ndarray, phi: np.ndarray, words: np.ndarray, cells: np.ndarray, alpha: float, beta: float,
) -> np.ndarray:
    """Each word's ``log2 Σ_k θ_ck φ_k(w)`` (module docstring).

    Parameters
    ----------
    around : (n_cells, K) int ndarray
        The topics of the observed words of each cell and its neighbours (a chain's neighbourhood sums).
    phi : (V, K) int ndarray
        Φ_p.
    words, cells : (H,) int ndarrays
        Each scored word's id and cell.
    alpha, beta : float

    Returns
    -------
    (H,) float64 ndarray
        In bits (<= 0).
    """
    from curiosity_cli.label._heldout_kernels import word_log2_kernel

    phi = np.asarray(phi, np.float64)
    topic_words = (phi + beta) / (phi.sum(axis=0) + phi.shape[0] * beta)  # (V, K): φ_k(w)
    prior = np.asarray(around, np.float64) + alpha
    mixture = prior / prior.sum(axis=1, keepdims=True)  # (n_cells, K): θ_c
    out = np.empty(len(words), np.float64)
    # a kernel, not numpy's gathers: on a map of a million words and K = 64 those are (H, K) arrays of 300 MB
    word_log2_kernel(mixture, topic_words, np.asarray(words, np.int64), np.asarray(cells, np.int64), out)
    return out


def heldout_sums(scores: np.ndarray, unvisited: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The bits and the count of the held-out words, over all of them and over those in cells not visited.

    Parameters
    ----------
    scores : (H,) float64 ndarray
        :func:`word_log2` of each held-out word.
    unvisited : (H,) bool ndarray
        Whether its cell is one the path had not visited.

    Returns
    -------
    bits : (2,) float64 ndarray
        The sum of ``scores``, added in their order: all, unvisited.
    words : (2,) int64 ndarray
        The words summed: all, unvisited.
    """
    from curiosity_cli.label._heldout_kernels import heldout_sums_kernel

    unvisited = np.asarray(unvisited, bool)
    bits = np.empty(2, np.float64)
    heldout_sums_kernel(np.asarray(scores, np.float64), unvisited, bits)
    return bits, np.array([scores.size, np.count_nonzero(unvisited)], np.int64)
