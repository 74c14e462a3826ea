"""The shared argument checks: each names the bad parameter and the range it expected."""

from __future__ import annotations

import math

import numpy as np
import pytest

from curiosity_cli.checks import check_float
from curiosity_cli.errors import ParameterError


@pytest.mark.parametrize(
    "value, bounds, message",
    [
        (0, dict(low=0, low_open=True), "alpha: got 0, expected a finite number > 0"),
        (math.nan, dict(low=0, low_open=True), "alpha: got nan, expected a finite number > 0"),
        (math.inf, {}, "alpha: got inf, expected a finite number"),
        (True, dict(low=0, high=1), "alpha: got True, expected a number between 0 and 1"),
        ("0.5", dict(low=0, high=1), "alpha: got '0.5', expected a number between 0 and 1"),
        (1.5, dict(low=0, high=1), "alpha: got 1.5, expected a number between 0 and 1"),
        (1, dict(low=1, high=2, low_open=True), r"alpha: got 1, expected a number in \(1, 2\]"),
    ],
)
def test_a_bad_float_is_refused_naming_it_and_the_range(value, bounds, message):
    with pytest.raises(ParameterError, match=message):
        check_float("alpha", value, **bounds)


def test_a_good_float_comes_back_as_a_float():
    assert check_float("eta", np.float32(0.5), 0, 1) == 0.5 and isinstance(check_float("eta", 1, 0, 1), float)
    assert check_float("scale_factor", 2, 1, 2, low_open=True) == 2.0
    assert check_float("beta", 1e-12, 0, low_open=True) == 1e-12
