"""The topic model of a map: an empty :class:`~curiosity_cli.topics.model.TopicModel` over its cell grid.

Exploration builds one per run and labelling one per map (with Φ frozen); both build it
here, from the map's word store and the ``model`` settings.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from curiosity_cli.config import ModelConfig
    from curiosity_cli.words.store import WordStore


def map_topic_model(store: WordStore, model: ModelConfig, seed: int, *, frozen_counts=None):
    """An empty :class:`~curiosity_cli.topics.model.TopicModel` over a map's cell grid.

    ``frozen_counts`` (V, K) fixes Φ (see the model); the vocabulary hashes of the store's
    word types go into the model, so a saved model names what its word ids mean.
    """
    from curiosity_cli.topics.model import TopicModel

    return TopicModel(
        model.topics,
        store.vocabulary_size,
        store.grid.neighbour_table(model.spatial_neighbours),
        alpha=model.alpha,
        beta=model.beta,
        seed=seed,
        vocabulary_hashes=[t.sha256 for t in store.types],
        frozen_counts=frozen_counts,
    )
