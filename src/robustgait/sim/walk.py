"""Walking a gait in MuJoCo (``docs/simulation.md``): steps taken before a fall, speed, and the switching states.

Stability in the sense of the paper is the number of steps completed before a fall, up to a cap.
"""

from __future__ import annotations

import copy
import json
import math
from collections.abc import Callable, Generator, Iterable
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import mujoco
import numpy as np
from numpy.typing import NDArray

from robustgait.config import ComfortConfig, SimConfig
from robustgait.config.work import MAX_GIF_FRAMES, MAX_VIDEO_PHYSICS_STEPS, Work, check_gif, check_work
from robustgait.errors import RobustGaitError, input_error
from robustgait.gait import Gait
from robustgait.io.output import atomic_output, check_output
from robustgait.robots import Robot
from robustgait.rotations import quat_to_mat
from robustgait.sim.comfort import Comfort, ComfortRecorder, measure
from robustgait.sim.controller import TrackingStats, pd_tracking
from robustgait.sim.engine import StepEngine, step_physics_steps
from robustgait.sim.factory import make_engine


@dataclass(frozen=True)
class SwitchEvent:
    """State of step ``step`` (1-based) at the end of its single support (touchdown or heel strike: the
    pre-impact state on the Poincaré section; for a flat-foot gait the end of the step); ``stance`` is the
    stance leg of that step, ``time`` and ``tau`` the time of the event and its phase in single support.
    qpos/qvel in MuJoCo's convention."""

    step: int
    time: float
    stance: str
    tau: float
    qpos: list[float]
    qvel: list[float]


@dataclass
class WalkResult:
    """Outcome of a walk: ``steps_taken`` completed steps (≤ cap); ``fell`` and ``fall_reason`` (one of
    :data:`robustgait.sim.engine.FALL_REASONS`, None if the cap was reached); ``time`` [s] walked until the
    fall or the last switching event; ``mean_speed`` [m/s] = base displacement along the initial heading /
    time; ``min_base_height`` [m] over the whole walk; one :class:`SwitchEvent` per completed step; the tracking
    ``controller`` that ran (and ``controller_note``: why not the one asked for, if so) and its ``tracking`` over
    every physics step: RMS and largest |q − y_d| [rad] and the torque saturation (joint-steps whose commanded
    torque exceeded the limit, and their fraction; :class:`~robustgait.sim.controller.TrackingStats`); ``comfort``:
    what a passenger feels (:class:`~robustgait.sim.comfort.Comfort`) when the walk was asked for it and completed a
    measured step, else None; ``physics_steps`` simulated; ``regulator``: what the step regulator did
    (:meth:`~robustgait.sim.regulator.StepRegulator.summary`), None when it did not run; ``planned_speed`` [m/s] the
    gait's own step length / step duration (None for a gait without its parameters, a FROST import); ``sole_turn``
    [rad] the stance sole's turn about its lateral axis at the end of single support, toe up > 0
    (:func:`stance_sole_turn`), averaged over the steps (None without a completed step): the plan holds the stance
    sole flat, and a model's soft contacts can turn it under the plan's centre of pressure."""

    steps_taken: int
    fell: bool
    fall_reason: str | None
    time: float
    mean_speed: float
    min_base_height: float
    max_steps: int
    switching: str
    events: list[SwitchEvent] = field(default_factory=list)
    controller: str = "pd"
    controller_note: str = ""
    tracking: dict[str, float] = field(default_factory=dict)
    comfort: Comfort | None = None
    trajectory: NDArray[np.float64] | None = field(default=None, repr=False)
    physics_steps: int = 0
    regulator: dict[str, Any] | None = None
    planned_speed: float | None = None
    sole_turn: float | None = None

    def speed_note(self, tolerance: float) -> str:
        """:func:`speed_note` of this walk: "" for a walk that fell (its speed is the fall's) or a gait without a
        planned speed."""
        if self.fell or self.planned_speed is None:
            return ""
        return speed_note(self.mean_speed, self.planned_speed, tolerance, self.sole_turn)

    def to_dict(self) -> dict[str, Any]:
        out = asdict(self)
        out.pop("trajectory")
        return out

    def to_json(self) -> str:
        return json.dumps(self.to_dict(), allow_nan=False)


def speed_note(speed: float, plan: float, tolerance: float, sole_turn: float | None = None) -> str:
    """A one-line note when a walk does not go where its gait was planned to: its mean forward ``speed`` [m/s]
    differs from the ``plan`` (L / T, :func:`planned_speed`) by more than ``tolerance`` × the plan
    (``sim.speed_agreement``), or has the other sign; "" otherwise and for a plan ≤ 0. A walk can settle on an orbit
    and survive pushes while marching in place or backwards: the orbit rule and the certified figure do not see it,
    so ``gait generate``, ``walk`` and ``certify`` each say it. The note
    gives the stance sole's mean turn at the end of single support (``sole_turn`` [rad], :func:`mean_sole_turn`)
    when it is known: a sole the contacts turn leans the whole robot with it."""
    if plan <= 0.0 or abs(speed - plan) <= tolerance * plan:
        return ""
    way = "backwards, " if speed < 0.0 else ""
    turn = "" if sole_turn is None else (
        f"; its stance sole ends single support turned {math.degrees(abs(sole_turn)):.2f}° "
        f"{'toe up' if sole_turn >= 0.0 else 'toe down'} on average, where the plan holds it flat "
        "(docs/robots.md: soft contacts turn a sole)")
    return (f"the walk advances {way}{speed:.3f} m/s, {100 * speed / plan:.0f} % of the gait's planned {plan:.3f} m/s "
            f"(step length / step duration; sim.speed_agreement {tolerance:g}): it does not walk the gait as "
            f"planned{turn}")


def planned_speed(gait: Gait) -> float | None:
    """v = L / T [m/s], the gait's step length over its step duration (all its domains), None when the gait does not
    carry its parameters (a FROST import)."""
    if gait.params is None:
        return None
    return float(gait.params.step_length) / gait.step_duration


def stance_sole_turn(robot: Robot, data: mujoco.MjData, qpos: NDArray[np.float64], side: str) -> float:
    """θ = asin(x_s · e_z) [rad]: how far ``side``'s sole is turned about its lateral axis at configuration ``qpos``
    (nq,), x_s the sole's heel-to-toe axis in the world (:meth:`~robustgait.robots.solebox.SoleBox.world_frame`), toe
    up > 0. ``data`` is scratch (its kinematics are overwritten)."""
    data.qpos[:] = qpos
    mujoco.mj_kinematics(robot.model, data)
    return math.asin(float(np.clip(robot.sole_boxes[side].world_frame(data)[2, 0], -1.0, 1.0)))


def mean_sole_turn(robot: Robot, events: list[SwitchEvent]) -> float | None:
    """The mean of :func:`stance_sole_turn` [rad] of each step's stance sole at its switching event (the end of its
    single support), None without events."""
    if not events:
        return None
    data = mujoco.MjData(robot.model)
    return float(np.mean([stance_sole_turn(robot, data, np.asarray(e.qpos), e.stance) for e in events]))


def _heading(qpos: NDArray[np.float64]) -> NDArray[np.float64]:
    """Unit horizontal direction of the base's x axis (from the quaternion w, x, y, z)."""
    fwd = quat_to_mat(qpos[3:7])[:2, 0]
    return fwd / max(float(np.linalg.norm(fwd)), 1e-12)


def check_walk_work(robot: Robot, gait: Gait, config: SimConfig, steps: int, video: str | Path | None = None) -> Work:
    """Bound a walk of ``steps`` steps before it starts (:mod:`robustgait.config.work`): each step up to its
    :func:`~robustgait.sim.engine.step_horizons`; with a ``video`` (its path checked first), every state is kept:
    the absolute :data:`~robustgait.config.work.MAX_VIDEO_PHYSICS_STEPS` (and a .gif's frames,
    :data:`~robustgait.config.work.MAX_GIF_FRAMES`)."""
    work = Work(steps, step_physics_steps(gait, robot.dt, config))
    if video is not None:
        check_output(video, "video")
        check_work(work, None, robot.dt, f"{steps} steps (sim.step_cap) with a video", MAX_VIDEO_PHYSICS_STEPS)
        if Path(video).suffix.lower() == ".gif":
            check_gif(work.physics_steps * robot.dt, str(video))
    else:
        defaults = Work(SimConfig().step_cap, step_physics_steps(gait, robot.dt, SimConfig()))
        check_work(work, defaults, robot.dt, f"{steps} steps (sim.step_cap)")
    return work


@dataclass
class _Run:
    """A walk's state between its steps: the state (1, nq), (1, nv), lowest base height [m], the last finite
    configuration (nq,), time [s], recorded trajectory chunks, whether and why it fell, physics steps so far."""

    qpos: NDArray[np.float64]
    qvel: NDArray[np.float64]
    min_z: float
    last: NDArray[np.float64]
    t: float = 0.0
    chunks: list[NDArray[np.float64]] = field(default_factory=list)
    fell: bool = False
    reason: str | None = None
    physics: int = 0


def _take_step(eng: StepEngine, run: _Run, i: int, stance: str, stats: TrackingStats,
               recorder: ComfortRecorder | None, keep_trajectory: bool) -> SwitchEvent | None:
    """Step ``i`` (0-based) of a walk on ``stance``: its domains in order from ``run``'s state (updated in place).
    Returns its switching event (the state at the end of domain 0: the Poincaré section), None when it fell."""
    section: SwitchEvent | None = None
    for d in range(len(eng.graph)):
        start_state = eng.full_states(run.qpos, run.qvel)[0]
        batch = eng.step(run.qpos, run.qvel, stance, domain=d, record=True)
        run.physics += batch.physics_steps
        tr = batch.trajectory[0]
        _track(stats, eng, batch, start_state, tr, stance, d)
        if recorder is not None:
            recorder.add(i + 1, d, stance, start_state, tr, batch.controls[0])
        if tr.size:
            run.min_z = min(run.min_z, float(np.nanmin(tr[:, 3])))
            if keep_trajectory:
                tr = tr.copy()
                tr[:, 0] += run.t
                run.chunks.append(tr)
        run.t += float(batch.duration[0])
        if batch.fell[0]:
            run.fell, run.reason = True, batch.fall_reason[0]
            finite = tr[np.isfinite(tr).all(axis=1)]
            run.last = finite[-1, 1:1 + eng.nq] if finite.size else run.last
            return None
        run.qpos, run.qvel = batch.qpos, batch.qvel
        run.last = run.qpos[0]
        if d == 0:
            section = SwitchEvent(i + 1, run.t, stance, float(batch.tau[0]), run.qpos[0].tolist(),
                                  run.qvel[0].tolist())
    assert section is not None
    return section


def walk(robot: Robot, gait: Gait, config: SimConfig | None = None, *, steps: int | None = None,
         keep_trajectory: bool = False, video: str | Path | None = None,
         engine: StepEngine | None = None, comfort: ComfortConfig | None = None,
         until: Callable[[list[SwitchEvent]], bool] | None = None,
         tracking: TrackingStats | None = None) -> WalkResult:
    """Walk ``gait`` from its initial state for up to ``steps`` steps (default ``config.step_cap``), switching
    stance at each event.

    A step runs the gait's domains in order (flat: single support; multi-contact: single support, then rolling
    double support); its :class:`SwitchEvent` is the state at the end of single support (touchdown or heel
    strike: the Poincaré section), and it counts as taken once all its domains are done.

    The trajectory (every physics step's full state, (n, nstate), MuJoCo's ``mjSTATE_FULLPHYSICS`` layout,
    time continuing across steps) is kept when ``keep_trajectory`` or ``video`` (an ``.mp4`` or ``.gif`` path,
    rendered after the walk by :func:`render_video`). The work is bounded before anything runs
    (:func:`check_walk_work`; a video's stricter limits, the output path checked). The orbit its switching events
    settle on is the certificate's to say (:func:`robustgait.certificate.find_orbit` of a ``Walked``).
    ``until(events)``, called after each completed step, ends the walk early when it returns true (the orbit search
    stops where the switching states have settled).

    ``comfort``: measure what a passenger feels over the steps it names (:mod:`robustgait.sim.comfort`,
    ``WalkResult.comfort``); None: not measured.

    ``tracking``: the :class:`TrackingStats` this walk's tracking is added to (None: a fresh one). Passing one
    changes nothing in the walk or its result (``WalkResult.tracking`` is its ``summary()`` either way, so pass an
    empty one); it lets the caller read the per-joint totals (``saturation``, ``error_max``, ``rms``) afterwards.
    """
    config = config or SimConfig()
    steps = config.step_cap if steps is None else steps
    if steps < 1:
        raise RobustGaitError(f"steps must be ≥ 1, got {steps}")
    if gait.initial_state is None:
        raise RobustGaitError("the gait has no initial state to start walking from")
    check_walk_work(robot, gait, config, steps, video)
    if video is not None:
        keep_trajectory = True
    recorder = ComfortRecorder(comfort, robot.dt) if comfort is not None else None
    own = engine is None
    eng = engine or make_engine(robot, gait, config)
    stats = TrackingStats() if tracking is None else tracking
    try:
        first = eng.gaits[gait.stance].initial_state  # in the model's size (Gait.closed)
        assert first is not None
        start = first.qpos.copy()
        run = _Run(start[None].copy(), first.qvel[None].copy(), min_z=float(start[2]), last=start)
        heading = _heading(start)
        stance = gait.stance
        events: list[SwitchEvent] = []
        for i in range(steps):
            section = _take_step(eng, run, i, stance, stats, recorder, keep_trajectory)
            if section is None:
                break
            events.append(section)
            if recorder is not None:
                recorder.end_step(i + 1)
            stance = "left" if stance == "right" else "right"
            if until is not None and until(events):
                break
        disp = float(np.dot(run.last[:2] - start[:2], heading))
        t = run.t
        result = WalkResult(
            steps_taken=len(events), fell=run.fell, fall_reason=run.reason, time=t,
            mean_speed=disp / t if t > 0 else 0.0, min_base_height=run.min_z, max_steps=steps,
            switching=eng.config.switching, events=events,
            trajectory=np.concatenate(run.chunks) if keep_trajectory and run.chunks else None,
            controller=eng.controller_name, controller_note=eng.controller_note, tracking=stats.summary(),
            comfort=measure(robot, eng.physics_model, recorder, heading) if recorder is not None else None,
            physics_steps=run.physics, regulator=eng.regulator.summary() if eng.regulator is not None else None,
            planned_speed=planned_speed(gait), sole_turn=mean_sole_turn(robot, events))
    finally:
        if own:
            eng.close()
    if video is not None and result.trajectory is not None:
        render_video(robot, result.trajectory, video)
    return result


def _track(stats: TrackingStats, eng: StepEngine, batch: object, start: NDArray[np.float64],
           trajectory: NDArray[np.float64], stance: str, domain: int) -> None:
    """Add one domain's tracking to ``stats``: the feedback engine's own counts, or the servo PD's recomputed from
    the states the recorded steps started from (the step's start, then each recorded state but the last)."""
    from robustgait.sim.feedback import FeedbackStepBatch

    if isinstance(batch, FeedbackStepBatch):
        stats.add(int(batch.control_steps[0]), batch.saturation[0], batch.error_sq[0], batch.error_max[0])
        return
    before = np.vstack([start[None], trajectory[:-1]]) if trajectory.size else start[None]
    rows = np.flatnonzero(np.isfinite(before).all(axis=1))
    before = before[rows]
    controls = None
    if eng.regulator is not None:
        # the servos' references carry the regulator's corrections: their torque is the applied controls', whose row
        # j was applied from row j of ``before`` (a step that ended at once recorded none)
        recorded = batch.controls[0]  # type: ignore[attr-defined]
        controls = recorded[rows[rows < len(recorded)]]
    stats.add(*pd_tracking(eng.robot, eng.gaits[stance], before, domain, feedforward=eng.config.feedforward,
                           controls=controls))


def offscreen_renderer(robot: Robot, width: int, height: int, *, shadows: bool = True,
                       antialias: bool = True) -> mujoco.Renderer:
    """MuJoCo's offscreen renderer for the robot's model, width × height pixels, or a one-line RobustGaitError naming
    the fix. ``shadows``: the light's shadows and the floor's reflections (the model's own look; without them a frame
    drawn in software, EGL or OSMesa without a GPU, costs a fraction); ``antialias``: multisampling with the model's
    ``visual/quality/offsamples`` (without it: one sample a pixel, jagged edges, again a fraction of the cost). The
    offscreen buffer is enlarged to width × height when the model's ``visual/global`` one is smaller."""
    model = robot.model
    g = model.vis.global_
    if (not antialias and model.vis.quality.offsamples != 0) or width > g.offwidth or height > g.offheight:
        model = copy.copy(model)  # read when the context is made: on a copy, the robot's model is left as it is
        model.vis.global_.offwidth = max(width, g.offwidth)
        model.vis.global_.offheight = max(height, g.offheight)
        if not antialias:
            model.vis.quality.offsamples = 0
    try:
        renderer = mujoco.Renderer(model, height, width)
    except Exception as exc:  # the GL backends raise a variety of errors when no context can be made
        raise RobustGaitError(
            f"offscreen rendering unavailable ({type(exc).__name__}: {exc}); MuJoCo needs EGL or OSMesa: set "
            "MUJOCO_GL=egl or MUJOCO_GL=osmesa and install libegl1 or libosmesa6") from None
    if not shadows:
        for flag in (mujoco.mjtRndFlag.mjRND_SHADOW, mujoco.mjtRndFlag.mjRND_REFLECTION):
            renderer.scene.flags[flag] = False
    return renderer


def pose_for_drawing(model: mujoco.MjModel, data: mujoco.MjData) -> None:
    """Compute from ``data``'s qpos what a frame draws, and no more: the bodies' and geoms' poses, the centre of mass
    a tracking camera follows, the cameras and lights, the tendons' paths (no dynamics, no contacts: those are not
    drawn); a model with flexible bodies gets the whole ``mj_forward``."""
    if model.nflex:
        mujoco.mj_forward(model, data)
        return
    mujoco.mj_kinematics(model, data)
    mujoco.mj_comPos(model, data)
    mujoco.mj_camlight(model, data)
    if model.ntendon:
        mujoco.mj_tendon(model, data)


def scene_option(robot: Robot) -> mujoco.MjvOption:
    """The visualization option of every rendering of the robot: MuJoCo's default (geom groups 0–2 shown), plus every
    group the robot's geoms are in when none of them is visible in 0–2 — a model stripped of its visual meshes
    keeps only collision geoms, which Menagerie puts in group 3 (Booster T1): without this the video shows the floor
    alone."""
    m = robot.model
    opt = mujoco.MjvOption()
    own = (m.geom_bodyid > 0) & (m.geom_rgba[:, 3] > 0)
    shown = own & (m.geom_group < 3)
    if own.any() and not shown.any():
        for g in np.unique(m.geom_group[own]):
            if 0 <= g < len(opt.geomgroup):
                opt.geomgroup[int(g)] = 1
    return opt


def video_frames(robot: Robot, trajectory: NDArray[np.float64], *, fps: int = 30, width: int = 640, height: int = 480,
                 shadows: bool = True, antialias: bool = True) -> Generator[NDArray[np.uint8], None, None]:
    """The frames of a trajectory (full-physics states, as kept by :func:`walk`, one per physics step of
    ``robot.dt``): every ``round(1 / (fps · dt))``-th state from the first, up to the first non-finite one, each
    (height, width, 3) RGB drawn by :func:`offscreen_renderer` (``shadows``, ``antialias``) from a camera tracking
    the base at 3 m, 15° above, from the front left. The renderer is made on the first frame and freed when the
    iteration ends."""
    every = max(1, round(1.0 / (fps * robot.dt)))
    renderer = offscreen_renderer(robot, width, height, shadows=shadows, antialias=antialias)
    option = scene_option(robot)
    m = robot.model
    data = mujoco.MjData(m)
    cam = mujoco.MjvCamera()
    cam.type = mujoco.mjtCamera.mjCAMERA_TRACKING
    cam.trackbodyid = robot.base_body_id
    cam.distance, cam.elevation, cam.azimuth = 3.0, -15.0, 120.0
    try:
        for state in trajectory[::every]:
            if not np.isfinite(state).all():
                break
            mujoco.mj_setState(m, data, state, mujoco.mjtState.mjSTATE_FULLPHYSICS.value)
            pose_for_drawing(m, data)
            renderer.update_scene(data, cam, scene_option=option)
            yield renderer.render()
    finally:
        renderer.close()


def write_video(frames: Iterable[NDArray[np.uint8]], path: str | Path, fps: int) -> int:
    """Write ``frames`` ((height, width, 3) RGB, all of one size) to ``path``, played at ``fps`` frames a second: an
    ``.mp4`` (H.264, yuv420p, CRF 25 with x264's ``veryfast`` preset, its index first — ``+faststart`` — so that a
    browser plays it as it loads) or an animated ``.gif`` (256 colours, looping). Returns the number of frames
    written; through :func:`robustgait.io.output.atomic_output` (checked target, atomic)."""
    import imageio.v2 as imageio
    from PIL import Image

    path = check_output(path, "video")
    count = 0
    with atomic_output(path, "video") as tmp:
        if path.suffix.lower() == ".gif":  # Pillow's fast octree quantizer: imageio's GIF path is far slower
            images = [Image.fromarray(f).quantize(colors=256, method=Image.Quantize.FASTOCTREE) for f in frames]
            count = len(images)
            if images:
                images[0].save(tmp, format="GIF", save_all=True, append_images=images[1:],
                               duration=round(1000 / fps), loop=0)
        else:
            with imageio.get_writer(tmp, fps=fps, codec="libx264", pixelformat="yuv420p", macro_block_size=1,
                                    ffmpeg_params=["-preset", "veryfast", "-movflags", "+faststart"]) as writer:
                for frame in frames:
                    writer.append_data(frame)  # type: ignore[attr-defined]
                    count += 1
    return count


def render_video(robot: Robot, trajectory: NDArray[np.float64], path: str | Path, *, fps: int = 30,
                 width: int = 640, height: int = 480, shadows: bool = True, antialias: bool = True) -> int:
    """Render a trajectory (full-physics states, as kept by :func:`walk`) to an ``.mp4`` or an animated ``.gif``
    (:func:`write_video`; a .gif at half the size, at most :data:`~robustgait.config.work.MAX_GIF_FRAMES` frames:
    GIFs are big) of ``fps`` frames a second, width × height pixels, with MuJoCo's offscreen renderer (EGL or
    OSMesa, chosen by ``MUJOCO_GL``; :func:`video_frames`: ``shadows`` and ``antialias`` as in
    :func:`offscreen_renderer`). Returns the number of frames written."""
    path = check_output(path, "video")
    if path.suffix.lower() == ".gif":
        width, height = width // 2, height // 2
        every = max(1, round(1.0 / (fps * robot.dt)))
        n_frames = -(-len(trajectory) // every)
        if n_frames > MAX_GIF_FRAMES:
            raise input_error(path, f"{n_frames} frames, over the {MAX_GIF_FRAMES} a .gif may hold (use .mp4)")
    frames = video_frames(robot, trajectory, fps=fps, width=width, height=height, shadows=shadows,
                          antialias=antialias)
    try:
        return write_video(frames, path, fps)
    finally:
        frames.close()  # the renderer is freed even when writing failed
