"""Symbolic rigid-body model of a robot (adam-robotics + CasADi), consistent with its MuJoCo model.

:class:`Dynamics` builds an adam ``KinDynComputations`` (CasADi backend) from the robot's MuJoCo model
(``KinDynComputations.from_mujoco_model``) with the joints in the robot spec's output order and the
model's own gravity (9.81 for our robots; adam's default is 9.80665).

Coordinates. MuJoCo: ``qpos = [p (3), quat (w, x, y, z), joints]``, ``qvel = [ṗ (world), ω_B (base
frame), joint rates]``, joints in model order. adam (mixed representation): base pose as the 4×4
transform ``H = [[R, p], [0, 1]]``, velocity ``ν = [ṗ (world), ω (world), ṡ]``, joints ``s`` in spec
order. With the (n+6)×(n+6) map ``T(q) = blockdiag(I₃, R(q), P)`` (``P`` the spec-order permutation of
the joint dofs) ``ν = T q̇`` and ``q̇ = Tᵀ ν`` (``T`` is orthogonal). The dynamics transform as

    M_mj = Tᵀ M_adam T + diag(armature),    h_mj = Tᵀ h_adam(q, T q̇)

(power balance; ``Ṫ q̇ = 0`` because ``d/dt(R) ω_B = R (ω_B × ω_B) = 0``), so ``M_mj q̈ + h_mj = τ``
is MuJoCo's ``mj_fullM`` / ``qfrc_bias`` form. Passive forces (joint damping, springs, friction loss)
are not in ``qfrc_bias`` and are not modelled here (the shipped robots have none), except a closed chain's springs
when they are planned compliant (``Dynamics(robot, springs="compliant")``: :meth:`Dynamics.spring_torque`).

Pitfalls of adam 0.5 ``from_mujoco_model`` (found with MuJoCo 4.0; handled here on a private copy of
the model, compiled from the robot's MjSpec, that only adam sees):

* Joint ``pos``: adam puts the child link's frame at the joint, keeping the body's inertial offset
  and children's positions — a wrong model (3.9 % mass-matrix error on a test model). We move each
  such body's frame to its joint (``body_pos += R_body p``, ``body_ipos`` and children's ``body_pos``
  ``-= p``), which leaves MuJoCo's dynamics unchanged. Link frames in adam are then at the joints.
* Frames: adam makes frames only from massless, childless, jointless bodies (sites are ignored). The
  foot frames ``{side}_{sole,toe,heel}_frame`` (centre of the sole's bottom face; midpoints of its
  bottom toe and heel edges; axes: x to the toe, z out of the sole) are taken from the MJCF when
  present (``exo``), else added from the spec's sole box geom in the model's zero posture (Atalante).
* Every other body below the world body becomes a second tree root (adam raises): the masses of
  static bodies outside the robot are zeroed (they do not move, so the dynamics are unchanged).
* A body with several joints is not supported by adam's factory: we raise a clear error.
* ``use_mujoco_actuators=True`` takes joint names from actuator *names* (ours are
  ``robustgait_<joint>``): we always pass ``joints_name_list`` (spec order) instead.
* Body quaternions with a ±90° pitch make scipy warn about gimbal lock while adam converts them to
  roll-pitch-yaw; the conversion stays exact to ~1e-16, so the warning is silenced.
* MuJoCo 4.0 itself: ``MjData.qM`` is gone and ``mj_fullM(m, d, dst)`` takes ``d`` (used in tests).
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from dataclasses import dataclass
from functools import cached_property
from typing import Any, overload

import casadi as cs
import mujoco
import numpy as np
from adam.casadi import KinDynComputations
from numpy.typing import ArrayLike, NDArray

from robustgait.closure import PlanLoop, plan_loops
from robustgait.config.robot import LOOP_TOLERANCE
from robustgait.domains import Contact
from robustgait.errors import input_error
from robustgait.robots import Robot
from robustgait.robots.loops import BALL, NULL_FRACTION, close_loops, closed_chains
from robustgait.robots.spec import SIDES
from robustgait.rotations import quat_to_mat

FOOT_FRAME_KINDS = ("sole", "toe", "heel")
Array = NDArray[np.float64]


def foot_frame(side: str, kind: str) -> str:
    """Name of a foot frame body, e.g. ``foot_frame("left", "toe") == "left_toe_frame"``."""
    return f"{side}_{kind}_frame"


def _rotation_rows(w: Any, x: Any, y: Any, z: Any) -> list[list[Any]]:
    return [
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    ]


@overload
def quat_to_rotation(quat: cs.SX) -> cs.SX: ...
@overload
def quat_to_rotation(quat: ArrayLike) -> Array: ...
def quat_to_rotation(quat: ArrayLike | cs.SX) -> Array | cs.SX:
    """Rotation matrix (3, 3) of a quaternion ``(w, x, y, z)`` (MuJoCo's order), normalized first as MuJoCo
    does. Numeric (NumPy array in and out) or symbolic (CasADi SX in and out)."""
    if isinstance(quat, cs.SX):
        qs = quat / cs.norm_2(quat)
        return cs.vertcat(*(cs.horzcat(*row) for row in _rotation_rows(qs[0], qs[1], qs[2], qs[3])))
    return quat_to_mat(quat)


@overload
def base_transform(qpos: cs.SX) -> cs.SX: ...
@overload
def base_transform(qpos: ArrayLike) -> Array: ...
def base_transform(qpos: ArrayLike | cs.SX) -> Array | cs.SX:
    """Base pose ``H`` (4, 4) = ``[[R, p], [0, 1]]`` from ``qpos[:7] = [p, quat (w, x, y, z)]`` (the rest
    of ``qpos`` is ignored): adam's ``base_transform`` argument. Numeric or symbolic like
    :func:`quat_to_rotation`."""
    if isinstance(qpos, cs.SX):
        return cs.vertcat(cs.horzcat(quat_to_rotation(qpos[3:7]), qpos[:3]), cs.horzcat(0, 0, 0, 1))
    q = np.asarray(qpos, dtype=float)
    H = np.eye(4)
    H[:3, :3] = quat_to_rotation(q[3:7])
    H[:3, 3] = q[:3]
    return H


def _sole_frames(robot: Robot, side: str) -> dict[str, tuple[Array, Array]]:
    """Foot frames of a sole box (:class:`~robustgait.robots.solebox.SoleBox`), as (pos, quat) in the geom's body
    frame: its bottom face's centre (``sole``), toe and heel, with the foot frame's axes (x heel to toe, z up)."""
    m, sole = robot.model, robot.sole_boxes[side]
    R_gb = quat_to_rotation(m.geom_quat[sole.geom])
    quat = np.zeros(4)
    mujoco.mju_mat2Quat(quat, (R_gb @ sole.frame_rotation()).ravel())
    return {k: (m.geom_pos[sole.geom] + R_gb @ sole.point(along), quat)
            for k, along in (("sole", 0.0), ("toe", 1.0), ("heel", -1.0))}


def _symmetrize(m: mujoco.MjModel, robot: Robot, frames: dict[str, dict[str, tuple[Array, Array]]]) -> None:
    """Place the added foot frames as exact mirror images of each other (in place).

    Each frame's world position in the zero posture is replaced by the mean of itself and the mirror image
    (y → −y about the base's sagittal plane) of its twin on the other foot. The mirror relabeling then maps
    one stance foot's frame onto the other's, as periodicity after relabeling assumes; a model whose soles
    are not placed symmetrically (Atalante: both sole boxes sit 33 µm to the right of their feet) has its
    frames moved by half the asymmetry.
    """
    d = mujoco.MjData(m)
    mujoco.mj_kinematics(m, d)
    flip = np.array([1.0, -1.0, 1.0])
    body = {side: int(m.geom_bodyid[robot.sole_geom_id[side]]) for side in SIDES}
    world = {side: {k: d.xpos[body[side]] + d.xmat[body[side]].reshape(3, 3) @ pos
                    for k, (pos, _) in frames[side].items()} for side in SIDES}
    for kind in frames["left"]:
        mean_left = 0.5 * (world["left"][kind] + flip * world["right"][kind])
        for side, target in (("left", mean_left), ("right", flip * mean_left)):
            R = d.xmat[body[side]].reshape(3, 3)
            frames[side][kind] = (R.T @ (target - d.xpos[body[side]]), frames[side][kind][1])


def _adam_model(robot: Robot) -> tuple[mujoco.MjModel, list[PlanLoop], tuple[int, ...]]:
    """The robot's model prepared for adam: foot frames added, joint frames moved, statics massless, and a closed
    chain's rods replaced by distance rows (:func:`robustgait.closure.plan_loops`). Returns it, the loops' rows and the
    passive joints (ids in ``robot.model``) that stay coordinates."""
    mjs = robot.mjspec()
    m = robot.model
    loops, hinges = plan_loops(mjs, m, robot.spec.source or robot.spec.mjcf) if robot.passive_ids else ([], ())
    frames = {side: _sole_frames(robot, side) for side in SIDES}
    _symmetrize(m, robot, frames)
    for side in SIDES:
        geom = robot.sole_geom_id[side]
        parent = mjs.body(m.body(int(m.geom_bodyid[geom])).name)
        if parent is None:
            raise input_error(robot.spec.mjcf, f"the body of the {side} sole geom needs a name")
        for kind, (pos, quat) in frames[side].items():
            if mjs.body(foot_frame(side, kind)) is None:
                parent.add_body(name=foot_frame(side, kind), pos=pos, quat=quat)
    m = mjs.compile()
    base = m.body(robot.spec.base_body).id
    for b in range(1, m.nbody):
        root = b
        while int(m.body_parentid[root]) != 0:
            root = int(m.body_parentid[root])
        if root != base:
            m.body_mass[b] = 0.0
            m.body_inertia[b] = 0.0
            continue
        if int(m.body_jntnum[b]) > 1:
            raise input_error(robot.spec.mjcf, f"body '{m.body(b).name}' has several joints (adam needs one)")
        if int(m.body_jntnum[b]) == 1 and b != base:
            j = int(m.body_jntadr[b])
            p = m.jnt_pos[j].copy()
            if np.any(p != 0.0):
                m.body_pos[b] += quat_to_rotation(m.body_quat[b]) @ p
                m.body_ipos[b] -= p
                m.jnt_pos[j] = 0.0
                m.body_pos[np.flatnonzero(m.body_parentid == b)] -= p
            _zero_reference(m, j)
    return m, loops, hinges


def _zero_reference(m: mujoco.MjModel, j: int) -> None:
    """Joint ``j`` of ``m`` (at the body's origin) measured from 0 instead of its reference ``qpos0`` (in place): MuJoCo
    turns a hinge's body by R(a, q − q_ref) from its ``body_quat`` (a slide moves it by (q − q_ref) a), adam by R(a, q)
    (by q a), so the body's own pose is taken back by the reference — quat ← quat R(a, −q_ref) (pos ← pos − q_ref R a)
    — and ``qpos0`` set to 0. A joint whose reference is 0 is left alone."""
    adr = int(m.jnt_qposadr[j])
    ref, b, axis = float(m.qpos0[adr]), int(m.jnt_bodyid[j]), m.jnt_axis[j]
    if ref == 0.0 or int(m.jnt_type[j]) not in (int(mujoco.mjtJoint.mjJNT_HINGE), int(mujoco.mjtJoint.mjJNT_SLIDE)):
        return
    if int(m.jnt_type[j]) == int(mujoco.mjtJoint.mjJNT_HINGE):
        turn, out = np.zeros(4), np.zeros(4)
        mujoco.mju_axisAngle2Quat(turn, axis, -ref)
        mujoco.mju_mulQuat(out, m.body_quat[b], turn)
        m.body_quat[b] = out
    else:
        m.body_pos[b] -= ref * (quat_to_rotation(m.body_quat[b]) @ axis)
    m.qpos0[adr] = 0.0


@dataclass(frozen=True)
class CompliantSpring:
    """A closed chain's spring planned compliant: its ``index`` among adam's joints, ``joint`` name, ``stiffness`` k
    [N m/rad], ``ref`` springref [rad] and its joint's ``damping`` d [N m s/rad] (the model's)."""

    index: int
    joint: str
    stiffness: float
    ref: float
    damping: float


class Dynamics:
    """Rigid-body dynamics and foot kinematics of a robot, symbolic (CasADi SX) and numeric.

    Symbolic functions are in adam's coordinates (``H`` (4, 4), ``s`` (n,), ``ν_base`` (6,), ``ṡ`` (n,),
    mixed representation, joints in spec order); numeric methods take MuJoCo's ``qpos`` (nq,) and
    ``qvel`` (nv,) and return arrays in MuJoCo's coordinates (see the module docstring).
    """

    def __init__(self, robot: Robot, springs: str = "rigid"):
        self.robot = robot
        m = self.robot.model
        self.nv: int = int(m.nv)
        self.armature: Array = m.dof_armature.copy()
        self.gravity: Array = m.opt.gravity.copy()
        with warnings.catch_warnings():
            warnings.filterwarnings("ignore", message="Gimbal lock")
            try:
                model, self.loops, hinges = _adam_model(self.robot)
                # the planning model as MuJoCo compiles it: the physics check's model of a closed chain's solution
                self.plan_model: mujoco.MjModel = model
                self.passive: tuple[str, ...] = tuple(str(m.joint(j).name) for j in hinges)
                self.kindyn = KinDynComputations.from_mujoco_model(
                    model, joints_name_list=[*self.robot.spec.joints, *self.passive],
                    gravity=np.concatenate([self.gravity, np.zeros(3)]))
            except ValueError as exc:
                raise input_error(self.robot.spec.mjcf, f"adam-robotics cannot build the model: {exc}") from None
        self.frames: tuple[str, ...] = tuple(self.kindyn.rbdalgos.model.frames)
        # adam's joints: the planned ones (spec order), then the passive hinges of closed chains (model order)
        self.qpos_idx = np.concatenate([robot.qpos_idx, [m.jnt_qposadr[j] for j in hinges]]).astype(np.int64)
        self.dof_idx = np.concatenate([robot.dof_idx, [m.jnt_dofadr[j] for j in hinges]]).astype(np.int64)
        self.n_joints = int(self.dof_idx.size)
        # compliant springs (docs/gaitgen.md, "Springs"): no rigid row; free coordinates under their torque
        names = [*robot.spec.joints, *self.passive]
        self.springs: tuple[CompliantSpring, ...] = ()
        if springs == "compliant":
            rigid = [lp for lp in self.loops if lp.kind == "spring"]
            self.loops = [lp for lp in self.loops if lp.kind != "spring"]
            self.springs = tuple(CompliantSpring(
                names.index(lp.joint), lp.joint, float(m.jnt_stiffness[m.joint(lp.joint).id]), lp.ref,
                float(m.dof_damping[m.jnt_dofadr[m.joint(lp.joint).id]])) for lp in rigid)
        elif springs != "rigid":
            raise ValueError(f"springs must be 'rigid' or 'compliant', got {springs!r}")
        spring_cols = {sp.index for sp in self.springs}
        # the passive joints the loops solve (all of them unless the springs are compliant), adam indices
        self.solved: tuple[int, ...] = tuple(j for j in range(robot.n_joints, self.n_joints) if j not in spring_cols)
        self._perm = np.zeros((self.n_joints, self.nv - 6))
        self._perm[np.arange(self.n_joints), self.dof_idx - 6] = 1.0
        self._fk: dict[str, cs.Function] = {}
        self._jac: dict[str, cs.Function] = {}
        self._jdot: dict[str, cs.Function] = {}

    @property
    def total_mass(self) -> float:
        """Total mass [kg] of adam's model (equals MuJoCo's ``body_subtreemass`` of the base)."""
        return float(cs.DM(self.kindyn.get_total_mass()))

    @cached_property
    def mass_matrix_fun(self) -> cs.Function:
        """CasADi function ``(H, s) -> M`` (n+6, n+6), adam's mixed coordinates, without armature."""
        return self.kindyn.mass_matrix_fun()

    @cached_property
    def mixed_armature(self) -> Array:
        """The rotor inertias on the mass matrix's diagonal in adam's mixed coordinates (6 + n,): the floating base's
        ``dof_armature`` (one value for all six, so a rotation of the base's velocity leaves it as it is), then the
        joints' in spec order."""
        return np.concatenate([self.armature[:6], self.armature[self.dof_idx]])

    def inertia(self, H: Any, s: Any) -> Any:
        """M(q) + diag(armature) ((6 + n) × (6 + n)), adam's mixed coordinates: the mass matrix of the equations of
        motion MuJoCo integrates, at base pose ``H`` (4, 4) and joints ``s`` (n,); CasADi DM for numbers, SX/MX for
        symbols (the gait problem's constraints)."""
        return self.mass_matrix_fun(H, s) + cs.diag(self.mixed_armature)

    @cached_property
    def bias_force_fun(self) -> cs.Function:
        """CasADi function ``(H, s, ν_base, ṡ) -> h`` (n+6,): Coriolis, centrifugal and gravity, mixed."""
        return self.kindyn.bias_force_fun()

    @cached_property
    def closed_posture(self) -> Array:
        """The joints s (n,) of the spec's posture (the model's ``qpos0`` where it sets none) with the passive joints
        solved so that the model's loops close (:func:`robustgait.robots.loops.close_loops`; springs held at their
        angle, a hinge first clipped into its range): where the loop rows' directions are picked and the passive
        joints' Newton iterations start."""
        robot, m = self.robot, self.robot.model
        q = m.qpos0.copy()
        if robot.spec.posture:
            q[robot.qpos_idx] = robot.spec.posture
        loops, passive = closed_chains(m)
        for j in passive:
            if int(m.jnt_type[j]) != BALL and m.jnt_limited[j]:
                q[m.jnt_qposadr[j]] = np.clip(q[m.jnt_qposadr[j]], *m.jnt_range[j])
        q = close_loops(m, q, loops, tuple(j for j in passive if m.jnt_stiffness[j] == 0), LOOP_TOLERANCE)
        return self.joint_positions(q)

    def _loop_offsets(self, s: cs.SX) -> list[cs.SX]:
        """Each loop's rows before selection (:mod:`robustgait.closure`) at joints s (n,), the base at the identity:
        a rod's distance row (|p_a − p_b|² − L²) / (2 L) [m] (1), a connect's anchor offset R_ancᵀ (p_a − p_b) [m] (3),
        a spring's s_j − springref [rad] (1)."""
        eye, names = cs.DM.eye(4), [*self.robot.spec.joints, *self.passive]
        out = []
        for lp in self.loops:
            if lp.kind == "spring":
                out.append(s[names.index(lp.joint)] - lp.ref)
                continue
            d = self.frame_fun(lp.frames[0])(eye, s)[:3, 3] - self.frame_fun(lp.frames[1])(eye, s)[:3, 3]
            if lp.kind == "distance":
                out.append((cs.sumsqr(d) - lp.length**2) / (2.0 * lp.length))
            else:
                R = cs.DM.eye(3) if lp.ancestor == "world" else self.frame_fun(lp.ancestor)(eye, s)[:3, :3]
                out.append(R.T @ d)
        return out

    @cached_property
    def loop_fun(self) -> cs.Function:
        """CasADi function ``(s, ṡ, s̈) -> (φ, J_h ṡ, J_h s̈ + J̇_h ṡ, J_h)`` of the loops' holonomic rows φ(s) (k,)
        [m or rad] (:meth:`_loop_offsets`; a connect's offset projected on its independent directions, the left
        singular vectors of its Jacobian at :attr:`closed_posture` whose singular values exceed
        :data:`robustgait.robots.loops.NULL_FRACTION` of the largest), J_h = ∂φ/∂s (k, n). The rows do not depend on
        the base: in adam's mixed coordinates their Jacobian is [0 (k × 6), J_h]. Raises RobustGaitError when the rows
        do not fix the passive joints they solve (J_h's columns of :attr:`solved` — every passive joint but compliant
        springs — not square and regular at the posture)."""
        n = self.n_joints
        s, sd, sdd = (cs.SX.sym(k, n) for k in ("s", "sd", "sdd"))
        s0 = self.closed_posture
        blocks = []
        for lp, r in zip(self.loops, self._loop_offsets(s), strict=True):
            if lp.kind == "connect":
                U, sv, _ = np.linalg.svd(np.asarray(cs.Function("J", [s], [cs.jacobian(r, s)])(s0)))
                r = cs.mtimes(cs.DM(U[:, :int(np.sum(sv > NULL_FRACTION * sv.max()))]).T, r)
            blocks.append(r)
        phi = cs.vertcat(*blocks)
        J = cs.jacobian(phi, s)
        vel = cs.mtimes(J, sd)
        fun = cs.Function("loops", [s, sd, sdd], [phi, vel, cs.mtimes(J, sdd) + cs.mtimes(cs.jacobian(vel, s), sd), J],
                          ["s", "sd", "sdd"], ["phi", "vel", "acc", "J"])
        Jp = np.asarray(fun(s0, np.zeros(n), np.zeros(n))[3])[:, list(self.solved)]
        if Jp.shape[0] != Jp.shape[1] or np.linalg.matrix_rank(Jp) < Jp.shape[1]:
            raise input_error(self.robot.spec.source or self.robot.spec.mjcf,
                              f"the closed chains' {Jp.shape[0]} independent rows (rank {np.linalg.matrix_rank(Jp)}) "
                              f"do not fix the {Jp.shape[1]} passive joints the gait problem keeps")
        return fun

    def close_passive(self, s: ArrayLike, iterations: int = 50, tol: float = 1e-12) -> Array:
        """Joints s (n,) with the passive ones the loops solve (:attr:`solved`: the last n − m, but compliant springs)
        moved so that φ(s) = 0: Newton steps Δs_p = −J_p⁻¹ φ (:attr:`loop_fun`) from the values given, until
        ‖φ‖∞ ≤ ``tol``."""
        q, cols = np.array(s, dtype=float), list(self.solved)
        zero = np.zeros(self.n_joints)
        for _ in range(iterations):
            phi, _, _, J = (np.asarray(v, dtype=float) for v in self.loop_fun(q, zero, zero))
            if phi.size == 0 or np.abs(phi).max() <= tol:
                break
            q[cols] -= np.linalg.solve(J[:, cols], phi.ravel())
        return q

    def spring_torque(self, s: Any, sd: Any) -> Any:
        """The compliant springs' torque on the joints (n,) at joints s and rates ṡ (n,): −k (s_j − springref) − d ṡ_j
        on each spring j (:attr:`springs`; MuJoCo's ``qfrc_spring`` + ``qfrc_damper`` there), 0 elsewhere; CasADi SX
        for symbols, else a NumPy array. All zeros when the springs are rigid."""
        symbolic = isinstance(s, cs.SX) or isinstance(sd, cs.SX)
        out: Any = cs.SX.zeros(self.n_joints) if symbolic else np.zeros(self.n_joints)
        for sp in self.springs:
            out[sp.index] = -sp.stiffness * (s[sp.index] - sp.ref) - sp.damping * sd[sp.index]
        return out

    def frame_fun(self, frame: str) -> cs.Function:
        """CasADi function ``(H, s) -> H_frame`` (4, 4): world pose of an adam frame or link."""
        if frame not in self._fk:
            self._fk[frame] = self.kindyn.forward_kinematics_fun(frame)
        return self._fk[frame]

    def jacobian_fun(self, frame: str) -> cs.Function:
        """CasADi function ``(H, s) -> J`` (6, 6 + n): adam's mixed Jacobian of a frame, built once per frame (adam
        builds a new function at every call: a node loop that asked it again spent most of its time there)."""
        if frame not in self._jac:
            self._jac[frame] = self.kindyn.jacobian_fun(frame)
        return self._jac[frame]

    def jacobian_dot_fun(self, frame: str) -> cs.Function:
        """CasADi function ``(H, s, v_base, ṡ) -> J̇`` (6, 6 + n) of a frame, built once per frame
        (:meth:`jacobian_fun`)."""
        if frame not in self._jdot:
            self._jdot[frame] = self.kindyn.jacobian_dot_fun(frame)
        return self._jdot[frame]

    def joint_positions(self, qpos: ArrayLike) -> Array:
        """Joint angles ``s`` (n,) in adam's order (spec order, then passive hinges) from MuJoCo's ``qpos``."""
        return np.asarray(qpos, dtype=float)[self.qpos_idx]

    def velocity_map(self, qpos: ArrayLike) -> Array:
        """``T`` (6 + n, nv) with ``ν_mixed = T qvel``; orthonormal rows, so ``qvel = Tᵀ ν_mixed`` (square and
        orthogonal unless a closed chain's rods on ball joints, not in adam's model, leave columns out)."""
        T = np.zeros((6 + self.n_joints, self.nv))
        T[:3, :3] = np.eye(3)
        T[3:6, 3:6] = quat_to_rotation(np.asarray(qpos, dtype=float)[3:7])
        T[6:, 6:] = self._perm
        return T

    def to_mixed(self, qpos: ArrayLike, qvel: ArrayLike) -> Array:
        """adam's ``ν = [ṗ, ω_world, ṡ (spec order)]`` (nv,) from MuJoCo's ``qvel``."""
        return self.velocity_map(qpos) @ np.asarray(qvel, dtype=float)

    def to_mujoco(self, qpos: ArrayLike, nu: ArrayLike) -> Array:
        """MuJoCo's ``qvel`` (nv,) from adam's mixed velocity ``ν``."""
        return self.velocity_map(qpos).T @ np.asarray(nu, dtype=float)

    def mass_matrix(self, qpos: ArrayLike) -> Array:
        """Joint-space inertia (nv, nv) in MuJoCo's coordinates (``mj_fullM``): ``Tᵀ (M + diag(armature)) T``
        (:meth:`inertia`, :meth:`velocity_map`)."""
        T = self.velocity_map(qpos)
        M = np.asarray(self.inertia(base_transform(qpos), self.joint_positions(qpos)), dtype=float)
        return T.T @ M @ T

    def bias_forces(self, qpos: ArrayLike, qvel: ArrayLike) -> Array:
        """Bias forces (nv,) in MuJoCo's coordinates (``qfrc_bias``): ``Tᵀ h(q, T qvel)``."""
        T = self.velocity_map(qpos)
        nu = T @ np.asarray(qvel, dtype=float)
        h = self.bias_force_fun(base_transform(qpos), self.joint_positions(qpos), nu[:6], nu[6:])
        return T.T @ np.asarray(h, dtype=float).ravel()

    def frame_pose(self, frame: str, qpos: ArrayLike) -> tuple[Array, Array]:
        """World position (3,) and rotation (3, 3) of a frame (e.g. ``foot_frame("left", "sole")``)."""
        H = np.asarray(self.frame_fun(frame)(base_transform(qpos), self.joint_positions(qpos)), dtype=float)
        return H[:3, 3], H[:3, :3]

    def foot_frames(self, qpos: ArrayLike) -> dict[str, tuple[Array, Array]]:
        """Poses of every foot frame, keyed by name (``left_sole_frame``, ..., ``right_heel_frame``)."""
        return {foot_frame(s, k): self.frame_pose(foot_frame(s, k), qpos) for s in SIDES for k in FOOT_FRAME_KINDS}

    def frame_jacobian(self, frame: str, qpos: ArrayLike) -> Array:
        """Jacobian (6, nv) of a frame's (linear; angular) world velocity w.r.t. MuJoCo's ``qvel``:
        J_mj = J_adam T (adam's mixed Jacobian times the velocity map), comparable to ``mj_jac``."""
        H, s = base_transform(qpos), self.joint_positions(qpos)
        return np.asarray(self.jacobian_fun(frame)(H, s), dtype=float) @ self.velocity_map(qpos)

    def frame_jacobian_dot_qvel(self, frame: str, qpos: ArrayLike, qvel: ArrayLike) -> Array:
        """J̇ q̇ (6,) of a frame, the velocity-product term of its acceleration: J̇_mj q̇ = J̇_adam ν, because
        Ṫ q̇ = (0, Ṙ ω_B, 0) = (0, R (ω_B × ω_B), 0) = 0."""
        nu = self.to_mixed(qpos, qvel)
        jd = self.jacobian_dot_fun(frame)(base_transform(qpos), self.joint_positions(qpos), nu[:6], nu[6:])
        return np.asarray(jd, dtype=float) @ nu

    def contact_jacobian(self, qpos: ArrayLike, contacts: Sequence[Contact], stance: str) -> Array:
        """Stacked Jacobian (Σ rows, nv) of a contact set in MuJoCo's velocity coordinates: each contact's
        fixed rows (:data:`robustgait.domains.CONTACT_ROWS`) of its foot frame's Jacobian."""
        return np.vstack([self.frame_jacobian(foot_frame(c.side(stance), c.frame_kind()), qpos)[list(c.rows)]
                          for c in contacts])

    def impact_map(self, qpos: ArrayLike, qvel: ArrayLike, target: str | Sequence[Contact],
                   stance: str | None = None) -> tuple[Array, Array]:
        """Rigid impact onto a contact set (:func:`impact_map`) with this model's M and J, MuJoCo coordinates.

        ``target``: a side (``"left"``) for its sole landing flat, or contacts in the labels of a step whose
        stance leg is ``stance``. Returns (q̇⁺ (nv,), Λ (rows,) the impulses, world axes, at the frames)."""
        if isinstance(target, str):
            contacts: Sequence[Contact] = (Contact("stance", "flat"),)
            stance = target
        else:
            contacts = target
            if stance is None:
                raise ValueError("a contact set needs the step's stance side")
        return impact_map(self.mass_matrix(qpos), self.contact_jacobian(qpos, contacts, stance),
                          np.asarray(qvel, dtype=float))


def impact_residual(M: Any, J: Any, v_minus: Any, v_plus: Any, impulse: Any) -> tuple[Any, Any]:
    """The rigid (plastic) impact map as residuals, for NumPy arrays or CasADi expressions alike:

        [M  −Jᵀ] [q̇⁺]   [M q̇⁻]
        [J   0 ] [Λ ] = [ 0   ]   →   (M (q̇⁺ − q̇⁻) − Jᵀ Λ,  J q̇⁺)

    M (nv, nv) the mass matrix at the impact configuration, J (k, nv) the Jacobian of the contact set that
    holds after the impact (the target domain's contacts), q̇⁻, q̇⁺ (nv,), Λ (k,) the impulses. The velocity
    coordinates of M, J and q̇ must agree (MuJoCo's or adam's mixed ones). Westervelt et al., *Feedback
    Control of Dynamic Bipedal Robot Locomotion* (2007), §3.4; docs/design.md §4.
    """
    return M @ (v_plus - v_minus) - J.T @ impulse, J @ v_plus


def impact_map(M: Array, J: Array, v_minus: Array) -> tuple[Array, Array]:
    """Solve the impact map of :func:`impact_residual` for q̇⁺ (nv,) and Λ (k,): by the Schur complement
    of the KKT system, Λ = −(J M⁻¹ Jᵀ)⁻¹ J q̇⁻ and q̇⁺ = q̇⁻ + M⁻¹ Jᵀ Λ (so J q̇⁺ = 0)."""
    minv_jt = np.linalg.solve(M, J.T)
    impulse = -np.linalg.solve(J @ minv_jt, J @ v_minus)
    return np.asarray(v_minus + minv_jt @ impulse, dtype=np.float64), np.asarray(impulse, dtype=np.float64)
