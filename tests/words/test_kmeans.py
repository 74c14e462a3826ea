from __future__ import annotations

import numpy as np
import pytest

from curiosity_cli.errors import ParameterError
from curiosity_cli.words.kmeans import kmeans
from curiosity_cli.words.textons import nearest_centres


def blobs(seed=0):
    rng = np.random.default_rng(seed)
    truth = rng.normal(0, 10, size=(6, 3))
    return (truth[rng.integers(0, 6, 3000)] + rng.normal(0, 0.3, size=(3000, 3))).astype(np.float32), truth


def inertia(vectors, centres):
    return float(((vectors - centres[nearest_centres(vectors, centres)]) ** 2).sum())


def test_kmeans_is_seeded_and_deterministic():
    vectors, _ = blobs()
    assert np.array_equal(kmeans(vectors, 6, seed=3), kmeans(vectors, 6, seed=3))


def test_kmeans_finds_well_separated_blobs():
    vectors, truth = blobs()
    centres = kmeans(vectors, 6, seed=0)
    # every true centre has a found centre close by
    distance = np.sqrt(((truth[:, None, :] - centres[None]) ** 2).sum(-1)).min(axis=1)
    assert distance.max() < 0.2


def test_lloyd_lowers_inertia_below_the_seeding():
    vectors, _ = blobs(1)
    assert inertia(vectors, kmeans(vectors, 12, seed=0)) < inertia(vectors, kmeans(vectors, 12, seed=0, iterations=0))


@pytest.mark.parametrize(
    ("vectors", "kwargs", "message"),
    [
        (np.zeros((3, 2)), {"k": 5}, r"^vectors: got shape \(3, 2\), expected \(N, D\) with N >= k = 5$"),
        (np.zeros(6), {}, r"^vectors: got shape \(6,\), expected a 2-D \(N, D\) array$"),
        (np.full((6, 2), np.nan), {}, r"^vectors: got NaN or infinite values .*, expected finite numbers$"),
        (np.zeros((6, 2)), {"k": 0}, r"^k: got 0, expected an integer >= 1$"),
        (np.zeros((6, 2)), {"seed": -1}, r"^seed: got -1, expected an integer >= 0$"),
        (np.zeros((6, 2)), {"iterations": 2.5}, r"^iterations: got 2\.5, expected an integer >= 0$"),
    ],
)
def test_kmeans_rejects_bad_arguments_naming_the_parameter(vectors, kwargs, message):
    args = {"k": 2, "seed": 0, **kwargs}
    with pytest.raises(ParameterError, match=message):
        kmeans(vectors, args.pop("k"), **args)
