"""Gait tiles (the paper's Fig. 6): frames of one step side by side, the robot seen from the side (top row)
and from the front (bottom row), rendered with MuJoCo's offscreen renderer."""

from __future__ import annotations

from pathlib import Path

import mujoco
import numpy as np
from numpy.typing import NDArray

from robustgait.config import ReportConfig, SimConfig
from robustgait.errors import RobustGaitError
from robustgait.gait import Gait
from robustgait.io.output import atomic_output, check_output
from robustgait.robots import Robot
from robustgait.sim.walk import offscreen_renderer, pose_for_drawing, scene_option, walk

# camera azimuths [deg] of the two rows: MuJoCo's free camera at azimuth 90 looks along +y (it sees the
# robot's right side; the robot walks to the right of the image), at 180 along −x (the robot walks towards it)
VIEWS = (("side", 90.0), ("front", 180.0))


def step_frames(robot: Robot, gait: Gait, frames: int, warmup_steps: int,
                sim: SimConfig | None = None) -> NDArray[np.float64]:
    """Full-physics states (frames, nstate) equally spaced in time over one step, from its first to its last
    physics step, after ``warmup_steps`` steps from the gait's initial state (to be on the periodic orbit)."""
    res = walk(robot, gait, sim, steps=warmup_steps + 1, keep_trajectory=True)
    if res.fell or res.trajectory is None or len(res.events) < warmup_steps + 1:
        raise RobustGaitError(f"the gait fell ({res.fall_reason}) after {res.steps_taken} steps: no step to draw")
    t0 = res.events[warmup_steps - 1].time if warmup_steps > 0 else 0.0
    t1 = res.events[warmup_steps].time
    tr = res.trajectory
    seg = tr[(tr[:, 0] > t0 - 1e-9) & (tr[:, 0] <= t1 + 1e-9)]
    idx = np.round(np.linspace(0, seg.shape[0] - 1, frames)).astype(int)
    return np.asarray(seg[idx])


def render_tiles(robot: Robot, gait: Gait, path: str | Path, config: ReportConfig | None = None,
                 sim: SimConfig | None = None, *, width: int = 320, height: int = 480,
                 distance: float = 3.4) -> tuple[int, int]:
    """Write a PNG of ``config.tile_frames`` frames of one step (columns), after ``config.tile_warmup_steps``
    steps, seen from the side and from the front (rows); each tile is width × height pixels, the camera follows
    the base. Returns the image's (height, width)."""
    import imageio.v2 as imageio

    config = config or ReportConfig()
    check_output(path, "plot")
    if width < 16 or height < 16:
        raise RobustGaitError("tiles need at least 16 × 16 pixels")
    states = step_frames(robot, gait, config.tile_frames, config.tile_warmup_steps, sim)
    m = robot.model
    data = mujoco.MjData(m)
    renderer = offscreen_renderer(robot, width, height)
    option = scene_option(robot)
    rows = []
    try:
        for _, azimuth in VIEWS:
            row = []
            for state in states:
                mujoco.mj_setState(m, data, state, mujoco.mjtState.mjSTATE_FULLPHYSICS.value)
                pose_for_drawing(m, data)
                cam = mujoco.MjvCamera()
                cam.type = mujoco.mjtCamera.mjCAMERA_FREE
                base = data.xpos[robot.base_body_id]
                cam.lookat[:] = [base[0], base[1], 0.95 * base[2]]  # the middle of a standing person
                cam.distance, cam.elevation, cam.azimuth = distance, -5.0, azimuth
                renderer.update_scene(data, cam, scene_option=option)
                row.append(renderer.render().copy())
            rows.append(np.concatenate(row, axis=1))
    finally:
        renderer.close()
    image = np.concatenate(rows, axis=0)
    with atomic_output(path, "plot") as tmp:
        imageio.imwrite(tmp, image, format="png")
    return int(image.shape[0]), int(image.shape[1])
