"""Figures the paper reports about its own maps, for comparison beside ours.

Girdhar & Dudek, Table 1 (words per map) and section 5.1.2 (mean MI of topic-perplexity
exploration against human labels at 80 steps over the next best weight function's). A
dataset YAML says which of these maps it stands in for (``stands_in_for``).
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class PaperMap:
    """One of the paper's maps.

    Attributes
    ----------
    name : str
    size : (int, int)
        Rows and columns in pixels.
    words : int
        Visual words of the map (Table 1).
    texton_stride : int
        Texton words at every ``texton_stride``-th pixel (section 5.1).
    headline_ratio : float
        Topic perplexity's mean MI against human labels at 80 steps over the next best's.
    """

    name: str
    size: tuple[int, int]
    words: int
    texton_stride: int
    headline_ratio: float

    @property
    def orb_share(self) -> float:
        """The ORB words' share of all words, implied by Table 1 with a texton at every
        ``texton_stride``-th pixel (rows and columns) and ORB words making up the rest."""
        rows, cols = self.size
        textons = -(-rows // self.texton_stride) * -(-cols // self.texton_stride)
        return (self.words - textons) / self.words


PAPER_MAPS = {
    m.name: m
    for m in (
        PaperMap("Montreal1", (1024, 1024), 3_239_631, 1, 1.51),
        PaperMap("Montreal2", (1024, 1024), 1_675_171, 1, 1.20),
        PaperMap("SouthBellairs", (2500, 2500), 1_664_749, 2, 1.05),
    )
}
