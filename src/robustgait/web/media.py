"""The looping videos a person ranks (docs/person.md): each gait walked from its initial state, its last
``person.video_steps`` steps after the comfort figures' skipped transient, seen from the side and from the front side by
side — the cameras of the gait tiles (:data:`robustgait.report.tiles.VIEWS`), at the same distance and height for every
gait, following the pelvis forward only — as H.264 (yuv420p, ``+faststart``) MP4, which the Chromium of Debian plays.

:class:`GaitVideos`: where a study's videos are (``gaits/<label>/person.mp4``), which of a batch's are rendered, and
rendering those a batch shows."""

from __future__ import annotations

import logging
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import mujoco
import numpy as np
from numpy.typing import NDArray

from robustgait.config import ComfortConfig, PersonConfig, SimConfig
from robustgait.errors import RobustGaitError
from robustgait.gait import Gait
from robustgait.io.studyfile import StudySetup
from robustgait.learn.space import ActionSpace
from robustgait.robots import Robot
from robustgait.sim.walk import offscreen_renderer, pose_for_drawing, scene_option, walk, write_video
from robustgait.study.run import GAITS_DIR, gait_label
from robustgait.web.records import StudyRecords
from robustgait.web.view import gait_names

LOG = logging.getLogger("robustgait.web")
VIDEO_FILE = "person.mp4"

DISTANCE = 3.4  # m: the tiles' camera distance


def render_person_video(robot: Robot, gait: Gait, path: str | Path, steps: int, comfort: ComfortConfig,
                        sim: SimConfig | None = None, person: PersonConfig | None = None) -> int:
    """Walk ``gait`` for ``comfort.skip_steps`` + ``steps`` steps and write the last ``steps`` of them, side | front,
    to ``path`` (.mp4, :func:`~robustgait.sim.walk.write_video`) with the video settings of ``person`` (default
    :class:`PersonConfig`): ``video_fps`` frames a second, each (``video_height``, 2 × ``video_width``, 3), drawn
    with ``video_shadows`` and ``video_antialias`` (:func:`~robustgait.sim.walk.offscreen_renderer`); returns the
    number of frames."""
    from robustgait.report.tiles import VIEWS  # here: the report package is loaded by the first video only

    person = person or PersonConfig()
    res = walk(robot, gait, sim, steps=comfort.skip_steps + steps, keep_trajectory=True)
    if res.trajectory is None or res.fell or len(res.events) < comfort.skip_steps + steps:
        raise RobustGaitError(f"the gait fell ({res.fall_reason}) after {res.steps_taken} steps: no video")
    t0 = res.events[comfort.skip_steps - 1].time if comfort.skip_steps > 0 else 0.0
    tr = res.trajectory
    seg = tr[tr[:, 0] > t0 - 1e-9]
    every = max(1, round(1.0 / (person.video_fps * robot.dt)))
    renderer = offscreen_renderer(robot, person.video_width, person.video_height, shadows=person.video_shadows,
                                  antialias=person.video_antialias)
    option = scene_option(robot)
    m = robot.model
    data = mujoco.MjData(m)
    cameras = []
    for _, azimuth in VIEWS:
        cam = mujoco.MjvCamera()
        cam.type = mujoco.mjtCamera.mjCAMERA_FREE
        cam.distance, cam.elevation, cam.azimuth = DISTANCE, -5.0, azimuth
        cameras.append(cam)

    def frames() -> Iterator[NDArray[np.uint8]]:
        for state in seg[::every]:
            mujoco.mj_setState(m, data, state, mujoco.mjtState.mjSTATE_FULLPHYSICS.value)
            pose_for_drawing(m, data)
            views = []
            for cam in cameras:  # follows the walk forward; height fixed for every gait
                cam.lookat[:] = [data.xpos[robot.base_body_id][0], 0.0, 0.9]
                renderer.update_scene(data, cam, scene_option=option)
                views.append(renderer.render().copy())
            yield np.concatenate(views, axis=1)

    try:
        return write_video(frames(), path, person.video_fps)
    finally:
        renderer.close()


class GaitVideos:
    """The looping videos of one study's gaits, one per grid point: ``path`` says where, :meth:`prepare` and
    :meth:`render_ahead` render them (:func:`render_person_video`), ``errors`` keeps why a shown gait has none.

    ``errors``: ``(iteration, slot) -> "ExceptionType: message"`` for each shown gait whose video could not be made;
    the page shows the line in place of the video."""

    def __init__(self, directory: Path, space: ActionSpace, records: StudyRecords):
        self.directory = directory
        self.space = space
        self.records = records
        self.errors: dict[tuple[int, int], str] = {}
        self._robot: Robot | None = None

    def path(self, index: int) -> Path:
        """Where the looping video of grid point ``index`` is rendered."""
        return self.directory / GAITS_DIR / gait_label(self.space, index) / VIDEO_FILE

    def shown(self, k: int, slot: int) -> Path | None:
        """The rendered video of iteration k's gait in ``slot`` when the page shows that gait (None: no such trial, a
        hidden gait, or no video rendered)."""
        rec, batch = self.records.batch(k)
        r = next((t for t in batch if t.slot == slot), None)
        shown = rec.get("pending", {}).get("shown", [])
        if r is None or slot not in shown or not self.path(r.index).is_file():
            return None
        return self.path(r.index)

    def prepare(self, k: int, setup: StudySetup) -> None:
        """Render the videos of iteration k's shown gaits that are not rendered yet (a video that cannot be made: the
        gait is shown without one, and ``errors`` says why). A shown gait whose evaluation has no gait file is a
        :class:`RobustGaitError`."""
        rec, batch = self.records.batch(k)
        t0, rendered = time.perf_counter(), 0
        for r in batch:
            if r.slot not in rec.get("pending", {}).get("shown", []) or self.path(r.index).is_file():
                continue
            gait_file = (self.records.source(r).result or {}).get("gait_file")
            if gait_file is None:
                raise RobustGaitError(f"trial {r.number}: a shown gait without a gait file")
            try:
                self.render(r.index, gait_file, setup)
                rendered += 1
            except Exception as exc:  # no offscreen GL, a gait that falls in the video's walk: shown without video
                self.errors[(k, r.slot)] = f"{type(exc).__name__}: {exc}"
                LOG.warning("iteration %d, gait %s: no video (%s)", k + 1, gait_names(r.slot + 1)[-1],
                            self.errors[(k, r.slot)])
        if rendered:
            LOG.info("iteration %d: %d videos rendered in %.1f s", k + 1, rendered, time.perf_counter() - t0)

    def render_ahead(self, index: int, result: dict[str, Any], setup: StudySetup) -> None:
        """Render the video of grid point ``index``, evaluated ahead of an answer (``result``: its evaluation as the
        study stores it), unless it has no gait file or is rendered already; a video that cannot be made is logged
        and left to :meth:`prepare`. Never raises."""
        gait_file = result.get("gait_file")
        if gait_file is None or self.path(index).is_file():
            return
        try:
            self.render(index, gait_file, setup)
        except Exception as exc:
            LOG.info("a gait evaluated ahead has no video yet (%s: %s)", type(exc).__name__, exc)

    def render(self, index: int, gait_file: str, setup: StudySetup) -> None:
        """Render grid point ``index``'s video from its gait file (relative to the study directory), with the
        robot of ``setup`` (loaded once) and its ``person.video_steps``, ``comfort`` and ``sim``; raises whatever
        loading or :func:`render_person_video` raises."""
        from robustgait.io.gaitfile import load_gait
        from robustgait.io.robotfile import load_robot

        if self._robot is None:
            self._robot = load_robot(setup.robot)
        cfg = setup.config
        gait = load_gait(self.directory / gait_file, self._robot)
        render_person_video(self._robot, gait, self.path(index), cfg.person.video_steps, cfg.comfort, cfg.sim,
                            cfg.person)
