"""Node trajectories of the flat-foot problem and their conversion to MuJoCo states."""

from __future__ import annotations

from dataclasses import dataclass, field

import mujoco
import numpy as np
from numpy.typing import NDArray

from robustgait.robots import Robot
from robustgait.robots.loops import BALL, complete_rods

FloatArray = NDArray[np.float64]


@dataclass
class NodeStates:
    """The trajectory on the nodes, in adam's coordinates: base pose H (n, 4, 4), joints s, ṡ, s̈ (n, m + p: the
    planned joints, then a closed chain's passive ones), base velocity/acceleration ν_b, ν̇_b (n, 6), torques u (n, m)
    [N·m], stance wrench λ (n, 6) [N, N·m], post-impact velocity ν⁺ (6 + m + p) and impulse Λ (6, then the loops'
    k), the loop forces λ_h (n, k) [N or N m] (none without closed chains)."""

    H: FloatArray
    s: FloatArray
    sd: FloatArray
    sdd: FloatArray
    vb: FloatArray
    ab: FloatArray
    u: FloatArray
    lam: FloatArray
    nu_plus: FloatArray
    impulse: FloatArray
    lamh: FloatArray = field(default_factory=lambda: np.zeros((0, 0)))


def to_mujoco_state(robot: Robot, H: FloatArray, s: FloatArray, vb: FloatArray, sd: FloatArray
                    ) -> tuple[FloatArray, FloatArray]:
    """MuJoCo (qpos, qvel) of an adam state: quaternion (w, x, y, z) from R, ω_body = Rᵀ ω_world, joints
    placed from spec order at the model's qpos/dof addresses. A robot with closed chains: ``s`` and ``ṡ`` (m + p,)
    carry the passive hinges too (model order, :class:`robustgait.dynamics.Dynamics`), and the rods on ball joints,
    not in adam's model, are solved from the loops (:func:`robustgait.robots.loops.complete_rods`)."""
    m = robot.n_joints
    qpos = np.zeros(robot.model.nq)
    qvel = np.zeros(robot.model.nv)
    qpos[:3] = H[:3, 3]
    mujoco.mju_mat2Quat(qpos[3:7], H[:3, :3].ravel())
    qpos[robot.qpos_idx] = s[:m]
    qvel[:3] = vb[:3]
    qvel[3:6] = H[:3, :3].T @ vb[3:6]
    qvel[robot.dof_idx] = sd[:m]
    if len(s) > m:
        hinges = [j for j in robot.passive_ids if int(robot.model.jnt_type[j]) != BALL]
        qpos[robot.model.jnt_qposadr[hinges]] = s[m:]
        qvel[robot.model.jnt_dofadr[hinges]] = sd[m:]
        qpos, qvel = complete_rods(robot.model, qpos, qvel)
    return qpos, qvel
