"""Batched state-feedback engine: K samples stepped in lockstep at the physics rate with a torque law
τ(q, q̇, t) evaluated for all K at once.

:class:`~robustgait.sim.engine.StepEngine` rolls a step out open loop with :func:`mujoco.rollout`: its
controls are a function of time only (the PD is folded into MuJoCo position servos), so no state-feedback law
can run there. :class:`FeedbackEngine` is a StepEngine whose chunks are stepped by MuJoCo's batch API
(:class:`mujoco.batch.Batch`, MuJoCo ≥ 4.0: K simulations in C on a thread pool, the GIL released,
bit-identical to stepping one ``MjData`` per simulation) one physics step at a time; between two steps a
:class:`FeedbackController` computes the K torques in vectorized NumPy from the K states (and, if it asks
for them, MuJoCo's position/velocity-stage quantities of the K states, e.g. ``cdof``: the batch is then
persistent and computes those stages at each new state, which runs well below a plain step's speed (docs/feedback.md),
so the shipped laws compute what they need themselves). The
chunking, the event scan (switching, falls), the outputs (:class:`~robustgait.sim.engine.StepBatch`) and the
disturbances (:class:`~robustgait.sim.engine.StepInputs`) are StepEngine's own: this class only replaces
the rollout of one chunk (:meth:`StepEngine._rollout`), so a walk (:func:`robustgait.sim.walk.walk`, which
takes an ``engine``), a Poincaré map or a certificate run on it unchanged.

What carries over from one chunk to the next is exactly what :func:`mujoco.rollout` carries over: each
chunk restarts from the full-physics state (time, qpos, qvel; ``mjSTATE_FULLPHYSICS``) of the end of the
previous one, with the constraint solver's warm start (``qacc_warmstart``) reset to zero, the warning
counters cleared, and the applied forces zeroed unless a base wrench is given; within a chunk the warm start
carries over from step to step, and a simulation whose warning counters rise is frozen for the rest of the
chunk (its records repeat), as :func:`mujoco.rollout` does. Hence with the PD law
(:class:`PDController`) the engine reproduces the rollout engine (tests/sim/test_feedback.py: states equal to
~1e-13 with the torque-level PD; bit-identical when the servo control itself is written, ``servo_exact``).

Actuation: the robot's actuators are affine servos u = kp (c − q) − kd q̇ clamped to ±torque_limit
(:mod:`robustgait.robots.spec`). ``actuation="servo"`` (default) applies a torque τ through them with the
control c = τ/kp + q + (D/kp) q̇, D the servos' damping, so the servo produces τ and its force range enforces
the torque limit. MuJoCo's ``implicitfast`` integrator integrates the servo's −D q̇ implicitly (at the end of
the step), so of a torque law computed at the start of the step the −D q̇ part acts implicitly — for the PD
with D = kd exactly as in the rollout engine. A controller may choose D
(:meth:`FeedbackController.servo_damping`; the engine then steps copies of the models with that damping):
the passivity law sets D = K_D, which makes its own damping implicit; with the spec's kd instead
(``implicit_damping=False``) its extra damping K_D − kd is explicit, which tracks worse (docs/feedback.md;
``benchmarks/perf/feedback.py --variants``). ``actuation="motor"`` makes the actuators direct torque motors
(gain 1, bias 0, same force range): every torque acts explicitly, as computed from the sampled state (a zero-order
hold over the physics step); the PD law then no longer matches the rollout engine (docs/feedback.md).
Torques beyond the limit are counted per joint and step (``saturation``).
"""

from __future__ import annotations

import contextlib
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Literal

import mujoco
import numpy as np
from numpy.typing import NDArray

from robustgait.bezier import bezier_derivative
from robustgait.config import SimConfig
from robustgait.errors import RobustGaitError
from robustgait.gait import Gait
from robustgait.robots import Robot
from robustgait.robots.model import actuated_model
from robustgait.sim.controller import TrackingStats, desired_outputs, feedforward_torque, step_controls
from robustgait.sim.engine import StepBatch, StepEngine, StepInputs
from robustgait.sim.regulator_rules import regulator_rule

Array = NDArray[np.float64]
_FULL = mujoco.mjtState.mjSTATE_FULLPHYSICS.value
_INTEGRATION = mujoco.mjtState.mjSTATE_INTEGRATION.value
STAGE_NONE = int(mujoco.mjtStage.mjSTAGE_NONE)
STAGE_VEL = int(mujoco.mjtStage.mjSTAGE_VEL)


@dataclass(frozen=True)
class Desired:
    """A domain's desired outputs at physics steps k = 0..H−1 (τ_k = k Δt / T): y_d, ẏ_d, ÿ_d and the
    feedforward torque u_ff, each (H, m). Past τ = 1 the outputs continue along their tangent (ÿ_d = 0), as
    :func:`robustgait.sim.controller.desired_outputs` does."""

    y: Array
    dy: Array
    ddy: Array
    uff: Array


def desired_tables(robot: Robot, gait: Gait, n_steps: int, domain: int = 0) -> Desired:
    dom = gait.domains[domain]
    tau = np.arange(n_steps, dtype=np.float64) * (robot.dt / dom.duration)
    y, dy = desired_outputs(gait, tau, domain)
    ddy = bezier_derivative(dom.beta, np.clip(tau, 0.0, 1.0), 2) / dom.duration**2
    ddy[tau > 1.0] = 0.0
    return Desired(y, dy, ddy, feedforward_torque(gait, tau, domain))


@dataclass
class Observation:
    """What a controller sees at one physics step for the A samples being stepped: ``qpos`` (A, nq),
    ``qvel`` (A, nv), and the MuJoCo data fields it asked for (:attr:`FeedbackController.fields`, each
    (A, ...), computed at this state by MuJoCo's stages up to :attr:`FeedbackController.stage`). Read-only
    views valid until the next step. ``samples``: the samples' indices in the engine's batch (K)."""

    qpos: Array
    qvel: Array
    samples: NDArray[np.int64]
    fields: dict[str, Array] = field(default_factory=dict)


class FeedbackController:
    """A joint-torque law for :class:`FeedbackEngine`, evaluated for all samples at once.

    ``stage``: the MuJoCo stage computed at each state before :meth:`torque` (``STAGE_NONE``: state only;
    ``STAGE_VEL``: the position- and velocity-dependent quantities, as after ``mj_step1``); ``fields``: the
    MjData fields handed to :meth:`torque` in :attr:`Observation.fields`; ``actuation``: how the torque is
    applied (module docstring). Subclasses implement :meth:`torque`; :meth:`setup` is called by the engine.
    """

    name = "feedback"
    stage: int = STAGE_NONE
    fields: tuple[str, ...] = ()
    actuation: Literal["servo", "motor"] = "servo"
    # actuation latency (StepInputs.delay_steps) delays the law's torque: a law computed centrally
    latency: Literal["command", "torque"] = "torque"

    def servo_damping(self) -> Array | None:
        """With ``servo`` actuation: the damping D (m,) the servos integrate implicitly (the torque's −D q̇
        part, evaluated by MuJoCo's implicit integrator at the end of the step), or None for the spec's kd."""
        return None

    def setup(self, engine: FeedbackEngine) -> None:
        """Precompute what the law needs from the engine (robot, gaits, horizons)."""
        self.robot = engine.robot
        self.qpos_idx = engine.robot.qpos_idx
        self.dof_idx = engine.robot.dof_idx
        self.desired = {key: desired_tables(engine.robot, engine.gaits[key[0]], engine.horizons[key[1]], key[1])
                        for key in engine.controls}
        self.stance, self.domain = "right", 0

    def begin(self, stance: str, domain: int) -> None:
        """Called at the start of each :meth:`FeedbackEngine.step` with the step's stance and domain."""
        self.stance, self.domain = stance, domain

    def torque(self, k: int, obs: Observation) -> tuple[Array, Array]:
        """Joint torques (A, m) in actuator (output) order at physics step k of the domain, and the
        tracking error q − y_d (A, m) at this state (for the engine's statistics)."""
        raise NotImplementedError


class PDController(FeedbackController):
    """The rollout engine's law as a state feedback: τ = kp (y_d − q) + kd (ẏ_d − q̇) + u_ff (u_ff when
    ``feedforward`` and the gait has it), kp/kd the spec's servo gains. Through ``actuation="servo"`` it
    reproduces :class:`StepEngine` to rounding (the servo applies kp·c − kp q − kd q̇ with c = τ/kp + q +
    (kd/kp) q̇); with ``servo_exact`` it writes the rollout engine's servo control itself
    (:func:`robustgait.sim.controller.step_controls`), which is bit-identical."""

    name = "pd"
    latency = "command"  # joint servos: the delayed quantity is their reference, as in the rollout engine

    def __init__(self, *, feedforward: bool = True, servo_exact: bool = False,
                 actuation: Literal["servo", "motor"] = "servo"):
        if servo_exact and actuation != "servo":
            raise RobustGaitError("servo_exact needs actuation='servo'")
        self.feedforward = feedforward
        self.servo_exact = servo_exact
        self.actuation = actuation

    def setup(self, engine: FeedbackEngine) -> None:
        super().setup(engine)
        self.kp, self.kd = engine.robot.kp, engine.robot.kd
        self.servo = {key: step_controls(engine.robot, engine.gaits[key[0]], engine.horizons[key[1]],
                                         feedforward=self.feedforward, domain=key[1]) for key in engine.controls}

    def torque(self, k: int, obs: Observation) -> tuple[Array, Array]:
        des = self.desired[(self.stance, self.domain)]
        q = obs.qpos[:, self.qpos_idx]
        qd = obs.qvel[:, self.dof_idx]
        tau = self.kp * (des.y[k] - q) + self.kd * (des.dy[k] - qd)
        if self.feedforward:
            tau += des.uff[k]
        return tau, q - des.y[k]

    def servo_control(self, k: int) -> Array | None:
        """The servo control to write instead of converting the torque (``servo_exact``), or None."""
        return self.servo[(self.stance, self.domain)][k] if self.servo_exact else None


@dataclass
class FeedbackStepBatch(StepBatch):
    """:class:`StepBatch` plus, per sample over the physics steps of this step up to its event:
    ``control_steps`` (K,) the number of controlled steps, ``saturation`` (K, m) the number of steps whose
    commanded torque exceeded the joint's torque limit (the servo then clamps it), ``error_sq`` (K, m) the sum
    of squared tracking errors (q − y_d)² and ``error_max`` (K, m) the largest |q − y_d|."""

    control_steps: NDArray[np.int64] = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    # with StepInputs.delay_steps: (K, T, m) the central commands (law torque + the drives' local damping D q̇)
    # computed in the T = max delay physics steps before each sample's event (the next step's
    # StepInputs.torque_tail); None otherwise
    torque_tail: Array | None = None
    saturation: NDArray[np.int64] = field(default_factory=lambda: np.zeros((0, 0), dtype=np.int64))
    error_sq: Array = field(default_factory=lambda: np.zeros((0, 0)))
    error_max: Array = field(default_factory=lambda: np.zeros((0, 0)))


_THREADPOOLS: list[object] = []


def _one_blas_thread() -> contextlib.AbstractContextManager[object]:
    """Limit BLAS to one thread (threadpoolctl's controller is made once, not at every call)."""
    if not _THREADPOOLS:
        try:
            from threadpoolctl import ThreadpoolController
        except ImportError:  # pragma: no cover - threadpoolctl comes with botorch
            return contextlib.nullcontext()
        _THREADPOOLS.append(ThreadpoolController())
    return _THREADPOOLS[0].limit(limits=1, user_api="blas")  # type: ignore[attr-defined]


# -- the disturbances and the actuation of one physics step ---------------------------------------------------
# Each factory binds what is fixed over a chunk and returns the function the closed loop calls at physics step k
# of the domain: one call per step and active disturbance, no allocation beyond the arithmetic itself.

Observe = Callable[[int], Observation]  # physics step k → the state the law reads
Command = Callable[[int, Array], Array]  # (k, an (A, m) torque or control) → the (A, m) one applied
Push = Callable[[int], None]  # physics step k → writes the applied forces


def encoder_noise(obs: Observation, noise: Array, active: NDArray[np.int64], qpos_idx: NDArray[np.int64],
                  dof_idx: NDArray[np.int64]) -> Observe:
    """Sensor noise: the law reads noisy encoders. At physics step k the law sees ``obs`` (the true state: qpos
    (A, nq), qvel (A, nv), live views of the batch) with the encoder noise ``noise[active, k]`` added on the actuated
    joints — n_q [rad] to their positions (``qpos_idx``), n_v [rad/s] to their velocities (``dof_idx``); ``noise``:
    (K, n, 2, m) per sample of the engine's batch, physics step and actuated joint, none from step n on (the law then
    sees ``obs``). The servo conversion keeps reading the true state. The noisy state is written into two arrays
    made here, so its observation is valid until the next call (as :class:`Observation` promises)."""
    pq, pv = np.empty(obs.qpos.shape), np.empty(obs.qvel.shape)
    seen = Observation(qpos=pq, qvel=pv, samples=obs.samples, fields=obs.fields)
    horizon = noise.shape[1]

    def observe(k: int) -> Observation:
        if k >= horizon:
            return obs
        np.copyto(pq, obs.qpos)
        np.copyto(pv, obs.qvel)
        pq[:, qpos_idx] += noise[active, k, 0]
        pv[:, dof_idx] += noise[active, k, 1]
        return seen

    return observe


def command_latency(hist: Array, inputs: StepInputs, active: NDArray[np.int64], damping: Array, qvel: Array,
                    dof_idx: NDArray[np.int64]) -> Command:
    """Command latency of a law computed centrally (``inputs.delay_steps`` (K,) physics steps per sample). At physics
    step k the central command — the law's torque τ (A, m) [N m] plus the drives' local damping D q̇ (``damping`` D
    (m,) [N m s/rad], q̇ the true joint velocities from ``qvel`` (A, nv), a live view) — is recorded in ``hist``
    (K, H, m), and the torque applied is the command computed ``delay_steps`` earlier
    (:meth:`FeedbackEngine._delayed`) minus the current D q̇: the drives' damping acts on the current velocity, as
    the PD servos' own loop does under command latency."""

    def delay(k: int, tau: Array) -> Array:
        local = damping * qvel[:, dof_idx]
        hist[active, k] = tau + local
        return FeedbackEngine._delayed(hist, inputs, active, k) - local

    return delay


def servo_command(kp: Array, damping: Array, qpos: Array, qvel: Array, qpos_idx: NDArray[np.int64],
                  dof_idx: NDArray[np.int64]) -> Command:
    """Torque to servo control: the position command c = τ/kp + q + (D/kp) q̇ (A, m) [rad] for which the affine servo
    u = kp (c − q) − D q̇ produces the torque τ (A, m) [N m] at the true state q, q̇ (the actuated joints of ``qpos``
    (A, nq), ``qvel`` (A, nv), live views); kp (m,) [N m/rad], D = ``damping`` (m,) [N m s/rad]."""
    ratio = damping / kp

    def command(k: int, tau: Array) -> Array:
        return tau / kp + qpos[:, qpos_idx] + ratio * qvel[:, dof_idx]

    return command


def motor_command(k: int, tau: Array) -> Array:
    """Torque to direct-torque motor control: the torque τ (A, m) [N m] itself."""
    return tau


def exact_servo_command(controller: PDController, shape: tuple[int, int]) -> Command:
    """The PD's own servo control (``servo_exact``): at physics step k the rollout engine's control
    :meth:`PDController.servo_control` (m,) [rad], the same for all samples, as a fresh (A, m) array; the torque is
    not used."""

    def command(k: int, tau: Array) -> Array:
        control = controller.servo_control(k)
        assert control is not None
        return np.broadcast_to(control, shape).copy()

    return command


def control_offset(offset: Array, active: NDArray[np.int64], kp: Array | None) -> Command:
    """The control offset (``StepInputs.ctrl_offset`` (K, n, m) [rad], none from physics step n on) added to the
    control c (A, m) at physics step k: ``offset[active, k]`` as is for servos (``kp`` None: it shifts their position
    command), or as the servo would apply it, kp·offset [N m] with kp (m,) [N m/rad], for torque motors."""
    horizon = offset.shape[1]
    if kp is None:
        def shift(k: int, c: Array) -> Array:
            return c + offset[active, k] if k < horizon else c
    else:
        gain = kp

        def shift(k: int, c: Array) -> Array:
            return c + gain * offset[active, k] if k < horizon else c

    return shift


def base_push(xfrc: Array, body: int, wrench: Array, active: NDArray[np.int64]) -> Push:
    """The base wrench (pushes): at physics step k writes ``wrench[active, k]`` (K, n, 6 per sample: world-frame
    force [N] and torque [N m] at the base's centre of mass) into the applied forces ``xfrc`` (A, nbody, 6, the batch's
    ``xfrc_applied``) of body ``body``; zero from step n on."""
    horizon = wrench.shape[1]

    def push(k: int) -> None:
        xfrc[:, body] = wrench[active, k] if k < horizon else 0.0

    return push


class FeedbackEngine(StepEngine):
    """:class:`StepEngine` whose steps run a state-feedback :class:`FeedbackController` (module docstring).

    ``controller``: the law (default: :class:`PDController` with the config's ``feedforward``). The
    interface and the outputs are StepEngine's; :meth:`step` returns a :class:`FeedbackStepBatch`, and
    :attr:`stats` accumulates tracking errors and saturation over every step until :meth:`TrackingStats.reset`.
    """

    def __init__(self, robot: Robot, gait: Gait, controller: FeedbackController | None = None,
                 config: SimConfig | None = None):
        try:
            from mujoco import batch as mjbatch
        except ImportError:  # pragma: no cover - MuJoCo < 4.0
            raise RobustGaitError("the feedback engine needs MuJoCo ≥ 4.0 (mujoco.batch)") from None
        self._mjbatch = mjbatch
        cfg = config or SimConfig()
        on, reason = regulator_rule(cfg.regulator, robot.sole_width, robot.leg_length,
                                    len(gait.domains))
        if on:  # before the engine is built: the regulator would measure its walk on this engine's laws
            raise RobustGaitError(f"the H-LIP step regulator runs with the pd controller, not the feedback engine's "
                                  f"laws ({reason}): use sim.controller pd, or sim.regulator.mode off")
        super().__init__(robot, gait, config)
        self.controller = controller if controller is not None else PDController(
            feedforward=self.config.feedforward)
        self.controller_name = self.controller.name
        self.latency = self.controller.latency
        self.controller.setup(self)
        self.motor = self.controller.actuation == "motor"
        self.persistent = self.controller.stage > STAGE_NONE
        damping = None if self.motor else self.controller.servo_damping()
        # the servo damping the stepped models integrate implicitly (motor: none)
        self.damping = np.zeros(robot.n_joints) if self.motor else (robot.kd if damping is None
                                                                    else np.asarray(damping, dtype=float))
        self._convert = (lambda mm: actuated_model(mm, self.controller.actuation, damping))
        self._model = self._convert(robot.model)
        self._converted: dict[int, tuple[mujoco.MjModel, mujoco.MjModel]] = {}
        self._batches: dict[int, mujoco.batch.Batch] = {}
        data = robot.new_data()
        self._row_template = np.empty(mujoco.mj_stateSize(robot.model, _INTEGRATION))
        mujoco.mj_getState(robot.model, data, self._row_template, _INTEGRATION)
        self._row_template[:] = np.where(np.isfinite(self._row_template), self._row_template, 0.0)
        self.stats = TrackingStats()
        self._step_ctx: dict[str, object] | None = None

    # -- batches -------------------------------------------------------------------------------------------

    def _layout_model(self, model: mujoco.MjModel) -> mujoco.MjModel:
        """The model the engine steps for a robot or per-sample model (:func:`actuated_model`, cached)."""
        if model is self.robot.model:
            return self._model
        if self._model is self.robot.model:  # servos as specified: the models themselves
            return model
        hit = self._converted.get(id(model))
        if hit is None or hit[0] is not model:
            hit = (model, self._convert(model))
            self._converted[id(model)] = hit
        return hit[1]

    def _batch(self, model: mujoco.MjModel, n: int) -> mujoco.batch.Batch:
        """A batch with at least n simulations of ``model``'s layout (cached per size signature). A batch of the
        robot's layout is made from the robot's model (the one it runs when no per-sample models are set); one
        of another layout (e.g. a terrain) only ever runs per-sample models (``set_models``)."""
        if model.signature == self._model.signature:
            model = self._model
        b = self._batches.get(model.signature)
        if b is None or b.nsim < n:
            b = self._mjbatch.Batch(model, max(n, 1), nthread=self.config.threads, persistent=self.persistent)
            for name in self.controller.fields:
                b.bind(name)
            self._batches[model.signature] = b
            # column indices of the full-physics state in a batch row (mjSTATE_INTEGRATION layout)
            cols: list[int] = []
            bit = 1
            while bit <= _FULL:
                if _FULL & bit:
                    off, size = b._component(bit)
                    cols.extend(range(off, off + size))
                bit <<= 1
            self._full_cols = np.asarray(cols)
            c = self._full_cols
            self._full_slice = slice(int(c[0]), int(c[-1]) + 1) if np.array_equal(c, np.arange(c[0], c[-1] + 1)) \
                else None
        return b

    def close(self) -> None:
        super().close()
        self._batches.clear()

    # -- stepping ------------------------------------------------------------------------------------------

    def step(self, qpos: NDArray[np.float64], qvel: NDArray[np.float64], stance: str, *, domain: int = 0,
             record: bool = False, progress: object = None,
             inputs: StepInputs | None = None) -> FeedbackStepBatch:
        """As :meth:`StepEngine.step`, with the controller's law; returns a :class:`FeedbackStepBatch`."""
        kk = np.atleast_2d(np.asarray(qpos)).shape[0]
        self.controller.begin(stance, domain)
        m = self.controller.robot.n_joints
        ctx: dict[str, object] = {"chunks": []}
        self._step_ctx = ctx
        delay = inputs.delay_steps if inputs is not None else None
        if delay is not None and self.latency == "torque":
            ctx["torques"] = np.zeros((kk, self.horizons[domain], m))
        try:
            out = super().step(qpos, qvel, stance, domain=domain, record=record, progress=progress,  # type: ignore[arg-type]
                               inputs=inputs)
        finally:
            self._step_ctx = None
        at = np.rint(out.duration / self.robot.dt).astype(np.int64)
        sat = np.zeros((kk, m), dtype=np.int64)
        sq = np.zeros((kk, m))
        mx = np.zeros((kk, m))
        for active, k0, s_sat, s_err in ctx["chunks"]:  # type: ignore[attr-defined]
            n = s_err.shape[1]
            valid = (k0 + np.arange(n))[None, :] < at[active][:, None]  # steps before each sample's event
            sat[active] += (s_sat & valid[..., None]).sum(axis=1)
            e = np.where(valid[..., None], s_err, 0.0)
            sq[active] += (e * e).sum(axis=1)
            mx[active] = np.maximum(mx[active], np.abs(e).max(axis=1, initial=0.0))
        tail = None
        if "torques" in ctx:
            assert inputs is not None and inputs.delay_steps is not None
            tail = self._torque_tail(ctx["torques"], inputs, at)  # type: ignore[arg-type]
        res = FeedbackStepBatch(**vars(out), control_steps=at, saturation=sat, error_sq=sq, error_max=mx,
                                torque_tail=tail)
        self.stats.add(int(at.sum()), sat.sum(axis=0), sq.sum(axis=0), mx.max(axis=0, initial=0.0))
        return res

    def _engine_inputs(self, inputs: StepInputs) -> StepInputs:
        """The inputs as given (the law reads the sensor noise itself, :meth:`_closed_loop`); for a law whose
        latency is a servo command's (the PD), delay_steps is refused as by the rollout engine."""
        if inputs.delay_steps is not None and self.latency != "torque":
            return super()._engine_inputs(inputs)
        return inputs

    @staticmethod
    def _delayed(hist: Array, inputs: StepInputs, active: NDArray[np.int64], k: int) -> Array:
        """The central commands (A, m) that reach the drives at physics step k under actuation latency: computed
        ``delay_steps`` earlier — in this step (``hist``, (K, H, m)), or before it (``torque_tail``; without one,
        this step's first)."""
        assert inputs.delay_steps is not None
        j = k - inputs.delay_steps[active]
        out = hist[active, np.maximum(j, 0)]
        tail = inputs.torque_tail
        if tail is not None:
            t = tail.shape[1] + j
            rows = np.flatnonzero((j < 0) & (t >= 0))
            out[rows] = tail[active[rows], t[rows]]
        return out

    @staticmethod
    def _torque_tail(hist: Array, inputs: StepInputs, at: NDArray[np.int64]) -> Array:
        """(K, T, m), T = the largest delay (or the given tail's width, if wider: a tail keeps its width from step to
        step): the commands computed in the T physics steps before each sample's event, reaching back into this
        step's own ``torque_tail`` (or its first torque) for an event before step T."""
        assert inputs.delay_steps is not None
        given = 0 if inputs.torque_tail is None else inputs.torque_tail.shape[1]
        t = max(int(inputs.delay_steps.max(initial=0)), given)
        kk = hist.shape[0]
        before = np.repeat(hist[:, :1], t, axis=1)
        if inputs.torque_tail is not None and t:
            have = min(t, inputs.torque_tail.shape[1])
            before[:, t - have:] = inputs.torque_tail[:, inputs.torque_tail.shape[1] - have:]
        both = np.concatenate([before, hist], axis=1)
        rows = np.clip(at, 0, hist.shape[1])[:, None] + np.arange(t)[None, :]
        return np.asarray(both[np.arange(kk)[:, None], rows])

    @property
    def physics_model(self) -> mujoco.MjModel:
        """The model the closed loop steps (:func:`actuated_model`: the servo damping or torque motors of the law)."""
        return self._model

    def _rollout(self, active: NDArray[np.int64], current: NDArray[np.float64], ctrl: NDArray[np.float64],
                 k0: int, n: int, inputs: StepInputs | None, reg: NDArray[np.float64] | None = None
                 ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
        """n physics steps of the closed loop from step k0 for the samples ``active`` (module docstring); ``reg`` is
        always None (this engine refuses the step regulator).

        The controller's NumPy runs with one BLAS thread: its products are small, and a multi-threaded BLAS
        competing with the batch's threads (or another process) for the cores is several times slower
        (docs/feedback.md)."""
        with _one_blas_thread():
            return self._closed_loop(active, current, k0, n, inputs)

    def _step_functions(self, active: NDArray[np.int64], obs: Observation, xfrc: Array, inputs: StepInputs | None
                        ) -> tuple[Observe | None, Command | None, Command, Command | None, Push | None]:
        """What the closed loop calls at each physics step for the samples ``active`` (``obs``: their true state, live
        views of the batch; ``xfrc``: their applied forces), chosen once per chunk: the sensor noise
        (:func:`encoder_noise`), the command latency (:func:`command_latency`), the torque → control conversion
        (:func:`exact_servo_command`, :func:`motor_command` or :func:`servo_command`), the control offset
        (:func:`control_offset`) and the base wrench (:func:`base_push`); None for a disturbance not given."""
        robot, ctl = self.robot, self.controller
        observe = delay = offset = push = None
        if inputs is not None and inputs.sensor_noise is not None:
            observe = encoder_noise(obs, inputs.sensor_noise, active, robot.qpos_idx, robot.dof_idx)
        hist = self._step_ctx.get("torques") if self._step_ctx is not None else None  # latency: computed torques
        assert hist is None or isinstance(hist, np.ndarray)
        if hist is not None:
            assert inputs is not None
            delay = command_latency(hist, inputs, active, self.damping, obs.qvel, robot.dof_idx)
        command: Command
        if isinstance(ctl, PDController) and ctl.servo_exact:
            command = exact_servo_command(ctl, (active.size, robot.model.nu))
        elif self.motor:
            command = motor_command
        else:
            command = servo_command(robot.kp, self.damping, obs.qpos, obs.qvel, robot.qpos_idx, robot.dof_idx)
        if inputs is not None and inputs.ctrl_offset is not None:
            offset = control_offset(inputs.ctrl_offset, active, robot.kp if self.motor else None)
        if inputs is not None and inputs.base_wrench is not None:
            push = base_push(xfrc, robot.base_body_id, inputs.base_wrench, active)
        return observe, delay, command, offset, push

    def _closed_loop(self, active: NDArray[np.int64], current: NDArray[np.float64], k0: int, n: int,
                     inputs: StepInputs | None
                     ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
        robot, ctl = self.robot, self.controller
        na = active.size
        models: Sequence[mujoco.MjModel] | None = None
        base = self._model
        if inputs is not None and inputs.models is not None:
            models = [self._layout_model(inputs.models[i]) for i in active]
            base = models[0]
        b = self._batch(base, na)
        if models is not None:
            b.set_models(list(models) + [base] * (b.nsim - na))
        elif b.models is not None:
            b.set_models(None)
        ids = None if na == b.nsim else np.arange(na, dtype=np.int32)
        rows = b.state[:na]
        rows[:] = self._row_template
        rows[:, self._full_cols] = current[active]
        b.warning[:na] = 0
        qpos, qvel = b.bind("qpos")[:na], b.bind("qvel")[:na]
        ctrl_b, sd = b.bind("ctrl")[:na], b.bind("sensordata")[:na]
        fields = {name: b.bind(name)[:na] for name in ctl.fields}
        xfrc = b.bind("xfrc_applied")[:na]
        stage = ctl.stage
        if stage > STAGE_NONE:
            b.forward(ids, stage=stage)
        nu = robot.model.nu
        st = np.empty((na, n, self.nstate))
        sens = np.empty((na, n, robot.model.nsensordata))
        ctrls = np.zeros((na, n, robot.model.nu))  # the controls written, as StepEngine._rollout returns them
        sat = np.zeros((na, n, nu), dtype=bool)
        err = np.zeros((na, n, nu))
        full = self._full_slice if self._full_slice is not None else self._full_cols
        limit = robot.torque_limit
        frozen_at = np.full(na, -1)
        obs = Observation(qpos=qpos, qvel=qvel, samples=active, fields=fields)
        observe, delay, command, offset, push = self._step_functions(active, obs, xfrc, inputs)
        step_ids = ids
        for j in range(n):
            k = k0 + j
            tau, e = ctl.torque(k, obs if observe is None else observe(k))
            if delay is not None:
                tau = delay(k, tau)
            err[:, j] = e
            sat[:, j] = np.abs(tau) > limit
            c = command(k, tau)
            if offset is not None:
                c = offset(k, c)
            ctrl_b[:] = c
            ctrls[:, j] = c
            if push is not None:
                push(k)
            if stage > STAGE_NONE:
                sens[:, j] = sd  # the sensors of the state this step starts from, as mj_step records them
            b.step(step_ids, nstep=1, stage=stage)
            st[:, j] = rows[:, full]
            if stage == STAGE_NONE:
                sens[:, j] = sd
            # a simulation whose warning counters rose stops for the rest of the chunk (as mujoco.rollout)
            warned = (b.warning[:na, :, 1] > 0).any(axis=1) & (frozen_at < 0)
            if warned.any():
                frozen_at[warned] = j
                alive = np.flatnonzero(frozen_at < 0).astype(np.int32)
                step_ids = alive
                if alive.size == 0:
                    st[:, j + 1:] = st[:, j:j + 1]
                    sens[:, j + 1:] = sens[:, j:j + 1]
                    break
        for r in np.flatnonzero(frozen_at >= 0):
            sens[r, frozen_at[r] + 1:] = sens[r, frozen_at[r]]
        assert self._step_ctx is not None
        self._step_ctx["chunks"].append((active.copy(), k0, sat, err))  # type: ignore[attr-defined]
        return st, sens, ctrls
