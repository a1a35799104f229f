"""Held joints (``[joints.held]``, ``docs/robots.md``): joints the gait does not plan — a humanoid's arms, head and
waist. In simulation each is a servo held at its angle; in the optimization's model it is welded at that angle
(:func:`weld_joints`), its bodies' mass and inertia kept, so that the NLP has only the planned joints."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import mujoco
import numpy as np

from robustgait.errors import input_error
from robustgait.robots.spec import HeldJoint
from robustgait.rotations import quat_to_mat


def _axis_angle_quat(axis: np.ndarray, angle: float) -> np.ndarray:
    """Unit quaternion (w, x, y, z) of a rotation by ``angle`` [rad] about the unit ``axis``."""
    return np.concatenate([[np.cos(angle / 2)], np.sin(angle / 2) * axis])


def weld_joints(mjs: mujoco.MjSpec, model: mujoco.MjModel, held: Sequence[HeldJoint], src: str | Path | None) -> None:
    """Remove the held joints from ``mjs`` (edited in place; ``model`` is it compiled), each body fixed where the
    joint's angle θ puts it.

    A hinge of unit axis a through the point p (both in the body's frame) at angle θ (from its reference
    ``ref``, MuJoCo's qpos0) moves the body's frame by the rigid motion x ↦ R_a(θ − ref)(x − p) + p in that frame;
    composed on the right of the body's pose in its parent: pos' = pos + R (p − R_a p), quat' = quat ⊗ q_a. A
    slide joint translates it by (θ − ref) a. The inertial frame and the children move with the body frame."""
    for h in held:
        j = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, h.name)
        kind = int(model.jnt_type[j])
        if kind not in (int(mujoco.mjtJoint.mjJNT_HINGE), int(mujoco.mjtJoint.mjJNT_SLIDE)):
            raise input_error(src, f"held joint '{h.name}' is not a hinge or slide joint")
        joint = mjs.joint(h.name)
        body = joint.parent
        if body.alt.type == mujoco.mjtOrientation.mjORIENTATION_QUAT:
            quat = np.asarray(body.quat, dtype=float)
        else:
            quat = np.asarray(mjs.resolve_orientation(mjs.compiler.degree, mjs.compiler.eulerseq, body.alt))
        quat = quat / np.linalg.norm(quat)
        axis = np.asarray(model.jnt_axis[j], dtype=float)
        p = np.asarray(model.jnt_pos[j], dtype=float)
        delta = h.angle - float(model.qpos0[int(model.jnt_qposadr[j])])
        pos = np.asarray(body.pos, dtype=float)
        if kind == int(mujoco.mjtJoint.mjJNT_SLIDE):
            body.pos = pos + quat_to_mat(quat) @ (delta * axis)
        else:
            qa = _axis_angle_quat(axis, delta)
            body.pos = pos + quat_to_mat(quat) @ (p - quat_to_mat(qa) @ p)
            out = np.zeros(4)
            mujoco.mju_mulQuat(out, quat, qa)
            body.alt.type = mujoco.mjtOrientation.mjORIENTATION_QUAT
            body.quat = out
        mjs.delete(joint)
