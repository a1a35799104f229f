"""The step-to-step Poincaré map on the switching surface, in a reduced state (``docs/certificate.md``).

Section S: the switching events of the simulator (swing-foot touchdown once τ ≥ ``min_switch_tau``, the paper's
x⁻ ∈ S). A state on S starts a step of one stance. *Canonical* states are written for the gait's own stance
(``gait.stance``); a state that starts a step of the other stance is mirrored (:meth:`Robot.mirror_state`),
so a symmetric gait has a period-1 fixed point of the **step map** P: S → S (one step, then mirror). The
**stride map** is two steps, no mirroring. With a horizon k the map certified is P^k: k maps on full states, a
fall in any of them a fall.

The fixed point x* is searched on full states and converged in the paper's reduced state, the base angular
velocity ω in the ``heading`` frame (:func:`robustgait.reduced.reduce_state`); the certificate's reduced state
(Φ, ι and metric of ``certify.state``: :class:`robustgait.reduced.ReducedState`) is set up at it. Frames of ω:

* ``heading`` (default): ω in the world frame rotated by the base's yaw, R_z(ψ)ᵀ ω. Equals the world frame
  for a robot heading along +x, and is invariant to the slow heading drift of a real walk — which the
  world frame is not once states are mirrored (measured on the Atalante gait, step-map iterates 50–100:
  yaw drifts from +0.007 to −0.083 rad; world-frame residual median 6.9e-3, max 1.6e-2 rad/s; heading
  frame median 2.7e-3, max 4.9e-3).
* ``world``: ω in the world frame, R ω_body.
* ``body``: ω_body, MuJoCo's ``qvel[3:6]``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from robustgait.config import CertifyConfig, Frame, SimConfig
from robustgait.domains import step_segments
from robustgait.errors import RobustGaitError
from robustgait.gait import Gait
from robustgait.reduced import ReducedState, reduce_state
from robustgait.robots import Robot
from robustgait.sim.factory import make_engine
from robustgait.sim.walk import SwitchEvent

FloatArray = NDArray[np.float64]


def canonical_reduced_events(robot: Robot, gait: Gait, events: list[SwitchEvent], frame: Frame) -> FloatArray:
    """Reduced states (len(events), 3) of a walk's switching events, each written for the gait's own stance
    (events that start a step of the other stance are mirrored) — the sequence the step map acts on."""
    rows = []
    for e in events:
        qpos, qvel = np.asarray(e.qpos)[None], np.asarray(e.qvel)[None]
        if e.stance == gait.stance:  # the step that ended was canonical: the next one is not
            qpos, qvel = robot.mirror_state(qpos, qvel)
        rows.append(reduce_state(qpos, qvel, frame)[0])
    return np.array(rows).reshape(-1, 3)


class FixedPointFailure(RobustGaitError):
    """The fixed-point search failed — a property of the gait, not bad input: ``status`` is
    ``fell_before_fixed_point`` or ``no_fixed_point``; ``steps`` the steps walked (completed) before it ended."""

    def __init__(self, status: str, steps: int, message: str):
        super().__init__(message)
        self.status = status
        self.steps = steps


@dataclass(frozen=True)
class FixedPoint:
    """x* of the chosen map: its full canonical state (qpos, qvel), its base angular velocity ω* (3,) in the search's
    frame, the residual ‖ω_k − ω_{k−1}‖ of the map's iterates where it was taken, the steps walked, and all
    residuals."""

    qpos: FloatArray
    qvel: FloatArray
    omega: FloatArray
    residual: float
    steps: int
    residuals: tuple[float, ...]


class ReturnMap:
    """The batched return map P^k: (N, n) → (N, n) of a gait in its reduced state (NaN rows: the sample fell within
    the k maps), of the kind, horizon, state, frame and reconstruction of ``config`` (``map``, ``horizon``,
    ``state``, ``frame``, ``reconstruction``), simulated with ``sim``. The reduced state is set up at the fixed
    point: call :meth:`find_fixed_point` (or :meth:`set_fixed_point`) first."""

    def __init__(self, robot: Robot, gait: Gait, config: CertifyConfig | None = None, sim: SimConfig | None = None):
        config = config or CertifyConfig()
        if gait.initial_state is None:
            raise RobustGaitError("the gait has no initial state to find a fixed point from")
        self.config = config
        self.robot, self.gait, self.kind, self.frame = robot, gait, config.map, config.frame
        self.reconstruction = config.reconstruction
        self.engine = make_engine(robot, gait, sim)
        self.stance = gait.stance
        self.other = "left" if gait.stance == "right" else "right"
        self.horizon = config.horizon
        self.fixed_point: FixedPoint | None = None
        self._reduced: ReducedState | None = None
        self.physics_steps = 0
        # the reduced iterates P^1 … P^k of the last call's samples, (k, N, n); NaN from a fall on
        self.last_path: FloatArray | None = None

    def close(self) -> None:
        self.engine.close()

    def __enter__(self) -> ReturnMap:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    @property
    def period(self) -> int:
        return 1 if self.kind == "step" else 2

    def find_fixed_point(self, progress: Callable[[int, float], None] | None = None) -> FixedPoint:
        """Iterate the map on full states from the gait's initial state until the reduced state converges:
        x* = the first iterate after ``min_steps`` steps with ‖x̄_k − x̄_{k−1}‖ < tol (the config's ``fp_tol``,
        ``min_steps``, ``fp_max_steps``).

        Iterating the map itself (canonical stance, then mirror) rather than walking on alternating legs
        makes x̄* a fixed point of exactly the map that is certified, also for a robot whose MJCF is not
        perfectly left/right symmetric. Raises :class:`FixedPointFailure` (a RobustGaitError) if the gait falls
        first or no iterate within ``max_steps`` steps converges (with the residuals seen).
        ``progress(step, residual)`` after each.
        """
        tol, min_steps, max_steps = self.config.fp_tol, self.config.min_steps, self.config.fp_max_steps
        qpos, qvel = self.initial_section()
        prev = reduce_state(qpos, qvel, self.frame)[0]
        residuals: list[float] = []
        for k in range(self.period, max_steps + 1, self.period):
            qpos, qvel, reason = self._advance(qpos, qvel)
            if reason[0] is not None:
                raise FixedPointFailure("fell_before_fixed_point", k - self.period,
                                        f"the gait fell within step {k} ({reason[0]}) before a fixed point was "
                                        "reached")
            x = reduce_state(qpos, qvel, self.frame)[0]
            residuals.append(float(np.linalg.norm(x - prev)))
            prev = x
            if progress is not None:
                progress(k, residuals[-1])
            if k >= min_steps and residuals[-1] < tol:
                return self.set_fixed_point(FixedPoint(qpos[0].copy(), qvel[0].copy(), x.copy(), residuals[-1], k,
                                                       tuple(residuals)))
        raise FixedPointFailure("no_fixed_point", len(residuals) * self.period,
                                f"no fixed point within {max_steps} steps: the {self.kind}-map residual "
                                f"‖x̄_k+1 − x̄_k‖ stayed above tol = {tol:g} (smallest {min(residuals):.3g}, last "
                                f"{residuals[-1]:.3g})")

    def initial_section(self) -> tuple[FloatArray, FloatArray]:
        """The gait's initial state as a canonical section state (1, nq), (1, nv): itself for a flat-foot gait; a
        multi-contact gait starts at the beginning of single support, so it is walked to its heel strike first and
        mirrored. Raises :class:`FixedPointFailure` if it falls on the way."""
        init = self.gait.initial_state
        if init is None:
            raise RobustGaitError("the gait has no initial state to start from")
        qpos, qvel = init.qpos[None].copy(), init.qvel[None].copy()
        if len(self.engine.graph) > 1:
            qpos, qvel, reason = self._run(qpos, qvel, [(self.stance, 0)])
            if reason[0] is not None:
                raise FixedPointFailure("fell_before_fixed_point", 0,
                                        f"the gait fell within step 1 ({reason[0]}) before a fixed point was reached")
            qpos, qvel = self.robot.mirror_state(qpos, qvel)
        return qpos, qvel

    def _run(self, qpos: FloatArray, qvel: FloatArray, phases: list[tuple[str, int]],
             progress: Callable[[int], None] | None = None) -> tuple[FloatArray, FloatArray, list[str | None]]:
        """Simulate phases in order (``progress`` on the last); a sample that falls in one is NaN afterwards."""
        reasons: list[str | None] = [None] * qpos.shape[0]
        for j, (stance, d) in enumerate(phases):
            b = self.engine.step(qpos, qvel, stance, domain=d, progress=progress if j == len(phases) - 1 else None)
            self.physics_steps += b.physics_steps
            reasons = [r0 if r0 is not None else r1 for r0, r1 in zip(reasons, b.fall_reason, strict=True)]
            qpos, qvel = b.qpos, b.qvel
        fell = np.array([r is not None for r in reasons])
        qpos, qvel = qpos.copy(), qvel.copy()
        qpos[fell] = np.nan
        qvel[fell] = np.nan
        return qpos, qvel, reasons

    def _advance(self, qpos: FloatArray, qvel: FloatArray,
                 progress: Callable[[int], None] | None = None) -> tuple[FloatArray, FloatArray, list[str | None]]:
        """The map on full canonical states (K, nq), (K, nv): one step and a mirror, or a stride. Returns the
        images (NaN rows for falls) and each sample's fall reason (None if it did not fall).

        A canonical state lies on the section at the end of a single support of the other leg, so the step
        map simulates the rest of that step (multi-contact: its double support) and the gait's own stance's
        single support, then mirrors; the stride map goes on through the other leg's step instead."""
        n = len(self.engine.graph)
        if self.kind == "step":
            qpos, qvel, reasons = self._run(qpos, qvel, step_segments(self.stance, n), progress)
            mq, mv = self.robot.mirror_state(qpos, qvel)
            return mq, mv, reasons
        return self._run(qpos, qvel, step_segments(self.stance, n) + step_segments(self.other, n), progress)

    def set_fixed_point(self, fp: FixedPoint) -> FixedPoint:
        """Use ``fp`` as x* (e.g. found earlier by this map) and set the reduced state up at it."""
        self.fixed_point = fp
        self._reduced = ReducedState.at(self.config.state, self.robot, fp.qpos, fp.qvel, self.stance, self.config)
        return fp

    @property
    def reduced(self) -> ReducedState:
        """The certificate's reduced state (Φ, ι, metric) at the fixed point."""
        if self._reduced is None:
            raise RobustGaitError("find the fixed point first (ReturnMap.find_fixed_point)")
        return self._reduced

    @property
    def dim(self) -> int:
        return self.reduced.dim

    def reconstruct(self, xbar: FloatArray) -> tuple[FloatArray, FloatArray]:
        """ι(x̄): full canonical states (N, nq), (N, nv) from reduced states (N, n)
        (:meth:`robustgait.reduced.ReducedState.iota`)."""
        return self.reduced.iota(np.atleast_2d(np.asarray(xbar, dtype=float)))

    def __call__(self, xbar: FloatArray, progress: Callable[[int], None] | None = None) -> FloatArray:
        """P^k(x̄) = Φ(Δ^k(ι(x̄))) for a batch (N, n), k = the horizon; NaN rows where the sample fell within any of
        the k steps (or strides). The iterates P^1 … P^k are kept in ``last_path`` (k, N, n)."""
        red = self.reduced
        qpos, qvel = self.reconstruct(xbar)
        path = np.full((self.horizon, qpos.shape[0], red.dim), np.nan)
        for j in range(self.horizon):
            qpos, qvel, _ = self._advance(qpos, qvel, progress=progress if j == self.horizon - 1 else None)
            ok = np.isfinite(qvel).all(axis=1)
            if ok.any():
                path[j, ok] = red.phi(qpos[ok], qvel[ok])
        self.last_path = path
        return path[-1].copy()
