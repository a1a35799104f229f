"""The robot's model as inspection sees it: the compiled MuJoCo model, its floating base, the standing posture
(a keyframe, else every joint at 0 clipped to its range), and the geometry that the discovery reads from it —
collision geoms, their lowest points, the kinematic tree.

Frames: the base frame is MuJoCo's (and ROS REP 103's) x forward, y left, z up. Inspection puts the base at the
world origin with the identity orientation, so world coordinates *are* base coordinates.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import mujoco
import numpy as np
from numpy.typing import NDArray

from robustgait.errors import input_error
from robustgait.io.robotfile import ModelKind, read_model
from robustgait.robots.legs import subtree
from robustgait.robots.soles import GEOM_TYPES, collides, hull_vertices

FREE = int(mujoco.mjtJoint.mjJNT_FREE)
HINGE = int(mujoco.mjtJoint.mjJNT_HINGE)
SLIDE = int(mujoco.mjtJoint.mjJNT_SLIDE)
JOINT_TYPES = {FREE: "free", int(mujoco.mjtJoint.mjJNT_BALL): "ball", SLIDE: "slide", HINGE: "hinge"}


@dataclass
class RobotModel:
    """A robot's model file compiled for inspection. ``mjspec``: the parsed file (a URDF's root link with the free
    joint the loader gives it); ``model``: its compilation; ``base``: the body id of the floating base;
    ``keyframe``: the name (or index) of the keyframe the posture came from, None when the model has none;
    ``angles``: the posture's angle of every non-base joint (joint id → rad)."""

    path: Path
    kind: ModelKind
    mjspec: mujoco.MjSpec
    model: mujoco.MjModel
    base: int
    keyframe: str | None
    angles: dict[int, float] = field(default_factory=dict)

    @property
    def joints(self) -> list[int]:
        """The non-base joints, in model order."""
        return [j for j in range(self.model.njnt) if int(self.model.jnt_type[j]) != FREE]

    def joint_name(self, j: int) -> str:
        return str(mujoco.mj_id2name(self.model, mujoco.mjtObj.mjOBJ_JOINT, j) or "")

    def body_name(self, b: int) -> str:
        return str(mujoco.mj_id2name(self.model, mujoco.mjtObj.mjOBJ_BODY, b) or "")

    def geom_name(self, g: int) -> str:
        return str(mujoco.mj_id2name(self.model, mujoco.mjtObj.mjOBJ_GEOM, g) or "")

    @property
    def base_name(self) -> str:
        return self.body_name(self.base)

    @property
    def mass(self) -> float:
        return float(self.model.body_subtreemass[self.base])

    def qpos(self, angles: dict[int, float] | None = None, height: float = 0.0) -> NDArray[np.float64]:
        """A configuration: the base at (0, 0, height) with the identity orientation, each joint at ``angles``
        (default: the posture's), other coordinates at the model's reference ``qpos0``."""
        m = self.model
        q = m.qpos0.copy()
        adr = int(m.jnt_qposadr[m.body_jntadr[self.base]])
        q[adr:adr + 7] = [0.0, 0.0, height, 1.0, 0.0, 0.0, 0.0]
        for j, a in (self.angles if angles is None else angles).items():
            q[m.jnt_qposadr[j]] = a
        return q

    def kinematics(self, qpos: NDArray[np.float64]) -> mujoco.MjData:
        """Positions and orientations of every body, geom and joint axis at ``qpos`` (and its mass matrix)."""
        d = mujoco.MjData(self.model)
        d.qpos[:] = qpos
        mujoco.mj_forward(self.model, d)
        return d

    def subtree(self, body: int) -> list[int]:
        """``body`` and every body below it (:func:`robustgait.robots.legs.subtree`)."""
        return subtree(self.model, body)

    def ancestors(self, body: int) -> list[int]:
        """The bodies above ``body``, nearest first, up to the world body (0) excluded."""
        out = []
        b = int(self.model.body_parentid[body])
        while b > 0:
            out.append(b)
            b = int(self.model.body_parentid[b])
        return out

    def body_joints(self, body: int) -> list[int]:
        m = self.model
        return list(range(int(m.body_jntadr[body]), int(m.body_jntadr[body] + m.body_jntnum[body])))

    def body_geoms(self, body: int) -> list[int]:
        m = self.model
        return list(range(int(m.body_geomadr[body]), int(m.body_geomadr[body] + m.body_geomnum[body])))

    def is_collision(self, g: int) -> bool:
        """A geom that takes part in contacts: contype or conaffinity ≠ 0, or named by a ``<pair>``
        (:func:`robustgait.robots.soles.collides`)."""
        return collides(self.model, g)


def joint_range(m: mujoco.MjModel, j: int) -> tuple[float, float] | None:
    """A limited joint's [low, high] range, None for an unlimited one."""
    return (float(m.jnt_range[j][0]), float(m.jnt_range[j][1])) if m.jnt_limited[j] else None


def clip_to_range(m: mujoco.MjModel, j: int, angle: float) -> float:
    r = joint_range(m, j)
    return angle if r is None else float(np.clip(angle, r[0], r[1]))


def _base_of_mjcf(m: mujoco.MjModel, src: Path) -> int:
    free = [j for j in range(m.njnt) if int(m.jnt_type[j]) == FREE]
    if not free:
        raise input_error(src, "no free joint: robustgait needs a floating-base robot (add <freejoint/> to the base "
                          "body of the MJCF)")
    if len(free) > 1:
        names = ", ".join(repr(mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_BODY, m.jnt_bodyid[j])) for j in free)
        raise input_error(src, f"{len(free)} bodies have a free joint ({names}): robustgait needs the model of one "
                          "robot (remove the other free bodies)")
    if free[0] != 0:
        raise input_error(src, "the free joint of the base must be the model's first joint")
    return int(m.jnt_bodyid[free[0]])


def _add_urdf_free_joint(mjs: mujoco.MjSpec, src: Path) -> None:
    """A URDF cannot express a floating base: give its root link a free joint, as the spec loader does."""
    roots = []
    b = mjs.worldbody.first_body()
    while b is not None:
        roots.append(b)
        b = mjs.worldbody.next_body(b)
    if len(roots) != 1:
        raise input_error(src, f"the URDF has {len(roots)} root links: robustgait needs one robot (one root link)")
    if roots[0].first_joint() is not None:
        raise input_error(src, f"the URDF's root link '{roots[0].name}' already moves on a joint")
    roots[0].add_freejoint()


def posture_angles(m: mujoco.MjModel, keyframe: str | None, src: Path) -> tuple[dict[int, float], str | None]:
    """Every non-base joint's angle in the standing posture: the keyframe ``keyframe`` (None: the model's first),
    else 0 clipped to the joint's range. Returns (joint id → angle, the keyframe's name or None)."""
    joints = [j for j in range(m.njnt) if int(m.jnt_type[j]) != FREE]
    if keyframe is not None:
        k = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_KEY, keyframe)
        if k < 0:
            names = [mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_KEY, i) for i in range(m.nkey)]
            raise input_error(src, f"no keyframe named {keyframe!r} (the model has {names or 'none'})")
    elif m.nkey > 0:
        k = 0
    else:
        return {j: clip_to_range(m, j, 0.0) for j in joints}, None
    q = m.key_qpos[k]
    name = mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_KEY, k) or f"#{k}"
    return {j: clip_to_range(m, j, float(q[m.jnt_qposadr[j]])) for j in joints}, name


def open_model(path: str | Path, keyframe: str | None = None) -> RobotModel:
    """Read and compile a robot's MJCF or URDF for inspection (one-line errors for a file MuJoCo cannot read or
    compile, a model without exactly one floating base, a keyframe that does not exist)."""
    src = Path(path)
    mjs, kind = read_model(src)
    if kind == "urdf":
        _add_urdf_free_joint(mjs, src)
    try:
        m = mjs.compile()
    except ValueError as exc:
        raise input_error(src, f"MuJoCo could not compile the model: {exc}") from None
    base = _base_of_mjcf(m, src)
    for j in range(m.njnt):
        if j != m.body_jntadr[base] and int(m.jnt_type[j]) not in (HINGE, SLIDE):
            raise input_error(src, f"joint '{mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_JOINT, j)}' is a "
                              f"{JOINT_TYPES[int(m.jnt_type[j])]} joint: robustgait plans and holds hinge and slide "
                              "joints only")
    angles, key = posture_angles(m, keyframe, src)
    return RobotModel(src, kind, mjs, m, base, key, angles)


# ----------------------------------------------------------------------------------------------- geometry
def geom_lowest_point(m: mujoco.MjModel, d: mujoco.MjData, g: int) -> NDArray[np.float64]:
    """The lowest point (world frame, least z) of geom ``g`` at the kinematics ``d``: exact for spheres,
    capsules, cylinders, ellipsoids, boxes (support point in the direction −z) and meshes (their convex hull's
    vertices); the bounding box for other shapes. A face lying flat has many lowest points: this is one of them."""
    p = d.geom_xpos[g]
    r = d.geom_xmat[g].reshape(3, 3)
    s = m.geom_size[g]
    t = GEOM_TYPES[int(m.geom_type[g])]
    down = np.array([0.0, 0.0, -1.0])
    local = r.T @ down  # the direction −z in the geom's frame
    if t == "sphere":
        return p + s[0] * down
    if t == "capsule":
        end = r[:, 2] * s[1] * (1.0 if local[2] > 0 else -1.0)
        return p + end + s[0] * down
    if t == "cylinder":
        axial = r[:, 2] * s[1] * (1.0 if local[2] > 0 else -1.0)
        radial = r @ np.array([local[0], local[1], 0.0])
        norm = float(np.linalg.norm(radial))
        return p + axial + (s[0] * radial / norm if norm > 1e-12 else 0.0)
    if t == "ellipsoid":
        scaled = s[:3] * local
        norm = float(np.linalg.norm(scaled))
        return p + r @ (s[:3] * scaled / norm) if norm > 0 else p
    if t == "mesh" and m.geom_dataid[g] >= 0:
        pts = p + hull_vertices(m, g) @ r.T  # the hull MuJoCo collides (maxhullvert may drop mesh vertices)
        return np.asarray(pts[int(np.argmin(pts[:, 2]))])
    if t == "box":
        half = s[:3]
    else:  # height field, SDF, ...: the geom's bounding box (centre, half sizes) in its frame
        half = m.geom_aabb[g][3:]
        p = p + r @ m.geom_aabb[g][:3]
    return p + r @ (half * np.where(local >= 0, 1.0, -1.0))


def geom_bottom(m: mujoco.MjModel, d: mujoco.MjData, g: int) -> float:
    """The height of geom ``g``'s lowest point [m]."""
    return float(geom_lowest_point(m, d, g)[2])
