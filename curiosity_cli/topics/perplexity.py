"""Surprise of a candidate cell's words under a topic model (paper eqs. 11 and 12).

The words are *not* in the model: they are what the robot sees in a neighbouring cell
it may step to. Both scores use the model's topic totals as the topic distribution of
the path so far::

    P(k | path) = (n_k + α) / (N + Kα)         n_k = model.topic_totals(), N = Σ_k n_k

and are 1.0 ("no surprise") for an empty word list. Neither changes the model.
"""

from __future__ import annotations

import numpy as np

from curiosity_cli.checks import check_int
from curiosity_cli.topics.model import TopicModel


def word_perplexity(model: TopicModel, words) -> float:
    """Word perplexity of ``words`` (eq. 11).

    ``exp(-(1/W) Σ_i log Σ_k P(w_i | k) P(k | path))`` with
    ``P(w | k) = (n_kw + β) / (n_k + Vβ)`` (:meth:`TopicModel.phi`) and ``P(k | path)``
    as in the module docstring; ``W`` is the number of words.

    Parameters
    ----------
    model : TopicModel
    words : (W,) int array_like
        Word ids in ``0 .. V - 1``.

    Returns
    -------
    float
        >= 1 (every word's probability is at most 1); 1.0 when ``W == 0``.
    """
    from curiosity_cli.topics._perplexity_kernels import word_perplexity_kernel

    words = model._check_words(words)
    if not words.size:
        return 1.0
    nwk, nk, _, _ = _arrays(model)
    vbeta = model.vocabulary_size * model.beta
    return float(word_perplexity_kernel(words, nwk, nk, model.n_topics, model.alpha, model.beta, vbeta))


def topic_perplexity(model: TopicModel, words, cell: int, *, return_topics: bool = False):
    """Topic perplexity of ``words`` seen at ``cell`` (eq. 12).

    Each word first gets a temporary topic ``z_i`` drawn from eq. 5 without being added
    to the model: Φ from the model, and as neighbourhood counts the model's ``n_Gk`` of
    ``cell`` (the topic counts of the observed cells among ``cell`` and its neighbours)
    plus the temporary topics already drawn for the earlier words of ``words`` (as if
    the candidate cell were being added one word at a time; Φ is left as is). Then::

        TopicPerplexity = exp(-(1/W) Σ_i log P(z_i | path))

    If ``cell`` is already in the model, its own counts are part of the neighbourhood,
    as for any word of that cell.

    The draws come from the model's seed and its current random state with a stream of
    their own (``(counter, n_cells + 1 + cell)``), without advancing the state: the
    result is a deterministic function of the model's state, ``words`` and ``cell``,
    and calling it does not change what later refinement draws.

    Parameters
    ----------
    model : TopicModel
    words : (W,) int array_like
        Word ids in ``0 .. V - 1``.
    cell : int
        Where the words are seen, ``0 .. n_cells - 1``.
    return_topics : bool
        Also return the temporary topics.

    Returns
    -------
    float, or (float, (W,) int32 ndarray)
        1.0 (and no topics) when ``W == 0``.
    """
    from curiosity_cli.topics._perplexity_kernels import topic_perplexity_kernel

    words = model._check_words(words)
    cell = check_int("cell", cell, 0, model.n_cells - 1)
    if not words.size:
        return (1.0, np.zeros(0, np.int32)) if return_topics else 1.0
    nwk, nk, inv, ng = _arrays(model)
    value, topics = topic_perplexity_kernel(
        words, cell, nwk, nk, inv, ng, model.n_topics, model.alpha, np.float32(model.alpha),
        np.float32(model.beta), model._key(), np.uint64(model._counter),
    )
    return (float(value), topics) if return_topics else float(value)


def _arrays(model: TopicModel):
    """The model's own (padded) count arrays, read-only use."""
    return model._nwk, model._nk, model._inv, model._ng
