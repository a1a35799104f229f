"""Mirroring a closed chain's passive joints (``Robot.mirror_state``; docs/robots.md, "Closed chains, springs and line
feet").

The mirrored state of a robot reflects the base by S (about the sagittal plane) and relabels the planned and held
joints by the spec's ``[mirror]``. A closed chain's passive joints (:mod:`robustgait.robots.loops`) are not in the
spec's mirror: each is mapped onto its *partner*, the passive joint of the same type on the body at the reflected
place. The map is the one that makes every body k of the mirrored configuration the reflection of its partner j,
R_k = S R_j C_j, with the constant C_j = X_j0ᵀ S X_k0 (X the bodies' rotations relative to the base in the model's
reference configuration ``qpos0``, det C_j = det S = −1):

* a hinge: q_k = σ q_j, σ = a_k · (det S) S a_j (±1; a, the joints' axes relative to the base at ``qpos0``) — a
  rotation by θ about a reflects into a rotation by θ about (det S) S a (an axial vector); a slide: σ = a_k · S a_j
  (a displacement is a polar vector);
* a ball joint on body j with parent p: its rotation relative to the body's frame in the parent, Q_j, becomes
  Q_k = B_kᵀ C_pᵀ B_j Q_j C_j (B: the bodies' fixed rotations ``body_quat``); its angular velocity, in the child's
  frame, ω_k = (det C_j) C_jᵀ ω_j.

Each mirrored state then closes the loops exactly where the state did (tested on Cassie's and a test biped's model).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import mujoco
import numpy as np
from numpy.typing import NDArray

from robustgait.errors import input_error
from robustgait.robots.loops import BALL, HINGE
from robustgait.rotations import quat_to_mat

FloatArray = NDArray[np.float64]
PARTNER_TOLERANCE = 2e-3  # [m] a partner body's origin within 2 mm of the reflected origin (rounded model files)
AXIS_TOLERANCE = 0.99  # |σ| of a hinge's partner axis: mirrored axes are parallel to within ~8°


@dataclass(frozen=True)
class PassiveMirror:
    """The partner map of a model's passive joints (module docstring): hinges and slides ``(qpos/dof address of the
    joint written, address read, σ)``; ball joints ``(qpos address written, qpos address read, dof written, dof
    read, A = B_kᵀ C_pᵀ B_j, C_j)`` with Q_k = A Q_j C_j."""

    hinges: tuple[tuple[int, int, int, int, float], ...]
    balls: tuple[tuple[int, int, int, int, FloatArray, FloatArray], ...]

    def apply(self, qpos_in: FloatArray, qvel_in: FloatArray, qpos_out: FloatArray, qvel_out: FloatArray) -> None:
        """Write the mirrored passive coordinates of ``qpos_in`` (..., nq), ``qvel_in`` (..., nv) into ``qpos_out``,
        ``qvel_out`` (in place; every other coordinate is left as it is)."""
        for qk, qj, vk, vj, sign in self.hinges:
            qpos_out[..., qk] = sign * qpos_in[..., qj]
            qvel_out[..., vk] = sign * qvel_in[..., vj]
        for qk, qj, vk, vj, A, C in self.balls:
            Q = A @ quat_to_mat(qpos_in[..., qj:qj + 4]) @ C
            qpos_out[..., qk:qk + 4] = _mat_to_quat(Q)
            qvel_out[..., vk:vk + 3] = -np.einsum("ji,...j->...i", C, qvel_in[..., vj:vj + 3])  # det C = −1


def _mat_to_quat(R: FloatArray) -> FloatArray:
    """Unit quaternions (..., 4) (w, x, y, z; w ≥ 0) of rotation matrices (..., 3, 3), MuJoCo's ``mju_mat2Quat``
    row by row."""
    flat = R.reshape(-1, 9)
    out = np.zeros((flat.shape[0], 4))
    for i, r in enumerate(flat):
        mujoco.mju_mat2Quat(out[i], r)
    out[out[:, 0] < 0] *= -1.0
    return out.reshape(*R.shape[:-2], 4)


def _relative(data: mujoco.MjData, base: int, body: int) -> tuple[FloatArray, FloatArray]:
    """(position, rotation) of ``body`` in the base's frame."""
    Rb = data.xmat[base].reshape(3, 3)
    return Rb.T @ (data.xpos[body] - data.xpos[base]), Rb.T @ data.xmat[body].reshape(3, 3)


def passive_mirror(model: mujoco.MjModel, passive: tuple[int, ...], base: int, base_sign: tuple[float, ...],
                   source: str | Path | None) -> PassiveMirror:
    """The partner map of the ``passive`` joints (ids) of ``model`` whose base body is ``base``, S =
    diag(``base_sign[:3]``) (module docstring). Raises RobustGaitError (naming ``source`` and the joint) when a
    passive joint has no partner: no passive joint of its type on a body within :data:`PARTNER_TOLERANCE` of its
    body's reflected origin, or a hinge whose partner's axis is not its reflection."""
    S = np.diag(np.asarray(base_sign[:3], dtype=float))
    det = float(np.prod(base_sign[:3]))
    data = mujoco.MjData(model)
    mujoco.mj_kinematics(model, data)  # qpos0
    hinges, balls = [], []
    for j in passive:
        b = int(model.jnt_bodyid[j])
        p, X = _relative(data, base, b)
        found = [k for k in passive if int(model.jnt_type[k]) == int(model.jnt_type[j])
                 and np.linalg.norm(_relative(data, base, int(model.jnt_bodyid[k]))[0] - S @ p) <= PARTNER_TOLERANCE]
        if len(found) != 1:
            raise input_error(source, f"passive joint '{model.joint(j).name}': {len(found)} passive joints of its type "
                                      f"at the mirror image of its body (one needed to mirror a state)")
        k = found[0]
        c = int(model.jnt_bodyid[k])
        Xk = _relative(data, base, c)[1]
        if int(model.jnt_type[j]) == BALL:
            pj, pk = int(model.body_parentid[b]), int(model.body_parentid[c])
            Cp = _relative(data, base, pj)[1].T @ S @ _relative(data, base, pk)[1]
            A = quat_to_mat(model.body_quat[c]).T @ Cp.T @ quat_to_mat(model.body_quat[b])
            balls.append((int(model.jnt_qposadr[k]), int(model.jnt_qposadr[j]), int(model.jnt_dofadr[k]),
                          int(model.jnt_dofadr[j]), A, X.T @ S @ Xk))
            continue
        Rb = data.xmat[base].reshape(3, 3)
        axial = det if int(model.jnt_type[j]) == HINGE else 1.0
        sign = float(np.dot(Rb.T @ data.xaxis[k], axial * S @ (Rb.T @ data.xaxis[j])))
        if abs(sign) < AXIS_TOLERANCE:
            raise input_error(source, f"passive joint '{model.joint(j).name}': its partner "
                                      f"'{model.joint(k).name}' turns about an axis that is not its mirror image")
        hinges.append((int(model.jnt_qposadr[k]), int(model.jnt_qposadr[j]), int(model.jnt_dofadr[k]),
                       int(model.jnt_dofadr[j]), float(np.sign(sign))))
    return PassiveMirror(tuple(hinges), tuple(balls))
