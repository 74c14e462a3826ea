"""Drawing a whole map's topic labels: with a path's model (Z_p) or in batch mode (Z_b).

This module computes labels and writes nothing; which runs need them, and the files and
tasks of the ``label`` stage, are in :mod:`~curiosity_cli.label.stage`.

Paper section 5.1: "Each of these exploration runs returned a topic model Φ_p, which we
then used to compute topic labels for each pixel in the map in batch mode."

- **Z_p** (:func:`label_paths`): every word of the map gets a topic from Gibbs
  sweeps with the word-topic counts frozen to Φ_p (cells and neighbourhoods as in the
  model, initial topics uniformly random), then its maximum-likelihood topic; the
  chains of many paths of a map advance in lock-step. ``label.reading`` says which
  topics each word may take (:mod:`~curiosity_cli.label.readings`). Whether the sweeps were enough is
  checked by a second chain from a placed start: ``label`` runs one for the restarts
  below ``label.check_restarts``, and ``scripts/study_label_sweeps.py`` runs both for
  every schedule it compares.
- **Z_b** (:func:`batch_labels`): a model learned on all words of the map with random
  access (Algorithm 1), then each word's maximum-likelihood topic.
- **Pixels** (:func:`pixel_labels`, :func:`pixel_words`): the per-pixel texton words carry the labels; with a
  word stride ``s`` each pixel takes the label of its nearest texton word (ties go to
  the upper and left one). ORB words take part in the cells' neighbourhoods only.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence

import numpy as np

from curiosity_cli.config import ModelConfig
from curiosity_cli.errors import ParameterError
from curiosity_cli.label.readings import Reading
from curiosity_cli.seeds import PATH_TAG, THAW_TAG
from curiosity_cli.words.store import PIXEL_KINDS, WordStore


def whole_map_model(store: WordStore, model: ModelConfig, seed: int, frozen_counts=None):
    """A map's topic model holding every word of the map, each with a uniformly random topic.

    What Z_b and Z_p are sampled on: the map's model
    (:func:`~curiosity_cli.topics.map_model.map_topic_model`) with every cell added in
    cell order, so each cell's words in the store's order.

    Parameters
    ----------
    store : WordStore
        The map's words.
    model : ModelConfig
        K, α, β and the neighbourhood.
    seed : int
        0 .. 2**64 - 1: the model's seed, which draws the initial topics.
    frozen_counts : (V, K) int ndarray, optional
        Fix Φ to these word-topic counts (a path model's, for Z_p); default: Φ is
        learned from the map's words (Z_b).

    Returns
    -------
    TopicModel
        Every one of the store's ``n_cells`` cells observed.
    """
    from curiosity_cli.topics.map_model import map_topic_model

    topic_model = map_topic_model(store, model, seed, frozen_counts=frozen_counts)
    for cell in range(store.n_cells):
        topic_model.add_cell(cell, store.cell_words(cell))
    return topic_model


def map_chains(
    store: WordStore, model: ModelConfig, device: str = "cpu", kept: np.ndarray | None = None,
    n_topics: int | None = None,
):
    """Frozen-Φ Gibbs chains over every word of a map (:class:`~curiosity_cli.topics.chains.FrozenChains`), none started.

    What Z_p is sampled on: the map's cells and neighbour table, each cell's words in
    the store's order, as :func:`whole_map_model` holds them; on ``device`` (``"cpu"`` or
    ``"cuda"``, the same bytes). ``kept``, (N,) bool, keeps only those words (the
    observed half of a held-out split, :mod:`~curiosity_cli.label.heldout`): every cell
    and neighbour stays, a cell with none of its words kept is empty. ``n_topics``: the
    chains' topics, if not the model's (a reading's labels: :mod:`~curiosity_cli.label.readings`).
    """
    from curiosity_cli.topics.chains import FrozenChains

    words, cells = store.words, store.word_cells()
    if kept is not None:
        words, cells = words[kept], cells[kept]
    return FrozenChains(
        words, cells, store.grid.neighbour_table(model.spatial_neighbours),
        n_topics=model.topics if n_topics is None else n_topics,
        vocabulary_size=store.vocabulary_size, alpha=model.alpha, beta=model.beta, device=device,
    )


def label_paths(
    store: WordStore, model: ModelConfig, paths: Sequence[Sequence[np.ndarray]], seeds: Sequence[int], *,
    sweeps: int, warm_sweeps: int | None, placed: Sequence[bool] | None = None, reading: Reading | None = None,
    device: str = "cpu", on_sweep=None,
) -> Iterator[tuple[int, list[int], np.ndarray]]:
    """Z_p of every word for each checkpoint of several paths, their chains in lock-step.

    Each path gets its own frozen-Φ Gibbs chain over the whole map
    (:class:`~curiosity_cli.topics.chains.FrozenChains`, all of them advanced together).
    At a path's first checkpoint its chain starts from uniformly random topics (stream
    ``seeds[c]``) and gets ``sweeps`` sweeps; each later checkpoint starts from the
    topics the one before left and gets ``warm_sweeps`` (a warm start), or, with
    ``warm_sweeps`` None, starts again (stream ``seeds[c] + j`` for the ``j``-th) with
    ``sweeps``. Each label is the word's maximum-likelihood topic after its sweeps. A
    path's labels depend only on its own checkpoints, seed and start, never on the
    other paths labelled with it.

    Parameters
    ----------
    store : WordStore
    model : ModelConfig
        K, α, β and the neighbourhood.
    paths : sequence of sequences of (V, K) int ndarrays
        Each path's word-topic counts at its checkpoints, shortest path first; paths may
        have different numbers of checkpoints.
    seeds : sequence of int
        One per path; any integer (taken modulo 2**64).
    sweeps, warm_sweeps : int
        As above; ``warm_sweeps`` None for a cold start at every checkpoint.
    placed : sequence of bool, optional
        Per path, start from placed topics instead of uniformly random ones
        (:meth:`~curiosity_cli.topics.chains.FrozenChains.start`): the second chain of a
        convergence check.
    reading : Reading, optional
        Which topics each word may take (:mod:`~curiosity_cli.label.readings`); None:
        ``frozen``, every one.
    device : str
        Where the chains run, a name in :data:`curiosity_cli.topics.devices.DEVICES`; the
        labels are the same bytes on each.
    on_sweep : callable, optional
        ``on_sweep(chains)`` after each sweep of the chains (progress; the labels do not
        depend on it).

    Yields
    ------
    j : int
        The checkpoint.
    chains : list of int
        The paths that have a ``j``-th checkpoint, in order.
    labels : (N, len(chains)) int16 ndarray
        Their labels, each word of the store in the store's order: ``0 .. reading.labels(K) - 1``.
    """
    chains = map_chains(store, model, device, n_topics=None if reading is None else reading.labels(model.topics))
    thaw = 0 if reading is None else reading.thaw_sweeps
    if reading is not None:
        inputs = [[reading.chain_inputs(phi) for phi in path] for path in paths]
        paths = [[counts for counts, _ in path] for path in inputs]
        allowed = [[mask for _, mask in path] for path in inputs]
    else:
        allowed = None
    for j, active in advance_chains(
        chains, paths, seeds, sweeps=sweeps, warm_sweeps=warm_sweeps, placed=placed, allowed=allowed, on_sweep=on_sweep,
    ):
        labels = chains.ml_topics()
        if thaw:
            labels = thawed_labels(store, model, labels, [thaw_seed(seeds[c], j) for c in active], thaw)
        yield j, active, labels


def advance_chains(
    chains, paths: Sequence[Sequence[np.ndarray]], seeds: Sequence[int], *, sweeps: int, warm_sweeps: int | None,
    placed: Sequence[bool] | None = None, allowed: Sequence[Sequence[np.ndarray | None]] | None = None, on_sweep=None,
) -> Iterator[tuple[int, list[int]]]:
    """Take :class:`~curiosity_cli.topics.chains.FrozenChains` through each path's checkpoints, as :func:`label_paths`
    describes (its parameters; ``allowed``, per path and checkpoint, the topics each word may take, or None for all),
    yielding ``(j, chains)`` once the paths with a ``j``-th checkpoint have swept at it: the caller reads the chains'
    state then (their labels, their counts)."""
    placed = [False] * len(paths) if placed is None else list(placed)
    active = list(range(len(paths)))
    for j in range(max(len(path) for path in paths)):
        still = [c for c in active if len(paths[c]) > j]
        if j > 0 and still != active:
            chains.keep([active.index(c) for c in still])
        active = still
        phis = [paths[c][j] for c in active]
        masks = None if allowed is None else [allowed[c][j] for c in active]
        if j > 0 and warm_sweeps is not None:
            chains.switch(phis, masks)
            chains.sweep(warm_sweeps, on_sweep)
        else:
            chains.start(phis, [(seeds[c] + j) % 2**64 for c in active], [placed[c] for c in active], masks)
            chains.sweep(sweeps, on_sweep)
        yield j, active


def thawed_labels(store: WordStore, model: ModelConfig, labels: np.ndarray, seeds: Sequence[int], sweeps: int) -> np.ndarray:
    """The ``thawed`` reading (:mod:`~curiosity_cli.label.readings`): Algorithm 1 from each column's labels.

    Each column of ``labels`` (N, R), the map's words in the store's order, starts a model
    of the whole map (:func:`whole_map_model`, seed ``seeds[r]``) whose Φ is counted from
    those labels, and so is updated with the map's words from then on; after ``sweeps``
    batch sweeps each word's maximum-likelihood topic. Returns (N, R) int16.
    """
    out = np.empty(labels.shape, np.int16)
    for r in range(labels.shape[1]):
        topic_model = whole_map_model(store, model, seeds[r])
        topic_model.set_topics(labels[:, r])
        topic_model.refine_batch(sweeps)
        out[:, r] = topic_model.ml_topics()
    return out


def thaw_seed(chain_seed: int, checkpoint: int) -> int:
    """The seed of the ``thawed`` reading's sweeps after a chain of seed ``chain_seed`` at its ``checkpoint``-th."""
    return path_seed((chain_seed % 2**64, checkpoint), THAW_TAG)


def batch_labels(store: WordStore, model: ModelConfig, *, sweeps: int, seed: int, threads: int = 1):
    """Z_b of every word of the map: a model learned on all of it (Algorithm 1).

    Parameters
    ----------
    store : WordStore
    model : ModelConfig
    sweeps : int
        Batch Gibbs sweeps.
    seed : int
    threads : int
        For the sweeps (the result does not depend on it).

    Returns
    -------
    labels : (N,) int16 ndarray
        The topic of each word, in the store's order.
    log_likelihood : (sweeps,) float64 ndarray
        The model's mean per-word log-likelihood after each sweep (nats): the trace that
        shows whether the sweeps were enough.
    """
    topic_model = whole_map_model(store, model, seed)
    trace = topic_model.refine_batch(sweeps, threads=threads, trace=True)
    return topic_model.ml_topics().astype(np.int16), trace


def pixel_labels(store: WordStore, word_labels: np.ndarray, image_shape: tuple[int, int]) -> np.ndarray:
    """Spread the labels of the texton words over the pixels of the map (:func:`pixel_words`).

    Parameters
    ----------
    store : WordStore
    word_labels : (N,) int ndarray
        A label per word of ``store``.
    image_shape : (int, int)
        Rows and columns of the map.

    Returns
    -------
    (H, W) int16 ndarray
    """
    return np.asarray(word_labels)[pixel_words(store, image_shape)].astype(np.int16, copy=False)


def pixel_words(store: WordStore, image_shape: tuple[int, int]) -> np.ndarray:
    """The word whose label each pixel of the map takes.

    Its texton words (a generated map's words) sit on a regular grid every ``stride``
    pixels from (0, 0); each pixel takes its nearest texton word (ties go to the upper
    and left one; of two texton words at one place, the later in the store).

    Parameters
    ----------
    store : WordStore
    image_shape : (int, int)
        Rows and columns of the map.

    Returns
    -------
    (H, W) int64 ndarray
        Indices into the store's words.

    Raises
    ------
    ParameterError
        The store has no texton words, or they leave a ``stride`` x ``stride`` block of the map without one.
    """
    texton = next((t for t in store.types if t.kind in PIXEL_KINDS), None)
    if texton is None:
        raise ParameterError("store: has no texton (or generated) words to label pixels with")
    stride = int(store.params.get("stride", 1))
    rows, cols = image_shape
    is_texton = (store.words >= texton.offset) & (store.words < texton.offset + texton.size)
    grid = np.full((-(-rows // stride), -(-cols // stride)), -1, np.int64)
    grid[store.rows[is_texton] // stride, store.cols[is_texton] // stride] = np.flatnonzero(is_texton)
    if (grid < 0).any():
        raise ParameterError(f"store: texton words do not cover every {stride} x {stride} block of the map")
    # on a regular grid the nearest word is the nearest along each axis (ties go up and left)
    nearest_row = np.minimum((np.arange(rows) + (stride - 1) // 2) // stride, grid.shape[0] - 1)
    nearest_col = np.minimum((np.arange(cols) + (stride - 1) // 2) // stride, grid.shape[1] - 1)
    return grid[np.ix_(nearest_row, nearest_col)]


def path_seed(run_seed, tag: int = PATH_TAG) -> int:
    """The seed of one of a run's chains, from the run's own seed entropy and ``tag``, a tag of
    :mod:`curiosity_cli.seeds` (default its labelling chain's)."""
    return int(np.random.SeedSequence((*run_seed, tag)).generate_state(1, np.uint64)[0])
