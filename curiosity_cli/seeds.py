"""Seed entropy from names, the same on every machine."""

from __future__ import annotations

import zlib


def name_key(name: str) -> int:
    """A map's or weight function's name as seed entropy (CRC-32, the same on every machine)."""
    return zlib.crc32(name.encode())


#: Seed entropy tags of the label stage's random streams, after a run's own seed entropy or
#: a map's: a run's labelling chain, a map's batch reference, a run's second (checking) chain,
#: a map's split of its words into observed and held-out halves, a run's chain over the observed half, the sweeps
#: of the ``thawed`` labelling reading after a chain.
PATH_TAG, BATCH_TAG, SECOND_CHAIN_TAG, SPLIT_TAG, HELDOUT_CHAIN_TAG, THAW_TAG = 1, 2, 3, 4, 5, 6
