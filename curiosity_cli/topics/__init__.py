"""The ROST spatial topic model (paper section 3) and the perplexities of section 4.

- :mod:`~curiosity_cli.topics.neighbours`: neighbour tables of frame streams, and their check
  (a map's table is its grid's, :mod:`curiosity_cli.maps.cell_grid`).
- :mod:`~curiosity_cli.topics.model`: :class:`TopicModel`, its Gibbs refinement
  (batch, realtime, frozen Φ), ML topics; what it accepts: :mod:`~curiosity_cli.topics.model_checks`.
- :mod:`~curiosity_cli.topics.batch_sweeps`: a batch refinement's phases and the threads
  that sweep them (Algorithm 1).
- :mod:`~curiosity_cli.topics.persistence`: snapshots of a model's state, and model files
  (which keep its compact state, :mod:`~curiosity_cli.topics.compact_state`).
- :mod:`~curiosity_cli.topics.perplexity`: word and topic perplexity of a candidate cell.

Numba kernels live in the private ``_*_kernels.py`` modules and are imported only when a
model computes, so importing this package stays cheap.
"""

from curiosity_cli.topics.model import TopicModel
from curiosity_cli.topics.neighbours import stream_neighbours
from curiosity_cli.topics.perplexity import topic_perplexity, word_perplexity
from curiosity_cli.topics.persistence import ModelSnapshot, load_model, restore_snapshot, save_model, take_snapshot

__all__ = [
    "ModelSnapshot",
    "TopicModel",
    "load_model",
    "restore_snapshot",
    "save_model",
    "stream_neighbours",
    "take_snapshot",
    "topic_perplexity",
    "word_perplexity",
]
