"""The looping videos a person ranks (docs/person.md): each gait walked from its initial state, its last
``person.video_steps`` steps after the comfort figures' skipped transient, seen from the side and from the front side by
side — the cameras of the gait tiles (:data:`robustgait.report.tiles.VIEWS`), at the same distance and height for every
gait, following the pelvis forward only — as H.264 (yuv420p, ``+faststart``) MP4, which the Chromium of Debian plays."""

from __future__ import annotations

from pathlib import Path

import mujoco
import numpy as np

from robustgait.config import ComfortConfig, SimConfig
from robustgait.errors import RobustGaitError
from robustgait.gait import Gait
from robustgait.io.output import atomic_output
from robustgait.report.tiles import VIEWS
from robustgait.robots import Robot
from robustgait.sim.walk import offscreen_renderer, scene_option, walk

FPS = 20
WIDTH, HEIGHT = 288, 324  # one view; the video is two views wide
DISTANCE = 3.4  # m: the tiles' camera distance


def render_person_video(robot: Robot, gait: Gait, path: str | Path, steps: int, comfort: ComfortConfig,
                        sim: SimConfig | None = None) -> int:
    """Walk ``gait`` for ``comfort.skip_steps`` + ``steps`` steps and write the last ``steps`` of them, side | front,
    to ``path`` (.mp4); returns the number of frames."""
    import imageio.v2 as imageio

    res = walk(robot, gait, sim, steps=comfort.skip_steps + steps, keep_trajectory=True)
    if res.trajectory is None or res.fell or len(res.events) < comfort.skip_steps + steps:
        raise RobustGaitError(f"the gait fell ({res.fall_reason}) after {res.steps_taken} steps: no video")
    t0 = res.events[comfort.skip_steps - 1].time if comfort.skip_steps > 0 else 0.0
    tr = res.trajectory
    seg = tr[tr[:, 0] > t0 - 1e-9]
    every = max(1, round(1.0 / (FPS * robot.dt)))
    m = robot.model
    data = mujoco.MjData(m)
    renderer = offscreen_renderer(robot, WIDTH, HEIGHT)
    option = scene_option(robot)
    count = 0
    try:
        with atomic_output(path, "video") as tmp, imageio.get_writer(
                tmp, fps=FPS, codec="libx264", pixelformat="yuv420p", macro_block_size=1,
                ffmpeg_params=["-movflags", "+faststart"]) as writer:
            for state in seg[::every]:
                mujoco.mj_setState(m, data, state, mujoco.mjtState.mjSTATE_FULLPHYSICS.value)
                mujoco.mj_forward(m, data)
                base = data.xpos[robot.base_body_id]
                views = []
                for _, azimuth in VIEWS:
                    cam = mujoco.MjvCamera()
                    cam.type = mujoco.mjtCamera.mjCAMERA_FREE
                    cam.lookat[:] = [base[0], 0.0, 0.9]  # follows the walk forward; height fixed for every gait
                    cam.distance, cam.elevation, cam.azimuth = DISTANCE, -5.0, azimuth
                    renderer.update_scene(data, cam, scene_option=option)
                    views.append(renderer.render().copy())
                writer.append_data(np.concatenate(views, axis=1))  # type: ignore[attr-defined]
                count += 1
    finally:
        renderer.close()
    return count
