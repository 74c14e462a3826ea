"""Argument checks shared by the public functions: each names the bad parameter."""

from __future__ import annotations

import math

import numpy as np

from curiosity_cli.errors import ParameterError
from curiosity_cli.yamlfile import shown


def check_int(name: str, value, minimum: int, maximum: int | None = None) -> int:
    """``value`` as an int in ``[minimum, maximum]``, else :class:`ParameterError` naming ``name``."""
    expected = f"between {minimum} and {maximum}" if maximum is not None else f">= {minimum}"
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise ParameterError(f"{name}: got {shown(value)}, expected an integer {expected}")
    if value < minimum or (maximum is not None and value > maximum):
        raise ParameterError(f"{name}: got {value}, expected an integer {expected}")
    return int(value)


def check_choice(name: str, value, choices: tuple):
    """``value``, if it is one of ``choices``, else :class:`ParameterError` naming ``name``.

    ``choices`` are all ints (``value`` is returned as an int; a bool is not one) or all
    strings.
    """
    if all(isinstance(c, str) for c in choices):
        if not isinstance(value, str) or value not in choices:
            raise ParameterError(f"{name}: got {value!r}, expected one of {', '.join(choices)}")
        return value
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or int(value) not in choices:
        expected = " or ".join(str(c) for c in choices)
        raise ParameterError(f"{name}: got {value!r}, expected {expected}")
    return int(value)


def check_float(
    name: str, value, low: float | None = None, high: float | None = None, *, low_open: bool = False,
    high_open: bool = False,
) -> float:
    """``value`` as a finite float within the bounds given, else :class:`ParameterError` naming ``name``.

    ``low`` and ``high`` are inclusive unless ``low_open`` / ``high_open``; a bool is not a number.
    """
    if low is not None and high is None:
        expected = f"a finite number {'>' if low_open else '>='} {low:g}"
    elif low is not None and not (low_open or high_open):
        expected = f"a number between {low:g} and {high:g}"
    elif low is not None:
        expected = f"a number in {'(' if low_open else '['}{low:g}, {high:g}{')' if high_open else ']'}"
    else:
        expected = "a finite number"
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise ParameterError(f"{name}: got {shown(value)}, expected {expected}")
    too_low = low is not None and (value <= low if low_open else value < low)
    too_high = high is not None and (value >= high if high_open else value > high)
    if not math.isfinite(value) or too_low or too_high:
        raise ParameterError(f"{name}: got {value}, expected {expected}")
    return float(value)


def as_uint8(name: str, array, ndim: int, shape_text: str) -> np.ndarray:
    """``array`` as a C-contiguous uint8 array, if it is an integer array of 0..255."""
    array = np.asarray(array)
    if array.ndim != ndim:
        raise ParameterError(f"{name}: got shape {array.shape}, expected {shape_text}")
    if array.dtype != np.uint8:
        if array.dtype == np.bool_ or not np.issubdtype(array.dtype, np.integer):
            raise ParameterError(f"{name}: got dtype {array.dtype}, expected uint8")
        if array.size and (array.min() < 0 or array.max() > 255):
            raise ParameterError(f"{name}: got values outside 0..255, expected uint8")
        array = array.astype(np.uint8)
    return np.ascontiguousarray(array)
