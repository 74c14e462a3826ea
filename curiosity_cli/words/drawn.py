"""A generated map's words: drawn from its generative model (:mod:`curiosity_cli.maps.generated`), not extracted.

The store holds one kind of word, ``generated``, of the model's V ids; its vocabulary's
"content hash" is the digest of the generative spec
(:func:`~curiosity_cli.maps.generative_spec.spec_digest`), so a run's recipe, which records
the vocabularies' hashes, changes whenever the words would. The words settings of a
config (ORB, textons, hue) do not enter: they make no word of such a map.
"""

from __future__ import annotations

import dataclasses

from curiosity_cli.maps.generated import generate_map
from curiosity_cli.maps.generative_spec import spec_digest
from curiosity_cli.maps.map_data import MapData
from curiosity_cli.words.store import GENERATED, WordStore, WordType, build_store


def drawn_types(map_data: MapData) -> tuple[WordType, ...]:
    """The one word type of a generated map: its V ids, hashed by the spec that draws them."""
    config = map_data.config
    generate = config.generate
    digest = spec_digest(generate, config.cell_width, config.word_stride)
    return (WordType(GENERATED, f"generated-{generate.vocabulary}", 0, generate.vocabulary, digest),)


def drawn_params(map_data: MapData) -> dict:
    """What made a generated map's store (JSON-ready): its name, spec, grid and stride."""
    config = map_data.config
    return {
        "dataset": config.name,
        "generate": dataclasses.asdict(config.generate),
        "image_shape": list(map_data.image.shape[:2]),
        "stride": config.word_stride,
        "cell_width": config.cell_width,
    }


def draw_store(map_data: MapData) -> WordStore:
    """The word store of a generated map: its drawn words at their pixels, grouped by cell."""
    config = map_data.config
    drawn = generate_map(config.generate, config.cell_width, config.word_stride)
    return build_store(
        drawn.pixel_rows, drawn.pixel_cols, drawn.words, map_data.image.shape[:2], config.cell_width,
        drawn_types(map_data), drawn_params(map_data),
    )
