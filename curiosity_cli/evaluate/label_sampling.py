"""Drawing a whole map's topic labels: with a path's model (Z_p) or in batch mode (Z_b).

This module computes labels and writes nothing; which runs need them, and the files and
tasks of the ``label`` stage, are in :mod:`~curiosity_cli.evaluate.label_stage`.

Paper section 5.1: "Each of these exploration runs returned a topic model Φ_p, which we
then used to compute topic labels for each pixel in the map in batch mode."

- **Z_p** (:func:`label_with_phi`): every word of the map gets a topic from Gibbs
  sweeps with the word-topic counts frozen to Φ_p (cells and neighbourhoods as in the
  model, initial topics uniformly random), then its maximum-likelihood topic. Whether
  the sweeps were enough is checked by a second chain from a placed start
  (:meth:`PathLabeller.start`): ``label`` runs one for the restarts below
  ``label.check_restarts``, and ``scripts/study_label_sweeps.py`` runs both for every
  schedule it compares.
- **Z_b** (:func:`batch_labels`): a model learned on all words of the map with random
  access (Algorithm 1), then each word's maximum-likelihood topic.
- **Pixels** (:func:`pixel_labels`): the per-pixel texton words carry the labels; with a
  word stride ``s`` each pixel takes the label of its nearest texton word (ties go to
  the upper and left one). ORB words take part in the cells' neighbourhoods only.
"""

from __future__ import annotations

import numpy as np

from curiosity_cli.config import ModelConfig
from curiosity_cli.errors import ParameterError
from curiosity_cli.words.store import WordStore


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


class PathLabeller:
    """Z_p of a map for path models, on one whole-map model built once.

    The model holds every word of the map with Φ frozen; labelling a path's checkpoints
    swaps the frozen counts in turn instead of building a model per checkpoint.

    Parameters
    ----------
    store : WordStore
    model : ModelConfig
        K, α, β and the neighbourhood.
    """

    def __init__(self, store: WordStore, model: ModelConfig):
        self._store = store
        self._config = model
        zeros = np.zeros((store.vocabulary_size, model.topics), np.int32)
        self._model = whole_map_model(store, model, 0, frozen_counts=zeros)

    def start(self, phi: np.ndarray, seed: int, *, placed: bool = False) -> None:
        """Freeze Φ to ``phi`` (V, K) and give every word a uniformly random topic (stream ``seed``).

        With ``placed``, draw each word from eq. 5 given the words drawn before it
        instead (:meth:`~curiosity_cli.topics.model.TopicModel.place`): a start on the
        far side of the chain's fixed point from the uniform one (its labels begin
        smooth, the uniform ones begin as noise), which a convergence study checks the
        uniform start against.
        """
        self.switch(phi)
        if placed:
            self._model.place(seed % 2**64)
        else:
            self._model.restart(seed % 2**64)

    def switch(self, phi: np.ndarray) -> None:
        """Freeze Φ to ``phi`` (V, K), keeping every word's topic (a warm start)."""
        if phi.shape != (self._store.vocabulary_size, self._config.topics):
            raise ParameterError(f"phi: shape {phi.shape}, expected (V, K) = {(self._store.vocabulary_size, self._config.topics)}")
        self._model.set_frozen_counts(phi)

    def sweep(self, sweeps: int, threads: int = 1) -> None:
        """``sweeps`` frozen-Φ Gibbs sweeps over the whole map (the result does not depend on ``threads``)."""
        self._model.refine_batch(sweeps, threads=threads)

    def labels(self) -> np.ndarray:
        """(N,) int16: each word's maximum-likelihood topic now, in the store's order."""
        return self._model.ml_topics().astype(np.int16)

    def label_path(
        self, phis: list[np.ndarray], *, seed: int, sweeps: int, warm_sweeps: int | None, threads: int = 1,
        placed: bool = False,
    ) -> list[np.ndarray]:
        """Z_p of every word for each of a path's checkpoints, in order.

        The first checkpoint starts from uniformly random topics (stream ``seed``) and
        gets ``sweeps`` frozen-Φ Gibbs sweeps; each later one starts from the topics the
        one before left and gets ``warm_sweeps`` (a warm start), or, with
        ``warm_sweeps`` None, starts from random topics again (stream ``seed + j`` for
        the ``j``-th) with ``sweeps``. Each label is the word's maximum-likelihood topic
        after its sweeps. Every step is the exact sampler of eq. 5; only the starting
        topics differ. With ``placed``, every start is a placed one instead
        (:meth:`start`): the second chain of a convergence check.

        Parameters
        ----------
        phis : list of (V, K) int ndarrays
            The word-topic counts of the path's checkpoints, shortest path first.
        seed : int
            0 .. 2**64 - 1.
        sweeps, warm_sweeps : int
            As above; ``warm_sweeps`` None for a cold start at every checkpoint.
        threads : int
            For the sweeps (the result does not depend on it).
        placed : bool
            Start from placed topics instead of uniformly random ones.

        Returns
        -------
        list of (N,) int16 ndarrays
            The topic of each word of the store, in the store's order, per checkpoint.
        """
        out = []
        for j, phi in enumerate(phis):
            if j > 0 and warm_sweeps is not None:
                self.switch(phi)
                self.sweep(warm_sweeps, threads)
            else:
                self.start(phi, seed + j, placed=placed)
                self.sweep(sweeps, threads)
            out.append(self.labels())
        return out


def label_with_phi(store: WordStore, phi: np.ndarray, model: ModelConfig, *, sweeps: int, seed: int, threads: int = 1) -> np.ndarray:
    """Z_p of every word of the map, given one path model's word-topic counts.

    Parameters
    ----------
    store : WordStore
    phi : (V, K) int ndarray
        Word-topic counts of a path's model (a checkpoint).
    model : ModelConfig
        K, α, β and the neighbourhood.
    sweeps : int
        Frozen-Φ Gibbs sweeps from uniformly random topics before the maximum-likelihood topics.
    seed : int
        Of the initial topics and the sweeps.
    threads : int
        For the sweeps (the result does not depend on it).

    Returns
    -------
    (N,) int16 ndarray
        The topic of each word of ``store``, in the store's order.
    """
    return PathLabeller(store, model).label_path([phi], seed=seed, sweeps=sweeps, warm_sweeps=None, threads=threads)[0]


def batch_labels(store: WordStore, model: ModelConfig, *, sweeps: int, seed: int, threads: int = 1, on_sweep=None):
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
    on_sweep : callable, optional
        Called with the sweep number after each sweep.

    Returns
    -------
    labels : (N,) int16 ndarray
        The topic of each word, in the store's order.
    log_likelihood : (sweeps,) float64 ndarray
        The model's mean per-word log-likelihood after each sweep (nats): the trace that
        shows whether the sweeps were enough.
    """
    topic_model = whole_map_model(store, model, seed)
    trace = np.empty(sweeps)
    for sweep in range(sweeps):
        topic_model.refine_batch(1, threads=threads)
        trace[sweep] = topic_model.log_likelihood()
        if on_sweep is not None:
            on_sweep(sweep + 1)
    return topic_model.ml_topics().astype(np.int16), trace


def pixel_labels(store: WordStore, word_labels: np.ndarray, image_shape: tuple[int, int]) -> np.ndarray:
    """Spread the labels of the texton words over the pixels of the map.

    Parameters
    ----------
    store : WordStore
        Its texton words sit on a regular grid every ``stride`` pixels from (0, 0).
    word_labels : (N,) int ndarray
        A label per word of ``store``.
    image_shape : (int, int)
        Rows and columns of the map.

    Returns
    -------
    (H, W) int16 ndarray
    """
    texton = next((t for t in store.types if t.kind == "texton"), None)
    if texton is None:
        raise ParameterError("store: has no texton words to label pixels with")
    stride = int(store.params.get("stride", 1))
    rows, cols = image_shape
    is_texton = (store.words >= texton.offset) & (store.words < texton.offset + texton.size)
    grid = np.full((-(-rows // stride), -(-cols // stride)), -1, np.int16)
    grid[store.rows[is_texton] // stride, store.cols[is_texton] // stride] = word_labels[is_texton]
    if (grid < 0).any():
        raise ParameterError(f"store: texton words do not cover every {stride} x {stride} block of the map")
    # on a regular grid the nearest word is the nearest along each axis (ties go up and left)
    nearest_row = np.minimum((np.arange(rows) + (stride - 1) // 2) // stride, grid.shape[0] - 1)
    nearest_col = np.minimum((np.arange(cols) + (stride - 1) // 2) // stride, grid.shape[1] - 1)
    return grid[np.ix_(nearest_row, nearest_col)]
