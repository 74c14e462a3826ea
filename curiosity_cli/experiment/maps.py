"""An experiment's maps as every stage needs them: what its files depend on in each map, and its word store.

Runs record their map's word store (a hash of the image's pixels, the word settings and
the vocabularies) and label files the digest of its human labels. A stage that reads
those files must compare them with the map *now*, not with what the files say, or an
image or labels file edited after exploring passes unnoticed. :class:`MapFacts` is that
comparison's one source: :func:`map_facts` reads a map without extracting its words;
:func:`prepare_stores`, where ``explore`` and ``label`` start, also extracts them into
the cache (or finds them there) and keeps what the stages need in a :class:`StoreInfo`.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from curiosity_cli.maps.cell_grid import SquareGrid
from curiosity_cli.config import ExperimentConfig, WordsConfig
from curiosity_cli.errors import ConfigError
from curiosity_cli.files import check_inside, display_path

if TYPE_CHECKING:
    from curiosity_cli.maps.map_data import MapData


@dataclass(frozen=True)
class MapFacts:
    """A map's facts that runs, batch references and label files are made from.

    Attributes
    ----------
    entry : str
        The config's ``datasets`` entry (a name or a YAML path).
    name : str
        The map's name, which files its runs.
    store : str
        The file name of the word store the image and word settings give now.
    vocabulary_hashes : list of str
        Of each word kind's vocabulary.
    shape : (int, int)
        The image's rows and columns of pixels.
    labels_digest : str or None
        Of the human labels (:attr:`curiosity_cli.maps.map_data.MapData.labels_digest`); None without.
    stands_in_for : str or None
        The paper's map it compares with.
    """

    entry: str
    name: str
    store: str
    vocabulary_hashes: list[str]
    shape: tuple[int, int]
    labels_digest: str | None
    stands_in_for: str | None

    @classmethod
    def of(cls, entry: str, map_data: MapData, words: WordsConfig) -> MapFacts:
        """The facts of a loaded map."""
        from curiosity_cli.words.extract import store_name

        store, hashes = store_name(map_data, words)
        return cls(
            entry, map_data.config.name, store, hashes, tuple(map_data.image.shape[:2]), map_data.labels_digest,
            map_data.config.stands_in_for,
        )

    def record(self) -> dict:
        """The facts later files must still agree with (JSON-ready)."""
        return {"store": self.store, "human": self.labels_digest}


def map_facts(entry: str, words: WordsConfig) -> MapFacts:
    """The facts of the map a ``datasets`` entry names, as the map is now; no words are extracted.

    Raises
    ------
    CuriosityError
        The map cannot be loaded (as :func:`~curiosity_cli.maps.map_data.load_map`), or its
        vocabularies cannot be read.
    """
    from curiosity_cli.maps.map_data import load_map

    return MapFacts.of(entry, load_map(entry), words)


@dataclass(frozen=True)
class StoreInfo:
    """A map's facts and its cached word store, as ``explore`` and ``label`` need them."""

    facts: MapFacts
    path: Path
    grid: SquareGrid
    vocabulary_size: int
    word_counts: dict[str, int]  # words of each kind ("orb", "texton", "hue")

    @property
    def name(self) -> str:
        return self.facts.name


def prepare_stores(config: ExperimentConfig, cache_dir: Path) -> dict[str, StoreInfo]:
    """Each entry of ``config.datasets``: its map's facts and word store, extracted now if not cached.

    Raises
    ------
    ConfigError
        Two entries naming maps of the same name (their runs would share folders).
    CuriosityError
        A vocabulary the words name that is not there, before any map is fetched.
    """
    from curiosity_cli.maps.map_data import load_map
    from curiosity_cli.words.extract import extract_words
    from curiosity_cli.words.kinds import WordRecipe

    # a vocabulary that is not there is refused before any map is fetched or read (config show refuses it so too)
    WordRecipe(config.words)
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
            MapFacts.of(entry, map_data, config.words), extraction.path, store.grid, store.vocabulary_size,
            store.count_by_type(),
        )
    return stores
