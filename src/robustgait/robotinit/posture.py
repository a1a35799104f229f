"""The posture ``robot init`` writes (``docs/robots.md``, "Your robot"): the model's keyframe (or every joint at 0)
made left/right symmetric (:func:`symmetric_angles`), its soles levelled by the ankles (:func:`level_soles`: a foot
plate's geoms rotated 90.5°), and its centre of mass brought over the soles when it stood near their edge
(:func:`centre_over_soles`: a model without a keyframe stands with straight legs wherever its mass happens to lie),
and, for legs with springs, its soles levelled as it stands under its weight (:func:`level_under_load`).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from robustgait.config.robot import LOAD_ROUNDS
from robustgait.inspection.discover import SIDES, Legs, tread_points
from robustgait.inspection.gains import settle_springs
from robustgait.inspection.mirror import Mirror
from robustgait.inspection.model import RobotModel, clip_to_range
from robustgait.robots.legs import ankle_joints, axis_kinds, zero_axes
from robustgait.robots.soles import sole_slopes


def symmetric_angles(robot: RobotModel, mirror: Mirror) -> tuple[dict[int, float], float]:
    """The posture made left/right symmetric — a_j = (q_j + s_j q_partner) / 2, clipped to the joint's range — and
    the largest change [rad] (a keyframe of a walking robot is usually symmetric: 0)."""
    q = robot.angles
    out = {j: clip_to_range(robot.model, j, (q[j] + mirror.sign[j] * q[mirror.partner[j]]) / 2) if j in mirror.partner
           else q[j] for j in q}  # a passive joint (not in the mirror) is solved from its loop afterwards
    return out, max((abs(out[j] - q[j]) for j in q), default=0.0)


# iterations of the ankle's Gauss-Newton levelling, its finite-difference step [rad] and the slope it stops at (a
# slope below it, a model file's round-off, is left alone)
LEVEL_ITERATIONS, LEVEL_STEP, LEVEL_SLOPE = 8, 1e-6, 1e-5


def sole_tilt(robot: RobotModel, legs: Legs, side: str, angles: dict[int, float]) -> NDArray[np.float64]:
    """The slopes (2,) of a sole's plane in the world (:func:`robustgait.robots.soles.sole_slopes` over its tread,
    :func:`~.discover.tread_points`: not an arch above it, along x and y) with the joints at ``angles``."""
    d = robot.kinematics(robot.qpos(angles))
    pts = tread_points(robot.model, d, legs[side].sole.geoms)
    return np.array(sole_slopes(pts[:, 0], pts[:, 1], pts[:, 2]))


def level_soles(robot: RobotModel, legs: Legs, mirror: Mirror) -> float:
    """Level the soles in the posture: the left leg's ankle (its joints below the knee,
    :func:`robustgait.robots.legs.ankle_joints`) turned by Gauss-Newton on the slopes
    of :func:`sole_tilt` (least squares: a leg whose ankle cannot level every slope levels what it can), the right
    leg's mirrored onto it (the posture stays symmetric), each clipped to its range. Edits ``robot.angles``; returns
    the largest change [rad] (0 for a model whose soles are level)."""
    angles = dict(robot.angles)
    ankle = ankle_joints(robot.model, legs.left.joints)
    turned = False
    for _ in range(LEVEL_ITERATIONS):
        s = sole_tilt(robot, legs, "left", angles)
        if float(np.abs(s).max()) <= LEVEL_SLOPE:
            break
        jac = np.column_stack([(sole_tilt(robot, legs, "left", angles | {j: angles[j] + LEVEL_STEP}) - s)
                               / LEVEL_STEP for j in ankle])
        step = np.linalg.lstsq(jac, -s, rcond=None)[0]
        for j, dq in zip(ankle, step, strict=True):
            angles[j] = clip_to_range(robot.model, j, angles[j] + float(dq))
        turned = True
    if not turned:  # level: the symmetric posture stays as it is (re-mirroring could move a clipped partner)
        return 0.0
    for j in ankle:
        angles[mirror.partner[j]] = clip_to_range(robot.model, mirror.partner[j], mirror.sign[j] * angles[j])
    change = max(abs(angles[j] - robot.angles[j]) for j in angles)
    robot.angles = angles
    return change


CENTRE_ITERATIONS, CENTRE_STEP, CENTRE_TOLERANCE = 8, 1e-6, 1e-4  # Newton on the lean [rad], stop within [m]


def com_over_soles(robot: RobotModel, legs: Legs, angles: dict[int, float]) -> tuple[float, float, float]:
    """(the centre of mass's x, the soles' rearmost and foremost x) [m] in the base's frame with the joints at
    ``angles``: the soles' extent over both feet's tread points (:func:`~.discover.tread_points`)."""
    d = robot.kinematics(robot.qpos(angles))
    x = np.concatenate([tread_points(robot.model, d, legs[side].sole.geoms)[:, 0] for side in SIDES])
    return float(d.subtree_com[robot.base][0]), float(x.min()), float(x.max())


def centre_over_soles(robot: RobotModel, legs: Legs, mirror: Mirror, stand_fraction: float) -> float:
    """Bring the posture's centre of mass over the middle of the soles when it lies outside their middle
    ``stand_fraction`` (``robot.stand_fraction``): every leg leaned by one angle about its ankle pitch, the hip
    pitch turned back by as much about the world's y (its axis's sign read in the zero posture: soles and pelvis keep
    their orientation; the knees stay), the right leg's mirrored from the left. Edits ``robot.angles``; returns the
    lean [rad] (0 when the mass already stands over the soles)."""
    com, rear, front = com_over_soles(robot, legs, robot.angles)
    margin = (1.0 - stand_fraction) / 2.0 * (front - rear)
    if rear + margin <= com <= front - margin:
        return 0.0
    m, chain = robot.model, legs.left.joints
    kinds = axis_kinds(m, chain)
    pitches = [j for j, k in zip(chain, kinds, strict=True) if k == "y"]
    ankle = next((j for j in ankle_joints(m, chain) if j in pitches), None)
    if ankle is None or len(pitches) < 2:
        return 0.0  # no ankle pitch to lean on: left as it is (robot check's stand says whether it stands)

    # the hip pitch turns back by as much about the world's y: the same angle, or its opposite where the two axes point
    # opposite ways along y
    axes = zero_axes(m, (ankle, pitches[0]))
    back = -float(np.sign(axes[0, 1]) * np.sign(axes[1, 1]))

    def leaned(lean: float) -> dict[int, float]:
        out = dict(robot.angles)
        for j, delta in ((ankle, lean), (pitches[0], back * lean)):
            out[j] = clip_to_range(m, j, robot.angles[j] + delta)
            out[mirror.partner[j]] = clip_to_range(m, mirror.partner[j], mirror.sign[j] * out[j])
        return out

    def offset(lean: float) -> float:
        c, r, f = com_over_soles(robot, legs, leaned(lean))
        return c - (r + f) / 2.0

    lean = 0.0
    for _ in range(CENTRE_ITERATIONS):
        e = offset(lean)
        if abs(e) <= CENTRE_TOLERANCE:
            break
        slope = (offset(lean + CENTRE_STEP) - e) / CENTRE_STEP
        if abs(slope) < 1e-9:
            break
        lean -= e / slope
    robot.angles = leaned(lean)
    return abs(lean)


def level_under_load(robot: RobotModel, legs: Legs, mirror: Mirror) -> tuple[dict[int, float], float]:
    """Level the soles as the posture stands under the robot's weight: the springs settled at their static deflection
    standing on both feet (:func:`robustgait.inspection.gains.settle_springs`), the soles levelled there by the
    ankles (:func:`level_soles`), repeated while the ankles still turn; then the springs back at their posture angles
    and the loops closed again (the spec's posture holds the springs rigid, as gait generation does; ``robot check``
    settles them again before it stands the posture). A leg whose spring turns its foot under load would otherwise
    stand on one end of its sole: a line foot then balances on a point and tips over. Edits ``robot.angles``; returns
    the springs' loaded angles (joint id → rad or m) and the ankles' largest change [rad] ({} and 0 for a robot
    without springs)."""
    if not robot.springs:
        return {}, 0.0
    rest = {s.joint: robot.angles[s.joint] for s in robot.springs}
    before = dict(robot.angles)
    feet = [legs[side].foot for side in SIDES]
    loaded: dict[int, float] = {}
    for _ in range(LOAD_ROUNDS):
        loaded = settle_springs(robot, feet)
        if level_soles(robot, legs, mirror) == 0.0:
            break
    robot.angles.update(rest)
    robot.close()
    ankles = ankle_joints(robot.model, legs.left.joints) + ankle_joints(robot.model, legs.right.joints)
    return loaded, max((abs(robot.angles[j] - before[j]) for j in ankles), default=0.0)
