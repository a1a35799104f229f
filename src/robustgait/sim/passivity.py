"""Passivity-based tracking of a flat-foot gait (Slotine–Li), written for the dynamics constrained by the stance
sole, for the feedback engine (:mod:`robustgait.sim.feedback`).

Law (actuated joints q_a ∈ Rᵐ in output order, desired y_d(τ) from the gait's Bézier outputs)::

    e = q_a − y_d,   q̇_r = ẏ_d − Λ e,   q̈_r = ÿ_d − Λ (q̇_a − ẏ_d),   s = q̇_a − q̇_r
    τ = M̃(q) q̈_r + C̃(q, q̇_a) q̇_r + G̃(q) − K_D s          (+ the gait's feedforward u_ff, optional)

with M̃, C̃, G̃ the reduced dynamics of the robot with its stance sole fixed to the ground, derived as follows.

Reduced dynamics. The full dynamics in MuJoCo's coordinates (free base: world linear velocity, body angular
velocity; then the joints) are M q̈ + c(q, q̇) + G = B τ + J_sᵀ λ, B = [0; I], with J_s = [J_b J_a] the 6 × nv
Jacobian of the stance sole's spatial velocity (J_b the 6 × 6 base block, invertible). While the sole is flat
on the ground J_s q̇ = 0, so the actuated velocities determine the base: q̇ = T q̇_a, T = [−J_b⁻¹ J_a; I]; and
J_s T = 0 ⇒ J_s Ṫ = −J̇_s T, so Ṫ x = [−J_b⁻¹ J̇_s T x; 0]. Since Tᵀ B = I and Tᵀ J_sᵀ = 0, premultiplying by
Tᵀ removes the contact force:

    M̃ q̈_a + c̃(q, q̇_a) + G̃ = τ,   M̃ = Tᵀ M T,   G̃ = Tᵀ G,   c̃(q, x) = Tᵀ [c(q, T x) + M Ṫ x]

(the projected dynamics of Aghili 2005 / Mistry & Righetti 2012 for a full-rank contact). With the foot fixed,
the base pose is a function of q_a, so this is a holonomic system in the true coordinates q_a with kinetic
energy ½ q̇_aᵀ M̃ q̇_a; c̃(q, ·) is its quadratic velocity term.

Choice of C̃. Slotine–Li's argument needs a factorization c̃(x) = C̃(x) x with dM̃/dt − 2 C̃ skew-symmetric.
The Christoffel factorization of M̃ has it, and it is the unique factorization that is symmetric,
C̃(x) y = C̃(y) x; so it is the polarization of the quadratic map c̃:

    C̃(q, q̇_a) q̇_r = ¼ [c̃(q, q̇_a + q̇_r) − c̃(q, q̇_a − q̇_r)]

Each c̃ evaluation needs c(q, v) = C(q, v) v (MuJoCo's RNE velocity terms) and the sole's bias acceleration
J̇_s(q, v) v at v = T x, both quadratic in v and computed for all samples at once by
:class:`robustgait.sim.rigidbody.TreeDynamics`. (Polarizing the full-coordinate c(q, v) instead and adding
Tᵀ M Ṫ(q̇_a) q̇_r is *not* skew-consistent here: MuJoCo's base angular velocity is a quasi-velocity, for
which the symmetric factorization of the full c does not give dM/dt − 2C skew-symmetric (already for a free
rigid body, ω × Iω); tests/sim/test_feedback.py measures both.) With it the closed loop is
M̃ ṡ + (C̃ + K_D) s = 0, V = ½ sᵀ M̃ s decreases as V̇ = −sᵀ K_D s, so s → 0 and then e → 0 as ė = −Λ e + s.

The state used is the simulated one; the reduced model takes the base velocity as T q̇_a (what the stance
contact imposes: MuJoCo's soft contacts let the sole creep slightly). The model is the robot's nominal one
(kinematics by :class:`~robustgait.sim.rigidbody.NominalKinematics`, dynamics by
:class:`~robustgait.sim.rigidbody.TreeDynamics`), also when the simulated plants are perturbed
(:class:`~robustgait.sim.engine.StepInputs` models). The law is meant for the single support
of flat-foot (one-domain) gaits; multi-contact gaits keep joint PD (:class:`~robustgait.sim.feedback.PDController`).

References: J.-J. E. Slotine and W. Li, "On the adaptive control of robot manipulators", IJRR 6(3), 1987;
Slotine & Li, *Applied Nonlinear Control*, 1991, §9.3; F. Aghili, "A unified approach for inverse and direct
dynamics of constrained multibody systems based on linear projection operator", IEEE T-RO 21(5), 2005;
M. Mistry and L. Righetti, "Operational space control of constrained and underactuated systems", RSS 2011;
Tucker, Li, Ames, arXiv 2310.06169 (passivity-based tracking of flat-foot exoskeleton gaits at 1 kHz).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Literal

import numpy as np
from numpy.typing import NDArray

from robustgait.errors import RobustGaitError
from robustgait.sim.feedback import STAGE_NONE, FeedbackController, Observation
from robustgait.sim.rigidbody import NominalKinematics, TreeDynamics

if TYPE_CHECKING:
    from robustgait.robots import Robot
    from robustgait.sim.feedback import FeedbackEngine

Array = NDArray[np.float64]


@dataclass(frozen=True)
class PassivityGains:
    """Per-joint gains of the passivity-based law (output order): ``lam`` Λ [1/s] and ``kd`` K_D [N m s/rad].
    The law's stiffness about the desired trajectory is about K_D Λ and its damping K_D + M̃ Λ."""

    lam: tuple[float, ...]
    kd: tuple[float, ...]

    def __post_init__(self) -> None:
        if len(self.lam) != len(self.kd) or any(v <= 0 for v in (*self.lam, *self.kd)):
            raise RobustGaitError("passivity gains: lambda and kd must be lists of positive numbers of one length")

    @classmethod
    def from_robot(cls, robot: Robot) -> PassivityGains:
        """The spec's ``[controller.passivity]`` gains; a spec without them cannot run the law (one-line error):
        gains are a property of the robot, tuned on it (docs/feedback.md), not derived from the PD's."""
        gains = getattr(robot.spec, "passivity", None)
        if gains is None:
            where = robot.spec.source or robot.name
            raise RobustGaitError(f"{where}: no [controller.passivity] gains (lambda, kd: one per joint): the "
                                  "passivity controller needs them (docs/robots.md)")
        return cls(tuple(gains.lam), tuple(gains.kd))

    @classmethod
    def matching_pd(cls, robot: Robot) -> PassivityGains:
        """Λ = kp/kd and K_D = kd: the PD's stiffness about the desired trajectory (K_D Λ = kp), for comparisons."""
        return cls(tuple(float(v) for v in robot.kp / robot.kd), tuple(float(v) for v in robot.kd))


class PassivityController(FeedbackController):
    """The passivity-based tracking law of this module for :class:`~robustgait.sim.feedback.FeedbackEngine`.

    ``gains``: Λ and K_D (default :meth:`PassivityGains.from_robot`); ``feedforward``: add the gait's
    feedforward torque (off by default: the law already contains the model's torque M̃ q̈_r + C̃ q̇_r + G̃);
    ``actuation``: see :mod:`robustgait.sim.feedback`.
    """

    name = "passivity"
    stage = STAGE_NONE  # the law computes its kinematics itself, with the nominal model (NominalKinematics)

    def __init__(self, gains: PassivityGains | None = None, *, feedforward: bool = False,
                 actuation: Literal["servo", "motor"] = "servo", implicit_damping: bool = True):
        self.gains = gains
        self.feedforward = feedforward
        self.actuation = actuation
        self.implicit_damping = implicit_damping and actuation == "servo"

    def servo_damping(self) -> Array | None:
        """With ``implicit_damping``: K_D, so that the law's −K_D q̇ is integrated implicitly by the servos."""
        return self.kd_s if self.implicit_damping else None

    def setup(self, engine: FeedbackEngine) -> None:
        super().setup(engine)
        robot = engine.robot
        if len(engine.graph) != 1:
            raise RobustGaitError("the passivity-based law is for flat-foot (one-domain) gaits; multi-contact "
                                  "gaits keep joint PD (PDController)")
        gains = self.gains or PassivityGains.from_robot(robot)
        if len(gains.lam) != robot.n_joints:
            raise RobustGaitError(f"passivity gains for {len(gains.lam)} joints, the robot has {robot.n_joints}")
        self.lam = np.asarray(gains.lam, dtype=float)
        self.kd_s = np.asarray(gains.kd, dtype=float)
        m = robot.model
        self.dyn = TreeDynamics(m)
        self.kinematics = NominalKinematics(m)
        self.base = np.arange(6)
        self.foot = {s: int(m.geom_bodyid[g]) for s, g in robot.sole_geom_id.items()}
        self.nv = m.nv

    def reduced(self, cdof: Array, stance: str) -> tuple[Array, Array, Array]:
        """For the stance sole: P = J_b⁻¹ J_a (K, 6, m), T = [−P; I] (K, nv, m) in MuJoCo's dof order, and the
        inverse J_b⁻¹ (K, 6, 6) of the base block of the sole's Jacobian (its spatial velocity in MuJoCo's
        com-based frame)."""
        foot = self.foot[stance]
        mask = self.dyn.anc[foot]
        jac = (cdof * mask[None, :, None]).transpose(0, 2, 1)  # (K, 6, nv): sole spatial velocity = jac q̇
        jb = jac[:, :, self.base]
        ja = jac[:, :, self.dof_idx]
        jb_inv = np.linalg.inv(jb)
        p = jb_inv @ ja
        t = np.zeros((cdof.shape[0], self.nv, p.shape[2]))
        t[:, self.base] = -p
        t[:, self.dof_idx, np.arange(p.shape[2])] = 1.0
        return p, t, jb_inv

    def law(self, cdof: Array, cinert: Array, qa: Array, dqa: Array, y: Array, dy: Array, ddy: Array,
            stance: str) -> Array:
        """τ (K, m) from the kinematic quantities of K states (``cdof`` (K, nv, 6), ``cinert`` (K, nbody, 10)),
        the actuated positions and velocities (K, m) and the desired outputs (m,) or (K, m)."""
        dyn = self.dyn
        st = dyn.prepare(cdof, cinert)
        e = qa - y
        dqr = dy - self.lam * e
        ddqr = ddy - self.lam * (dqa - dy)
        s = dqa - dqr
        p, t, jb_inv = self.reduced(cdof, stance)
        x = np.stack([dqa + dqr, dqa - dqr], axis=1)  # (K, 2, m)
        v = x @ t.transpose(0, 2, 1)  # (K, 2, nv)
        c, acc = dyn.velocity_terms(st, v)
        dc = 0.25 * (c[:, 0] - c[:, 1])  # symmetric bilinear part of c at (T q̇_a, T q̇_r)
        dh = 0.25 * (acc[:, 0, self.foot[stance]] - acc[:, 1, self.foot[stance]])  # same for J̇_s v
        a = (t @ ddqr[..., None])[..., 0]
        a[:, self.base] -= (jb_inv @ dh[..., None])[..., 0]
        f = dyn.acceleration_terms(st, a) + dc  # M a + G + sym. Coriolis
        return f[:, self.dof_idx] - (f[:, None, self.base] @ p)[:, 0] - self.kd_s * s

    def reduced_model(self, cdof: Array, cinert: Array, dqa: Array, stance: str) -> tuple[Array, Array, Array]:
        """The reduced dynamics as matrices, for analysis and tests: M̃ (K, m, m), C̃(q, q̇_a) (K, m, m) (the
        Christoffel factorization, column j = C̃ e_j by polarization) and G̃ (K, m)."""
        dyn = self.dyn
        st = dyn.prepare(cdof, cinert)
        _, t, jb_inv = self.reduced(cdof, stance)
        nj = dqa.shape[1]
        eye = np.eye(nj)
        x = np.concatenate([dqa[:, None] + eye[None], dqa[:, None] - eye[None]], axis=1)  # (K, 2m, m)
        v = np.einsum("knm,kpm->kpn", t, x)
        c, acc = dyn.velocity_terms(st, v)
        foot = self.foot[stance]
        dc = 0.25 * (c[:, :nj] - c[:, nj:])  # (K, m, nv): row j = C(T q̇_a, T e_j) part
        dh = 0.25 * (acc[:, :nj, foot] - acc[:, nj:, foot])  # (K, m, 6)
        mass = dyn.mass_matrix(st)
        base_acc = -(jb_inv[:, None] @ dh[..., None])[..., 0]  # (K, m, 6): Ṫ-part per column
        full = dc + np.einsum("kij,kmj->kmi", mass[:, :, self.base], base_acc)  # (K, m, nv)
        cmat = np.einsum("knm,kjn->kmj", t, full)  # C̃[:, j] = Tᵀ full_j
        mt = np.einsum("kni,knl,klj->kij", t, mass, t)
        gt = np.einsum("kni,kn->ki", t, dyn.gravity(st))
        return mt, cmat, gt

    def torque(self, k: int, obs: Observation) -> tuple[Array, Array]:
        des = self.desired[(self.stance, self.domain)]
        qa = obs.qpos[:, self.qpos_idx]
        dqa = obs.qvel[:, self.dof_idx]
        cdof, cinert = self.kinematics(obs.qpos)
        tau = self.law(cdof, cinert, qa, dqa, des.y[k], des.dy[k], des.ddy[k], self.stance)
        if self.feedforward:
            tau += des.uff[k]
        return tau, qa - des.y[k]
