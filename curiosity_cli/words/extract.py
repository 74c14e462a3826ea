"""Extraction: a map image → its word store, cached by what made it.

A store is keyed by a hash of the decoded image pixels, the vocabularies' content hashes
and every parameter that changes the words (the words settings'
:meth:`~curiosity_cli.config.WordsConfig.store_settings`), so a cached store is reused exactly when
re-extracting would give the same words, and never otherwise. A generated map's words are
drawn, not extracted (:mod:`curiosity_cli.words.drawn`), and its store is keyed by its
generative spec alone: the words settings and vocabularies make none of its words, and are
not read for it.
"""

from __future__ import annotations

import hashlib
import json
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from curiosity_cli.checks import check_int
from curiosity_cli.config import WordsConfig
from curiosity_cli.maps.datasets import stride_problem
from curiosity_cli.maps.map_data import MapData
from curiosity_cli.errors import CuriosityError, ParameterError
from curiosity_cli.files import CorruptFileError, note
from curiosity_cli.paths import DEFAULT_CACHE
from curiosity_cli.words.kinds import OrbSettings, Picture, WordRecipe
from curiosity_cli.words.store import STORE_FORMAT, WordStore, WordType, build_store, load_store, save_store


@dataclass(frozen=True)
class Extraction:
    """A store and how it was obtained."""

    store: WordStore
    path: Path
    reused: bool
    seconds: dict[str, float]  # per stage; empty when reused

    @property
    def orb_share(self) -> float:
        """Fraction of the store's words that are ORB words (0 for an empty store)."""
        total = len(self.store.words)
        return self.store.count_by_type().get("orb", 0) / total if total else 0.0


def _params(map_data: MapData, words: WordsConfig, stride: int, cell_width: int) -> dict:
    image_hash = hashlib.sha256(map_data.image.tobytes() + str(map_data.image.shape).encode()).hexdigest()
    return {
        "dataset": map_data.config.name,
        "image_sha256": image_hash,
        "image_shape": list(map_data.image.shape[:2]),
        "stride": stride,
        "cell_width": cell_width,
        # every words key that changes the words (WordsConfig.store_settings says which do not)
        **words.store_settings(),
    }


def store_path(cache_dir: Path, params: dict, types: tuple[WordType, ...]) -> Path:
    """``<cache_dir>/<dataset>-<hash>.npz``, the hash covering params, vocabularies and format."""
    key = json.dumps({"params": params, "types": [t.__dict__ for t in types], "format": STORE_FORMAT}, sort_keys=True)
    return Path(cache_dir) / f"{params['dataset']}-{hashlib.sha256(key.encode()).hexdigest()[:16]}.npz"


def store_name(map_data: MapData, words: WordsConfig) -> tuple[str, list[str]]:
    """The file name of the word store a map's image and ``words`` give at the dataset's stride and cell width,
    and the vocabularies' hashes, without extracting: what a run made from them records.

    A generated map's: of its generative spec (:mod:`curiosity_cli.words.drawn`), whatever ``words`` says.
    """
    if map_data.config.generate is not None:
        from curiosity_cli.words.drawn import drawn_params, drawn_types

        types = drawn_types(map_data)
        return store_path(Path(), drawn_params(map_data), types).name, [t.sha256 for t in types]
    types = WordRecipe(words).types
    params = _params(map_data, words, map_data.config.word_stride, map_data.config.cell_width)
    return store_path(Path(), params, types).name, [t.sha256 for t in types]


def extract_words(
    map_data: MapData,
    words: WordsConfig,
    *,
    stride: int | None = None,
    cell_width: int | None = None,
    cache_dir: Path = DEFAULT_CACHE,
    force: bool = False,
) -> Extraction:
    """The word store of a map: from the cache when present, else extracted (a generated map's: drawn) and cached.

    Parameters
    ----------
    map_data : MapData
        The map (its dataset gives the default stride and cell width).
    words : WordsConfig
        Vocabularies and ORB settings.
    stride : int, optional
        Texton (and hue) words at every ``stride``-th pixel; default the dataset's.
    cell_width : int, optional
        Cell side in pixels; default the dataset's.
    cache_dir : Path
        Where stores are kept.
    force : bool
        Extract again even when a cached store exists.

    Returns
    -------
    Extraction

    Raises
    ------
    ParameterError
        A bad stride or cell width: not an int >= 1, a cell wider than the image, or a
        stride wider than a cell, naming the one given; for a generated map, one other
        than its own.
    CuriosityError
        A missing or malformed vocabulary, a grey image with colour words on.
    """
    if map_data.config.generate is not None:
        return _drawn(map_data, stride, cell_width, cache_dir, force)
    import cv2

    # the one given is at fault when the two do not go together (the dataset's own were checked when it loaded)
    blamed = "stride" if stride is not None else "cell_width"
    stride = check_int("stride", map_data.config.word_stride if stride is None else stride, 1)
    cell_width = check_int("cell_width", map_data.config.cell_width if cell_width is None else cell_width, 1)
    if cell_width > min(map_data.image.shape[:2]):
        raise ParameterError(
            f"cell_width: got {cell_width}, expected at most the image's smaller side ({min(map_data.image.shape[:2])} px)",
            parameter="cell_width",
        )
    problem = stride_problem(stride, cell_width)
    if problem is not None:
        raise ParameterError(f"{blamed}: {problem}", parameter=blamed)
    image = map_data.image
    if words.colour_words and np.array_equal(image[:, :, 0], image[:, :, 1]) and np.array_equal(image[:, :, 1], image[:, :, 2]):
        raise CuriosityError(
            f"{map_data.config.image}: the image is grey; colour words need colour (set words.colour_words: false)"
        )
    recipe = WordRecipe(words)
    types = recipe.types
    params = _params(map_data, words, stride, cell_width)
    path = store_path(cache_dir, params, types)
    if (cached := None if force else _cached(path, "extracting")) is not None:
        return cached

    start = time.perf_counter()
    grey = cv2.cvtColor(image, cv2.COLOR_RGB2GRAY)
    rows, cols, ids, seconds = recipe.find(Picture(image, grey, stride, OrbSettings.for_maps(words)))
    store = build_store(
        rows,
        cols,
        ids,
        image.shape[:2],
        cell_width,
        types,
        params,
    )
    if words.orb_detector == "grid" and store.count_by_type().get("orb", 0) == 0:
        # a grid that coarse puts no point far enough inside the map for a descriptor: a store without ORB words
        # would run, and answer another question than the config asks
        raise CuriosityError(
            f"words.orb_grid_step: got {words.orb_grid_step}, but its grid places no ORB word on "
            f"{map_data.config.name} ({image.shape[0]} x {image.shape[1]} px); expected a step that leaves grid points "
            "inside the map, away from its border",
        )
    if words.orb_detector == "keypoints" and store.count_by_type().get("orb", 0) == 0:
        raise CuriosityError(  # as above: 255 found no corner on any shipped map, and the store ran without ORB words
            f"words.orb_fast_threshold: got {words.orb_fast_threshold}, but FAST finds no corner on "
            f"{map_data.config.name} at it; expected a lower threshold, or a map with texture ORB can see"
        )
    save_store(store, path)
    seconds["total"] = time.perf_counter() - start
    return Extraction(store, path, reused=False, seconds=seconds)


def _drawn(map_data: MapData, stride: int | None, cell_width: int | None, cache_dir: Path, force: bool) -> Extraction:
    """A generated map's store (:func:`extract_words`): from the cache, else drawn and cached."""
    from curiosity_cli.words.drawn import draw_store, drawn_params, drawn_types

    config = map_data.config
    for name, given, own in (("stride", stride, config.word_stride), ("cell_width", cell_width, config.cell_width)):
        if given is not None and given != own:
            raise ParameterError(
                f"{name}: got {given}, but {config.name} is a generated map whose words are drawn at its own "
                f"{own}; expected {own} or none",
                parameter=name,
            )
    path = store_path(cache_dir, drawn_params(map_data), drawn_types(map_data))
    if (cached := None if force else _cached(path, "drawing")) is not None:
        return cached
    start = time.perf_counter()
    store = draw_store(map_data)
    save_store(store, path)
    return Extraction(store, path, reused=False, seconds={"total": time.perf_counter() - start})


def _cached(path: Path, making: str) -> Extraction | None:
    """The store cached at ``path``, or None when there is none; a corrupt one is noted (``making`` the words
    again, as the caller will) and not used: it is a cache."""
    if not path.is_file():
        return None
    try:
        return Extraction(load_store(path), path, reused=True, seconds={})
    except CorruptFileError as exc:
        note(f"{exc}; {making} the words again")
        return None
