"""Synthetic corpora with known answers, for statistical tests and benchmarks.

Two generators, both numpy only and seeded with ``np.random.default_rng(seed)``:

* :func:`planted_lda` draws a corpus from the LDA generative process (each cell a
  document): topics ``Φ ~ Dirichlet(β)``, per-cell mixtures ``θ ~ Dirichlet(α)``,
  then for every word a topic ``z ~ θ_cell`` and a word ``w ~ φ_z``. It returns the
  planted ``Φ``, ``θ`` and ``z`` so a sampler's output can be scored against the truth.
* :func:`planted_map` draws a spatially smooth map: the grid is cut into a few
  contiguous regions (the Voronoi cells of random seed points), each region mixes one
  or two topics, and every cell draws its words from its region's mixture. The region
  of each cell is the ground truth that spatial neighbours should help recover.

Words are grouped by cell exactly as in :class:`curiosity_cli.words.store.WordStore`:
the words of cell ``c`` are ``words[cell_start[c]:cell_start[c + 1]]``; cells are
numbered row-major on a grid.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from curiosity_cli.maps.cell_grid import SquareGrid
from curiosity_cli.maps.generated import voronoi_regions
from curiosity_cli.checks import check_float, check_int
from curiosity_cli.errors import ParameterError


@dataclass(frozen=True)
class PlantedCorpus:
    """A corpus drawn from a known topic model.

    Attributes
    ----------
    words : (N,) int32 ndarray
        Word ids in ``[0, V)``, grouped by cell.
    cell_start : (n_cells + 1,) int64 ndarray
        Words of cell ``c`` are ``words[cell_start[c]:cell_start[c + 1]]``.
    topics : (N,) int32 ndarray
        The planted topic of every word, in ``[0, K)``.
    phi : (K, V) float64 ndarray
        Planted topic-word distributions; each row sums to 1.
    theta : (n_cells, K) float64 ndarray
        Planted topic mixture of every cell; each row sums to 1.
    """

    words: np.ndarray
    cell_start: np.ndarray
    topics: np.ndarray
    phi: np.ndarray
    theta: np.ndarray

    @property
    def n_cells(self) -> int:
        return len(self.cell_start) - 1

    @property
    def vocabulary_size(self) -> int:
        return self.phi.shape[1]

    @property
    def n_topics(self) -> int:
        return self.phi.shape[0]

    @property
    def cell_of_word(self) -> np.ndarray:
        """(N,) int64 ndarray: the cell of every word."""
        return np.repeat(np.arange(self.n_cells), np.diff(self.cell_start))

    def cell_words(self, cell: int) -> np.ndarray:
        """Word ids of one cell."""
        return self.words[self.cell_start[cell] : self.cell_start[cell + 1]]


@dataclass(frozen=True, kw_only=True)
class PlantedMap(PlantedCorpus):
    """A spatially smooth corpus on a ``rows x cols`` grid of cells.

    Attributes
    ----------
    grid : SquareGrid
        The ``rows x cols`` cells (row-major).
    regions : (n_cells,) int32 ndarray
        The region of every cell, in ``[0, n_regions)``; each region is contiguous.
    region_theta : (n_regions, K) float64 ndarray
        The topic mixture of every region (one or two topics carry the weight).

    Other attributes as in :class:`PlantedCorpus`; here ``theta[c] == region_theta[regions[c]]``.
    """

    grid: SquareGrid
    regions: np.ndarray
    region_theta: np.ndarray


def _cell_lengths(rng: np.random.Generator, n_cells: int, words_per_cell: int, vary: bool) -> np.ndarray:
    """(n_cells,) int64: words in each cell, Poisson around the mean (at least one) or fixed."""
    if not vary:
        return np.full(n_cells, words_per_cell, dtype=np.int64)
    return np.maximum(rng.poisson(words_per_cell, size=n_cells), 1).astype(np.int64)


def _draw_words(
    rng: np.random.Generator, theta: np.ndarray, phi: np.ndarray, lengths: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Draw topics and words of every cell given ``θ`` (C, K), ``Φ`` (K, V) and cell lengths (C,).

    Returns ``(words, cell_start, topics)``. Topic counts per cell are one multinomial
    draw per cell, then each topic's words are drawn from its ``φ`` in one call, and the
    words of each cell are put in random order.
    """
    n_cells, n_topics = theta.shape
    cell_start = np.zeros(n_cells + 1, dtype=np.int64)
    np.cumsum(lengths, out=cell_start[1:])
    # multinomial needs probabilities summing to <= 1 in float64; renormalise rounding away
    pvals = theta / theta.sum(axis=1, keepdims=True)
    counts = rng.multinomial(lengths, pvals)  # (C, K)
    # topics laid out cell by cell, sorted by topic inside a cell ...
    topics = np.repeat(np.tile(np.arange(n_topics, dtype=np.int32), n_cells), counts.ravel())
    cells = np.repeat(np.arange(n_cells), lengths)
    # ... then shuffled inside each cell (sort by cell, ties broken at random)
    order = np.lexsort((rng.random(len(topics)), cells))
    topics = topics[order]
    words = np.empty(len(topics), dtype=np.int32)
    vocabulary_size = phi.shape[1]
    for k in range(n_topics):
        at = np.flatnonzero(topics == k)
        if len(at):
            words[at] = rng.choice(vocabulary_size, size=len(at), p=phi[k] / phi[k].sum())
    return words, cell_start, topics


def planted_lda(
    n_cells: int,
    vocabulary_size: int,
    n_topics: int,
    words_per_cell: int,
    *,
    alpha: float,
    beta: float,
    seed: int,
    vary_length: bool = True,
) -> PlantedCorpus:
    """A corpus drawn from LDA with known topics, each cell a document.

    ``Φ_k ~ Dirichlet(β)`` for every topic, ``θ_c ~ Dirichlet(α)`` for every cell, then
    for each word of cell ``c``: ``z ~ Discrete(θ_c)``, ``w ~ Discrete(φ_z)``. Small β
    gives well-separated (sparse) topics; small α gives cells dominated by few topics.

    Parameters
    ----------
    n_cells : int
        Number of cells (documents), >= 1.
    vocabulary_size : int
        V, >= 2.
    n_topics : int
        K, >= 1.
    words_per_cell : int
        Mean words per cell, >= 1. With ``vary_length`` each cell has
        ``max(1, Poisson(words_per_cell))`` words, else exactly ``words_per_cell``.
    alpha, beta : float
        Symmetric Dirichlet parameters of ``θ`` and ``Φ``, > 0.
    seed : int
        Seed of ``np.random.default_rng``; the same seed gives the same corpus.
    vary_length : bool
        Poisson cell lengths (default) or fixed ones.

    Returns
    -------
    PlantedCorpus
        ``words`` (N,), ``cell_start`` (n_cells + 1,), ``topics`` (N,), ``phi`` (K, V),
        ``theta`` (n_cells, K).

    Examples
    --------
    The benchmark corpus: 4096 cells, V = 6000, K = 64, about 1.6 million words.

    >>> corpus = planted_lda(4096, 6000, 64, 400, alpha=0.1, beta=0.1, seed=0)
    """
    n_cells = check_int("n_cells", n_cells, 1)
    vocabulary_size = check_int("vocabulary_size", vocabulary_size, 2)
    n_topics = check_int("n_topics", n_topics, 1)
    words_per_cell = check_int("words_per_cell", words_per_cell, 1)
    alpha = check_float("alpha", alpha, 0, low_open=True)
    beta = check_float("beta", beta, 0, low_open=True)
    rng = np.random.default_rng(seed)
    phi = rng.dirichlet(np.full(vocabulary_size, beta), size=n_topics)
    theta = rng.dirichlet(np.full(n_topics, alpha), size=n_cells)
    lengths = _cell_lengths(rng, n_cells, words_per_cell, vary_length)
    words, cell_start, topics = _draw_words(rng, theta, phi, lengths)
    return PlantedCorpus(words=words, cell_start=cell_start, topics=topics, phi=phi, theta=theta)


def planted_map(
    rows: int,
    cols: int,
    n_regions: int,
    vocabulary_size: int,
    n_topics: int,
    words_per_cell: int,
    *,
    seed: int,
    beta: float = 0.1,
    main_weight: tuple[float, float] = (0.6, 0.9),
    vary_length: bool = True,
) -> PlantedMap:
    """A spatially smooth map: contiguous regions, each with its own topic mixture.

    The grid is cut into the Voronoi regions of ``n_regions`` random seed cells (see
    :func:`~curiosity_cli.maps.generated.voronoi_regions`). Topics are ``Φ_k ~ Dirichlet(β)``. Region ``r`` has a main
    topic (distinct regions get distinct main topics while ``n_regions <= n_topics``)
    with weight drawn uniformly from ``main_weight``, and gives the rest of its weight to
    one other topic; every cell of the region draws its words from that mixture. With few
    words per cell, a cell's own words are a noisy sample of its region's mixture, which
    is what pooling over spatial neighbours helps with.

    Parameters
    ----------
    rows, cols : int
        Grid shape in cells, each >= 1.
    n_regions : int
        Number of regions, in ``[1, rows * cols]``.
    vocabulary_size : int
        V, >= 2.
    n_topics : int
        K, >= 2.
    words_per_cell : int
        Mean words per cell (Poisson, at least one, unless ``vary_length`` is False).
    seed : int
        Seed of ``np.random.default_rng``.
    beta : float
        Symmetric Dirichlet parameter of the topics, > 0; larger means more overlap.
    main_weight : (float, float)
        Range of the main topic's weight in a region's mixture, within ``(0, 1]``.
    vary_length : bool
        Poisson cell lengths (default) or fixed ones.

    Returns
    -------
    PlantedMap
        ``words`` (N,), ``cell_start`` (rows * cols + 1,), ``topics`` (N,), ``phi`` (K, V),
        ``theta`` (rows * cols, K), ``grid``, ``regions`` (rows * cols,),
        ``region_theta`` (n_regions, K).
    """
    rows = check_int("rows", rows, 1)
    cols = check_int("cols", cols, 1)
    n_regions = check_int("n_regions", n_regions, 1, rows * cols)
    vocabulary_size = check_int("vocabulary_size", vocabulary_size, 2)
    n_topics = check_int("n_topics", n_topics, 2)
    words_per_cell = check_int("words_per_cell", words_per_cell, 1)
    beta = check_float("beta", beta, 0, low_open=True)
    low, high = (float(x) for x in main_weight)
    if not 0 < low <= high <= 1:
        raise ParameterError(f"main_weight: got {main_weight!r}, expected 0 < low <= high <= 1")
    rng = np.random.default_rng(seed)
    regions = voronoi_regions(rows, cols, n_regions, rng)
    phi = rng.dirichlet(np.full(vocabulary_size, beta), size=n_topics)
    # main topics: a random permutation, repeated when there are more regions than topics
    main = np.concatenate([rng.permutation(n_topics) for _ in range(-(-n_regions // n_topics))])[:n_regions]
    # second topic: any topic other than the region's main one
    second = (main + rng.integers(1, n_topics, size=n_regions)) % n_topics
    weight = rng.uniform(low, high, size=n_regions)
    region_theta = np.zeros((n_regions, n_topics))
    region_theta[np.arange(n_regions), main] = weight
    region_theta[np.arange(n_regions), second] += 1.0 - weight
    theta = region_theta[regions]
    lengths = _cell_lengths(rng, rows * cols, words_per_cell, vary_length)
    words, cell_start, topics = _draw_words(rng, theta, phi, lengths)
    return PlantedMap(
        words=words,
        cell_start=cell_start,
        topics=topics,
        phi=phi,
        theta=theta,
        grid=SquareGrid(rows, cols),
        regions=regions,
        region_theta=region_theta,
    )
