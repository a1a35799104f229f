"""What `robot init` reads from a model (``docs/robots.md``, "Your robot"): the two legs, their soles, the floor,
and each joint's range and torque limit with where it came from.

* **Legs.** The feet are the robot's lowest bodies in the standing posture: the body with the lowest collision
  geometry, and the lowest one on the other side of the base's sagittal plane (x–z), which must reach the same
  height within ``foot_level`` of the standing height (else the robot has one leg). A leg is the chain of joints
  from the body where the two feet's chains branch (the base, or a waist below it) down to its foot; left is
  y > 0 in the base frame.
* **Collision geoms.** Those MuJoCo may make contacts with: contype or conaffinity ≠ 0, or named by an explicit
  ``<pair>`` (:func:`robustgait.robots.soles.collides`): the soles of a model whose contacts are all pairs are the
  foot geoms paired with the floor.
* **Soles.** A foot's collision geoms whose lowest points lie within ``sole_tolerance`` of the foot's lowest
  point: one box (its bottom face is the sole), or a set of spheres, capsules, cylinders, boxes and meshes of that
  body (the loader spans a virtual sole box over where they meet the ground: a mesh's convex hull on its tread).
  Ellipsoids, planes, height fields and SDFs are refused: their contact patch is not a sole robustgait can
  constrain.
* **Floor.** A plane geom of the world body with its normal up; none: the loader adds one (``add_floor``).
* **Torque limits.** The smallest of the joint's ``actuatorfrcrange``, its joint actuators' ``forcerange`` × gear,
  and its motors' ``ctrlrange`` × gain × gear; a joint with none gets an estimate (:mod:`.gains`), said so.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np
from numpy.typing import NDArray

from robustgait.errors import input_error
from robustgait.inspection.model import RobotModel, geom_bottom
from robustgait.robots.legs import ankle_roll_joint
from robustgait.robots.solebox import box_up, sole_box
from robustgait.robots.soles import (
    GEOM_TYPES,
    MIN_TREAD_FILL,
    SOLE_TYPES,
    article,
    foot_up,
    geom_sole_points,
    line_chord,
    loader_rectangle,
    on_sole,
    one_box,
    sole_up,
    tread_fill,
)

SIDES = ("left", "right")
MIN_SOLE = 1e-3  # [m]: a sole narrower than this has no area to stand on (one sphere, a capsule on end)


@dataclass(frozen=True)
class FoundSole:
    """A leg's sole: the foot ``body`` and its sole ``geoms``; how the spec names it (``kind``: ``geom`` a named
    box, ``geoms`` named geoms, ``body`` every collision geom of the body — of ``sole_class`` when set); its
    footprint in the foot's frame (``length`` along the foot axis closest to forward, ``width`` along the one
    closest to left, [m]) and the foot's bottom height at the posture (``bottom``, base at height 0). What a model
    offers, before any spec exists; how a spec's sole is built into the robot's model is
    :class:`robustgait.robots.soles.ResolvedSole`. ``tread``: how many of each mesh geom's convex-hull vertices are
    on the sole (what ``robot init``'s comment says); ``foot``: ``flat`` or ``line`` (:func:`sole_kind`; a tread whose
    contact polygon covers less than :data:`~robustgait.robots.soles.MIN_TREAD_FILL` of its rectangle, ``fill``, is
    a line foot on its longest chord along the foot, :func:`~robustgait.robots.soles.line_chord`)."""

    body: int
    geoms: tuple[int, ...]
    kind: str
    sole_class: str | None
    length: float
    width: float
    bottom: float
    tread: tuple[tuple[int, int], ...] = ()  # (mesh geom, its hull vertices on the sole) for each mesh geom
    foot: str = "flat"  # flat, or line: no support width (:func:`sole_kind`)
    fill: float | None = None  # a tread with an area planned as a line foot: the share of its rectangle it covers


@dataclass(frozen=True)
class Leg:
    """One leg: its joints from the branch body down to the foot (chain order), its sole and its ankle roll joint
    (:func:`robustgait.robots.legs.ankle_roll_joint`; None: the leg has none)."""

    side: str
    joints: tuple[int, ...]
    sole: FoundSole
    ankle_roll: int | None = None

    @property
    def foot(self) -> int:
        return self.sole.body


@dataclass(frozen=True)
class Floor:
    """The floor: a named plane of the world body (``name``), the world's only plane if unnamed (``name`` None,
    ``add`` False: the loader names it), or none (``add`` True: the loader adds one); ``height`` [m]."""

    name: str | None
    add: bool
    height: float


@dataclass(frozen=True)
class TorqueLimit:
    """A joint's torque limit [N m] and where it came from (None: the model has none; estimated later)."""

    value: float | None
    source: str


@dataclass(frozen=True)
class Legs:
    """Both legs, the body where their chains branch, and the lengths the scaling rules use (posture and zero
    configuration, [m]): ``standing_height`` base origin above the soles in the posture; ``leg_length`` the
    vertical distance from the first leg joint to the sole with every joint at 0; ``hip_spacing`` the lateral
    distance between the two legs' first joints; ``sole_spacing`` the lateral distance between the soles' centres in
    the posture; ``upper_body_height`` the height of the centre of mass of everything but the legs above the legs'
    first joints in the posture."""

    left: Leg
    right: Leg
    branch: int
    standing_height: float
    leg_length: float
    hip_spacing: float
    sole_spacing: float = 0.0
    upper_body_height: float = 0.0

    @property
    def ankle_roll(self) -> bool:
        """Whether both legs have an ankle roll."""
        return self.left.ankle_roll is not None and self.right.ankle_roll is not None

    def __getitem__(self, side: str) -> Leg:
        return self.left if side == "left" else self.right

    @property
    def joints(self) -> tuple[int, ...]:
        return self.left.joints + self.right.joints


def robot_collision_geoms(robot: RobotModel) -> dict[int, list[int]]:
    """Body → its collision geoms, for the bodies of the robot (the base's subtree) that have some."""
    out = {}
    for b in robot.subtree(robot.base):
        geoms = [g for g in robot.body_geoms(b) if robot.is_collision(g)]
        if geoms:
            out[b] = geoms
    return out


def _lowest_bodies(robot: RobotModel, d: mujoco.MjData) -> dict[int, float]:
    m = robot.model
    return {b: min(geom_bottom(m, d, g) for g in geoms) for b, geoms in robot_collision_geoms(robot).items()}


def find_feet(robot: RobotModel, d: mujoco.MjData, foot_level: float) -> tuple[int, int]:
    """(left foot, right foot) body ids at the kinematics ``d`` (base at the origin): the lowest body, and the lowest
    body on the other side of the sagittal plane that is neither its ancestor nor its descendant, which must reach
    within ``foot_level`` × the base's height above the first of the same height."""
    src = robot.path
    low = _lowest_bodies(robot, d)
    if not low:
        raise input_error(src, f"no sole found: no geom of the robot below '{robot.base_name}' takes part in "
                          "contacts (every contype and conaffinity is 0 and no <pair> names one): give the soles' "
                          "geoms contype and conaffinity, or pair them with the floor")
    a = min(low, key=low.__getitem__)
    ya = float(d.xpos[a][1])
    name_a = robot.body_name(a) or f"#{a}"
    if abs(ya) < 1e-6:
        raise input_error(src, f"no two legs: the lowest body, '{name_a}', lies on the base's sagittal plane (y = 0)")
    related = set(robot.ancestors(a)) | set(robot.subtree(a))
    other = {b: z for b, z in low.items() if b not in related and float(d.xpos[b][1]) * ya < 0}
    height = -low[a]  # the base stands this high above its lowest point
    side_a, side_b = ("left", "right") if ya > 0 else ("right", "left")
    if not other:
        raise input_error(src, f"one leg: the lowest body, '{name_a}', is on the {side_a}; no body with collision "
                          f"geometry on the {side_b} side")
    b = min(other, key=other.__getitem__)
    gap = other[b] - low[a]
    if gap > foot_level * height:
        raise input_error(src, f"one leg: the lowest body, '{name_a}', is on the {side_a}; the lowest on the "
                          f"{side_b}, '{robot.body_name(b)}', is {gap:.3f} m higher (more than {foot_level:g} × the "
                          f"standing height {height:.3f} m) in the posture")
    return (a, b) if ya > 0 else (b, a)


def branch_body(robot: RobotModel, left: int, right: int) -> int:
    """The lowest common ancestor of the two feet (where the legs' chains branch)."""
    up = [left, *robot.ancestors(left)]
    return next(b for b in [right, *robot.ancestors(right)] if b in up)


def chain_joints(robot: RobotModel, top: int, foot: int) -> tuple[int, ...]:
    """The planned or held joints (not passive: a closed chain's, :attr:`RobotModel.passive`) of the bodies strictly
    below ``top`` down to ``foot``, from the top down."""
    bodies = [foot, *robot.ancestors(foot)]
    bodies = bodies[: bodies.index(top)]
    return tuple(j for b in reversed(bodies) for j in robot.body_joints(b) if j not in robot.passive)


def _geom_class(robot: RobotModel, body: int, g: int) -> str | None:
    """The default class of compiled geom ``g`` of ``body`` (read from the parsed spec: compiled order)."""
    spec_body = robot.mjspec.body(robot.body_name(body)) if robot.body_name(body) else None
    if spec_body is None:
        return None
    geoms = list(spec_body.geoms)
    i = g - int(robot.model.body_geomadr[body])
    if len(geoms) != int(robot.model.body_geomnum[body]) or not 0 <= i < len(geoms):
        return None
    return str(geoms[i].classname.name)


def footprint_points(m: mujoco.MjModel, d: mujoco.MjData, g: int, up: NDArray[np.float64] | None = None
                     ) -> NDArray[np.float64]:
    """Where sole geom ``g`` meets the ground, (k, 3) world, at the kinematics ``d``
    (:func:`robustgait.robots.soles.geom_sole_points` read along ``up`` (3,), world; default the foot body's axis
    closest to the world's z: a foot the posture tilts keeps its whole tread)."""
    if up is None:
        rb = d.xmat[int(m.geom_bodyid[g])].reshape(3, 3)
        up = rb @ foot_up(rb)
    return geom_sole_points(m, g, d.geom_xpos[g], d.geom_xmat[g].reshape(3, 3), up)


def tread_up(m: mujoco.MjModel, d: mujoco.MjData, geoms: tuple[int, ...]) -> NDArray[np.float64]:
    """The up (3,), world, along which a foot's sole geoms are read at the kinematics ``d``, as the loader reads them
    (:func:`robustgait.robots.soles.sole_up`: the foot body's axis closest to the vertical, or the vertical where
    the tread along it spans more); a sole that is one box: its own axis closest to the vertical, as the loader's
    sole box is (:func:`robustgait.robots.solebox.sole_box`) — its bottom face is the tread however the posture tilts
    it (a keyframe that stands the box 2.5° off level kept an edge of it along the others)."""
    if one_box(m, geoms):
        rg = d.geom_xmat[geoms[0]].reshape(3, 3)
        normal, up = box_up(rg)
        return np.asarray(rg[:, normal] * up)
    rf = d.xmat[int(m.geom_bodyid[geoms[0]])].reshape(3, 3)
    return sole_up(lambda up: np.vstack([footprint_points(m, d, g, up) for g in geoms]), rf @ foot_up(rf),
                   np.array([0.0, 0.0, 1.0]))


def tread_points(m: mujoco.MjModel, d: mujoco.MjData, geoms: tuple[int, ...]) -> NDArray[np.float64]:
    """A foot's ground points on its sole (k, 3), world, at the kinematics ``d``: its geoms' points along
    :func:`tread_up`, filtered by :func:`robustgait.robots.soles.on_sole` (the tread, not an arch above it)."""
    up = tread_up(m, d, geoms)
    pts = np.vstack([footprint_points(m, d, g, up) for g in geoms])
    return np.asarray(pts[on_sole(pts, up)])


def find_sole(robot: RobotModel, d: mujoco.MjData, foot: int, side: str, tol: float) -> FoundSole:
    """The sole of a foot body (module docstring)."""
    m, src = robot.model, robot.path
    name = robot.body_name(foot) or f"#{foot}"
    coll = robot_collision_geoms(robot)[foot]
    bottom = min(geom_bottom(m, d, g) for g in coll)
    geoms = tuple(g for g in coll if geom_bottom(m, d, g) <= bottom + tol)
    for g in geoms:
        if int(m.geom_type[g]) not in SOLE_TYPES:
            gname = f"'{robot.geom_name(g)}'" if robot.geom_name(g) else f"#{g - int(m.body_geomadr[foot])}"
            kind = GEOM_TYPES[int(m.geom_type[g])]
            raise input_error(src, f"the {side} sole (the lowest geometry of body '{name}', geom {gname}) is "
                              f"{article(kind)} {kind}, whose contact patch robustgait cannot bound: make it a box or "
                              "a mesh, or add a box geom under the foot")
    names = [robot.geom_name(g) for g in geoms]
    sole_class = None
    if one_box(m, geoms) and all(names):
        kind = "geom"
    elif all(names):
        kind = "geoms"
    else:
        kind = "body"
        if not robot.body_name(foot):
            raise input_error(src, f"the {side} foot body (#{foot}) and its sole geoms are unnamed: name one of them")
        if set(coll) != set(geoms):
            classes = {_geom_class(robot, foot, g) for g in geoms}
            others = {_geom_class(robot, foot, g) for g in coll if g not in geoms}
            if len(classes) != 1 or None in classes or classes & others:
                raise input_error(src, f"the {side} sole geoms of body '{name}' are unnamed and share their default "
                                  "class with the body's other collision geoms: name them")
            sole_class = classes.pop()
    up = tread_up(m, d, geoms)
    per_geom = [footprint_points(m, d, g, up) for g in geoms]
    on = on_sole(np.vstack(per_geom), up)  # across the geoms, as the loader's sole box
    pts = np.vstack(per_geom)[on]
    tread: NDArray[np.float64] | None = None  # the loader's ground points of a sole that is not one box
    if one_box(m, geoms):
        # one box is the sole itself, as the loader reads it: its own sizes and a rectangle, not its extent along the
        # foot body's axes, which a box turned in the foot would widen
        read = sole_box(m, geoms[0], src)
        length, width = 2.0 * read.half_length, 2.0 * read.half_width
    else:
        # several geoms: the rectangle the loader spans its virtual sole on (turned onto the tread's plane, read
        # along the vertical where the foot's frame is tilted from its sole), not the points' extent here
        rect = loader_rectangle(m, geoms, robot.base)
        length, width, tread = 2.0 * float(rect.half[0]), 2.0 * float(rect.half[1]), rect.tread
    foot_kind = sole_kind(pts, length, width)
    fill = None  # no flat sole (a heel point and a toe bar): a line on its longest chord
    if tread is not None and foot_kind == "flat" and 0.0 < (share := tread_fill(tread)) < MIN_TREAD_FILL:
        foot_kind, length, width, fill = "line", line_chord(tread).length, 0.0, share
    if foot_kind == "point":
        raise input_error(src, f"no sole found for the {side} leg: the lowest geometry of body '{name}' spans "
                          f"{length:.3g} × {width:.3g} m, no area to stand on (a point foot, which robustgait does not "
                          "plan yet: add a box geom under the foot, or a capsule along it: a line foot)")
    if foot_kind == "line" and fill is None:  # a capsule's line: its points' extent
        length, width = float(np.max(np.linalg.norm(pts[:, None, :] - pts[None, :, :], axis=-1))), 0.0
    return FoundSole(foot, geoms, kind, sole_class, length, width, bottom, _tread(m, geoms, per_geom, on), foot_kind,
                     fill)


def sole_kind(points: NDArray[np.float64], length: float, width: float) -> str:
    """A sole's kind by its ground points (k, 3) on the sole and its extent along the foot (``length``, ``width``
    [m]): ``flat`` when both reach :data:`MIN_SOLE`; ``line`` when its points lie on one segment at least
    :data:`MIN_SOLE` long and no wider than :data:`MIN_SOLE` across it (one capsule along the foot: no support width);
    ``point`` otherwise (one sphere, a capsule on end)."""
    if min(length, width) >= MIN_SOLE:
        return "flat"
    if len(points) < 2:
        return "point"
    centred = points - points.mean(axis=0)
    sv = np.linalg.svd(centred, compute_uv=False)
    spread = 2.0 * sv / np.sqrt(len(points))  # extent along the principal axes (exact for two points)
    return "line" if spread[0] >= MIN_SOLE and (len(sv) < 2 or spread[1] < MIN_SOLE) else "point"


def _tread(m: mujoco.MjModel, geoms: tuple[int, ...], per_geom: list[NDArray[np.float64]], on: NDArray[np.bool_]
           ) -> tuple[tuple[int, int], ...]:
    """(mesh geom, how many of its ground points are on the sole) for each mesh geom of ``geoms``, whose ground
    points ``per_geom`` were stacked in that order and filtered by the mask ``on``."""
    ends = np.cumsum([len(p) for p in per_geom])
    counts = [int(on[end - len(p):end].sum()) for end, p in zip(ends, per_geom, strict=True)]
    return tuple((g, c) for g, c in zip(geoms, counts, strict=True) if GEOM_TYPES[int(m.geom_type[g])] == "mesh")


def find_floor(robot: RobotModel) -> Floor:
    """The floor plane of the world body (module docstring)."""
    m = robot.model
    d = mujoco.MjData(m)
    mujoco.mj_kinematics(m, d)
    planes = [g for g in robot.body_geoms(0) if GEOM_TYPES[int(m.geom_type[g])] == "plane"
              and float(d.geom_xmat[g].reshape(3, 3)[2, 2]) > 0.999]
    if not planes:
        return Floor(None, True, 0.0)
    named = [g for g in planes if robot.geom_name(g)]
    if len(planes) > 1 and len(named) != 1:
        raise input_error(robot.path, f"the world has {len(planes)} horizontal plane geoms: name the floor's "
                          "(and only it) so that robot init can tell which one is the floor")
    g = named[0] if len(planes) > 1 else planes[0]
    return Floor(robot.geom_name(g) or None, False, float(d.geom_xpos[g][2]))


def _one_foot_body(robot: RobotModel, d: mujoco.MjData, leg: Leg, top: int, tol: float) -> None:
    """Refuse a foot that stands on two bodies (a toe on its own joint): the loader's sole is one body's geoms, and
    a contact of any other body with the floor is a fall."""
    m = robot.model
    others = [b for b, geoms in robot_collision_geoms(robot).items() if b in robot.subtree(top) and b != leg.foot
              and min(geom_bottom(m, d, g) for g in geoms) <= leg.sole.bottom + tol]
    if others:
        names = ", ".join(f"'{robot.body_name(b)}'" for b in [leg.foot, *others])
        raise input_error(robot.path, f"the {leg.side} foot stands on {len(others) + 1} bodies ({names}) in the "
                          "posture: robustgait's sole is the geoms of one body, any other body on the floor is a "
                          "fall (merge them, or lift the others' geoms)")


def find_legs(robot: RobotModel, foot_level: float, sole_tolerance: float) -> Legs:
    """Feet, leg chains and soles of the robot in its posture (module docstring)."""
    src = robot.path
    d = robot.kinematics(robot.qpos())
    left, right = find_feet(robot, d, foot_level)
    branch = branch_body(robot, left, right)
    legs = {}
    for side, foot in zip(SIDES, (left, right), strict=True):
        joints = chain_joints(robot, branch, foot)
        if not joints:
            raise input_error(src, f"the {side} foot '{robot.body_name(foot)}' has no joint between it and "
                              f"'{robot.body_name(branch)}', where the legs branch")
        legs[side] = Leg(side, joints, find_sole(robot, d, foot, side, sole_tolerance),
                         ankle_roll_joint(robot.model, joints))
        _one_foot_body(robot, d, legs[side], int(robot.model.jnt_bodyid[joints[0]]), sole_tolerance)
    if len(legs["left"].joints) != len(legs["right"].joints):
        raise input_error(src, f"the legs differ: {len(legs['left'].joints)} joints on the left, "
                          f"{len(legs['right'].joints)} on the right")
    height = -min(leg.sole.bottom for leg in legs.values())
    zero = robot.kinematics(robot.qpos({j: 0.0 for j in robot.joints}))
    m = robot.model
    hips = [zero.xanchor[legs[s].joints[0]] for s in SIDES]
    soles = [min(geom_bottom(m, zero, g) for g in legs[s].sole.geoms) for s in SIDES]
    length = float(np.mean([hips[i][2] - soles[i] for i in range(2)]))
    if length <= 0.0:
        raise input_error(src, f"the first leg joint '{robot.joint_name(legs['left'].joints[0])}' is not above the "
                          "sole with every joint at 0: is the base's z axis up?")
    centres = [_sole_centre(m, d, legs[s].sole.geoms) for s in SIDES]
    return Legs(legs["left"], legs["right"], branch, height, length, float(abs(hips[0][1] - hips[1][1])),
                sole_spacing=float(abs(centres[0][1] - centres[1][1])),
                upper_body_height=_upper_body_height(robot, d, legs))


def _sole_centre(m: mujoco.MjModel, d: mujoco.MjData, geoms: tuple[int, ...]) -> NDArray[np.float64]:
    """The centre (3,) of the rectangle spanning a sole's tread (:func:`tread_points`) at the kinematics ``d`` (world
    frame)."""
    pts = tread_points(m, d, geoms)
    return np.asarray((pts.min(axis=0) + pts.max(axis=0)) / 2.0)


def _upper_body_height(robot: RobotModel, d: mujoco.MjData, legs: dict[str, Leg]) -> float:
    """How high the centre of mass of every body but the legs' lies above the legs' first joints [m], at ``d``."""
    m = robot.model
    leg_bodies = {b for leg in legs.values() for b in robot.subtree(int(m.jnt_bodyid[leg.joints[0]]))}
    upper = [b for b in robot.subtree(robot.base) if b not in leg_bodies]
    mass = np.array([m.body_mass[b] for b in upper])
    com = (mass[:, None] * np.array([d.xipos[b] for b in upper])).sum(axis=0) / max(float(mass.sum()), 1e-12)
    hips = np.mean([d.xanchor[leg.joints[0]][2] for leg in legs.values()])
    return float(com[2] - hips)


def torque_limits(robot: RobotModel) -> dict[int, TorqueLimit]:
    """Each non-base joint's torque limit from the model (module docstring); value None where it has none."""
    m = robot.model
    found: dict[int, list[tuple[float, str]]] = {j: [] for j in robot.joints}
    for j in robot.joints:
        if m.jnt_actfrclimited[j]:
            lo, hi = m.jnt_actfrcrange[j]
            found[j].append((float(min(abs(lo), abs(hi))), "its actuatorfrcrange"))
    for a in range(m.nu):
        if int(m.actuator_trntype[a]) != int(mujoco.mjtTrn.mjTRN_JOINT):
            continue
        j = int(m.actuator_trnid[a][0])
        if j not in found:
            continue
        name = mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_ACTUATOR, a) or f"#{a}"
        gear = abs(float(m.actuator_gear[a][0]))
        if m.actuator_forcelimited[a]:
            lo, hi = m.actuator_forcerange[a]
            found[j].append((gear * float(min(abs(lo), abs(hi))), f"actuator '{name}' forcerange × gear"))
        elif (int(m.actuator_gaintype[a]) == int(mujoco.mjtGain.mjGAIN_FIXED)
              and int(m.actuator_biastype[a]) == int(mujoco.mjtBias.mjBIAS_NONE) and m.actuator_ctrllimited[a]):
            lo, hi = m.actuator_ctrlrange[a]
            gain = abs(float(m.actuator_gainprm[a][0]))
            found[j].append((gear * gain * float(min(abs(lo), abs(hi))), f"motor '{name}' ctrlrange × gain × gear"))
    out = {}
    for j, options in found.items():
        positive = [o for o in options if o[0] > 0.0]
        out[j] = TorqueLimit(*min(positive)) if positive else TorqueLimit(None, "none in the model")
    return out
