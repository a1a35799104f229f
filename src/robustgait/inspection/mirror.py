"""The left/right relabeling of a robot (the spec's ``[mirror]``), found from names and joint axes and verified by
reflecting the model.

A reflection S = diag(1, −1, 1) about the base's sagittal (x–z) plane maps a point p to S p and a hinge's axis
a to −S a (an axis is a pseudo-vector: det S = −1), a slide's direction d to S d. Each joint's *partner* is the
joint its mirror image lands on: found by name (left ↔ right, l ↔ r, L ↔ R, ...) and confirmed by geometry, or by
geometry alone when no name pairs it. For a hinge the geometry is its axis *line* (:func:`line_offset`): the
partner's axis is ±S a and passes within the tolerance of the reflected anchor S p, wherever along the line the
model put its anchor — so a joint on the sagittal plane whose line S maps onto itself is its own partner even when
its frame sits off the plane (a head's tilt joint mounted on one side of its bracket). A slide's anchor must be at
S p. The sign makes the partner's angle reproduce the reflected motion: a hinge's sign is +1 when the partner's axis
is −S a and −1 when it is +S a (a slide's, +1 when it is +S d). The relabeled configuration is
q'[partner(j)] = sign(j) · q[j].

**Verification** (:func:`fk_residual`): for random configurations q, forward kinematics of the relabeled q' must
move every body b's partner b' as the reflection moves b: its frame x_b'(q') = S x_b(q) + R_b'(q') d_b and
R_b'(q') = S R_b(q) S C_b, with a constant offset d_b and rotation C_b measured at q = 0 (where a frame sits on its
body, and the two sides' frame conventions, are modelling choices: a wrong partner or sign moves the body another
way, which no constant absorbs). The residual is the largest position [m] and orientation [rad] error over bodies
and samples.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass

import mujoco
import numpy as np
from numpy.typing import NDArray

from robustgait.errors import input_error
from robustgait.inspection.model import HINGE, RobotModel, joint_range
from robustgait.robots.sides import S, body_partners

# Side markers in names, longest first; a name's partner swaps one occurrence for the other side's marker.
SIDE_TOKENS = (("left", "right"), ("Left", "Right"), ("LEFT", "RIGHT"), ("l", "r"), ("L", "R"))
AXIS_TOLERANCE = 1e-3  # |1 − |a' · S a|| below which two unit axes are parallel (numerical round-off of the model)


def name_partner(name: str, names: Iterable[str]) -> tuple[str, str] | None:
    """The name among ``names`` that is ``name`` with one side marker swapped (module constants), and the side
    ``name`` says it is on ("left" or "right"); None when no swap gives a name in ``names``."""
    pool = set(names)
    for left, right in SIDE_TOKENS:
        for mine, theirs, side in ((left, right, "left"), (right, left, "right")):
            i = name.find(mine)
            while i >= 0:
                other = name[:i] + theirs + name[i + len(mine):]
                if other in pool:
                    return other, side
                i = name.find(mine, i + 1)
    return None


@dataclass(frozen=True)
class Mirror:
    """Each non-base joint's partner and sign (joint ids), and each body's partner (body ids)."""

    partner: dict[int, int]
    sign: dict[int, float]
    body_partner: dict[int, int]


@dataclass(frozen=True)
class Residual:
    """The verification's largest position [m] and orientation [rad] errors, where, over how many samples."""

    position: float
    angle: float
    body: int
    samples: int


def _axes(robot: RobotModel) -> tuple[mujoco.MjData, dict[int, NDArray[np.float64]], dict[int, NDArray[np.float64]]]:
    d = robot.kinematics(robot.qpos({j: 0.0 for j in robot.joints}))
    return d, {j: d.xanchor[j].copy() for j in robot.joints}, {j: d.xaxis[j].copy() for j in robot.joints}


def _sign(m: mujoco.MjModel, j: int, a: NDArray[np.float64], b: NDArray[np.float64]) -> float:
    """The relabeling sign of joint ``j`` (axis a) onto its partner (axis b)."""
    dot = float(b @ (S @ a))
    return -float(np.sign(dot)) if int(m.jnt_type[j]) == HINGE else float(np.sign(dot))


def line_offset(point: NDArray[np.float64], direction: NDArray[np.float64], other: NDArray[np.float64]) -> float:
    """Distance [m] from the point ``other`` (3,) to the line through ``point`` (3,) along the unit ``direction``
    (3,): ‖(o − p) − ((o − p)·d) d‖."""
    r = other - point
    return float(np.linalg.norm(r - float(r @ direction) * direction))


def find_mirror(robot: RobotModel, tolerance: float) -> Mirror:
    """Every non-base joint's partner and sign, and every body's partner (module docstring). ``tolerance`` [m]:
    how far a hinge partner's axis line may pass from the reflected anchor (a slide's anchor from the reflected
    one) with every joint at 0."""
    m, src = robot.model, robot.path
    d, anchor, axis = _axes(robot)
    by_name = {robot.joint_name(j): j for j in robot.joints if robot.joint_name(j)}

    def offset(j: int, k: int) -> float:
        if int(m.jnt_type[j]) == HINGE:
            return line_offset(S @ anchor[j], S @ axis[j], anchor[k])
        return float(np.linalg.norm(anchor[k] - S @ anchor[j]))

    def matches(j: int, k: int) -> bool:
        return (int(m.jnt_type[j]) == int(m.jnt_type[k]) and offset(j, k) <= tolerance
                and abs(abs(float(axis[k] @ (S @ axis[j]))) - 1.0) <= AXIS_TOLERANCE)

    partner: dict[int, int] = {}
    for j in robot.joints:
        name = robot.joint_name(j) or f"#{j}"
        named = name_partner(name, by_name)
        if named is not None:
            k = by_name[named[0]]
            if not matches(j, k):
                off = offset(j, k)
                raise input_error(src, f"the mirror does not reflect the model: joint '{name}' and its name partner "
                                  f"'{named[0]}' are not mirror images (anchor {1e3 * off:.2f} mm from the reflected "
                                  f"one, tolerance {1e3 * tolerance:g} mm: robot.mirror_tolerance; axes "
                                  f"{axis[j].round(3).tolist()} and {axis[k].round(3).tolist()})")
            partner[j] = k
            continue
        found = [k for k in robot.joints if matches(j, k)]
        if j in found:  # its own line reflects onto itself: on the plane (another joint may share that line)
            found = [j]
        if len(found) != 1:
            what = "no joint" if not found else f"{len(found)} joints ({', '.join(robot.joint_name(k) for k in found)})"
            raise input_error(src, f"the mirror does not reflect the model: joint '{name}' has {what} at its mirror "
                              "image and no left/right name partner")
        partner[j] = found[0]
    sign = {j: _sign(m, j, axis[j], axis[k]) for j, k in partner.items()}
    for j, k in partner.items():
        if partner[k] != j or sign[k] != sign[j]:
            raise input_error(src, f"the mirror does not reflect the model: joints '{robot.joint_name(j)}' and "
                              f"'{robot.joint_name(k)}' do not pair up")
    return Mirror(partner, sign, body_partners(robot.model, robot.base, partner, d, tolerance, robot.path))


def mirrored_angles(mirror: Mirror, angles: Mapping[int, float]) -> dict[int, float]:
    """The relabeled configuration: q'[partner(j)] = sign(j) q[j]."""
    return {mirror.partner[j]: mirror.sign[j] * a for j, a in angles.items()}


def _rotation_angle(r: NDArray[np.float64]) -> float:
    return float(np.arccos(np.clip((np.trace(r) - 1.0) / 2.0, -1.0, 1.0)))


def fk_residual(robot: RobotModel, mirror: Mirror, samples: int, seed: int) -> Residual:
    """Reflect the model (module docstring): the largest errors over ``samples`` random configurations, each joint
    uniform in its range (±π when unlimited)."""
    m = robot.model
    rng = np.random.default_rng(seed)
    zero = {j: 0.0 for j in robot.joints}
    bodies = list(mirror.body_partner.items())

    def frames(angles: Mapping[int, float]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        d = robot.kinematics(robot.qpos(dict(angles)))
        return d.xpos.copy(), d.xmat.reshape(-1, 3, 3).copy()

    x0, r0 = frames(zero)
    const = {b: r0[c].T @ S @ r0[b] @ S for b, c in bodies}
    shift = {b: r0[c].T @ (x0[c] - S @ x0[b]) for b, c in bodies}
    position = angle = 0.0
    body, worst = robot.base, -1.0
    for _ in range(samples):
        q = {}
        for j in robot.joints:
            lo, hi = joint_range(m, j) or (-np.pi, np.pi)
            q[j] = float(rng.uniform(lo, hi))
        x, r = frames(q)
        xm, rm = frames(mirrored_angles(mirror, q))
        for b, c in bodies:
            e_pos = float(np.linalg.norm(xm[c] - S @ x[b] - rm[c] @ shift[b]))
            e_rot = _rotation_angle(const[b].T @ rm[c].T @ S @ r[b] @ S)
            position, angle = max(position, e_pos), max(angle, e_rot)
            if e_pos + e_rot > worst:
                body, worst = b, e_pos + e_rot
    return Residual(position, angle, body, samples)


def mirror_from_names(robot: RobotModel, pairs: Mapping[str, tuple[str, float]], tolerance: float) -> Mirror:
    """A spec's relabeling (joint name → (partner name, sign)) as a :class:`Mirror` of ``robot``'s joints, with
    the body partners it implies (for :func:`fk_residual`)."""
    ids = {robot.joint_name(j): j for j in robot.joints}
    partner = {ids[a]: ids[b] for a, (b, _) in pairs.items()}
    sign = {ids[a]: float(s) for a, (_, s) in pairs.items()}
    d, _, _ = _axes(robot)
    return Mirror(partner, sign, body_partners(robot.model, robot.base, partner, d, tolerance, robot.path))
