"""Seed entropy from names, the same on every machine."""

from __future__ import annotations

import zlib


def name_key(name: str) -> int:
    """A map's or weight function's name as seed entropy (CRC-32, the same on every machine)."""
    return zlib.crc32(name.encode())
