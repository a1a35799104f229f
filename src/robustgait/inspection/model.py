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

from robustgait.config.robot import LOOP_TOLERANCE
from robustgait.errors import input_error
from robustgait.io.robotfile import ModelKind, read_model
from robustgait.robots.legs import subtree
from robustgait.robots.loops import (
    Loop,
    Spring,
    close_loops,
    closed_chains,
    find_springs,
    loop_residuals,
    undriven_motion,
)
from robustgait.robots.soles import GEOM_TYPES, collides, hull_vertices

FREE = int(mujoco.mjtJoint.mjJNT_FREE)
HINGE = int(mujoco.mjtJoint.mjJNT_HINGE)
SLIDE = int(mujoco.mjtJoint.mjJNT_SLIDE)
BALL = int(mujoco.mjtJoint.mjJNT_BALL)
JOINT_TYPES = {FREE: "free", int(mujoco.mjtJoint.mjJNT_BALL): "ball", SLIDE: "slide", HINGE: "hinge"}


@dataclass
class RobotModel:
    """A robot's model file compiled for inspection. ``mjspec``: the parsed file (a URDF's root link with the free
    joint the loader gives it); ``model``: its compilation; ``base``: the body id of the floating base;
    ``keyframe``: the name (or index) of the keyframe the posture came from, None when the model has none;
    ``angles``: the posture's angle of every non-base hinge and slide joint (joint id → rad); ``balls``: the
    posture's quaternion (4,) of every ball joint. ``loops``: the model's closed chains
    (:func:`robustgait.robots.loops.find_loops`); ``passive``: their joints that are neither planned nor held
    (:func:`~robustgait.robots.loops.passive_joints`); ``springs``: the passive joints with a stiffness; ``opened``:
    each loop's residual [m] at the keyframe as the model gives it, before :meth:`close`."""

    path: Path
    kind: ModelKind
    mjspec: mujoco.MjSpec
    model: mujoco.MjModel
    base: int
    keyframe: str | None
    angles: dict[int, float] = field(default_factory=dict)
    balls: dict[int, NDArray[np.float64]] = field(default_factory=dict)
    loops: tuple[Loop, ...] = ()
    passive: tuple[int, ...] = ()
    springs: tuple[Spring, ...] = ()
    opened: dict[str, float] = field(default_factory=dict)

    @property
    def joints(self) -> list[int]:
        """The non-base joints that are planned or held (not passive), in model order."""
        return [j for j in range(self.model.njnt) if int(self.model.jnt_type[j]) != FREE and j not in self.passive]

    @property
    def solved(self) -> tuple[int, ...]:
        """The passive joints the posture solves from the loops: every one but the springs, which it holds at their
        angle (rigid)."""
        springs = {s.joint for s in self.springs}
        return tuple(j for j in self.passive if j not in springs)

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
        for j, quat in self.balls.items():
            q[m.jnt_qposadr[j]:m.jnt_qposadr[j] + 4] = quat
        return q

    def close(self) -> float:
        """Solve the passive joints of the posture (``angles``, ``balls``; edited) so that its loops close
        (:func:`robustgait.robots.loops.close_loops`, the springs held); returns the largest change of a hinge or
        slide [rad or m]. Raises RobustGaitError naming the loop, its joints and the gap left when it cannot close
        within :data:`~robustgait.config.robot.LOOP_TOLERANCE`."""
        if not self.loops:
            return 0.0
        m = self.model
        q = close_loops(m, self.qpos(), self.loops, self.solved, LOOP_TOLERANCE)
        left = loop_residuals(m, q, self.loops)
        worst = max(self.loops, key=lambda loop: left[loop.key])
        if left[worst.key] > LOOP_TOLERANCE:
            where = f"the keyframe '{self.keyframe}'" if self.keyframe is not None else "the posture"
            moved = [self.joint_name(j) for j in worst.joints if j in self.solved]
            raise input_error(self.path, f"{worst.describe()} cannot close at {where}: its ends stay "
                              f"{left[worst.key] * 1e3:.4g} mm apart with its passive joints "
                              f"{', '.join(repr(n) for n in moved) or '(none)'} solved and its other joints "
                              f"({', '.join(repr(self.joint_name(j)) for j in worst.joints if j not in self.solved)}) "
                              f"at their angles (tolerance {LOOP_TOLERANCE * 1e3:g} mm)")
        change = 0.0
        for j in self.solved:
            adr = int(m.jnt_qposadr[j])
            if int(m.jnt_type[j]) == BALL:
                self.balls[j] = q[adr:adr + 4].copy()
            else:
                change = max(change, abs(float(q[adr]) - self.angles[j]))
                self.angles[j] = float(q[adr])
        return change

    def loop_residuals(self) -> dict[str, float]:
        """Each loop's residual at the posture (:func:`robustgait.robots.loops.loop_residuals`) [m], by key."""
        return loop_residuals(self.model, self.qpos(), self.loops)

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


def keyframe_index(m: mujoco.MjModel, keyframe: str | None, src: Path) -> int | None:
    """The posture's keyframe: the one named ``keyframe`` (None: the model's first); None when the model has none."""
    if keyframe is not None:
        k = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_KEY, keyframe)
        if k < 0:
            names = [mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_KEY, i) for i in range(m.nkey)]
            raise input_error(src, f"no keyframe named {keyframe!r} (the model has {names or 'none'})")
        return int(k)
    return 0 if m.nkey > 0 else None


def posture_angles(m: mujoco.MjModel, keyframe: str | None, src: Path) -> tuple[dict[int, float], str | None]:
    """Every non-base hinge and slide joint's angle in the standing posture: the keyframe ``keyframe`` (None: the
    model's first), else 0 clipped to the joint's range. Returns (joint id → angle, the keyframe's name or None)."""
    joints = [j for j in range(m.njnt) if int(m.jnt_type[j]) in (HINGE, SLIDE)]
    k = keyframe_index(m, keyframe, src)
    if k is None:
        return {j: clip_to_range(m, j, 0.0) for j in joints}, None
    q = m.key_qpos[k]
    name = mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_KEY, k) or f"#{k}"
    return {j: clip_to_range(m, j, float(q[m.jnt_qposadr[j]])) for j in joints}, name


def posture_balls(m: mujoco.MjModel, keyframe: str | None, joints: tuple[int, ...], src: Path
                  ) -> dict[int, NDArray[np.float64]]:
    """The quaternion (4,) of each ball joint of ``joints`` in the posture's keyframe (:func:`keyframe_index`), or
    the model's ``qpos0`` without one."""
    k = keyframe_index(m, keyframe, src)
    q = m.qpos0 if k is None else m.key_qpos[k]
    return {j: np.array(q[m.jnt_qposadr[j]:m.jnt_qposadr[j] + 4], dtype=float) for j in joints
            if int(m.jnt_type[j]) == BALL}


def with_closed_chains(robot: RobotModel) -> RobotModel:
    """``robot`` (edited, returned) with its model's closed chains read (:func:`robustgait.robots.loops.
    closed_chains`) and its posture's passive joints solved from them (:meth:`RobotModel.close`), starting from the
    model's ``qpos0`` clipped to each joint's range (a loaded robot's model has no keyframe); unchanged for a serial
    robot."""
    m = robot.model
    robot.loops, robot.passive = closed_chains(m)
    if not robot.loops:
        return robot
    robot.springs = find_springs(m, robot.passive)
    robot.balls = posture_balls(m, None, robot.passive, robot.path)
    robot.angles = {**{j: clip_to_range(m, j, float(m.qpos0[m.jnt_qposadr[j]])) for j in robot.passive
                       if int(m.jnt_type[j]) != BALL}, **robot.angles}  # a start in range: the model's branch
    robot.opened = robot.loop_residuals()
    robot.close()
    return robot


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
    loops, passive = closed_chains(m)
    for j in range(m.njnt):
        if j != m.body_jntadr[base] and int(m.jnt_type[j]) not in (HINGE, SLIDE) and j not in passive:
            raise input_error(src, f"joint '{mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_JOINT, j)}' is a "
                              f"{JOINT_TYPES[int(m.jnt_type[j])]} joint outside any closed chain: robustgait plans "
                              "and holds hinge and slide joints only (a ball joint is solved only inside a loop "
                              "that an equality constraint closes)")
    angles, key = posture_angles(m, keyframe, src)
    balls = posture_balls(m, keyframe, passive, src)
    robot = RobotModel(src, kind, mjs, m, base, key, angles, balls, loops, passive, find_springs(m, passive))
    free = undriven_motion(m, robot.qpos(), loops, robot.solved)
    if free is not None:
        loop = next(lp for lp in loops if free in lp.joints)
        raise input_error(src, f"{loop.describe()} leaves joint '{robot.joint_name(free)}' free to move with every "
                          "other joint fixed: no actuator of the model drives a joint that fixes it (add one, or "
                          "remove the equality)")
    robot.opened = robot.loop_residuals()
    robot.close()
    return robot


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
