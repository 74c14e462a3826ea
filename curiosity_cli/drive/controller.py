"""From the target image cell to a velocity command: a proportional controller.

The target's offset from the image centre, per axis, in units of half the image::

    e_row = (2 * row + 1 - rows) / rows      -1 (top edge) .. 1 (bottom edge)
    e_col = (2 * col + 1 - cols) / cols      -1 (left edge) .. 1 (right edge)

(the centre of the target cell, so the offsets of an ``rows x cols`` grid are always
strictly inside -1..1), and the command (``clip(v, lo, hi)`` limits ``v`` to ``lo..hi``)::

    surge      = clip(surge_cruise - surge_gain * e_row, surge_min, surge_max)      m/s
    yaw_rate   = clip(yaw_gain * e_col, -yaw_rate_max, yaw_rate_max)                rad/s
    pitch_rate = clip(-pitch_gain * e_row, -pitch_rate_max, pitch_rate_max)         rad/s

Body frame as in the protocol (NED: x forward, y right, z down): a target right of centre
turns the robot right (positive yaw), a target above centre speeds it up and, for a
forward-looking camera, pitches the nose up (positive pitch) towards it. A downward
camera sees the robot's forward direction at the top of the image.
"""

from __future__ import annotations

from dataclasses import dataclass

from curiosity_cli.config import DriveConfig


@dataclass(frozen=True)
class Command:
    """A velocity command: ``surge`` (m/s), ``yaw_rate`` and ``pitch_rate`` (rad/s)."""

    surge: float
    yaw_rate: float
    pitch_rate: float


def _clip(value: float, low: float, high: float) -> float:
    return min(max(value, low), high)


def target_offset(target: tuple[int, int], grid: tuple[int, int]) -> tuple[float, float]:
    """``(e_row, e_col)`` of a target cell (module docstring)."""
    (row, col), (rows, cols) = target, grid
    return (2 * row + 1 - rows) / rows, (2 * col + 1 - cols) / cols


def steer(target: tuple[int, int], grid: tuple[int, int], drive: DriveConfig) -> Command:
    """The command towards ``target`` (row, col) of a ``grid`` (rows, cols) of image cells."""
    e_row, e_col = target_offset(target, grid)
    return Command(
        surge=_clip(drive.surge_cruise - drive.surge_gain * e_row, drive.surge_min, drive.surge_max),
        yaw_rate=_clip(drive.yaw_gain * e_col, -drive.yaw_rate_max, drive.yaw_rate_max),
        pitch_rate=_clip(-drive.pitch_gain * e_row, -drive.pitch_rate_max, drive.pitch_rate_max),
    )
