"""A leg's joints by what they turn about (``docs/robots.md``, "Legs without an ankle roll").

A humanoid leg is a chain of hinges from the hip to the foot: yaw, roll and pitch at the hip, the knee, the ankle's
pitch and roll. Each joint is read by its axis in the model's zero posture — the world axis it is closest to: x a
roll, y a pitch, z a yaw — and the knee is the chain's second pitch joint. An *ankle roll* is a roll joint below the
knee. A leg without one (Unitree H1's) cannot turn its flat foot about the foot's long axis: standing on it, the
shank cannot lean sideways, so neither can the stance leg, and the centre of pressure moves sideways only as the
whole body does (the hips roll the upper body over the stance foot); two flat feet lie under parallel legs, so the
feet land flat at the spacing of the legs alone. The spec's consequences are :func:`robustgait.inspection.scale`'s.

A leg's planned joints are a serial chain from the hip to the foot; the passive joints of a closed chain through it
(Cassie's tarsus, driven by its knee through a rod) are not among them (:mod:`robustgait.robots.loops`).
"""

from __future__ import annotations

import mujoco
import numpy as np
from numpy.typing import NDArray

AXIS_KINDS = "xyz"  # roll, pitch, yaw: the world axis a joint's axis is closest to


def zero_axes(model: mujoco.MjModel, joints: tuple[int, ...]) -> NDArray[np.float64]:
    """Each joint's axis (len(joints), 3), world, in the model's zero posture (``qpos0``)."""
    d = mujoco.MjData(model)
    mujoco.mj_kinematics(model, d)
    return np.array([d.xaxis[j] for j in joints], dtype=float).reshape(len(joints), 3)


def axis_kinds(model: mujoco.MjModel, joints: tuple[int, ...]) -> tuple[str, ...]:
    """Each joint's kind, ``x`` (roll), ``y`` (pitch) or ``z`` (yaw): the world axis its axis is closest to in the
    model's zero posture (:func:`zero_axes`)."""
    return tuple(AXIS_KINDS[int(np.argmax(np.abs(a)))] for a in zero_axes(model, joints))


def _knee(kinds: tuple[str, ...]) -> int | None:
    """The knee's index in a leg's joint kinds (hip to foot): the second pitch joint; None without one."""
    pitches = [i for i, k in enumerate(kinds) if k == "y"]
    return pitches[1] if len(pitches) >= 2 else None


def ankle_joints(model: mujoco.MjModel, joints: tuple[int, ...]) -> tuple[int, ...]:
    """The joints below the knee (the second pitch joint) of a leg whose ``joints`` run hip to foot: its ankle (pitch,
    and roll when it has one); the last two joints for a leg without a knee."""
    knee = _knee(axis_kinds(model, joints))
    return joints[-2:] if knee is None else joints[knee + 1:]


def ankle_roll_joint(model: mujoco.MjModel, joints: tuple[int, ...]) -> int | None:
    """The ankle roll of a leg whose ``joints`` run hip to foot: the last roll joint below the knee (the second pitch
    joint), or None when the leg has none (or no knee)."""
    kinds = axis_kinds(model, joints)
    knee = _knee(kinds)
    if knee is None:
        return None
    below = [joints[i] for i in range(knee + 1, len(joints)) if kinds[i] == "x"]
    return below[-1] if below else None


def foot_chain(model: mujoco.MjModel, foot_body: int, base_body: int) -> tuple[int, ...]:
    """The joints (ids) of the bodies from below ``base_body`` down to ``foot_body``, hip to foot."""
    chain: list[int] = []
    body = foot_body
    while body not in (base_body, 0):
        chain += [int(model.body_jntadr[body]) + k for k in range(int(model.body_jntnum[body]))]
        body = int(model.body_parentid[body])
    return tuple(reversed(chain))


def subtree(model: mujoco.MjModel, root: int) -> list[int]:
    """The body ``root`` and every body below it (ids, ascending)."""
    out, inside = [int(root)], {int(root)}
    for b in range(int(root) + 1, model.nbody):  # a body's id is larger than its parent's
        if int(model.body_parentid[b]) in inside:
            out.append(b)
            inside.add(b)
    return out
