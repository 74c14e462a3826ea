"""The paper's own figures that reports compare with."""

from __future__ import annotations

import pytest

from curiosity_cli.paper import PAPER_MAPS


def test_orb_shares_implied_by_table_1():
    # Table 1's word counts less a texton at every pixel (every 2nd on SouthBellairs)
    assert PAPER_MAPS["Montreal1"].orb_share == pytest.approx((3_239_631 - 1024**2) / 3_239_631)
    assert [round(100 * m.orb_share) for m in PAPER_MAPS.values()] == [68, 37, 6]
    assert [m.headline_ratio for m in PAPER_MAPS.values()] == [1.51, 1.20, 1.05]
