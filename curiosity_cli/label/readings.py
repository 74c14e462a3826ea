"""How a path's frozen Φ_p labels the whole map: the readings of ``label.reading`` (issue 59).

The paper: each run's Φ_p "was used to compute topic labels for each pixel in the map in
batch mode". Every reading runs the same chains with Φ_p frozen
(:class:`~curiosity_cli.topics.chains.FrozenChains`); they differ in which topics a word
may take (the chains' ``allowed``: eq. 5's weights are unchanged where a topic is open),
or, under ``thawed``, in sweeps that update Φ after them:

``frozen`` (the default)
    Every topic open to every word. A word the path never saw weighs each topic by
    ``beta / (n_k + V beta)``, most the emptiest, so a path's spare topics label the
    terrain it did not visit apart from what it did: not visiting rare terrain can score
    as well as visiting it (the positive control of ``rare-patches``).
``unseen-topic``
    A word the path never saw (no count in any topic of Φ_p) takes one extra label, ``K``,
    and no other; every other word any of the ``K`` topics but that one. No seen word can
    take label ``K``, so the unseen words' counts there sway no other word's label: the
    seen words are labelled as if the unseen ones were not on the map.
``used-topics``
    Only the topics that hold at least ``label.used_share`` of the path's words (the
    largest always does), for every word: a spare topic cannot set unvisited terrain apart.
``thawed``
    The ``frozen`` labels, then ``label.thaw_sweeps`` sweeps of Algorithm 1 from them, Φ
    counted from the map's words' labels and updated as they change
    (:func:`~curiosity_cli.label.sampling.thawed_labels`): the paper's batch mode taken
    literally. Its chain tends to Z_b's posterior, whatever the path (the path holds a few
    percent of the map's words), so it is a transient: a contrast between walkers should
    fade as the sweeps grow.

Held-out scoring (:mod:`~curiosity_cli.label.heldout`) is a perplexity of the path's model,
not a labelling, and stays as it is under every reading.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from curiosity_cli.config import LABEL_READINGS, LabelConfig


@dataclass(frozen=True)
class Reading:
    """A labelling reading: its ``name`` (one of ``LABEL_READINGS``), ``used_share`` (``used-topics`` only) and
    ``thaw`` (``thawed`` only: its sweeps)."""

    name: str
    used_share: float
    thaw: int = 0

    @classmethod
    def of(cls, label: LabelConfig) -> Reading:
        return cls(label.reading, label.used_share, label.thaw_sweeps)

    @property
    def title(self) -> str:
        """Its name with the setting it reads: ``frozen``, ``unseen-topic``, ``used-topics-0.01``, ``thawed-4``."""
        if self.name == "used-topics":
            return f"{self.name}-{self.used_share:g}"
        return f"{self.name}-{self.thaw}" if self.name == "thawed" else self.name

    @property
    def thaw_sweeps(self) -> int:
        """Sweeps of Algorithm 1 after the frozen chains: ``thaw`` under ``thawed``, else 0."""
        return self.thaw if self.name == "thawed" else 0

    def labels(self, n_topics: int) -> int:
        """The labels a word can take with a model of ``n_topics`` topics: one more under ``unseen-topic``."""
        return n_topics + 1 if self.name == "unseen-topic" else n_topics

    def chain_inputs(self, phi: np.ndarray) -> tuple[np.ndarray, np.ndarray | None]:
        """What a chain labels with, from a path's (V, K) word-topic counts ``phi``.

        Returns
        -------
        counts : (V, L) int ndarray
            The frozen counts, ``L = labels(K)`` (``unseen-topic``: an empty column ``K`` added).
        allowed : (V, L) bool ndarray or None
            The topics each word may take; None: every one (``frozen``).
        """
        phi = np.asarray(phi)
        if self.name in ("frozen", "thawed"):
            return phi, None
        if self.name == "unseen-topic":
            seen = phi.sum(axis=1) > 0
            allowed = np.empty((phi.shape[0], phi.shape[1] + 1), bool)
            allowed[:, :-1] = seen[:, None]
            allowed[:, -1] = ~seen
            return np.concatenate([phi, np.zeros((phi.shape[0], 1), phi.dtype)], axis=1), allowed
        if self.name == "used-topics":
            per_topic = phi.sum(axis=0, dtype=np.int64)
            used = per_topic >= self.used_share * per_topic.sum()
            used[np.argmax(per_topic)] = True
            return phi, np.broadcast_to(used, phi.shape)
        raise ValueError(f"reading: got {self.name!r}, expected one of {', '.join(LABEL_READINGS)}")
