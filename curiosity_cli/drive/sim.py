"""A robot moving over a map, and what its downward-looking camera sees.

The world frame of the simulated robot is the map's: ``x`` along the map's columns and
``y`` along its rows, both in metres from the top-left corner (``x = col * mpp``,
``y = row * mpp`` for ``mpp`` metres per pixel), and ``heading`` in radians from ``+x``
towards ``+y``. Seen from above with rows pointing down, that is z pointing into the map,
as in the NED convention: a positive yaw rate turns the robot to its right (clockwise on
screen). The camera looks straight down; the robot's forward direction is up in the
image and its right side is on the image's right.

Used by the simulated robot (``curiosity simrobot``) for the motion and by the driver's
``--camera sim`` for the view.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from curiosity_cli.checks import check_float
from curiosity_cli.errors import ParameterError


@dataclass(frozen=True)
class Pose:
    """Where the robot is: ``x``, ``y`` (m) in the map frame, ``heading`` (rad) in (-pi, pi]."""

    x: float
    y: float
    heading: float

    def pixel(self, metres_per_pixel: float) -> tuple[float, float]:
        """(row, col) of the robot on the map, in (fractional) pixels."""
        return self.y / metres_per_pixel, self.x / metres_per_pixel

    @classmethod
    def at_pixel(cls, row: float, col: float, heading: float, metres_per_pixel: float) -> Pose:
        """The pose at (``row``, ``col``) on the map, in (fractional) pixels, facing ``heading`` (rad)."""
        return cls(col * metres_per_pixel, row * metres_per_pixel, heading)


class Body:
    """Unicycle kinematics over a bounded map: surge along the heading, yaw turns it.

    Parameters
    ----------
    map_shape : (int, int)
        The map's rows and columns in pixels; the robot stays within it.
    metres_per_pixel : float
        > 0.
    start : Pose
        Inside the map.
    """

    def __init__(self, map_shape: tuple[int, int], metres_per_pixel: float, start: Pose):
        metres_per_pixel = check_float("metres_per_pixel", metres_per_pixel, 0, low_open=True)
        self._height = map_shape[0] * metres_per_pixel
        self._width = map_shape[1] * metres_per_pixel
        if not (0 <= start.x <= self._width and 0 <= start.y <= self._height):
            raise ParameterError(
                f"start: ({start.y / metres_per_pixel:.0f}, {start.x / metres_per_pixel:.0f}) [row, col] "
                f"is outside the map of {map_shape[0]} x {map_shape[1]} px"
            )
        self.metres_per_pixel = metres_per_pixel
        self.pose = Pose(start.x, start.y, wrap_angle(start.heading))

    def step(self, surge: float, yaw_rate: float, dt: float) -> Pose:
        """Move for ``dt`` s at constant ``surge`` (m/s) and ``yaw_rate`` (rad/s); return the new pose.

        The arc is integrated exactly (a constant-velocity unicycle follows a circle),
        so the path does not depend on how finely time is cut. The robot cannot leave
        the map: at a border the coordinate is clamped and it slides along the border.
        """
        x, y, h = self.pose.x, self.pose.y, self.pose.heading
        turn = yaw_rate * dt
        if abs(turn) < 1e-9:
            x += surge * dt * math.cos(h)
            y += surge * dt * math.sin(h)
        else:
            radius = surge / yaw_rate
            x += radius * (math.sin(h + turn) - math.sin(h))
            y -= radius * (math.cos(h + turn) - math.cos(h))
        x = min(max(x, 0.0), self._width)
        y = min(max(y, 0.0), self._height)
        self.pose = Pose(x, y, wrap_angle(h + turn))
        return self.pose


def wrap_angle(angle: float) -> float:
    """``angle`` in (-pi, pi]."""
    wrapped = math.remainder(angle, 2 * math.pi)
    return math.pi if wrapped == -math.pi else wrapped


def render_view(image: np.ndarray, pose: Pose, metres_per_pixel: float, view_shape: tuple[int, int]) -> np.ndarray:
    """The downward camera's view: a window of the map centred on the robot, heading up.

    Parameters
    ----------
    image : (H, W, 3) uint8 ndarray
        The map, RGB.
    pose : Pose
    metres_per_pixel : float
        The map's scale.
    view_shape : (int, int)
        Rows and columns of the view, in map pixels (one view pixel per map pixel).

    Returns
    -------
    (rows, cols, 3) uint8 ndarray
        RGB. Beyond the map's border the map is mirrored, so the border itself shows
        no artificial edge that would look novel.
    """
    import cv2

    rows, cols = view_shape
    row, col = pose.pixel(metres_per_pixel)
    sin_h, cos_h = math.sin(pose.heading), math.cos(pose.heading)
    centre_row, centre_col = (rows - 1) / 2, (cols - 1) / 2
    # View pixel (r, c) lies (centre_row - r) px ahead of the robot and (c - centre_col)
    # px to its right; ahead is (cos h, sin h) and right is (-sin h, cos h) in (col, row).
    # OpenCV wants the map from view (x = c, y = r) to source (x = col, y = row).
    to_source = np.array(
        [
            [-sin_h, -cos_h, col + sin_h * centre_col + cos_h * centre_row],
            [cos_h, -sin_h, row - cos_h * centre_col + sin_h * centre_row],
        ]
    )
    return cv2.warpAffine(
        image,
        to_source,
        (cols, rows),
        flags=cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP,
        borderMode=cv2.BORDER_REFLECT_101,
    )
