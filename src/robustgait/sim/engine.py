"""Batched one-step engine (``docs/simulation.md``): K states at a step start → each one's state at its next switching
event, or a fall, on :func:`mujoco.rollout` (multi-threaded C) — no Python call per physics step.

A step's controls depend on time only (:mod:`robustgait.sim.controller`), so all K samples share one
control series. The step is rolled out in chunks of ``chunk_steps`` physics steps (a robot under the step regulator:
its ``update_interval``); after each chunk the
recorded states and contact sensors are scanned (vectorized) for each sample's first event — a switching
event or a fall — and only the samples still going are rolled on from their last state. Walking one robot
(:mod:`robustgait.sim.walk`) uses the same engine with K = 1, so a walk and a batch agree exactly.

Chunk boundaries restart MuJoCo's constraint-solver warm start from zero; they are fixed relative to the
step start, so results are deterministic and identical for K = 1 and K > 1.

Disturbances (:mod:`robustgait.validate`) enter through :class:`StepInputs`: per-sample control offsets and
base wrenches go through the rollout's control vector (``mjSTATE_CTRL | mjSTATE_XFRC_APPLIED``), and
per-sample models through the list of models that :func:`mujoco.rollout` accepts. Without inputs the
rollout calls are exactly those of the undisturbed engine.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, field, replace

import mujoco
import numpy as np
from mujoco import rollout
from numpy.typing import NDArray

from robustgait.config import SimConfig
from robustgait.domains import domain_graph
from robustgait.errors import RobustGaitError
from robustgait.gait import Gait
from robustgait.robots import Robot
from robustgait.robots.model import CONTACT_SENSORS
from robustgait.sim.controller import step_controls
from robustgait.sim.regulator import lateral_growth, regulator_for

FALL_REASONS = ("base_low", "tilt", "non_foot_contact", "diverged", "no_touchdown")
_FULL = mujoco.mjtState.mjSTATE_FULLPHYSICS.value
_CTRL = int(mujoco.mjtState.mjSTATE_CTRL)
_CTRL_XFRC = _CTRL | int(mujoco.mjtState.mjSTATE_XFRC_APPLIED)


@contextmanager
def quiet_mujoco() -> Iterator[None]:
    """Silence MuJoCo's default log handler (console and MUJOCO_LOG.TXT) for the duration of a rollout.

    A diverging sample makes MuJoCo warn ("Nan, Inf or huge value in QACC ...") from the rollout threads,
    through the global log handler, once per sample, and append the warning to MUJOCO_LOG.TXT in the current
    directory. The engine detects such a sample from its state (MuJoCo resets it) and counts it as a fall
    ``diverged``, so the message adds nothing. MuJoCo ≥ 3.10 exposes the handler's configuration
    (``MjLogConfig``); older releases keep printing.
    """
    config_type = getattr(mujoco, "MjLogConfig", None)
    if config_type is None:  # pragma: no cover - MuJoCo < 3.10
        yield
        return
    saved = config_type.get()
    quiet = config_type.get()
    quiet.logto_console = False
    quiet.logto_file = False
    quiet.set()
    try:
        yield
    finally:
        saved.set()


@dataclass
class StepBatch:
    """Outcome of one step for K samples.

    qpos (K, nq), qvel (K, nv): state at the switching event (NaN rows for falls); fell (K,);
    fall_reason: one of :data:`FALL_REASONS` or None per sample; duration (K,): seconds from the step start
    to the event; tau (K,): the phase at the event; physics_steps: steps simulated over all samples;
    trajectory: with ``record=True``, per sample the (n_k, nstate) full-physics states of the step;
    controls: with ``record=True``, per sample the (n_k, nu) controls (MuJoCo's ``ctrl``) of the physics steps
    that produced them — row j was applied from the state before trajectory row j (the start state for j = 0)
    and, with the actuators of :attr:`StepEngine.physics_model`, gives the torques the step applied.
    """

    qpos: NDArray[np.float64]
    qvel: NDArray[np.float64]
    fell: NDArray[np.bool_]
    fall_reason: list[str | None]
    duration: NDArray[np.float64]
    tau: NDArray[np.float64]
    physics_steps: int
    trajectory: list[NDArray[np.float64]] = field(default_factory=list)
    controls: list[NDArray[np.float64]] = field(default_factory=list)


@dataclass(frozen=True)
class StepInputs:
    """Per-sample inputs of one step for K samples (each optional; shapes checked by :meth:`StepEngine.step`).

    models: K compiled models with the robot model's size signature (e.g. copies with other masses,
    friction or terrain); ctrl_offset (K, n, nu): added to the gait's servo controls at physics steps
    0..n−1 of the step (none after n); base_wrench (K, n, 6): world-frame force [N] and torque [N m] on the
    floating base at its centre of mass (MuJoCo's ``xfrc_applied``) at physics steps 0..n−1; sensor_noise
    (K, n, 2, nu): encoder noise (n_q, n_v) [rad, rad/s] on the actuated joints' positions and velocities as the
    tracking law reads them at physics steps 0..n−1 — the servo PD u = kp (c − q̃) − kd q̃̇ of this engine takes
    it as the control offset −(n_q + (kd/kp) n_v) (exact), a state-feedback law evaluates at the noisy state;
    delay_steps (K,): actuation latency of a state-feedback law computed centrally (an engine with
    ``latency == "torque"``): the central command (the law's torque plus the drives' local damping D q̇) that
    reaches the drives at physics step k is the one computed at k − d, before the step's start the one of
    ``torque_tail`` (K, T, nu: the commands of the T physics steps before it, the latest last; without it the
    delay line starts full of the step's first command); the drives' damping acts on the current velocity. The
    servo PD takes latency as control offsets instead (``latency == "command"``: its reference is delayed, its
    servo loop is not; :func:`robustgait.validate.disturbances.latency_offsets`).
    """

    models: Sequence[mujoco.MjModel] | None = None
    ctrl_offset: NDArray[np.float64] | None = None
    base_wrench: NDArray[np.float64] | None = None
    sensor_noise: NDArray[np.float64] | None = None
    delay_steps: NDArray[np.int64] | None = None
    torque_tail: NDArray[np.float64] | None = None


def servo_noise_offset(robot: Robot, noise: NDArray[np.float64]) -> NDArray[np.float64]:
    """Control offset (K, n, nu) of encoder noise (K, n, 2, nu) for joint PD servos: −(n_q + (kd/kp) n_v), the
    exact change of u = kp (c − q̃) − kd q̃̇ with q̃ = q + n_q, q̃̇ = q̇ + n_v."""
    return np.asarray(-(noise[:, :, 0] + (robot.servo_kd / robot.servo_kp) * noise[:, :, 1]))


def step_horizons(durations: Sequence[float], graph: str, timestep: float, config: SimConfig) -> list[int]:
    """The most physics steps each domain of a step may last before it is a fall: round(τ_end T_d / Δt), with
    τ_end = ``max_step_tau`` for a domain ended by touchdown or heel strike (τ = 1 with ``time`` switching) and
    τ_end = 1 for the rolling double support, which ends at foot-flat or at τ = 1 at the latest (past its end its
    references would keep rolling the feet: the tangent continuation that helps a late touchdown). Their sum is
    the worst case of one step, what :mod:`robustgait.config.work` bounds."""
    g = domain_graph(graph)
    if len(durations) != len(g):
        raise RobustGaitError(f"a {graph} gait has {len(g)} domains, this one {len(durations)}")
    tau_end = 1.0 if config.switching == "time" else config.max_step_tau
    return [round((tau_end if spec.guard == "touchdown" else 1.0) * (d / timestep))
            for spec, d in zip(g.domains, durations, strict=True)]


def step_physics_steps(gait: Gait, timestep: float, config: SimConfig) -> int:
    """The most physics steps one step of ``gait`` may take (its domains' :func:`step_horizons`)."""
    return sum(step_horizons([d.duration for d in gait.domains], gait.domain_graph, timestep, config))


class StepEngine:
    """One gait on one robot, both stances; call :meth:`step` with batches of states.

    ``controller_name``: the tracking law that runs (``pd`` here: MuJoCo's position servos, open loop);
    ``controller_note``: why it is not the one ``sim.controller`` asked for, if it is not ("" otherwise)."""

    controller_name = "pd"
    # how actuation latency enters (StepInputs): "command" — the servos' reference is delayed (control offsets)
    latency = "command"

    def __init__(self, robot: Robot, gait: Gait, config: SimConfig | None = None):
        gait.check_robot(robot)
        self.controller_note = ""
        self.robot = robot
        self.config = config or SimConfig()
        self.graph = domain_graph(gait.domain_graph)
        self.horizons = step_horizons([dom.duration for dom in gait.domains], gait.domain_graph, robot.dt,
                                      self.config)
        # in the model's size: a closed-chain robot's gait file holds no passive joints (Gait.closed closes its loops)
        self.gaits = {gait.stance: gait.closed(robot),
                      ("left" if gait.stance == "right" else "right"): gait.mirrored(robot).closed(robot)}
        m = robot.model
        # per domain: physics steps per unit of phase, and the most a domain may last before it is a fall
        self.domain_steps = [dom.duration / robot.dt for dom in gait.domains]
        self.period = gait.domains[0].duration
        self.steps_per_period = self.domain_steps[0]
        self.horizon = self.horizons[0]
        self.controls = {(s, d): step_controls(robot, g, self.horizons[d], feedforward=self.config.feedforward,
                                               domain=d)
                         for s, g in self.gaits.items() for d in range(len(self.graph))}
        self.nq, self.nv = m.nq, m.nv
        self.nstate = mujoco.mj_stateSize(m, _FULL)
        data = robot.new_data()
        self._template = np.empty(self.nstate)
        mujoco.mj_getState(m, data, self._template, _FULL)
        self._datas = [robot.new_data() for _ in range(self.config.threads)]
        self._other_datas: dict[int, list[mujoco.MjData]] = {}
        self._pool: rollout.Rollout | None = rollout.Rollout(nthread=self.config.threads)
        adr = robot.sensor_adr
        self._sens = {s: adr[CONTACT_SENSORS[i]] for i, s in enumerate(("left", "right"))}
        self._sens_floor = adr[CONTACT_SENSORS[2]]
        self._cos_max_tilt = math.cos(robot.spec.fall.max_tilt)
        # a regulated step is rolled out in chunks of the regulator's update interval, the same in seconds at any
        # timestep (the controller must not change with the physics step); others in sim.chunk_steps
        update = max(1, round(self.config.regulator.update_interval / robot.dt))
        self.regulator = regulator_for(robot, self.gaits, self.config.regulator, update, self.horizons[0])
        self.chunk = self.config.chunk_steps if self.regulator is None else update
        if self.regulator is not None:
            self.controller_name = f"{self.controller_name}+{self.regulator.name}"
            if self.regulator.needs_growth:  # its share of the H-LIP gain depends on how this walk's error grows
                options = repr(self.config)
                self.regulator.settle_share(lambda share: lateral_growth(self, options, share))

    @property
    def physics_model(self) -> mujoco.MjModel:
        """The model this engine steps (the robot's; a feedback engine's may have other actuator parameters): with a
        recorded step's controls, its actuators give the applied torques."""
        return self.robot.model

    def close(self) -> None:
        if self._pool is not None:
            self._pool.close()
            self._pool = None

    def __enter__(self) -> StepEngine:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def full_states(self, qpos: NDArray[np.float64], qvel: NDArray[np.float64]) -> NDArray[np.float64]:
        """(K, nstate) MuJoCo full-physics states at time 0 from qpos (K, nq), qvel (K, nv)."""
        k = qpos.shape[0]
        out = np.tile(self._template, (k, 1))
        out[:, 0] = 0.0
        out[:, 1:1 + self.nq] = qpos
        out[:, 1 + self.nq:1 + self.nq + self.nv] = qvel
        return out

    def _scan(self, st: NDArray[np.float64], sens: NDArray[np.float64], k0: int, stance: str, domain: int
              ) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
        """First event per sample in a chunk: (index or −1, code: 0 = switch, 1.. = FALL_REASONS[code−1]).

        The switch is the domain's guard: ``touchdown`` — the swing sole touches the floor; ``foot_flat`` — the
        front (swing) sole lies flat (≥ 3 contact points: a box sole on a plane has 4 when flat, 2 on an edge;
        the back sole's toe-off is not waited for: the next single support lifts it) or τ = 1, whichever
        first — each once τ ≥ ``min_switch_tau``; or τ = 1 (``time`` switching)."""
        swing = "left" if stance == "right" else "right"
        fall = self.robot.spec.fall
        nq = self.nq
        z = st[..., 3]
        qw, qx, qy = st[..., 4], st[..., 5], st[..., 6]
        cos_tilt = (1.0 - 2.0 * (qx * qx + qy * qy)) / np.maximum(qw * qw + qx * qx + qy * qy
                                                                   + st[..., 7] ** 2, 1e-12)
        n = st.shape[1]
        k = k0 + 1 + np.arange(n)
        with np.errstate(invalid="ignore"):
            # diverged: NaN/inf, a runaway speed, or time not advancing by one step per record — MuJoCo, on a
            # bad acceleration (its warning mjWARN_BADQACC), resets the simulation, and time restarts
            diverged = (~np.isfinite(st).all(axis=-1)
                         | (np.abs(st[..., 0] - k * self.robot.dt) > 0.5 * self.robot.dt)
                         | (np.abs(st[..., 1 + nq:1 + nq + self.nv]).max(axis=-1) > self.config.max_speed))
            codes = [
                z < fall.min_base_height,
                cos_tilt < self._cos_max_tilt,
                sens[..., self._sens_floor] - sens[..., self._sens["left"]] - sens[..., self._sens["right"]] > 0,
                diverged,
            ]
        tau = k / self.domain_steps[domain]
        if self.config.switching == "impact":
            if self.graph.domains[domain].guard == "touchdown":
                guard = sens[..., self._sens[swing]] > 0
            else:
                guard = (sens[..., self._sens[swing]] >= 3) | (k == self.horizons[domain])
            switch = guard & (tau >= self.config.min_switch_tau)
        else:
            switch = np.broadcast_to(k == self.horizons[domain], z.shape)
        events: NDArray[np.bool_] = np.stack([switch, *codes], axis=-1)  # (K, n, 5)
        # a fall at the same instant as a touchdown counts as a fall; a diverged state makes the other fall
        # criteria meaningless, so it is reported as such
        code = np.where(events[..., 1:].any(axis=-1), 1 + np.argmax(events[..., 1:], axis=-1), 0)
        code = np.where(diverged, 1 + FALL_REASONS.index("diverged"), code)
        any_event = np.any(events, axis=-1)
        first = np.where(any_event.any(axis=1), np.argmax(any_event, axis=1), -1)
        first_code = np.where(first >= 0, code[np.arange(len(first)), np.maximum(first, 0)], -1)
        return first, first_code

    def _check_inputs(self, inputs: StepInputs, kk: int) -> None:
        m = self.robot.model
        if inputs.models is not None:
            if len(inputs.models) != kk:
                raise RobustGaitError(f"need one model per sample ({kk}), got {len(inputs.models)}")
            sig = inputs.models[0].signature
            if any(mi.signature != sig for mi in inputs.models) or any(
                    getattr(inputs.models[0], f) != getattr(m, f) for f in ("nq", "nv", "nu", "nbody", "nsensordata")):
                raise RobustGaitError("per-sample models must share one size signature and the robot's "
                                      "joints, actuators, bodies and sensors")
        for name, arr, width in (("ctrl_offset", inputs.ctrl_offset, m.nu), ("base_wrench", inputs.base_wrench, 6)):
            if arr is not None and (arr.ndim != 3 or arr.shape[0] != kk or arr.shape[2] != width):
                raise RobustGaitError(f"{name} must be (K={kk}, n, {width}), got {arr.shape}")
        noise = inputs.sensor_noise
        if noise is not None and (noise.ndim != 4 or noise.shape[0] != kk or noise.shape[2:] != (2, m.nu)):
            raise RobustGaitError(f"sensor_noise must be (K={kk}, n, 2, {m.nu}), got {noise.shape}")
        d, tail = inputs.delay_steps, inputs.torque_tail
        if d is not None and (d.shape != (kk,) or not np.issubdtype(d.dtype, np.integer) or (d < 0).any()):
            raise RobustGaitError(f"delay_steps must be (K={kk},) non-negative integers")
        if tail is not None and (d is None or tail.ndim != 3 or tail.shape[0] != kk or tail.shape[2] != m.nu):
            raise RobustGaitError(f"torque_tail must be (K={kk}, T, {m.nu}), with delay_steps")

    def _engine_inputs(self, inputs: StepInputs) -> StepInputs:
        """``inputs`` as this engine applies them: sensor noise folded into the control offset, as the servo PD
        takes it (a feedback engine hands the noise to its law instead)."""
        if inputs.delay_steps is not None:
            raise RobustGaitError("delay_steps is the latency of a state-feedback law (FeedbackEngine); the servo PD "
                                  "takes latency as control offsets (validate.disturbances.latency_offsets)")
        if inputs.sensor_noise is None:
            return inputs
        off = servo_noise_offset(self.robot, inputs.sensor_noise)
        if inputs.ctrl_offset is not None:
            n = max(off.shape[1], inputs.ctrl_offset.shape[1])
            both = np.zeros((off.shape[0], n, off.shape[2]))
            both[:, :off.shape[1]] += off
            both[:, :inputs.ctrl_offset.shape[1]] += inputs.ctrl_offset
            off = both
        return replace(inputs, ctrl_offset=off, sensor_noise=None)

    def _rollout(self, active: NDArray[np.int64], current: NDArray[np.float64], ctrl: NDArray[np.float64],
                 k0: int, n: int, inputs: StepInputs | None, reg: NDArray[np.float64] | None = None
                 ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
        """One chunk of n physics steps from step k0 for the samples ``active`` (see :class:`StepInputs`): states
        and sensors (A, n, ·), and the controls applied ((A or 1, n, nu): one series shared by all, or per sample).
        ``reg`` (A, n, nu): the step regulator's control offsets, if it runs."""
        assert self._pool is not None
        c = ctrl[None, k0:k0 + n]
        if reg is not None:
            c = c + reg
        if inputs is None:
            return (*self._pool.rollout(self.robot.model, self._datas, current[active], c, nstep=n), c)
        m = self.robot.model
        off = inputs.ctrl_offset
        if off is not None and k0 < off.shape[1]:
            c = np.repeat(c, active.size, axis=0) if c.shape[0] == 1 else c.copy()
            w = min(n, off.shape[1] - k0)
            c[:, :w] += off[active, k0:k0 + w]
        applied = c
        spec = _CTRL
        wr = inputs.base_wrench
        if wr is not None and k0 < wr.shape[1] and np.any(wr[active, k0:k0 + n]):
            w = min(n, wr.shape[1] - k0)
            full = np.zeros((active.size, n, m.nu + 6 * m.nbody))
            full[:, :, :m.nu] = c
            col = m.nu + 6 * self.robot.base_body_id
            full[:, :w, col:col + 6] = wr[active, k0:k0 + w]
            c, spec = full, _CTRL_XFRC
        models: mujoco.MjModel | list[mujoco.MjModel] = m
        datas = self._datas
        if inputs.models is not None:
            models = [inputs.models[i] for i in active]
            sig = models[0].signature
            if sig != m.signature:  # e.g. a terrain model: data must be allocated for it
                if sig not in self._other_datas:
                    self._other_datas[sig] = [mujoco.MjData(models[0]) for _ in range(self.config.threads)]
                datas = self._other_datas[sig]
        return (*self._pool.rollout(models, datas, current[active], c, control_spec=spec, nstep=n), applied)

    def step(self, qpos: NDArray[np.float64], qvel: NDArray[np.float64], stance: str, *, domain: int = 0,
             record: bool = False, progress: Callable[[int], None] | None = None,
             inputs: StepInputs | None = None) -> StepBatch:
        """Simulate domain ``domain`` of a step of the given ``stance`` from K start states (τ = 0) to each
        one's next event (for a one-domain gait: the whole step).

        ``progress`` is called after each chunk with the number of samples that reached their event in it.
        ``inputs``: per-sample disturbances (:class:`StepInputs`); None = the gait's controls for all.
        """
        qpos, qvel = self._start_states(qpos, qvel, stance, domain)
        kk = qpos.shape[0]
        if inputs is not None:
            self._check_inputs(inputs, kk)
            inputs = self._engine_inputs(inputs)
        bad = ~(np.isfinite(qpos).all(axis=1) & np.isfinite(qvel).all(axis=1))
        ctrl = self.controls[(stance, domain)]
        horizon = self.horizons[domain]
        current = self.full_states(np.nan_to_num(qpos), np.nan_to_num(qvel))
        out_state = np.full((kk, self.nstate), np.nan)
        code = np.full(kk, -1, dtype=np.int64)
        at = np.zeros(kk, dtype=np.int64)
        code[bad] = 1 + FALL_REASONS.index("diverged")
        active = np.flatnonzero(~bad)
        traj: list[list[NDArray[np.float64]]] = [[] for _ in range(kk)]
        ctrls: list[list[NDArray[np.float64]]] = [[] for _ in range(kk)]
        physics = 0
        k0 = 0
        if progress is not None and bad.any():
            progress(int(bad.sum()))
        regulator = self.regulator if domain == 0 else None
        if regulator is not None:
            regulator.begin(stance, current)
        while active.size and k0 < horizon:
            n = min(self.chunk, horizon - k0)
            reg = regulator.offsets(active, current[active], k0, n) if regulator is not None else None
            with quiet_mujoco():
                st, sens, applied = self._rollout(active, current, ctrl, k0, n, inputs, reg)
            physics += active.size * n
            first, first_code = self._scan(st, sens, k0, stance, domain)
            done = first >= 0
            # A touchdown is seen in the sensors of the step whose start state first penetrates the floor, so
            # that state is the pre-impact state x⁻ (its velocity is still contact-free) and an impact event ends
            # the step there; the recorded state of the sensing step already carries a millisecond of impact,
            # which made the section state jump by ~0.14 rad/s when touchdown crossed a millisecond boundary.
            end = np.where((first_code == 0) & (self.config.switching == "impact"), first - 1, first)
            if record:
                for j, i in enumerate(active):
                    c = applied[j if applied.shape[0] > 1 else 0]
                    traj[i].append(st[j, :end[j] + 1] if done[j] else st[j])
                    ctrls[i].append(c[:end[j] + 1] if done[j] else c)
            idx = active[done]
            ends = end[done]
            out_state[idx] = np.where((ends >= 0)[:, None], st[done, np.maximum(ends, 0)], current[idx])
            code[idx] = first_code[done]
            at[idx] = k0 + 1 + ends
            current[active[~done]] = st[~done, -1]
            active = active[~done]
            if progress is not None:
                progress(int(done.sum()) + (active.size if k0 + n >= horizon else 0))
            k0 += n
        if active.size:  # ran out of horizon without a touchdown (a double support always ends by τ = 1)
            code[active] = 1 + FALL_REASONS.index("no_touchdown")
            at[active] = horizon
        return self._step_batch(out_state, code, at, domain, physics, traj, ctrls, record)

    def _start_states(self, qpos: NDArray[np.float64], qvel: NDArray[np.float64], stance: str, domain: int
                      ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """A step's start states as (K, nq) and (K, nv) arrays; a one-line error for an unknown stance or domain,
        states of the wrong shape, or a closed engine."""
        if stance not in self.gaits:
            raise RobustGaitError(f"stance must be 'left' or 'right', got {stance!r}")
        qpos = np.atleast_2d(np.asarray(qpos, dtype=float))
        qvel = np.atleast_2d(np.asarray(qvel, dtype=float))
        if qpos.shape[1:] != (self.nq,) or qvel.shape != (qpos.shape[0], self.nv):
            raise RobustGaitError(f"states must be (K, {self.nq}) and (K, {self.nv}), got {qpos.shape} and "
                                  f"{qvel.shape}")
        if self._pool is None:
            raise RobustGaitError("this StepEngine is closed")
        if not 0 <= domain < len(self.graph):
            raise RobustGaitError(f"the gait has {len(self.graph)} domains, no domain {domain}")
        return qpos, qvel

    def _step_batch(self, out_state: NDArray[np.float64], code: NDArray[np.int64], at: NDArray[np.int64],
                    domain: int, physics: int, traj: list[list[NDArray[np.float64]]],
                    ctrls: list[list[NDArray[np.float64]]], record: bool) -> StepBatch:
        """The :class:`StepBatch` of a step's samples: their end states (K, nstate; NaN where they fell), event
        codes (0 an event, else 1 + the index of the fall reason), physics steps to the event, recorded pieces."""
        fell = code != 0
        out_state[fell] = np.nan
        return StepBatch(
            qpos=out_state[:, 1:1 + self.nq], qvel=out_state[:, 1 + self.nq:1 + self.nq + self.nv],
            fell=fell, fall_reason=[FALL_REASONS[c - 1] if c > 0 else None for c in code],
            duration=np.asarray(at * self.robot.dt, dtype=np.float64), tau=at / self.domain_steps[domain],
            physics_steps=physics,
            trajectory=[np.concatenate(t) if t else np.empty((0, self.nstate)) for t in traj] if record else [],
            controls=[np.concatenate(c) if c else np.empty((0, self.robot.model.nu)) for c in ctrls] if record else [],
        )
