"""A generated map's ``generate:`` section: the keys of section 3's generative model, and its digest.

A dataset YAML with ``generate:`` declares a word-level map (:mod:`curiosity_cli.maps.generated` draws it):
background topics over contiguous regions, rare topics in small square patches, each topic a
``Dirichlet(beta)`` over ``support`` words of a vocabulary of ``vocabulary`` words, and the
rare topics sharing ``overlap`` of their support with the background's. The map's grid is its
``rows x cols`` cells of the dataset's ``cell_width`` px, with a word every ``word_stride`` px.
The rules between keys, which need the layout drawn, are
:func:`~curiosity_cli.maps.generated.generation_problem`'s.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
from dataclasses import dataclass

from curiosity_cli.schema import spec

#: Bumped whenever the drawing in :mod:`curiosity_cli.maps.generated` changes, so stores drawn before are drawn again.
GENERATOR_VERSION = 1


@dataclass(frozen=True)
class GenerativeSpec:
    """The generative model of a generated map (module docstring); every key is required.

    Attributes
    ----------
    seed : int
        Seeds the layout, the topics and the words, each from a stream of its own, so two
        maps that differ only in ``overlap`` share their layout.
    rows, cols : int
        Cells of the grid.
    vocabulary : int
        V, the words a topic may draw from, ids ``0 .. V - 1``.
    support : int
        Words each topic draws from (its support), background and rare alike.
    beta : float
        Concentration of the symmetric Dirichlet each topic's weights over its support are drawn from.
    background_topics : int
        B topics over the Voronoi regions of B random seed cells (one region each).
    rare_topics : int
        R topics, each only in its own patches.
    patches_per_topic : int
        Patches of each rare topic.
    patch_cells : int
        A patch's side in cells.
    patch_gap : int
        Cells kept free between two patches' nearest edges.
    overlap : float
        Share of a rare topic's support drawn from the background topics' supports: 0 gives
        disjoint supports, 1 a rare topic of background words in other proportions.
    """

    seed: int = spec(min=0)
    rows: int = spec(min=2, max=4096)
    cols: int = spec(min=2, max=4096)
    vocabulary: int = spec(min=2)
    support: int = spec(min=1)
    beta: float = spec(min=0, min_exclusive=True)
    background_topics: int = spec(min=1, max=16)
    rare_topics: int = spec(min=1, max=64)
    patches_per_topic: int = spec(min=1)
    patch_cells: int = spec(min=1)
    patch_gap: int = spec(min=0)
    overlap: float = spec(min=0, max=1)

    @property
    def shared_words(self) -> int:
        """Words of a rare topic's support drawn from the background's supports."""
        return round(self.overlap * self.support)

    @property
    def own_words(self) -> int:
        """Words of a rare topic's support that no other topic has."""
        return self.support - self.shared_words

    @property
    def words_needed(self) -> int:
        """The vocabulary the supports take: B disjoint background supports, then R rare ones' own words."""
        return self.background_topics * self.support + self.rare_topics * self.own_words


def spec_digest(generate: GenerativeSpec, cell_width: int, word_stride: int) -> str:
    """SHA-256 of everything the drawn words depend on: the spec, the cell width, the stride and the generator's version."""
    recipe = {
        "generate": dataclasses.asdict(generate),
        "cell_width": cell_width,
        "word_stride": word_stride,
        "generator": GENERATOR_VERSION,
    }
    return hashlib.sha256(json.dumps(recipe, sort_keys=True).encode()).hexdigest()
