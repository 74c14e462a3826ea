"""Surprise of a candidate cell's words under a topic model (paper eqs. 11 and 12).

The words are *not* in the model: they are what the robot sees in a neighbouring cell
it may step to (topic perplexity may count them while it scores them, as the authors'
code does: its ``words_in_model``). Both scores use the model's topic totals as the
topic distribution of the path so far::

    P(k | path) = (n_k + α) / (N + Kα)         n_k = model.topic_totals(), N = Σ_k n_k

and are 1.0 ("no surprise") for an empty word list. Neither changes the model.
"""

from __future__ import annotations

import numpy as np

from curiosity_cli.checks import check_choice, check_int
from curiosity_cli.config import EXPLORE_READINGS
from curiosity_cli.topics.model import TopicModel
from curiosity_cli.topics.model_checks import check_word_ids


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

    words = check_word_ids(words, model.vocabulary_size)
    if not words.size:
        return 1.0
    nwk, nk, _, _ = _arrays(model)
    vbeta = model.vocabulary_size * model.beta
    return float(word_perplexity_kernel(words, nwk, nk, model.n_topics, model.alpha, model.beta, vbeta))


def topic_perplexity(
    model: TopicModel, words, cell: int, *, context: str = "neighbourhood", sweeps: int = 1, labels: str = "sample",
    words_in_model: str = "held-out", path_topics: str = "smoothed", return_topics: bool = False,
):
    """Topic perplexity of ``words`` seen at ``cell`` (eq. 12).

    Each word first gets a temporary topic ``z_i`` from eq. 5: with ``labels`` ``sample``
    drawn from it, with ``argmax`` its most likely topic (the largest float32 weight, the
    lowest topic of a tie), as the authors' ROST ``estimate()`` labels a cell. Eq. 5 takes
    Φ from the model, and as neighbourhood counts, by ``context``:

    - ``neighbourhood``: the model's ``n_Gk`` of ``cell`` (the topic counts of the
      observed cells among ``cell`` and its neighbours) plus the temporary topics already
      chosen for the earlier words of ``words``, as if the candidate cell were being added
      one word at a time. If ``cell`` is already in the model, its own counts are part of
      the neighbourhood, as for any word of that cell.
    - ``own``: the temporary topics of the other words of ``words`` only: the labels
      follow the words alone.

    With ``words_in_model`` ``held-out`` (the paper's "without adding"), Φ and the path's
    topic totals are the model's. With ``added``, the words count in the model while they
    are scored, as the authors' code scores words it has already added: each temporary
    topic counts in Φ (``n_kw``, ``n_k``) as well as in the neighbourhood, and ``n_k``
    below includes the candidate's words at their temporary topics. (A frozen model's Φ
    and totals stay as they are, as when it adds words.)

    The first pass chooses the words' topics in order; each of ``sweeps - 1`` further
    passes chooses every word's topic again, in order, given the others'. Then::

        TopicPerplexity = exp(-(1/W) Σ_i log P(z_i | path))

    with ``P(k | path)`` as in the module docstring when ``path_topics`` is
    ``smoothed``; with ``counts`` it is ``n_k / N``, as the authors' curiosity node
    computes it, and a temporary topic the path has never seen (``n_k = 0``) makes the
    perplexity infinite: the candidate is infinitely surprising (``inf`` too when the
    model holds no words). With ``added`` (and a model that is not frozen) every
    temporary topic counts at least once, so the perplexity is never infinite.

    Sampled labels come from the model's seed and its current random state with a stream
    of their own (``(counter, n_cells + 1 + cell)``, ``n_cells`` as the model was made,
    before any :meth:`~curiosity_cli.topics.TopicModel.grow`), without advancing the
    state: the result is a deterministic function of the model's state, ``words`` and
    ``cell``, and calling it changes neither the model nor what later refinement draws.

    Parameters
    ----------
    model : TopicModel
    words : (W,) int array_like
        Word ids in ``0 .. V - 1``.
    cell : int
        Where the words are seen, ``0 .. n_cells - 1``.
    context : {'neighbourhood', 'own'}
        The counts the temporary topics are chosen against (above).
    sweeps : int
        Passes over the temporary topics, >= 1.
    labels : {'sample', 'argmax'}
        Each temporary topic drawn from eq. 5, or eq. 5's most likely topic.
    words_in_model : {'held-out', 'added'}
        Whether the words count in Φ and the path's topics while they are scored.
    path_topics : {'smoothed', 'counts'}
        ``P(k | path)``: ``(n_k + α) / (N + Kα)`` or ``n_k / N``.
    return_topics : bool
        Also return the temporary topics.

    Returns
    -------
    float, or (float, (W,) int32 ndarray)
        1.0 (and no topics) when ``W == 0``; ``inf`` under ``counts`` when a temporary
        topic is one the path has not seen.

    Raises
    ------
    ParameterError
        Naming a bad ``words``, ``cell``, ``context``, ``sweeps``, ``labels``,
        ``words_in_model`` or ``path_topics``.
    """
    from curiosity_cli.topics._perplexity_kernels import topic_perplexity_kernel

    words = check_word_ids(words, model.vocabulary_size)
    cell = check_int("cell", cell, 0, model.n_cells - 1)
    own = check_choice("context", context, EXPLORE_READINGS["candidate_context"]) == "own"
    sweeps = check_int("sweeps", sweeps, 1)
    argmax = check_choice("labels", labels, EXPLORE_READINGS["candidate_labels"]) == "argmax"
    added = check_choice("words_in_model", words_in_model, EXPLORE_READINGS["candidate_words"]) == "added"
    smoothed = check_choice("path_topics", path_topics, EXPLORE_READINGS["path_topics"]) == "smoothed"
    if not words.size:
        return (1.0, np.zeros(0, np.int32)) if return_topics else 1.0
    nwk, nk, inv, ng = _arrays(model)
    value, topics = topic_perplexity_kernel(
        words, cell, nwk, nk, inv, ng, model.n_topics, model.alpha, np.float32(model.alpha),
        np.float32(model.beta), model.vocabulary_size * model.beta, model._key(), np.uint64(model._counter), own,
        sweeps, argmax, added, not model.frozen, smoothed, model._free_stream,
    )
    return (float(value), topics) if return_topics else float(value)


def _arrays(model: TopicModel):
    """The model's own (padded) count arrays, read-only use."""
    return model._nwk, model._nk, model._inv, model._ng
