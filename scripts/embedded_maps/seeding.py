"""The one seed of the embedded maps, and the random stream of each stage of each map."""

from __future__ import annotations

import numpy as np

#: The one seed every random choice derives from (per map and per stage, see `stage_rng`).
SEED = 20140914

#: The maps, in the order that numbers their random streams.
MAP_NAMES = ("aerial-mosaic", "sentinel-coast", "reef-mosaic", "rare-patches")


def stage_rng(map_name: str, stage: int) -> np.random.Generator:
    """Return the random generator of one stage of one map.

    Each (map, stage) pair has its own stream, so retuning one stage (say the trail)
    leaves every other stage's pixels unchanged.

    Parameters
    ----------
    map_name : str
        One of `MAP_NAMES`.
    stage : int
        Small integer naming the stage within the map.

    Returns
    -------
    numpy.random.Generator
    """
    return np.random.default_rng([SEED, MAP_NAMES.index(map_name), stage])
