"""Visual vocabularies: learned once from photographs unrelated to the maps, shipped in data/vocab/.

Paper section 5.1: "The dictionary was computed by extracting features from a completely
unrelated dataset." Here that dataset is the general photographs bundled in scikit-image
(an astronaut, a cameraman, a cat, a clock, coffee, coins, a Hubble field, a retina, a
rocket; each CC0 or public domain by its skimage docstring), none of
which any embedded map was cut from. A vocabulary file ``<kind>-<size>.npz`` holds the
centres and a JSON recipe; its content hash (SHA-256 of the centres) goes into every word
store made with it, so a changed vocabulary can never be mistaken for the old one.
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np

from curiosity_cli.checks import check_int
from curiosity_cli.config import MAX_VOCABULARY
from curiosity_cli.errors import RERUN, CuriosityError
from curiosity_cli.files import atomic_path, display_path, open_npz

#: scikit-image's bundled photographs used for the vocabularies; the maps use none of them.
SOURCE_IMAGES = (
    "astronaut",
    "camera",
    "chelsea",
    "clock",
    "coffee",
    "coins",
    "hubble_deep_field",
    "retina",
    "rocket",
)
# ORB descriptors are taken at several image scales: one set of photos then yields about
# 90 descriptors per word of a 5000-word vocabulary, and words cover a range of scales.
ORB_SCALES = (0.5, 0.71, 1.0, 1.41, 2.0)
# The shipped vocabulary was learned from keypoints capped per tile and topped up at FAST
# threshold 1, so smooth photos count too; the recipe stays, so a rebuild is bit for bit.
ORB_TILE, ORB_PER_TILE, ORB_FILL_THRESHOLD = 16, 4, 1
TEXTON_SAMPLES_PER_IMAGE = 40_000
ITERATIONS = 20

#: Shape of one centre, and dtype, per kind of vocabulary.
_CENTRE = {"orb": ((32,), np.uint8), "texton": ((8,), np.float32)}


@dataclass(frozen=True)
class Vocabulary:
    """A vocabulary: ``centres`` of shape (size, 32) uint8 for ORB, (size, 8) float32 for textons."""

    kind: str
    centres: np.ndarray
    recipe: dict

    @property
    def name(self) -> str:
        return f"{self.kind}-{len(self.centres)}"

    @property
    def sha256(self) -> str:
        return hashlib.sha256(np.ascontiguousarray(self.centres).tobytes()).hexdigest()


def vocabulary_path(directory: Path, kind: str, size: int) -> Path:
    """Where the ``kind`` vocabulary of ``size`` words lives in ``directory``."""
    return Path(directory) / f"{kind}-{size}.npz"


def load_vocabulary(directory: Path, kind: str, size: int) -> Vocabulary:
    """Read and check a vocabulary file.

    Raises
    ------
    CuriosityError
        The file is missing, truncated or not a vocabulary's (a
        :class:`~curiosity_cli.files.CorruptFileError`), or its centres have the wrong
        shape, dtype or non-finite values; the message names the file.
    """
    path = vocabulary_path(directory, kind, size)
    where = display_path(path)
    if not path.is_file():
        raise CuriosityError(
            f"{where}: vocabulary not found; {RERUN} builds the {kind} vocabulary of {size} words",
            rerun="vocab build", force=False,
        )
    with open_npz(path) as data:  # a truncated or foreign file is a CorruptFileError naming it
        centres, recipe = data["centres"], json.loads(str(data["recipe"]))
    shape, dtype = _CENTRE[kind]
    if centres.dtype != dtype or centres.shape != (size, *shape):
        raise CuriosityError(
            f"{where}: centres: got {centres.dtype} of shape {centres.shape}, "
            f"expected {np.dtype(dtype).name} of shape {(size, *shape)}"
        )
    if kind == "texton" and not np.isfinite(centres).all():
        raise CuriosityError(f"{where}: centres: got non-finite values, expected finite numbers")
    return Vocabulary(kind=kind, centres=centres, recipe=recipe)


def save_vocabulary(vocabulary: Vocabulary, directory: Path) -> Path:
    """Write ``<kind>-<size>.npz`` atomically; return its path."""
    path = vocabulary_path(directory, vocabulary.kind, len(vocabulary.centres))
    with atomic_path(path) as tmp:
        with open(tmp, "wb") as handle:
            np.savez_compressed(
                handle, centres=vocabulary.centres, recipe=np.array(json.dumps(vocabulary.recipe, sort_keys=True))
            )
    return path


def built_vocabulary(directory: Path, kind: str, size: int, seed: int) -> Vocabulary | None:
    """The ``kind`` vocabulary of ``size`` words in ``directory``, if it was built by the recipe a build with
    ``seed`` follows now (:func:`build_recipe`); else None, and it is to be built.

    A file is written whole or not at all (:func:`save_vocabulary`); one that does not
    read as a vocabulary, or was built otherwise (another seed, another version of
    scikit-image or of curiosity), is None.
    """
    try:
        vocabulary = load_vocabulary(directory, kind, size)
    except CuriosityError:
        return None
    expected = build_recipe(kind, size, seed)
    return vocabulary if all(vocabulary.recipe.get(key) == value for key, value in expected.items()) else None


def _skimage():
    """scikit-image, whose bundled photographs the vocabularies are learned from."""
    try:
        import skimage.data
    except ImportError:
        raise CuriosityError(
            "building vocabularies needs scikit-image's bundled photographs: pip install -e '.[maps]'"
        ) from None
    return skimage


def _source_images() -> dict[str, np.ndarray]:
    """The bundled photographs as (H, W) uint8 grey images."""
    import cv2

    photographs = _skimage().data
    images = {}
    for name in SOURCE_IMAGES:
        image = getattr(photographs, name)()
        if image.ndim == 3:
            image = cv2.cvtColor(np.ascontiguousarray(image[:, :, :3]), cv2.COLOR_RGB2GRAY)
        images[name] = image
    return images


def build_orb_vocabulary(size: int, *, seed: int, log: Callable[[str], None] = lambda _: None) -> Vocabulary:
    """Learn ORB words by k-majority clustering of descriptors from :data:`SOURCE_IMAGES`.

    Raises
    ------
    ParameterError
        ``size`` outside 2..:data:`~curiosity_cli.config.MAX_VOCABULARY`.
    """
    import cv2

    from curiosity_cli.words.binary_kmeans import binary_kmeans
    from curiosity_cli.words.orb import detect_orb

    size = check_int("size", size, 2, MAX_VOCABULARY)
    descriptors = []
    for name, image in _source_images().items():
        for scale in ORB_SCALES:
            scaled = cv2.resize(image, None, fx=scale, fy=scale, interpolation=cv2.INTER_AREA)
            features = detect_orb(scaled, tile=ORB_TILE, per_tile=ORB_PER_TILE, fill_threshold=ORB_FILL_THRESHOLD)
            descriptors.append(features.descriptors)
        log(f"  orb: {name}: {sum(len(d) for d in descriptors)} descriptors so far")
    pool = np.concatenate(descriptors)
    log(f"  orb: clustering {len(pool)} descriptors into {size} words")
    centres = binary_kmeans(pool, size, seed=seed, iterations=ITERATIONS)
    return Vocabulary("orb", centres, {**build_recipe("orb", size, seed), "descriptors": len(pool)})


def build_texton_vocabulary(
    size: int, *, seed: int, log: Callable[[str], None] = lambda _: None
) -> Vocabulary:
    """Learn texton words by k-means on normalised MR8 responses of :data:`SOURCE_IMAGES`.

    Raises
    ------
    ParameterError
        ``size`` outside 2..:data:`~curiosity_cli.config.MAX_VOCABULARY`.
    """
    from curiosity_cli.words.filterbank import mr8_responses, normalise_responses
    from curiosity_cli.words.kmeans import kmeans

    size = check_int("size", size, 2, MAX_VOCABULARY)
    rng = np.random.default_rng([seed, 1])
    samples = []
    for name, image in _source_images().items():
        responses = normalise_responses(mr8_responses(image)).reshape(-1, 8)
        take = min(TEXTON_SAMPLES_PER_IMAGE, len(responses))
        samples.append(responses[np.sort(rng.choice(len(responses), take, replace=False))])
        log(f"  texton: {name}: {take} response vectors")
    pool = np.concatenate(samples)
    log(f"  texton: clustering {len(pool)} vectors into {size} words")
    centres = kmeans(pool, size, seed=seed, iterations=ITERATIONS)
    return Vocabulary("texton", centres, {**build_recipe("texton", size, seed), "vectors": len(pool)})


def build_recipe(kind: str, size: int, seed: int) -> dict:
    """How a ``kind`` vocabulary of ``size`` words is built with ``seed`` now: the recipe its file records, less the
    number of descriptors or vectors clustered, which only the photographs say."""
    from curiosity_cli import __version__

    details = {
        "orb": {
            "scales": list(ORB_SCALES), "tile": ORB_TILE, "per_tile": ORB_PER_TILE,
            "method": "k-majority (binary k-means, Hamming distance), k-means++ start",
        },
        "texton": {
            "samples_per_image": TEXTON_SAMPLES_PER_IMAGE,
            "method": "k-means (Lloyd, k-means++ start) on contrast-normalised MR8 responses",
        },
    }[kind]
    return {
        "kind": kind,
        "size": size,
        "seed": seed,
        "iterations": ITERATIONS,
        "source_images": [f"skimage.data.{n}" for n in SOURCE_IMAGES],
        "scikit_image": _skimage().__version__,
        "curiosity": __version__,
        **details,
    }
