"""What a passenger feels: the comfort figures of a walk (``docs/comfort.md``).

A walk (:func:`robustgait.sim.walk.walk` with a :class:`~robustgait.config.ComfortConfig`) hands the physics steps of
the steps it measures — every full-physics state (MuJoCo's ``mjSTATE_FULLPHYSICS``) and the controls that produced
it — to a :class:`ComfortRecorder`; :func:`measure` turns them into one :class:`Comfort`. Each figure is one function
below with its formula, unit and window; :data:`FIGURES` names every figure with its unit (what the CLI, the study
report and anything built on the figures iterate over).

Window: whole steps ``skip_steps`` + 1 … ``skip_steps`` + ``steps`` of the walk (1-based; the first steps are the
transient from the gait's initial state), or those of them the walk completed. The pelvis is the robot's floating
base (for ``exo`` the exoskeleton's pelvis carrying the passenger's trunk); its acceleration is kinematic — gravity
is not in it (an accelerometer would read a − g).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, fields
from typing import Any

import mujoco
import numpy as np
from numpy.typing import NDArray

from robustgait.config import ComfortConfig
from robustgait.errors import RobustGaitError
from robustgait.robots import Robot
from robustgait.rotations import roll_pitch_yaw

FloatArray = NDArray[np.float64]
_FULL = mujoco.mjtState.mjSTATE_FULLPHYSICS.value
AXES = ("forward", "lateral", "vertical")

# every figure of a Comfort: name → (unit, what it is; the unit '' for a dimensionless figure); the per-joint torques
# are dicts joint → N m
FIGURES: dict[str, tuple[str, str]] = {
    "speed": ("m/s", "forward speed of the pelvis over the measured steps"),
    "step_length": ("m", "forward distance per step"),
    "cadence": ("steps/min", "steps per minute"),
    **{f"pelvis_acc_{a}_{s}": ("m/s²", f"{a} pelvis acceleration, {s.upper()} (gravity excluded, low-passed)")
       for s in ("rms", "peak") for a in AXES},
    **{f"pelvis_jerk_{a}_{s}": ("m/s³", f"{a} pelvis jerk, {s.upper()} (of the low-passed acceleration)")
       for s in ("rms", "peak") for a in AXES},
    "torque_rms": ("N m", "joint torque RMS over the servoed joints (planned and held) and the measured physics steps"),
    "torque_peak": ("N m", "largest |joint torque|"),
    "cost_of_transport": ("", "mechanical cost of transport Σ|τ·q̇| dt / (m g d)"),
    "impact_force": ("N", "largest peak normal force of a landing sole after touchdown"),
    "impact_force_ratio": ("body weights", "impact_force / (m g)"),
    "touchdown_speed": ("m/s", "largest speed of a landing sole at touchdown"),
    "touchdown_vertical_speed": ("m/s", "largest downward speed of a landing sole at touchdown"),
    "pelvis_roll_excursion": ("rad", "largest per-step range (max − min) of the pelvis roll"),
    "pelvis_pitch_excursion": ("rad", "largest per-step range (max − min) of the pelvis pitch"),
}


@dataclass(frozen=True)
class Comfort:
    """The comfort figures of one walk (:data:`FIGURES` for units; ``docs/comfort.md`` for the definitions).

    ``first_step``/``steps``: the measured steps (1-based first, count); ``duration`` [s] their time;
    ``touchdowns``: touchdowns whose impact was measured. ``cost_of_transport`` is None when the pelvis did not move
    forward; the impact and touchdown figures are None when no touchdown's window lies within the walk.
    ``torque_rms_joint``/``torque_peak_joint``: per servoed joint [N m] (the planned joints, then the held ones)."""

    first_step: int
    steps: int
    duration: float
    speed: float
    step_length: float
    cadence: float
    pelvis_acc_forward_rms: float
    pelvis_acc_lateral_rms: float
    pelvis_acc_vertical_rms: float
    pelvis_acc_forward_peak: float
    pelvis_acc_lateral_peak: float
    pelvis_acc_vertical_peak: float
    pelvis_jerk_forward_rms: float
    pelvis_jerk_lateral_rms: float
    pelvis_jerk_vertical_rms: float
    pelvis_jerk_forward_peak: float
    pelvis_jerk_lateral_peak: float
    pelvis_jerk_vertical_peak: float
    torque_rms: float
    torque_peak: float
    torque_rms_joint: dict[str, float]
    torque_peak_joint: dict[str, float]
    cost_of_transport: float | None
    touchdowns: int
    impact_force: float | None
    impact_force_ratio: float | None
    touchdown_speed: float | None
    touchdown_vertical_speed: float | None
    pelvis_roll_excursion: float
    pelvis_pitch_excursion: float

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)

    def text(self) -> list[str]:
        """The figures as a few lines of text (``robustgait walk``)."""
        def pair(kind: str) -> str:
            return ", ".join(f"{ax} {getattr(self, f'pelvis_{kind}_{ax}_rms'):.3g}/"
                             f"{getattr(self, f'pelvis_{kind}_{ax}_peak'):.3g}" for ax in AXES)

        cot = "undefined (no forward progress)" if self.cost_of_transport is None else f"{self.cost_of_transport:.3g}"
        last = self.first_step + self.steps - 1
        lines = [f"comfort over steps {self.first_step}–{last}: speed {self.speed:.3f} m/s, step length "
                 f"{self.step_length:.3f} m, cadence {self.cadence:.1f} steps/min",
                 f"  pelvis acceleration RMS/peak [m/s²]: {pair('acc')}",
                 f"  pelvis jerk RMS/peak [m/s³]: {pair('jerk')}",
                 f"  pelvis roll/pitch excursion {math.degrees(self.pelvis_roll_excursion):.2f}/"
                 f"{math.degrees(self.pelvis_pitch_excursion):.2f} deg; joint torque RMS {self.torque_rms:.3g} N m, "
                 f"peak {self.torque_peak:.3g} N m; cost of transport {cot}"]
        if self.impact_force is not None and self.impact_force_ratio is not None:
            lines.append(f"  touchdown ({self.touchdowns}): impact force {self.impact_force:.4g} N "
                         f"({self.impact_force_ratio:.2f} body weights), landing sole speed {self.touchdown_speed:.3f} "
                         f"m/s ({self.touchdown_vertical_speed:.3f} m/s down)")
        return lines

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> Comfort:
        """From :meth:`to_dict` (keys it does not know are ignored, so stored figures of a later version load)."""
        return cls(**{f.name: d[f.name] for f in fields(cls)})


# ------------------------------------------------------------------------------------------------- the figures
def check_cutoff(cutoff: float, dt: float) -> None:
    """A one-line error unless 0 < ``cutoff`` < the Nyquist frequency 1/(2Δt) of the physics rate."""
    nyquist = 0.5 / dt
    if not 0.0 < cutoff < nyquist:
        raise RobustGaitError(f"comfort.cutoff: {cutoff:g} Hz is not below the Nyquist frequency {nyquist:g} Hz of "
                              f"the {dt:g} s timestep")


def lowpass(x: FloatArray, dt: float, cutoff: float, order: int) -> FloatArray:
    """Zero-phase Butterworth low-pass of ``x`` (n, ...) along axis 0, sampled every ``dt`` [s]: each frequency f is
    scaled by the squared magnitude of an order-N Butterworth filter with its −3 dB point at ``cutoff`` f_c [Hz],

        |H(f)|² = 1 / (1 + (f / f_c)^{2N})

    — what the filter run forward and backward does (``scipy.signal.filtfilt``: no phase lag, −6 dB at f_c), without
    the bilinear transform's warping (< 0.2 % in f at f_c ≤ 20 Hz and 1 kHz). Applied with NumPy's FFT to the signal
    extended at both ends by its odd reflection (2 x₀ − x_k) and less the straight line through the extension's ends
    (added back after), so that the FFT's wrap-around joins the ends without a jump and a constant or a ramp passes
    unchanged. NumPy only (``scipy.signal`` costs 0.7 s to import)."""
    check_cutoff(cutoff, dt)
    x = np.asarray(x, dtype=float)
    n = x.shape[0]
    if n < 2:
        return x.copy()
    ext = np.concatenate([2.0 * x[:1] - x[n - 1:0:-1], x, 2.0 * x[-1:] - x[-2::-1]])
    m = ext.shape[0]
    shape = (-1,) + (1,) * (x.ndim - 1)
    line = ext[:1] + (ext[-1:] - ext[:1]) * (np.arange(m) / (m - 1)).reshape(shape)
    f = np.fft.rfftfreq(m, dt)
    gain = 1.0 / (1.0 + (f / cutoff) ** (2 * order))
    smooth = np.fft.irfft(np.fft.rfft(ext - line, axis=0) * gain.reshape(shape), n=m, axis=0) + line
    return np.asarray(smooth[n - 1:2 * n - 1])


def pelvis_acceleration(velocity: FloatArray, yaw: FloatArray, dt: float, cutoff: float, order: int) -> FloatArray:
    """The pelvis (base origin) acceleration (n, 3) [m/s²] in the heading frame — (forward, lateral, vertical): the
    world axes turned by the base's yaw ψ — from its world-frame velocity at n + 1 physics steps (n + 1, 3):

        a_k = lowpass( R_z(ψ_k)ᵀ (v_{k+1} − v_k) / Δt )

    (:func:`lowpass`). (v_{k+1} − v_k)/Δt is exactly the acceleration MuJoCo integrated over physics step k, gravity
    not included. The low-pass is what makes it a passenger's figure: at 1 kHz the differences carry the stiff
    contact's millisecond spikes (``docs/comfort.md`` measures raw against filtered)."""
    v = np.asarray(velocity, dtype=float)
    raw = np.diff(v, axis=0) / dt
    c, s = np.cos(yaw), np.sin(yaw)
    heading = np.stack([c * raw[:, 0] + s * raw[:, 1], -s * raw[:, 0] + c * raw[:, 1], raw[:, 2]], -1)
    return lowpass(heading, dt, cutoff, order)


def jerk(acceleration: FloatArray, dt: float) -> FloatArray:
    """The time derivative (n, 3) [m/s³] of a (low-passed) acceleration (n, 3) sampled every ``dt``: central
    differences (a_{k+1} − a_{k−1}) / 2Δt inside, one-sided at the ends (``numpy.gradient``)."""
    a = np.asarray(acceleration, dtype=float)
    return np.gradient(a, dt, axis=0) if a.shape[0] > 1 else np.zeros_like(a)


def rms(x: FloatArray) -> FloatArray:
    """Root mean square along axis 0: √(Σ_k x_k² / n)."""
    x = np.asarray(x, dtype=float)
    return np.asarray(np.sqrt(np.mean(x * x, axis=0)))


def peak(x: FloatArray) -> FloatArray:
    """Largest magnitude along axis 0: max_k |x_k|."""
    return np.asarray(np.max(np.abs(np.asarray(x, dtype=float)), axis=0))


def actuator_torque(model: mujoco.MjModel, states: FloatArray, controls: FloatArray) -> FloatArray:
    """Joint torques (n, nu) [N m] of the model's actuators at full-physics states (n, nstate) with controls (n, nu),
    as MuJoCo applies them in each physics step (``MjData.actuator_force`` times the gear): for fixed-gain, affine-bias
    actuators on a joint (robustgait's servos, :func:`robustgait.robots.model.build_mjspec`, and the feedback
    engine's torque motors)

        f = clamp(g₀ u + b₀ + b₁ l + b₂ l̇, forcerange),   l = γ q, l̇ = γ q̇,   τ = γ f

    (g the gain, b the bias parameters, γ the gear, u the control)."""
    if not (np.all(model.actuator_trntype == int(mujoco.mjtTrn.mjTRN_JOINT))
            and np.all(model.actuator_gaintype == int(mujoco.mjtGain.mjGAIN_FIXED))
            and np.all(np.isin(model.actuator_biastype, (int(mujoco.mjtBias.mjBIAS_NONE),
                                                         int(mujoco.mjtBias.mjBIAS_AFFINE))))
            and np.all(model.actuator_dyntype == int(mujoco.mjtDyn.mjDYN_NONE))):
        raise RobustGaitError("comfort figures need fixed-gain, affine-bias joint actuators without dynamics")
    joint = model.actuator_trnid[:, 0]
    gear = model.actuator_gear[:, 0]
    s = np.asarray(states, dtype=float)
    length = gear * s[:, 1 + model.jnt_qposadr[joint]]
    speed = gear * s[:, 1 + model.nq + model.jnt_dofadr[joint]]
    bias = np.where(model.actuator_biastype == int(mujoco.mjtBias.mjBIAS_AFFINE), 1.0, 0.0)
    b = model.actuator_biasprm * bias[:, None]
    force = model.actuator_gainprm[:, 0] * controls + b[:, 0] + b[:, 1] * length + b[:, 2] * speed
    lo, hi = model.actuator_forcerange[:, 0], model.actuator_forcerange[:, 1]
    limited = model.actuator_forcelimited.astype(bool)
    force = np.where(limited, np.clip(force, lo, hi), force)
    return np.asarray(gear * force)


def cost_of_transport(torque: FloatArray, joint_velocity: FloatArray, dt: float, mass: float, gravity: float,
                      distance: float) -> float | None:
    """Mechanical cost of transport [1]: the absolute mechanical work of the servoed joints per weight and distance,

        CoT = Σ_k Σ_j |τ_jk q̇_jk| Δt / (m g d)

    over physics steps k and servoed joints j (planned and held) — no energy recovered from one joint to another or
    from one instant to another (Collins et al., Science 2005, "mechanical cost of transport"). τ (n, m) [N m],
    q̇ (n, m) [rad/s] the joint velocity over each physics step ((q_{k+1} − q_k)/Δt, so that τ q̇ Δt is the step's
    work), m [kg] the whole robot with its passenger, g [m/s²], d [m] the forward distance. None when d ≤ 0 (no
    forward progress)."""
    if distance <= 0.0:
        return None
    work = float(np.sum(np.abs(np.asarray(torque) * np.asarray(joint_velocity)))) * dt
    return work / (mass * gravity * distance)


def excursion(angle: FloatArray, steps: list[tuple[int, int]]) -> float:
    """The largest per-step range of an angle (n,) [rad]: max over steps s of (max − min of angle[a_s … b_s]), each
    step the rows a_s … b_s (inclusive) of the physics steps it spans."""
    return max((float(np.ptp(angle[a:b + 1])) for a, b in steps), default=0.0)


def sole_contact_geoms(robot: Robot, side: str) -> frozenset[int]:
    """The geoms whose floor contacts are a sole's: those its contact sensor counts — the sole box, or every geom of
    the foot body of a virtual sole over spheres or capsules (:class:`robustgait.robots.soles.ResolvedSole`)."""
    kind, name = robot.soles[side].sensor
    m = robot.model
    if kind == mujoco.mjtObj.mjOBJ_BODY:
        return frozenset(int(g) for g in np.flatnonzero(m.geom_bodyid == m.body(name).id))
    return frozenset({int(m.geom(name).id)})


def sole_normal_force(model: mujoco.MjModel, data: mujoco.MjData, sole: frozenset[int], floor: int) -> float:
    """Normal force [N] between a sole's geoms and the floor geom in ``data`` (after a forward pass): Σ of the normal
    components of ``mj_contactForce`` over the contacts between them (pushing apart: ≥ 0)."""
    total = 0.0
    f = np.zeros(6)
    for i in range(data.ncon):
        c = data.contact[i]
        g1, g2 = int(c.geom1), int(c.geom2)
        if ((g1 in sole and g2 == floor) or (g2 in sole and g1 == floor)) and c.efc_address >= 0:
            mujoco.mj_contactForce(model, data, i, f)
            total += float(f[0])
    return total


def touchdown_impact(model: mujoco.MjModel, states: FloatArray, controls: FloatArray, row: int, window: int,
                     sole: frozenset[int], sole_box: int, floor: int) -> tuple[float, FloatArray]:
    """One touchdown: the landing sole's peak normal force [N] over the ``window`` physics steps that start from the
    pre-impact state (``states[row]``: the first state in which the sole touches the floor; docs/simulation.md) —
    each replayed by MuJoCo's forward pass at its state with the controls of its physics step, the solver warm-started
    from the previous one as ``mj_step`` does — over the sole's contact geoms ``sole`` (:func:`sole_contact_geoms`), and
    the sole's velocity (3,) [m/s, world frame] at that state (``mj_objectVelocity`` of the centre of ``sole_box``, the
    sole box geom, real or virtual)."""
    data = mujoco.MjData(model)
    velocity = np.zeros(6)
    top = 0.0
    for r in range(row, row + window):
        mujoco.mj_setState(model, data, states[r], _FULL)
        data.ctrl[:] = controls[r]
        mujoco.mj_forward(model, data)
        data.qacc_warmstart[:] = data.qacc
        if r == row:
            mujoco.mj_objectVelocity(model, data, mujoco.mjtObj.mjOBJ_GEOM, sole_box, velocity, 0)
        top = max(top, sole_normal_force(model, data, sole, floor))
    return top, velocity[3:].copy()


# ------------------------------------------------------------------------------------------------- the recording
class ComfortRecorder:
    """The physics steps a walk hands over for its comfort figures: every state and control of steps
    ``skip_steps`` … ``skip_steps`` + ``steps`` + 1 (the measured steps with one step on either side, which the
    low-pass runs over so that its ends fall outside the window), in one continuous series: row 0 is the state the
    first kept step starts from, row r + 1 the state after physics step r, driven by control r."""

    def __init__(self, config: ComfortConfig, dt: float):
        check_cutoff(config.cutoff, dt)  # before the walk: a bad cutoff is bad input
        self.config = config
        self.first = config.skip_steps + 1
        self.last = config.skip_steps + config.steps
        self._states: list[FloatArray] = []
        self._controls: list[FloatArray] = []
        self.rows = 0  # states kept so far
        self.step_end: dict[int, int] = {}  # step (1-based) → its last row
        self.touchdowns: dict[int, tuple[int, str]] = {}  # step → (row of its touchdown, landing sole)

    def wants(self, step: int) -> bool:
        """Whether step ``step`` (1-based) is kept (a step the figures are taken on, or the step before or after)."""
        return max(1, self.first - 1) <= step <= self.last + 1

    def add(self, step: int, domain: int, stance: str, start: FloatArray, trajectory: FloatArray,
            controls: FloatArray) -> None:
        """One domain of step ``step``: its start state (nstate,), recorded states (n, nstate) and controls (n, nu)
        (:attr:`robustgait.sim.engine.StepBatch.controls`). The end of domain 0 is the step's touchdown."""
        if not self.wants(step):
            return
        if not self.rows:
            self._states.append(start[None])
            self.rows = 1
        self._states.append(trajectory)
        self._controls.append(controls)
        self.rows += trajectory.shape[0]
        if domain == 0:
            self.touchdowns[step] = (self.rows - 1, "left" if stance == "right" else "right")

    def end_step(self, step: int) -> None:
        """Step ``step`` is complete (all its domains, no fall)."""
        if self.wants(step):
            self.step_end[step] = self.rows - 1

    def arrays(self) -> tuple[FloatArray, FloatArray]:
        """(states (N, nstate), controls (N − 1, nu)) up to the last finite state."""
        states = np.concatenate(self._states) if self._states else np.empty((0, 0))
        controls = np.concatenate(self._controls) if self._controls else np.empty((0, 0))
        finite = np.isfinite(states).all(axis=1)
        n = int(np.argmin(finite)) if not finite.all() else states.shape[0]
        return states[:n], controls[:max(n - 1, 0)]

    def measured(self) -> list[int]:
        """The measured steps the walk completed."""
        return [s for s in range(self.first, self.last + 1) if s in self.step_end]


def measure(robot: Robot, model: mujoco.MjModel, recording: ComfortRecorder, heading: FloatArray
            ) -> Comfort | None:
    """The :class:`Comfort` of a recorded walk (None when it completed no measured step). ``model``: the model the
    walk stepped (:attr:`robustgait.sim.engine.StepEngine.physics_model`), whose actuators turn the recorded controls
    into torques; ``heading`` (2,): the walk's forward direction (the base's initial heading, as
    :attr:`~robustgait.sim.walk.WalkResult.mean_speed`)."""
    cfg = recording.config
    steps = recording.measured()
    if not steps:
        return None
    states, controls = recording.arrays()
    dt, nq = robot.dt, model.nq
    # a completed step's predecessors are complete: step s starts where step s − 1 ended (row 0: the first kept step)
    spans = [(recording.step_end.get(s - 1, 0), recording.step_end[s]) for s in steps]
    a, b = spans[0][0], spans[-1][1]
    base_v = states[:, 1 + nq:1 + nq + 3]
    rpy = roll_pitch_yaw(states[:, 4:8])
    acc = pelvis_acceleration(base_v, rpy[:-1, 2], dt, cfg.cutoff, cfg.filter_order)
    jrk = jerk(acc, dt)
    acc, jrk = acc[a:b], jrk[a:b]  # physics steps a … b − 1: the measured steps
    torque = actuator_torque(model, states[a:b], controls[a:b])
    q = states[a:b + 1, 1 + model.jnt_qposadr[model.actuator_trnid[:, 0]]]  # each servo's joint
    duration = (b - a) * dt
    distance = float(np.dot(states[b, 1:3] - states[a, 1:3], heading))
    mass = robot.mass
    gravity = float(np.linalg.norm(model.opt.gravity))
    window = max(1, round(cfg.impact_window / dt))
    impacts, velocities = [], []
    for s in steps:
        row, side = recording.touchdowns[s]
        if row + window <= controls.shape[0]:
            f, v = touchdown_impact(model, states, controls, row, window, sole_contact_geoms(robot, side),
                                    robot.sole_geom_id[side], robot.floor_geom_id)
            impacts.append(f)
            velocities.append(v)
    acc_rms, acc_peak, jerk_rms, jerk_peak = rms(acc), peak(acc), rms(jrk), peak(jrk)
    joints = (*robot.spec.joints, *robot.spec.held_names)  # the servos' order (robots.model.build_mjspec)
    joint_rms, joint_peak = rms(torque), peak(torque)
    vel = np.asarray(velocities).reshape(-1, 3)
    figures: dict[str, Any] = {
        "first_step": steps[0], "steps": len(steps), "duration": duration,
        "speed": distance / duration, "step_length": distance / len(steps), "cadence": 60.0 * len(steps) / duration,
        **{f"pelvis_acc_{ax}_rms": float(acc_rms[i]) for i, ax in enumerate(AXES)},
        **{f"pelvis_acc_{ax}_peak": float(acc_peak[i]) for i, ax in enumerate(AXES)},
        **{f"pelvis_jerk_{ax}_rms": float(jerk_rms[i]) for i, ax in enumerate(AXES)},
        **{f"pelvis_jerk_{ax}_peak": float(jerk_peak[i]) for i, ax in enumerate(AXES)},
        "torque_rms": float(rms(torque.ravel())), "torque_peak": float(joint_peak.max()),
        "torque_rms_joint": {j: float(v) for j, v in zip(joints, joint_rms, strict=True)},
        "torque_peak_joint": {j: float(v) for j, v in zip(joints, joint_peak, strict=True)},
        "cost_of_transport": cost_of_transport(torque, np.diff(q, axis=0) / dt, dt, mass, gravity, distance),
        "touchdowns": len(impacts),
        "impact_force": max(impacts) if impacts else None,
        "impact_force_ratio": max(impacts) / (mass * gravity) if impacts else None,
        "touchdown_speed": float(np.linalg.norm(vel, axis=1).max()) if impacts else None,
        "touchdown_vertical_speed": float(max(0.0, -vel[:, 2].min())) if impacts else None,
        "pelvis_roll_excursion": excursion(rpy[:, 0], spans),
        "pelvis_pitch_excursion": excursion(rpy[:, 1], spans),
    }
    return Comfort(**figures)
