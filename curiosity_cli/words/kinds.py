"""The kinds of visual words: one recipe for a map (``curiosity extract``) and a camera frame (``drive``).

A kind is a registry entry (:data:`KINDS`): whether a config uses it, its vocabulary
(name, size and content hash) and how it finds its words in an image. The kinds' word
ids follow one another in registry order in one id space (ORB ``0 ..``, textons next,
hue last when ``words.colour_words``), and :class:`WordRecipe` is the one place that
says where each kind's ids start. A new kind of word is a function that finds it, one
entry here and its tests.

Maps and frames differ only in what :class:`Picture` holds: a frame is small, so the
driver has its own texton stride and ORB pyramid (``drive.*``).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from curiosity_cli.config import WordsConfig
from curiosity_cli.words.store import WordType

#: Hue words: OpenCV's 8-bit hue, 0..179.
HUE_BINS = 180


@dataclass(frozen=True)
class OrbSettings:
    """Where ORB words are: ``detector`` (``words.orb_detector``), the grid's ``grid_step``
    (:func:`~curiosity_cli.words.orb_grid.grid_orb`) or the keypoints' settings
    (:func:`~curiosity_cli.words.orb.detect_orb`'s keywords)."""

    tile: int
    per_tile: int | None
    max_features: int | None
    fast_threshold: int
    fill_threshold: int | None
    n_levels: int = 8
    detector: str = "keypoints"
    grid_step: int = 1

    @classmethod
    def for_maps(cls, words: WordsConfig) -> OrbSettings:
        return cls(words.orb_tile, words.orb_per_tile, words.orb_max_features, words.orb_fast_threshold,
                   words.orb_fill_threshold, detector=words.orb_detector, grid_step=words.orb_grid_step)

    @classmethod
    def for_frames(cls, words: WordsConfig, *, per_tile: int, fill_threshold: int | None, n_levels: int) -> OrbSettings:
        """The ORB settings of a camera frame, which is too small for a map's.

        The map's detector; for keypoints, the map's tiling, feature cap and FAST
        threshold, with the driver's own cap per tile, top-up threshold and pyramid depth
        (``drive.orb_per_tile``, ``drive.orb_fill_threshold``, ``drive.orb_levels``); for
        the grid, the map's step (the grid reads no other setting).
        """
        return cls(words.orb_tile, per_tile, words.orb_max_features, words.orb_fast_threshold, fill_threshold, n_levels,
                   detector=words.orb_detector, grid_step=words.orb_grid_step)


def orb_features(grey: np.ndarray, settings: OrbSettings):
    """The ORB points (keypoints or grid points) and descriptors of an (H, W) uint8 grey image."""
    if settings.detector == "grid":
        from curiosity_cli.words.orb_grid import grid_orb

        return grid_orb(grey, step=settings.grid_step)
    from curiosity_cli.words.orb import detect_orb

    return detect_orb(
        grey, tile=settings.tile, per_tile=settings.per_tile, max_features=settings.max_features,
        fast_threshold=settings.fast_threshold, fill_threshold=settings.fill_threshold, n_levels=settings.n_levels,
    )


@dataclass(frozen=True)
class Picture:
    """What the kinds read of an image.

    Attributes
    ----------
    rgb : (H, W, 3) uint8 ndarray
    grey : (H, W) uint8 ndarray
    stride : int
        Texton and hue words are taken at every ``stride``-th pixel.
    orb : OrbSettings
    """

    rgb: np.ndarray
    grey: np.ndarray
    stride: int
    orb: OrbSettings


@dataclass(frozen=True)
class Lexicon:
    """A kind's vocabulary: name, number of words, content hash ("" for a fixed one) and centres if learned."""

    name: str
    size: int
    sha256: str
    centres: np.ndarray | None = None


@dataclass(frozen=True)
class WordKind:
    """One kind of word: whether ``words`` uses it, its vocabulary, and ``find(picture, lexicon) -> (rows, cols, ids)``."""

    name: str
    used: Callable[[WordsConfig], bool]
    lexicon: Callable[[WordsConfig], Lexicon]
    find: Callable[[Picture, Lexicon], tuple[np.ndarray, np.ndarray, np.ndarray]]


def _learned(kind: str, size: Callable[[WordsConfig], int]) -> Callable[[WordsConfig], Lexicon]:
    def load(words: WordsConfig) -> Lexicon:
        from curiosity_cli.words.vocab import load_vocabulary

        vocabulary = load_vocabulary(words.vocabulary_dir, kind, size(words))
        return Lexicon(vocabulary.name, len(vocabulary.centres), vocabulary.sha256, vocabulary.centres)

    return load


def _find_orb(picture: Picture, lexicon: Lexicon):
    from curiosity_cli.words.hamming import nearest_binary_words

    features = orb_features(picture.grey, picture.orb)
    return features.rows, features.cols, nearest_binary_words(features.descriptors, lexicon.centres)


def _find_textons(picture: Picture, lexicon: Lexicon):
    from curiosity_cli.words.textons import texton_words

    return texton_words(picture.grey, lexicon.centres, picture.stride)


def _find_hues(picture: Picture, lexicon: Lexicon):
    import cv2

    from curiosity_cli.words.textons import sample_grid

    # at the texton words' pixels
    s = picture.stride
    hue = cv2.cvtColor(picture.rgb, cv2.COLOR_RGB2HSV)[::s, ::s, 0]
    return *sample_grid(picture.grey.shape, s), hue.ravel()


#: Every kind of word, in the order their ids follow each other.
KINDS = (
    WordKind("orb", lambda words: True, _learned("orb", lambda words: words.orb_vocabulary), _find_orb),
    WordKind("texton", lambda words: True, _learned("texton", lambda words: words.texton_vocabulary), _find_textons),
    WordKind("hue", lambda words: words.colour_words, lambda words: Lexicon(f"hue-{HUE_BINS}", HUE_BINS, ""), _find_hues),
)


class WordRecipe:
    """The kinds ``words`` uses, their vocabularies (loaded once) and where each kind's ids start.

    Attributes
    ----------
    types : tuple of WordType
        Each kind's name, vocabulary name, first id, number of ids and vocabulary hash.
    vocabulary_size : int
        Ids of all kinds together.

    Raises
    ------
    CuriosityError
        A missing or malformed vocabulary.
    """

    def __init__(self, words: WordsConfig):
        self._kinds = []
        types, offset = [], 0
        for kind in KINDS:
            if kind.used(words):
                lexicon = kind.lexicon(words)
                types.append(WordType(kind.name, lexicon.name, offset, lexicon.size, lexicon.sha256))
                self._kinds.append((kind, lexicon, offset))
                offset += lexicon.size
        self.types = tuple(types)
        self.vocabulary_size = offset

    def find(self, picture: Picture) -> tuple[np.ndarray, np.ndarray, np.ndarray, dict[str, float]]:
        """Every word of ``picture``: ``(rows, cols, ids, seconds)``, kinds in registry order.

        ``ids`` (N,) int64 are in the one id space; ``seconds`` is the time each kind took.
        """
        rows, cols, ids, seconds = [], [], [], {}
        for kind, lexicon, offset in self._kinds:
            began = time.perf_counter()
            r, c, w = kind.find(picture, lexicon)
            rows.append(r)
            cols.append(c)
            ids.append(np.asarray(w).astype(np.int64) + offset)
            seconds[kind.name] = time.perf_counter() - began
        return np.concatenate(rows), np.concatenate(cols), np.concatenate(ids), seconds
