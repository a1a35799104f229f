"""Node trajectories of the flat-foot problem and their conversion to MuJoCo states."""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np
from numpy.typing import NDArray

from robustgait.robots import Robot

FloatArray = NDArray[np.float64]


@dataclass
class NodeStates:
    """The trajectory on the nodes, in adam's coordinates: base pose H (n, 4, 4), joints s, ṡ, s̈ (n, m),
    base velocity/acceleration ν_b, ν̇_b (n, 6), torques u (n, m) [N·m], stance wrench λ (n, 6) [N, N·m],
    post-impact velocity ν⁺ (6 + m) and impulse Λ (6)."""

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


def to_mujoco_state(robot: Robot, H: FloatArray, s: FloatArray, vb: FloatArray, sd: FloatArray
                    ) -> tuple[FloatArray, FloatArray]:
    """MuJoCo (qpos, qvel) of an adam state: quaternion (w, x, y, z) from R, ω_body = Rᵀ ω_world, joints
    placed from spec order at the model's qpos/dof addresses."""
    qpos = np.zeros(robot.model.nq)
    qvel = np.zeros(robot.model.nv)
    qpos[:3] = H[:3, 3]
    mujoco.mju_mat2Quat(qpos[3:7], H[:3, :3].ravel())
    qpos[robot.qpos_idx] = s
    qvel[:3] = vb[:3]
    qvel[3:6] = H[:3, :3].T @ vb[3:6]
    qvel[robot.dof_idx] = sd
    return qpos, qvel
