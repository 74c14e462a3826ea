"""How surprising each image cell of a camera frame is to the drive: the readings of the paper's surprise (5.2).

``drive.surprise`` names the one the drive steers by and logs (:data:`~curiosity_cli.config.DRIVE_SURPRISES`):

- ``paper``: eq. 12 as the drive computed it first (:func:`~curiosity_cli.drive.curiosity.cell_perplexity`), each
  cell's refined topics under the whole memory's topic frequencies, after the frame joined the model;
- ``predictive``: each word of the cell under the model before the frame joins it,
  ``p(w) = Σ_k θ_ck φ_k(w)``, θ_c the topic mix of the same image cell's neighbourhood in the frame before (its
  topics and its neighbours', plus α, normalised; uniform before the first frame), φ the model's; the cell's
  surprise is its words' perplexity, ``exp(-mean log p(w))``;
- ``recent``: eq. 12 against the topic mix of the newest :data:`RECENT_FRAMES` frames instead of the whole memory's;
- ``bayesian``: Bayesian surprise (Itti & Baldi 2009), how far the frame moves the cell's belief about its topic
  mix: the KL divergence, in bits, of the cell's neighbourhood mix after the frame's refinement from the mix
  ``predictive`` predicted before it.

A cell without words has surprise 1 under the perplexities, as eq. 12's cells do, and 0 bits under ``bayesian``
only where its neighbourhood's mix did not move. ``scripts/check_revisits.py`` compares them on four laps of one
loop with a change in the third (docs/GUIDE.md, "Revisiting and change detection").
"""

from __future__ import annotations

from collections.abc import Collection

import numpy as np

from curiosity_cli.config import DRIVE_SURPRISES
from curiosity_cli.drive.curiosity import cell_perplexity
from curiosity_cli.errors import ParameterError

#: Frames whose topic mix ``recent`` reads: 4 s at the paper robot's 5 frames a second.
RECENT_FRAMES = 20
#: The readings that need the mix predicted before the frame joins.
_PREDICTED = {"predictive", "bayesian"}


def predicted_mix(stream) -> np.ndarray:
    """(rows * cols, K) float64: each image cell's topic mix predicted before the next frame joins the stream: its
    neighbourhood's topic counts in the newest frame, plus α, normalised; uniform before any frame."""
    model = stream.model
    cells = stream.frame_cells()
    if cells is None:
        return np.full((stream.cells_per_frame, model.n_topics), 1.0 / model.n_topics)
    prior = model.neighbourhood_counts(cells).astype(np.float64) + model.alpha
    return prior / prior.sum(axis=1, keepdims=True)


def word_perplexity(stream, cell_words: list[np.ndarray], mix: np.ndarray) -> np.ndarray:
    """(rows * cols,) float64: each cell's words' perplexity under ``Σ_k mix[c, k] φ_k(w)``; 1 for a cell without
    words."""
    out = np.ones(len(cell_words))
    sizes = np.array([np.size(words) for words in cell_words])
    if not sizes.any():
        return out
    words = np.concatenate([np.asarray(w, np.int64).ravel() for w in cell_words])
    owner = np.repeat(np.arange(len(cell_words)), sizes)
    log_p = np.log(np.einsum("ik,ik->i", stream.model.phi(words), mix[owner]))
    held = sizes > 0
    out[held] = np.exp(-np.bincount(owner, weights=log_p, minlength=len(cell_words))[held] / sizes[held])
    return out


def bayesian_surprise(stream, prior: np.ndarray) -> np.ndarray:
    """(rows * cols,) float64: per cell of the newest frame, KL(posterior || prior) in bits, the posterior its
    neighbourhood's topic counts now, plus α, normalised."""
    posterior = stream.model.neighbourhood_counts(stream.frame_cells()).astype(np.float64) + stream.model.alpha
    posterior /= posterior.sum(axis=1, keepdims=True)
    return np.sum(posterior * np.log2(posterior / prior), axis=1)


def add_and_score(stream, cell_words: list[np.ndarray], readings: Collection[str], alpha: float) -> dict:
    """Add a frame's words to ``stream`` (:meth:`~curiosity_cli.drive.stream.StreamModel.add_frame`) and score its
    cells by each of ``readings``, each as it reads the model (before the frame joins, or after).

    Parameters
    ----------
    stream : StreamModel
    cell_words : list of (n_c,) int ndarray
        The frame's words per image cell, row-major.
    readings : collection of str
        Some of :data:`~curiosity_cli.config.DRIVE_SURPRISES`.
    alpha : float
        The model's α, which eq. 12 adds to the topic counts.

    Returns
    -------
    dict of str to (rows * cols,) float64 ndarray
        Per reading, each cell's surprise.

    Raises
    ------
    ParameterError
        A reading that is none of them.
    """
    unknown = set(readings) - set(DRIVE_SURPRISES)
    if unknown:
        raise ParameterError(f"readings: got {sorted(unknown)}, expected some of {', '.join(DRIVE_SURPRISES)}")
    mix = predicted_mix(stream) if _PREDICTED & set(readings) else None
    out = {}
    if "predictive" in readings:
        out["predictive"] = word_perplexity(stream, cell_words, mix)
    counts = stream.add_frame(cell_words)
    if "paper" in readings:
        out["paper"] = cell_perplexity(counts, stream.topic_totals(), alpha)
    if "recent" in readings:
        out["recent"] = cell_perplexity(counts, stream.recent_totals(RECENT_FRAMES), alpha)
    if "bayesian" in readings:
        out["bayesian"] = bayesian_surprise(stream, mix)
    return out
