"""A robot's soles and floor in its parsed MJCF (``docs/robots.md``, "Soles and floor").

The pipeline places a foot by its *sole box*: a box geom whose bottom face is the sole (the gait generator's foot
frames, the centre-of-pressure bounds, the touchdown guard's flatness). A spec names the sole as one box geom, a set
of geoms of one body, or a body (optionally one default class of its geoms). When that is not a single box — the
sphere or capsule feet of some Menagerie robots, an unnamed box — :func:`resolve_sole` adds a *virtual sole*: a box
geom ``robustgait_{side}_sole`` on the foot body that takes part in no contact and has no mass, spanning the
rectangle of the geoms' lowest points (its bottom face at their lowest point). Contacts stay the real geoms'; the
contact sensor of that sole then counts the foot body's contacts.

:func:`resolve_floor` finds the world's plane (naming it if unnamed) or adds one (``add_floor``).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import mujoco
import numpy as np
from numpy.typing import NDArray

from robustgait.errors import input_error
from robustgait.robots.spec import ADDED_FLOOR, SIDES, LegSpec, RobotSpec
from robustgait.rotations import quat_to_mat

FloatArray = NDArray[np.float64]
SOLE_TYPES = {int(mujoco.mjtGeom.mjGEOM_BOX): "box", int(mujoco.mjtGeom.mjGEOM_SPHERE): "sphere",
              int(mujoco.mjtGeom.mjGEOM_CAPSULE): "capsule"}
# thickness of a virtual sole box [m]: only its bottom face matters (it takes part in no contact)
VIRTUAL_SOLE_THICKNESS = 0.002
# points within this height of a foot's lowest point are on its sole [m] (a box's bottom face, sphere bottoms
# at one height); higher points (a heel sphere raised by 1 cm) do not widen the sole
SOLE_PLANE_TOLERANCE = 0.002


def virtual_sole_name(side: str) -> str:
    return f"robustgait_{side}_sole"


@dataclass(frozen=True)
class ResolvedSole:
    """How one sole entered the model: ``geom`` the sole box's name (real or virtual); ``sensor`` the contact sensor's
    object (type and name): the box geom itself, or the foot body for a virtual sole; ``geoms`` the real geoms. (What
    ``robot init`` finds in a model before a spec exists is :class:`robustgait.inspection.discover.FoundSole`.)"""

    geom: str
    sensor: tuple[mujoco.mjtObj, str]
    geoms: tuple[int, ...]
    virtual: bool


def _colliding(g: mujoco.MjsGeom) -> bool:
    return bool(g.contype or g.conaffinity)


def _sole_geoms(mjs: mujoco.MjSpec, model: mujoco.MjModel, leg: LegSpec, side: str,
                src: str | Path | None) -> list[int]:
    """Compiled ids of the geoms a leg's sole is named by (one-line errors for unknown or unsuitable names)."""
    if leg.sole_geom is not None or leg.sole_geoms:
        names = (leg.sole_geom,) if leg.sole_geom is not None else leg.sole_geoms
        ids = []
        for name in names:
            gid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, name)
            if gid < 0:
                raise input_error(src, f"unknown geom name '{name}' for the {side} sole")
            ids.append(gid)
    else:
        body = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, leg.sole_body)
        if body < 0:
            raise input_error(src, f"unknown body name '{leg.sole_body}' for the {side} sole")
        specs = [g for g in mjs.geoms if g.parent.name == leg.sole_body and _colliding(g)
                 and (leg.sole_class is None or g.classname.name == leg.sole_class)]
        ids = [int(g.id) for g in specs]
        if not ids:
            raise input_error(src, f"no sole found for the {side} leg: body '{leg.sole_body}' has no colliding geom"
                              + (f" of class '{leg.sole_class}'" if leg.sole_class is not None else ""))
    bodies = {int(model.geom_bodyid[g]) for g in ids}
    if len(bodies) > 1:
        raise input_error(src, f"the {side} sole's geoms ({leg.describe()}) belong to {len(bodies)} bodies: a sole is "
                          "geoms of one foot body")
    for g in ids:
        if int(model.geom_type[g]) not in SOLE_TYPES:
            kind = mujoco.mjtGeom(int(model.geom_type[g])).name.removeprefix("mjGEOM_").lower()
            raise input_error(src, f"the {side} sole ({leg.describe()}) has a {kind} geom: a sole is one box or a set "
                              "of boxes, spheres or capsules")
    return ids


def _lowest_points(model: mujoco.MjModel, g: int) -> FloatArray:
    """Candidate contact points (k, 3) of a sole geom in its body's frame: a box's 8 corners, a sphere's centre, a
    capsule's two segment ends — each to be pushed down by the radius (:func:`sole_rectangle`)."""
    pos, rot, size = model.geom_pos[g], quat_to_mat(model.geom_quat[g]), model.geom_size[g]
    kind = SOLE_TYPES[int(model.geom_type[g])]
    if kind == "box":
        corners = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)]) * size
        return np.asarray(pos + corners @ rot.T)
    if kind == "sphere":
        return np.asarray(pos[None])
    half = size[1] * rot[:, 2]  # a capsule's segment runs along its z axis
    return np.asarray(np.stack([pos - half, pos + half]))


def _radius(model: mujoco.MjModel, g: int) -> float:
    return 0.0 if SOLE_TYPES[int(model.geom_type[g])] == "box" else float(model.geom_size[g][0])


def sole_rectangle(model: mujoco.MjModel, data: mujoco.MjData, geoms: list[int], forward: FloatArray
                   ) -> tuple[FloatArray, FloatArray, FloatArray]:
    """The sole of a foot's geoms as a box in the foot body's frame: (centre (3,), rotation (3, 3) whose columns
    are the box's x (toe), y (left) and z (up) axes, half-sizes (3,)), at the posture of ``data``.

    Up is the body axis closest to the world's vertical and toe the remaining body axis closest to ``forward``
    (the base's x axis in the world), so the box is aligned with the foot. The sole plane is the lowest point of
    the geoms along up (a sphere or capsule's bottom: its centre minus its radius); the rectangle spans the
    points within :data:`SOLE_PLANE_TOLERANCE` of it; the box is :data:`VIRTUAL_SOLE_THICKNESS` thick above it.
    """
    body = int(model.geom_bodyid[geoms[0]])
    rb = data.xmat[body].reshape(3, 3)  # body axes in the world (columns)
    up_k = int(np.argmax(np.abs(rb[2])))
    up = np.eye(3)[up_k] * np.sign(rb[2, up_k])
    rest = [k for k in range(3) if k != up_k]
    fwd_k = max(rest, key=lambda k: abs(float(rb[:, k] @ forward)))
    fwd = np.eye(3)[fwd_k] * (1.0 if float(rb[:, fwd_k] @ forward) >= 0 else -1.0)
    left = np.cross(up, fwd)
    pts, heights = [], []
    for g in geoms:
        p = _lowest_points(model, g)
        pts.append(p)
        heights.append(p @ up - _radius(model, g))
    points, height = np.concatenate(pts), np.concatenate(heights)
    bottom = float(height.min())
    on = height <= bottom + SOLE_PLANE_TOLERANCE
    along, across = points[on] @ fwd, points[on] @ left
    half = np.array([(along.max() - along.min()) / 2, (across.max() - across.min()) / 2,
                     VIRTUAL_SOLE_THICKNESS / 2])
    centre = ((along.max() + along.min()) / 2 * fwd + (across.max() + across.min()) / 2 * left
              + (bottom + half[2]) * up)
    return centre, np.column_stack([fwd, left, up]), half


def resolve_soles(spec: RobotSpec, mjs: mujoco.MjSpec, model: mujoco.MjModel) -> dict[str, ResolvedSole]:
    """Both soles (:func:`resolve_sole`); the geoms are found before ``mjs`` is edited (an edit renumbers it)."""
    src = spec.source or spec.mjcf
    ids = {side: _sole_geoms(mjs, model, spec.legs[side], side, src) for side in SIDES}
    geoms = {g.id: g for g in mjs.geoms}
    bodies = {b.id: b for b in mjs.bodies}
    return {side: resolve_sole(spec, mjs, model, side, ids[side], geoms, bodies) for side in SIDES}


def resolve_sole(spec: RobotSpec, mjs: mujoco.MjSpec, model: mujoco.MjModel, side: str, ids: list[int],
                 geoms: dict[int, mujoco.MjsGeom], bodies: dict[int, mujoco.MjsBody]) -> ResolvedSole:
    """Make a leg's sole (its geoms ``ids`` in ``model``, ``mjs`` compiled before any edit; ``geoms``, ``bodies``:
    the spec's elements by those ids) a box geom of ``mjs`` (edited in place): the named box itself, or a virtual
    sole spanning the geoms (module docstring)."""
    src = spec.source or spec.mjcf
    leg = spec.legs[side]
    name = model.geom(ids[0]).name
    if len(ids) == 1 and SOLE_TYPES[int(model.geom_type[ids[0]])] == "box":
        if not name:  # an unnamed box (named by its body): our sensors need a name
            name = virtual_sole_name(side)
            geoms[ids[0]].name = name
        return ResolvedSole(name, (mujoco.mjtObj.mjOBJ_GEOM, name), tuple(ids), virtual=False)
    data = mujoco.MjData(model)
    mujoco.mj_kinematics(model, data)
    base = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, spec.base_body)
    forward = data.xmat[base].reshape(3, 3)[:, 0]
    centre, rot, half = sole_rectangle(model, data, ids, forward)
    if min(half[0], half[1]) <= 1e-4:
        raise input_error(src, f"the {side} sole ({leg.describe()}) spans no area ({2 * half[0]:.3g} × "
                          f"{2 * half[1]:.3g} m): name geoms that cover the foot's support")
    body = bodies[int(model.geom_bodyid[ids[0]])]
    if not body.name:
        body.name = f"robustgait_{side}_foot"
    quat = np.zeros(4)
    mujoco.mju_mat2Quat(quat, rot.ravel())
    geom = body.add_geom(name=virtual_sole_name(side), type=mujoco.mjtGeom.mjGEOM_BOX, size=half, pos=centre,
                         quat=quat, contype=0, conaffinity=0, density=0.0, group=5, rgba=[0.2, 0.6, 1.0, 0.0])
    geom.mass = 0.0
    return ResolvedSole(virtual_sole_name(side), (mujoco.mjtObj.mjOBJ_BODY, body.name), tuple(ids), virtual=True)


def resolve_floor(spec: RobotSpec, mjs: mujoco.MjSpec, soles: list[mujoco.MjsGeom]) -> str:
    """The floor geom's name in ``mjs`` (edited in place): the spec's ``floor_geom``; or with ``add_floor`` a plane
    :data:`ADDED_FLOOR` added to the world body, colliding with the soles' geoms (their contype/conaffinity bits); or
    the world body's only plane, named :data:`ADDED_FLOOR` if unnamed. ``soles``: the real sole geoms."""
    src = spec.source or spec.mjcf
    planes = [g for g in mjs.worldbody.geoms if g.type == mujoco.mjtGeom.mjGEOM_PLANE]
    if spec.add_floor:
        if planes:
            names = ", ".join(f"'{g.name}'" if g.name else "an unnamed plane" for g in planes)
            raise input_error(src, f"add_floor: the MJCF already has a floor ({names}): remove add_floor "
                              "(the world's only plane is the floor) or set floor_geom")
        contype = conaffinity = 0
        for g in soles:
            contype |= int(g.conaffinity)
            conaffinity |= int(g.contype)
        mjs.worldbody.add_geom(name=ADDED_FLOOR, type=mujoco.mjtGeom.mjGEOM_PLANE, size=[0, 0, 0.05],
                               contype=contype or 1, conaffinity=conaffinity or 1, rgba=[0.8, 0.8, 0.8, 1])
        return ADDED_FLOOR
    if spec.floor_geom is not None:
        if not any(g.name == spec.floor_geom for g in mjs.geoms):
            raise input_error(src, f"unknown geom name '{spec.floor_geom}' for the floor")
        return spec.floor_geom
    if len(planes) != 1:
        raise input_error(src, f"the MJCF's world body has {len(planes)} plane geoms: name the floor with "
                          "floor_geom" + ("" if planes else ", or set add_floor = true to add one"))
    if not planes[0].name:
        planes[0].name = ADDED_FLOOR
    return str(planes[0].name)
