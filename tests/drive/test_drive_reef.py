"""On the reef, curiosity draws the simulated robot to coral (paper 5.2, scenario 1).

The driver's own dry-run loop (lockstep simulated robot, simulated camera, the paper's
parameters from configs/paper-grid.yaml) against random walkers: the same robot, camera
and controller, but a target cell drawn uniformly at random every frame. Both start
from the same eight poses (fixed seeds); the measure is the fraction of frames the robot
spends over coral-like classes (coral heads and sponges).

Stated margin: averaged over the eight starts, the curious robot's fraction is at least
1.5 times the random walkers' (measured when the newest frame got its share of the budget
for certain, issue 45: 0.27 against 0.14 for 250 frames: 0.10, 0.10, 0.20, 0.46, 0.61,
0.11, 0.33, 0.26 against 0.06, 0.25, 0.07, 0.26, 0.19, 0.17, 0.02, 0.09). One start says
little: a start's fraction runs from 0.03 to 0.71. This test had three starts, where a coin
per refinement pick read 0.22, 0.06, 0.42 and the share 0.10, 0.10, 0.20 (1.05 times the
walkers'); over twelve starts the two are alike, 0.29 and 0.28 against 0.15.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from curiosity_cli.config import CONFIG_DIR, load_config
from curiosity_cli.maps.map_data import load_map
from curiosity_cli.drive.camera import LockstepRobot, SimCamera
from curiosity_cli.drive.controller import steer
from curiosity_cli.drive.driver import Outputs, StopRequest, run
from curiosity_cli.drive.jsonlines import JsonLines
from curiosity_cli.drive.pipeline import CuriosityPipeline
from curiosity_cli.drive.sim import Body, Pose

FRAMES = 250
STARTS = tuple(range(8))
WALKERS = 20
MARGIN = 1.5
CORAL_LIKE = ("coral", "sponge")


def start_pose(seed: int, size_m: float) -> Pose:
    rng = np.random.default_rng([seed, 7])
    low, high = 0.2 * size_m, 0.8 * size_m
    return Pose(rng.uniform(low, high), rng.uniform(low, high), rng.uniform(-math.pi, math.pi))


def fraction_over(mask: np.ndarray, poses: list[Pose], mpp: float) -> float:
    rows = np.clip([int(p.y / mpp) for p in poses], 0, mask.shape[0] - 1)
    cols = np.clip([int(p.x / mpp) for p in poses], 0, mask.shape[1] - 1)
    return float(mask[rows, cols].mean())


@pytest.mark.slow
def test_the_curious_robot_spends_more_time_over_coral_than_a_random_walker(tmp_path):
    config = load_config(CONFIG_DIR / "paper-grid.yaml")
    d = config.drive
    reef = load_map("reef-mosaic")
    ids = [c.id for c in reef.legend if c.name in CORAL_LIKE]
    assert len(ids) == 2
    coral = np.isin(reef.labels, ids)
    size_m = reef.image.shape[0] * d.sim_metres_per_pixel
    grid = (d.grid_rows, d.grid_cols)

    curious, random = [], []
    for seed in STARTS:
        robot = LockstepRobot(Body(reef.image.shape[:2], d.sim_metres_per_pixel, start_pose(seed, size_m)), d.sim_frame_interval)
        camera = SimCamera(reef.image, d.sim_metres_per_pixel, (d.sim_view_rows, d.sim_view_cols), robot, 0.0, 1.0)
        poses = []
        log = JsonLines(tmp_path / f"log-{seed}.jsonl")
        run(
            CuriosityPipeline(config, seed), camera, robot, Outputs(tmp_path, None, 0), log,
            max_frames=FRAMES, stop=StopRequest(), on_frame=lambda n, decision: poses.append(robot.body.pose),
        )
        log.close()
        curious.append(fraction_over(coral, poses, d.sim_metres_per_pixel))

        walks = []
        for walker in range(WALKERS):
            rng = np.random.default_rng([seed, 8, walker])
            body = Body(reef.image.shape[:2], d.sim_metres_per_pixel, start_pose(seed, size_m))
            poses = []
            for _ in range(FRAMES):
                command = steer((int(rng.integers(grid[0])), int(rng.integers(grid[1]))), grid, d)
                body.step(command.surge, command.yaw_rate, d.sim_frame_interval)
                poses.append(body.pose)
            walks.append(fraction_over(coral, poses, d.sim_metres_per_pixel))
        random.append(float(np.mean(walks)))

    summary = f"curious {np.round(curious, 3).tolist()}, random walkers {np.round(random, 3).tolist()}"
    assert np.mean(curious) >= MARGIN * np.mean(random), summary
