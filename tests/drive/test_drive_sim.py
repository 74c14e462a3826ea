"""The simulated robot's motion and its camera view."""

from __future__ import annotations

import math

import numpy as np
import pytest

from curiosity_cli.drive.sim import Body, Pose, render_view, wrap_angle
from curiosity_cli.errors import ParameterError


def test_straight_motion_follows_the_heading():
    body = Body((100, 200), 0.01, Pose(0.5, 0.5, math.pi / 2))  # heading +y: down the rows
    body.step(0.2, 0.0, 1.0)
    assert body.pose.x == pytest.approx(0.5) and body.pose.y == pytest.approx(0.7)


def test_a_turn_is_an_exact_arc_whatever_the_time_step():
    # a quarter circle of radius v / w = 0.2 m, turning right (clockwise on screen)
    coarse = Body((100, 200), 0.01, Pose(1.0, 0.3, 0.0))
    coarse.step(0.1, 0.5, math.pi)
    fine = Body((100, 200), 0.01, Pose(1.0, 0.3, 0.0))
    for _ in range(1000):
        fine.step(0.1, 0.5, math.pi / 1000)
    for body in (coarse, fine):
        assert body.pose.x == pytest.approx(1.2) and body.pose.y == pytest.approx(0.5)
        assert body.pose.heading == pytest.approx(math.pi / 2)


def test_the_robot_slides_along_the_border_and_headings_wrap():
    body = Body((300, 200), 0.01, Pose(1.9, 0.5, math.pi / 4))
    body.step(1.0, 0.0, 1.0)
    assert body.pose.x == 2.0 and body.pose.y == pytest.approx(0.5 + math.sqrt(0.5))
    assert wrap_angle(3 * math.pi) == pytest.approx(math.pi) and wrap_angle(-math.pi) == math.pi
    with pytest.raises(ParameterError, match="outside the map"):
        Body((100, 200), 0.01, Pose(2.5, 0.5, 0.0))


def test_the_view_puts_the_heading_up_and_the_robots_right_on_the_right():
    image = np.zeros((300, 300, 3), np.uint8)
    image[150, 200] = 255  # 50 px east of the robot at (row 150, col 150)
    east = render_view(image, Pose(150.0, 150.0, 0.0), 1.0, (121, 81))
    assert np.argwhere(east[:, :, 0] > 100).tolist() == [[10, 40]]  # 50 px ahead: above the centre
    south = render_view(image, Pose(150.0, 150.0, math.pi / 2), 1.0, (121, 121))
    assert np.argwhere(south[:, :, 0] > 100).tolist() == [[60, 10]]  # facing south, east is on the left
    north = render_view(image, Pose(150.0, 150.0, -math.pi / 2), 1.0, (121, 121))
    assert np.argwhere(north[:, :, 0] > 100).tolist() == [[60, 110]]


def test_the_view_scales_with_metres_per_pixel_and_mirrors_beyond_the_border():
    image = np.zeros((100, 100, 3), np.uint8)
    image[:, :50] = 200
    view = render_view(image, Pose(0.5, 0.25, 0.0), 0.01, (20, 40))  # at row 25, col 50, facing east
    assert view.shape == (20, 40, 3)
    assert view[:9, :, 0].max() == 0 and view[11:, :, 0].min() == 200  # dark ahead (east), bright behind
    corner = render_view(image, Pose(0.0, 0.0, 0.0), 0.01, (41, 41))
    assert corner[20, 20, 0] == 200 and corner[:, :, 0].min() == 200  # mirrored: no black border
