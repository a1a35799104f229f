"""The step-to-step Poincaré map on the switching surface, reduced to the base angular velocity
(``docs/certificate.md``).

Section S: the switching events of the simulator (swing-foot touchdown once τ ≥ 0.8, the paper's x⁻ ∈ S).
A state on S starts a step of one stance. *Canonical* states are written for the gait's own stance
(``gait.stance``); a state that starts a step of the other stance is mirrored (:meth:`Robot.mirror_state`),
so a symmetric gait has a period-1 fixed point of the **step map** P: S → S (one step, then mirror). The
**stride map** is two steps, no mirroring.

Reduced coordinates x̄ = Φ(x) (paper: x̄ = [0 I 0] x, the base angular velocity):

* ``heading`` (default): ω in the world frame rotated by the base's yaw, R_z(ψ)ᵀ ω. Equals the world frame
  for a robot heading along +x, and is invariant to the slow heading drift of a real walk — which the
  world frame is not once states are mirrored (measured on the Atalante gait, step-map iterates 50–100:
  yaw drifts from +0.007 to −0.083 rad; world-frame residual median 6.9e-3, max 1.6e-2 rad/s; heading
  frame median 2.7e-3, max 4.9e-3).
* ``world``: ω in the world frame, R ω_body.
* ``body``: ω_body, MuJoCo's ``qvel[3:6]``.

Reconstruction ι(x̄) of a full state from the fixed point's full state x* (names reported in certificates):

* ``holonomic`` (default): set the base angular velocity to x̄ and change the joint velocities and base
  linear velocity by the least-squares change (in the joint velocities) that keeps the stance sole's
  linear and angular velocity what they are at x*: J_s δq̇ = 0 (:func:`holonomic_reconstruction`).
  ι(x̄*) = x* exactly, so x̄* stays a fixed point of the reconstructed map.
* ``angular-only``: replace the base angular velocity, nothing else.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import mujoco
import numpy as np
from numpy.typing import NDArray

from robustgait.config import CertifyConfig, Frame, SimConfig
from robustgait.errors import RobustGaitError
from robustgait.gait import Gait
from robustgait.robots import Robot
from robustgait.rotations import quat_to_mat
from robustgait.sim.engine import StepEngine
from robustgait.sim.walk import SwitchEvent

FloatArray = NDArray[np.float64]


def frame_rotation(qpos: FloatArray, frame: Frame) -> FloatArray:
    """A (..., 3, 3) with Φ = A ω_body: R (world), R_z(ψ)ᵀ R (heading, ψ = yaw of the base x axis), I (body)."""
    r = quat_to_mat(np.asarray(qpos)[..., 3:7])
    if frame == "body":
        return np.broadcast_to(np.eye(3), r.shape).copy()
    if frame == "world":
        return r
    psi = np.arctan2(r[..., 1, 0], r[..., 0, 0])
    c, s = np.cos(psi), np.sin(psi)
    zero, one = np.zeros_like(c), np.ones_like(c)
    rz_t = np.stack([np.stack([c, s, zero], -1), np.stack([-s, c, zero], -1), np.stack([zero, zero, one], -1)], -2)
    return np.asarray(rz_t @ r)


def reduce_state(qpos: FloatArray, qvel: FloatArray, frame: Frame) -> FloatArray:
    """Φ(x) = A(q) ω_body, the base angular velocity in ``frame``: qpos (K, nq), qvel (K, nv) → (K, 3).

    Paper: x̄ = [0 I 0] x (Tucker, Li, Ames, arXiv 2310.06169, §IV).
    """
    a = frame_rotation(qpos, frame)
    return np.einsum("kij,kj->ki", a, np.asarray(qvel)[..., 3:6])


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
    """x* of the chosen map: its full canonical state (qpos, qvel), reduced x̄* (3,), the residual
    ‖x̄_k − x̄_{k−1}‖ of the map's iterates where it was taken, the steps walked, and all residuals."""

    qpos: FloatArray
    qvel: FloatArray
    x_star: FloatArray
    residual: float
    steps: int
    residuals: tuple[float, ...]


class ReturnMap:
    """The batched return map P: (N, 3) → (N, 3) of a gait (NaN rows: the sample fell), of the kind, frame and
    reconstruction of ``config`` (``map``, ``frame``, ``reconstruction``), simulated with ``sim``."""

    def __init__(self, robot: Robot, gait: Gait, config: CertifyConfig | None = None, sim: SimConfig | None = None):
        config = config or CertifyConfig()
        if gait.initial_state is None:
            raise RobustGaitError("the gait has no initial state to find a fixed point from")
        self.config = config
        self.robot, self.gait, self.kind, self.frame = robot, gait, config.map, config.frame
        self.reconstruction = config.reconstruction
        self.engine = StepEngine(robot, gait, sim)
        self.stance = gait.stance
        self.other = "left" if gait.stance == "right" else "right"
        self.fixed_point: FixedPoint | None = None
        self.physics_steps = 0

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
        init = self.gait.initial_state
        assert init is not None
        qpos, qvel = init.qpos[None].copy(), init.qvel[None].copy()
        if len(self.engine.graph) > 1:
            # a multi-contact gait starts at the beginning of single support: walk to its section first
            qpos, qvel, reason = self._run(qpos, qvel, [(self.stance, 0)])
            if reason[0] is not None:
                raise FixedPointFailure("fell_before_fixed_point", 0,
                                        f"the gait fell within step 1 ({reason[0]}) before a fixed point was reached")
            qpos, qvel = self.robot.mirror_state(qpos, qvel)
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
                self.fixed_point = FixedPoint(qpos[0].copy(), qvel[0].copy(), x.copy(), residuals[-1], k,
                                              tuple(residuals))
                return self.fixed_point
        raise FixedPointFailure("no_fixed_point", len(residuals) * self.period,
                                f"no fixed point within {max_steps} steps: the {self.kind}-map residual "
                                f"‖x̄_k+1 − x̄_k‖ stayed above tol = {tol:g} (smallest {min(residuals):.3g}, last "
                                f"{residuals[-1]:.3g})")

    def _phases(self, first: str) -> list[tuple[str, int]]:
        """(stance, domain) of one step's worth of simulation from a section state that ends the single
        support of the leg other than ``first``: that step's remaining domains, then ``first``'s single
        support up to its section (flat gaits: just ``first``'s step)."""
        other = "left" if first == "right" else "right"
        return [(other, d) for d in range(1, len(self.engine.graph))] + [(first, 0)]

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
        if self.kind == "step":
            qpos, qvel, reasons = self._run(qpos, qvel, self._phases(self.stance), progress)
            mq, mv = self.robot.mirror_state(qpos, qvel)
            return mq, mv, reasons
        return self._run(qpos, qvel, self._phases(self.stance) + self._phases(self.other), progress)

    def reconstruct(self, xbar: FloatArray) -> tuple[FloatArray, FloatArray]:
        """ι(x̄): full canonical states (N, nq), (N, nv) from reduced states (N, 3) (module docstring)."""
        fp = self._fp()
        xbar = np.asarray(xbar, dtype=float)
        n = xbar.shape[0]
        qpos = np.tile(fp.qpos, (n, 1))
        qvel = np.tile(fp.qvel, (n, 1))
        a = frame_rotation(fp.qpos, self.frame)
        d_omega = (xbar - fp.x_star) @ np.linalg.inv(a).T  # body-frame change of ω for each sample
        if self.reconstruction == "angular-only":
            qvel[:, 3:6] += d_omega
        else:
            qvel += d_omega @ holonomic_reconstruction(self.robot, fp.qpos, self.stance).T
        return qpos, qvel

    def _fp(self) -> FixedPoint:
        if self.fixed_point is None:
            raise RobustGaitError("find the fixed point first (ReturnMap.find_fixed_point)")
        return self.fixed_point

    def __call__(self, xbar: FloatArray, progress: Callable[[int], None] | None = None) -> FloatArray:
        """P(x̄) = Φ(Δ(ι(x̄))) for a batch (N, 3); NaN rows where the sample fell (within the step or stride)."""
        qpos, qvel, _ = self._advance(*self.reconstruct(xbar), progress=progress)
        out = np.full((qpos.shape[0], 3), np.nan)
        ok = np.isfinite(qvel).all(axis=1)
        out[ok] = reduce_state(qpos[ok], qvel[ok], self.frame)
        return out


def holonomic_reconstruction(robot: Robot, qpos: FloatArray, stance: str) -> FloatArray:
    """Linear map G (nv, 3): the velocity change δq̇ = G δω for a change δω of the base's body-frame
    angular velocity that keeps the stance sole's twist unchanged, with the least joint-velocity change.

    Solves  min ½‖δq̇_j‖²  s.t.  J_s δq̇ = 0,  δq̇ = (δv, δω, δq̇_j),  δω given,  δv free,
    via its KKT system [[I, 0, J_jᵀ], [0, 0, J_vᵀ], [J_j, J_v, 0]] [δq̇_j; δv; λ] = [0; 0; −J_ω δω], where
    J_s = [J_v J_ω J_j] (6 × nv) is the stance sole geom's (translational; rotational) Jacobian in MuJoCo's
    velocity coordinates (``mj_jacGeom``). qpos (nq,). (``docs/certificate.md``, "holonomic" reconstruction.)
    """
    m = robot.model
    d = mujoco.MjData(m)
    d.qpos[:] = qpos
    mujoco.mj_kinematics(m, d)
    mujoco.mj_comPos(m, d)
    jp, jr = np.zeros((3, m.nv)), np.zeros((3, m.nv))
    mujoco.mj_jacGeom(m, d, jp, jr, robot.sole_geom_id[stance])
    js = np.vstack([jp, jr])
    jv, jw, jj = js[:, 0:3], js[:, 3:6], js[:, 6:]
    nj = jj.shape[1]
    kkt = np.zeros((nj + 3 + 6, nj + 3 + 6))
    kkt[:nj, :nj] = np.eye(nj)
    kkt[:nj, nj + 3:] = jj.T
    kkt[nj:nj + 3, nj + 3:] = jv.T
    kkt[nj + 3:, :nj] = jj
    kkt[nj + 3:, nj:nj + 3] = jv
    rhs = np.zeros((nj + 9, 3))
    rhs[nj + 3:] = -jw
    sol = np.linalg.lstsq(kkt, rhs, rcond=None)[0]
    g = np.zeros((m.nv, 3))
    g[3:6] = np.eye(3)
    g[0:3] = sol[nj:nj + 3]
    g[6:] = sol[:nj]
    return g
