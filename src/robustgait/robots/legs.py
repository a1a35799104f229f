"""A leg's joints by what they turn about (``docs/robots.md``, "Legs without an ankle roll").

A humanoid leg is a chain of hinges from the hip to the foot: yaw, roll and pitch at the hip, the knee, the ankle's
pitch and roll. Each joint is read by its axis in the model's zero posture — the world axis it is closest to: x a
roll, y a pitch, z a yaw — and the knee is the chain's second pitch joint. An *ankle roll* is a roll joint below the
knee. A leg without one (Unitree H1's) cannot turn its flat foot about the foot's long axis: standing on it, the
shank cannot lean sideways, so neither can the stance leg, and the centre of pressure moves sideways only as the
whole body does (the hips roll the upper body over the stance foot); two flat feet lie under parallel legs, so the
feet land flat at the spacing of the legs alone. The spec's consequences are :func:`robustgait.inspection.scale`'s.

A leg is planned as a serial chain, each joint driven by its own servo: :func:`closed_chain` finds an equality
constraint that closes a loop through it (an ankle driven through rods), which robot init and the loader refuse
(``docs/robots.md``, "Your robot: robot init and robot check").
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


EQUALITY_KINDS = {int(mujoco.mjtEq.mjEQ_CONNECT): "connect", int(mujoco.mjtEq.mjEQ_WELD): "weld",
                  int(mujoco.mjtEq.mjEQ_JOINT): "joint"}


def subtree(model: mujoco.MjModel, root: int) -> list[int]:
    """The body ``root`` and every body below it (ids, ascending)."""
    out, inside = [int(root)], {int(root)}
    for b in range(int(root) + 1, model.nbody):  # a body's id is larger than its parent's
        if int(model.body_parentid[b]) in inside:
            out.append(b)
            inside.add(b)
    return out


def closed_chain(model: mujoco.MjModel, leg_root: int) -> str | None:
    """The first active equality constraint that ties a body or joint of the leg below body ``leg_root`` (the body of
    the leg's first joint, and every body under it) to anything — a closed linkage such as an ankle driven through
    rods (``connect``/``weld`` of two bodies, a ``joint`` coupling) — said in a clause naming it and what it ties;
    None when the leg is a serial chain. Other kinds (tendon, flex, distance) are not read."""
    leg = set(subtree(model, leg_root))
    for e in range(model.neq):
        if not model.eq_active0[e]:
            continue
        kind = int(model.eq_type[e])
        a, b = int(model.eq_obj1id[e]), int(model.eq_obj2id[e])
        if kind in (int(mujoco.mjtEq.mjEQ_CONNECT), int(mujoco.mjtEq.mjEQ_WELD)):
            ends = [mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, x) or f"body {x}" for x in (a, b)]
            inside = a in leg or b in leg
        elif kind == int(mujoco.mjtEq.mjEQ_JOINT):
            ends = [mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_JOINT, x) or f"joint {x}" for x in (a, b) if x >= 0]
            inside = any(int(model.jnt_bodyid[x]) in leg for x in (a, b) if x >= 0)
        else:
            continue
        if inside:
            name = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_EQUALITY, e)
            what = f"equality constraint {name!r}" if name else f"equality constraint {e}"
            return f"{what} ({EQUALITY_KINDS[kind]}) ties {' to '.join(repr(x) for x in ends)}"
    return None


def closed_chain_problem(side: str, clause: str) -> str:
    """The one-line refusal of a leg that is a closed chain (:func:`closed_chain`'s ``clause``): the feature and what a
    user changes."""
    return (f"the {side} leg is a closed chain: {clause}; robustgait plans serial legs whose joints its servos drive "
            "one by one — model the leg as a serial chain (the ankle's pitch and roll as joints driven directly, the "
            "linkage's bodies and the equality constraint removed)")
