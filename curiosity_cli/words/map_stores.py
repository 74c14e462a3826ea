"""An experiment's maps as every stage needs them: each one's name, cached word store and facts.

``explore`` and ``label`` both start from :func:`prepare_stores`: each ``datasets`` entry
loaded, its words extracted into the cache (or found there), and what the stages need
of it kept in a :class:`StoreInfo`.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from curiosity_cli.cell_grid import SquareGrid
from curiosity_cli.config import ExperimentConfig
from curiosity_cli.errors import ConfigError
from curiosity_cli.files import check_inside, display_path


@dataclass(frozen=True)
class StoreInfo:
    """A map's cached word store and the facts about the map the stages need."""

    name: str
    path: Path
    grid: SquareGrid
    vocabulary_size: int
    vocabulary_hashes: list[str]
    word_counts: dict[str, int]  # words of each kind ("orb", "texton", "hue")
    stands_in_for: str | None  # the paper's map it compares with
    labels_digest: str | None  # of the map's human labels (MapData.labels_digest)


def prepare_stores(config: ExperimentConfig, cache_dir: Path) -> dict[str, StoreInfo]:
    """Each entry of ``config.datasets``: its map's word store, extracted now if not cached.

    Raises
    ------
    ConfigError
        Two entries naming maps of the same name (their runs would share folders).
    """
    from curiosity_cli.data import load_map
    from curiosity_cli.words.extract import extract_words

    stores = {}
    for entry in config.datasets:
        map_data = load_map(entry)
        name = map_data.config.name
        # the store is named <cache_dir>/<name>-<hash>.npz
        check_inside(Path(cache_dir) / f"{name}-store", cache_dir, f"{display_path(Path(entry))}: name")
        if any(info.name == name for info in stores.values()):
            raise ConfigError(f"datasets: two entries are maps named {name!r}; runs are filed by map name")
        extraction = extract_words(map_data, config.words, cache_dir=cache_dir)
        store = extraction.store
        stores[entry] = StoreInfo(
            name, extraction.path, store.grid, store.vocabulary_size, [t.sha256 for t in store.types],
            store.count_by_type(), map_data.config.stands_in_for, map_data.labels_digest,
        )
    return stores
