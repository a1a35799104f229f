"""A robot's soles and floor in its parsed MJCF (``docs/robots.md``, "Soles and floor").

The pipeline places a foot by its *sole box*: a box geom whose bottom face is the sole (the gait generator's foot
frames, the centre-of-pressure bounds, the touchdown guard's flatness). A spec names the sole as one box geom, a set
of geoms of one body, or a body (optionally one default class of its geoms). When that is not a single box — the
sphere, capsule or cylinder feet of some Menagerie robots, an unnamed box — :func:`resolve_sole` adds a *virtual
sole*: a box geom ``robustgait_{side}_sole`` on the foot body that takes part in no contact and has no mass,
spanning the rectangle of the points where the geoms meet the ground (:func:`sole_points`; its bottom face at the
lowest). Contacts stay the real geoms'; the contact sensor of that sole then counts the foot body's contacts. A mesh
sole (the mesh-only feet of some Menagerie robots) is one such set: MuJoCo collides a mesh through its convex hull,
so it stands on the hull's vertices at the bottom of the foot (its tread), not on its bounding box.

:func:`resolve_floor` finds the world's plane (naming it if unnamed) or adds one (``add_floor``).

A geom takes part in contacts as MuJoCo reads the model (:func:`collides`): by its contype/conaffinity, or because an
explicit ``<contact><pair>`` names it. A model whose contacts are all pairs (contype = conaffinity = 0 everywhere)
stands on the foot geoms paired with its floor; its pairs stay as they are and keep their own contact parameters.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import NamedTuple

import mujoco
import numpy as np
from numpy.typing import NDArray

from robustgait.errors import input_error
from robustgait.robots.spec import ADDED_FLOOR, SIDES, LegSpec, RobotSpec
from robustgait.rotations import quat_to_mat

FloatArray = NDArray[np.float64]
# MuJoCo's geom types by their names in messages and specs ("box", "mesh", …): the one table of them
GEOM_TYPES = {int(v): k.removeprefix("mjGEOM_").lower() for k, v in mujoco.mjtGeom.__members__.items()
              if k.startswith("mjGEOM_")}
# the types a sole may be made of
SOLE_TYPES = {t: name for t, name in GEOM_TYPES.items()
              if name in ("box", "sphere", "capsule", "cylinder", "mesh")}
# points on the rim of a cylinder standing on its end: its bottom disk as a polygon (its bounding rectangle is the
# disk's to within 1 − cos(π/8) ≈ 8 % of the radius when the foot's axes are at 22.5° to the disk's)
RIM_POINTS = 8
# half width of a line foot's sole box [m] (one capsule along the foot: no support width; MuJoCo's box needs a size)
LINE_HALF_WIDTH = 1e-4
# thickness of a virtual sole box [m]: only its bottom face matters (it takes part in no contact)
VIRTUAL_SOLE_THICKNESS = 0.002
# points within this height of a foot's lowest point are on its sole [m] (a box's bottom face, sphere bottoms
# at one height); higher points (a heel sphere raised by 1 cm) do not widen the sole
SOLE_PLANE_TOLERANCE = 0.002
# ... plus this slope times their horizontal distance from it: a sole a model tilts by up to atan(slope) ≈ 1° in its
# foot's frame (a foot plate's geoms rotated 90.5° rather than 90°) spans its whole length
SOLE_TILT_SLOPE = 0.0175
# a mesh's tread: its hull's vertices within this distance [m] of the plane of its ground face (:func:`ground_face`).
# A flat face's vertices lie on it to float32 precision (MuJoCo stores mesh vertices so: ~1e-8 m), and a chamfer's or
# a rounded edge's a few millimetres above it (a 4 mm chamfer widened a 0.034 m face to 0.042 m under on_sole's band)
MESH_FACE_TOLERANCE = 0.001
# a tread whose contact polygon covers less than this share of the rectangle around it is no flat sole: the planner
# keeps a flat sole's centre of pressure inside that rectangle, where a triangle (a heel point and a toe bar: 0.5) has
# no contact at the heel's corners, so it is planned as a line foot on its longest chord (:func:`line_chord`); a disk
# (π/4 ≈ 0.79, its 8 rim points 0.71–0.83) or a trapezoid whose heel is a quarter as wide (0.63) is a flat sole
MIN_TREAD_FILL = 0.6


def article(noun: str) -> str:
    """"an" before a vowel, else "a" (geom type names in messages)."""
    return "an" if noun[:1] in "aeiou" else "a"


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


def one_box(model: mujoco.MjModel, geoms: Sequence[int]) -> bool:
    """Whether the sole geoms ``geoms`` of ``model`` are one box: that box is the sole itself, read by its own faces
    and sizes (:func:`robustgait.robots.solebox.sole_box`), not a virtual sole spanning ground points."""
    return len(geoms) == 1 and GEOM_TYPES[int(model.geom_type[geoms[0]])] == "box"


def collides(model: mujoco.MjModel, g: int) -> bool:
    """Whether geom ``g`` of ``model`` takes part in contacts, as MuJoCo reads the model: its contype or conaffinity
    is not 0 (MuJoCo's filter may pair it with another geom), or an explicit contact pair (``<contact><pair>``) names
    it — pairs bypass the filter, so a model whose geoms all have contype = conaffinity = 0 (Apptronik Apollo's) may
    touch its floor through pairs alone. Whether it may touch one given geom: :func:`can_touch`; the same rule on a
    parsed spec: :func:`spec_collides`."""
    paired = bool(np.any(model.pair_geom1 == g) or np.any(model.pair_geom2 == g))
    return paired or bool(model.geom_contype[g] or model.geom_conaffinity[g])


def can_touch(model: mujoco.MjModel, g1: int, g2: int) -> bool:
    """Whether MuJoCo may make contacts between geoms ``g1`` and ``g2`` of ``model``: an explicit pair names the two,
    or its filter lets them (the contype of one shares a bit with the conaffinity of the other). The filter's other
    exclusions (geoms of one body or of a parent and child, ``<exclude>``) are not read: the callers ask about a
    robot's geom and the world's floor."""
    for a, b in zip(model.pair_geom1, model.pair_geom2, strict=True):
        if {int(a), int(b)} == {g1, g2}:
            return True
    return bool((model.geom_contype[g1] & model.geom_conaffinity[g2])
                or (model.geom_contype[g2] & model.geom_conaffinity[g1]))


def paired_names(mjs: mujoco.MjSpec) -> frozenset[str]:
    """The names of the geoms the explicit contact pairs of the parsed ``mjs`` name (a pair names its geoms)."""
    return frozenset(name for p in mjs.pairs for name in (p.geomname1, p.geomname2))


def spec_collides(g: mujoco.MjsGeom, paired: frozenset[str]) -> bool:
    """:func:`collides` read on a parsed spec's geom ``g``: its contype or conaffinity, or its name among ``paired``
    (:func:`paired_names` of its spec) — for edits made before compiling (a compiled model's ids are not a spec's)."""
    return bool(g.contype or g.conaffinity) or (bool(g.name) and g.name in paired)


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
        specs = [g for g in mjs.geoms if g.parent.name == leg.sole_body and collides(model, int(g.id))
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
            kind = GEOM_TYPES[int(model.geom_type[g])]
            raise input_error(src, f"the {side} sole ({leg.describe()}) has {article(kind)} {kind} geom: a sole is "
                              "one box or a set of boxes, spheres, capsules, cylinders or meshes (name those)")
    return ids


def on_sole(points: FloatArray, up: FloatArray) -> NDArray[np.bool_]:
    """Which of a foot's ground points (k, 3) lie on its sole, (k,) booleans: those within
    :data:`SOLE_PLANE_TOLERANCE` + :data:`SOLE_TILT_SLOPE` × their horizontal distance [m] of the lowest along ``up``
    (3,), a unit vector). The one rule for every shape: a box's bottom corners, sphere bottoms at one height, a
    mesh's tread vertices are on it; a heel sphere raised by 1 cm, a toe that rises off the tread are not. Empty
    ``points``: an empty mask."""
    points, up = np.asarray(points, dtype=float), np.asarray(up, dtype=float)
    if len(points) == 0:
        return np.zeros(0, dtype=bool)
    height = points @ up
    lowest = int(np.argmin(height))
    flat = points - np.outer(height, up)  # the points projected on the plane normal to up
    reach = np.linalg.norm(flat - flat[lowest], axis=1)
    return np.asarray(height <= height[lowest] + SOLE_PLANE_TOLERANCE + SOLE_TILT_SLOPE * reach)


def ground_face(points: FloatArray, up: FloatArray) -> NDArray[np.bool_]:
    """Which of a mesh's convex-hull vertices (k, 3) lie on its ground face, (k,) booleans: those within
    :data:`MESH_FACE_TOLERANCE` [m] of the plane of the face it rests on with ``up`` (3,), a unit vector) up.

    That plane is the hull's facet whose outward normal is closest to −``up`` (a face the model tilts within its foot
    by a degree is still that facet), then fitted by least squares through the vertices within the tolerance of it
    (a face triangulated with sub-millimetre noise). So a chamfer's or a rounded edge's vertices a few millimetres
    above the face are not on the sole, however far they lie from the lowest vertex — :func:`on_sole`'s band widens
    by 1.75 % of that distance, which took a 4 mm chamfer into a 0.034 m face. Points that span no volume (a flat
    mesh, fewer than 4 points): the band of :data:`MESH_FACE_TOLERANCE` above the lowest along ``up``."""
    from scipy.spatial import ConvexHull, QhullError

    points, up = np.asarray(points, dtype=float), np.asarray(up, dtype=float)
    height = points @ up
    if len(points) < 4:
        return np.asarray(height <= height.min() + MESH_FACE_TOLERANCE)
    try:
        facets = ConvexHull(points).equations  # rows (n, d): n · x + d ≤ 0 inside, n the outward unit normal
    except QhullError:  # coplanar or collinear: the mesh is its own face
        return np.asarray(height <= height.min() + MESH_FACE_TOLERANCE)
    lowest = facets[int(np.argmax(facets[:, :3] @ -up))]
    on = np.abs(points @ lowest[:3] + lowest[3]) <= MESH_FACE_TOLERANCE  # the facet's own vertices at least
    centre = points[on].mean(axis=0)
    normal = np.linalg.svd(points[on] - centre)[2][-1]  # the direction the face's vertices spread least along
    return np.asarray(np.abs((points - centre) @ normal) <= MESH_FACE_TOLERANCE)


def hull_vertices(model: mujoco.MjModel, g: int) -> FloatArray:
    """The vertices (n, 3) of mesh geom ``g``'s convex hull, in the geom's frame [m] (MuJoCo stores a mesh's vertices
    in its compiled mesh frame, recentred and scaled, and folds that frame's offset into geom_pos/geom_quat).

    MuJoCo collides a mesh through its convex hull, whose vertices are mesh vertices: its graph (mesh_graph: vertex
    and face counts, each vertex's edge address, then each vertex's index among the mesh's) names them; a hull
    limited by ``maxhullvert`` has fewer. A mesh without a graph (MuJoCo built none) gives all its vertices, which
    serve as well: the lowest plane supports the mesh and its hull alike, and the mesh vertices within a tolerance of
    it are the hull's plus vertices inside the hull within that same band, which add nothing the band does not."""
    mesh = int(model.geom_dataid[g])
    adr, count = int(model.mesh_vertadr[mesh]), int(model.mesh_vertnum[mesh])
    verts = np.asarray(model.mesh_vert[adr:adr + count], dtype=float)
    graph = int(model.mesh_graphadr[mesh])
    if graph < 0:
        return verts
    numvert = int(model.mesh_graph[graph])
    ids = model.mesh_graph[graph + 2 + numvert: graph + 2 + 2 * numvert]
    return np.asarray(verts[ids])


def sole_points(kind: str, pos: FloatArray, rot: FloatArray, size: FloatArray, up: FloatArray,
                vertices: FloatArray | None = None) -> FloatArray:
    """Where a sole geom meets a ground plane of normal ``up`` (3,) when it rests on it, (k, 3), in the frame of
    ``pos`` (3,), ``rot`` (3, 3; columns: the geom's axes) and ``up``; ``kind`` a :data:`SOLE_TYPES` name, ``size``
    MuJoCo's geom size [m]. A box: the four corners of its face that looks down; a sphere: its bottom; a capsule:
    the bottoms of its two end spheres; a cylinder lying on its side: the two ends of its lowest line; a cylinder
    standing on an end: :data:`RIM_POINTS` points of that end's rim (tilted: the lowest point of each end's rim); a
    mesh: its convex hull's ``vertices`` (n, 3, in the geom's frame: :func:`hull_vertices`) on its ground face
    (:func:`ground_face`), its tread. A mesh without ``vertices`` is a ValueError."""
    pos, rot, size, up = (np.asarray(a, dtype=float) for a in (pos, rot, size, up))
    if kind == "mesh":
        if vertices is None:
            raise ValueError("sole_points: a mesh's points need its hull's vertices")
        points = pos + np.asarray(vertices, dtype=float) @ rot.T
        return np.asarray(points[ground_face(points, up)])
    if kind == "box":
        axis = int(np.argmax(np.abs(up @ rot)))  # the box axis closest to up: its bottom face's normal
        others = [k for k in range(3) if k != axis]
        local = np.zeros((4, 3))
        local[:, axis] = -np.sign(up @ rot[:, axis]) * size[axis]
        local[:, others] = np.array([[i, j] for i in (-1.0, 1.0) for j in (-1.0, 1.0)]) * size[others]
        return np.asarray(pos + local @ rot.T)
    if kind == "sphere":
        return np.asarray(pos - size[0] * up)[None]
    ends = np.stack([pos - size[1] * rot[:, 2], pos + size[1] * rot[:, 2]])  # along the geom's z axis
    if kind == "capsule":
        return np.asarray(ends - size[0] * up)
    down = -up - float(-up @ rot[:, 2]) * rot[:, 2]  # −up within the end disks' plane
    norm = float(np.linalg.norm(down))
    if norm > 1e-6:
        return np.asarray(ends + size[0] * down / norm)
    theta = 2.0 * np.pi * np.arange(RIM_POINTS) / RIM_POINTS
    rim = size[0] * (np.cos(theta)[:, None] * rot[:, 0] + np.sin(theta)[:, None] * rot[:, 1])
    low = ends[int(np.argmin(ends @ up))]
    return np.asarray(low + rim)


def geom_sole_points(model: mujoco.MjModel, g: int, pos: FloatArray, rot: FloatArray, up: FloatArray) -> FloatArray:
    """:func:`sole_points` of sole geom ``g`` of ``model`` placed at ``pos`` (3,) with axes ``rot`` (3, 3) — its
    body-frame placement, or its world placement after the kinematics — for a ground normal ``up`` (3,) in that
    frame; a mesh's hull vertices read from the model (:func:`hull_vertices`)."""
    kind = SOLE_TYPES[int(model.geom_type[g])]
    vertices = hull_vertices(model, g) if kind == "mesh" else None
    return sole_points(kind, pos, rot, model.geom_size[g], up, vertices)


def foot_up(rot: FloatArray) -> FloatArray:
    """The unit axis (3,) of a body with axes ``rot`` (3, 3, columns, in the world) closest to the world's vertical
    and pointing up, in the body's frame: the up a foot's sole is read along, so that a foot the posture tilts keeps
    its whole tread (the world's vertical would keep only the edge it tilts down to)."""
    rot = np.asarray(rot, dtype=float)
    k = int(np.argmax(np.abs(rot[2])))
    return np.asarray(np.eye(3)[k] * np.sign(rot[2, k]))


def tread_spread(points: FloatArray, up: FloatArray) -> float:
    """How much area the ground points (k, 3) on the sole along ``up`` (3,) span: the determinant of their
    covariance in the plane normal to ``up`` (0 for a line or a point; rotation-invariant in that plane)."""
    pts = np.asarray(points, dtype=float)
    on = pts[on_sole(pts, up)]
    if len(on) < 3:
        return 0.0
    e1 = np.cross(up, np.eye(3)[int(np.argmin(np.abs(up)))])
    e1 /= float(np.linalg.norm(e1))
    flat = np.column_stack([on @ e1, on @ np.cross(up, e1)])
    return float(np.linalg.det(np.atleast_2d(np.cov(flat.T))))


def sole_up(points_along: Callable[[FloatArray], FloatArray], body_up: FloatArray, vertical: FloatArray
            ) -> FloatArray:
    """The up a foot's sole is read along (3,): the foot body's axis closest to the vertical (``body_up``, so that a
    foot the posture tilts keeps its whole tread), or the ``vertical`` itself where the ground points on the sole
    along it span clearly more area (:func:`tread_spread`, by over 1 %): a foot body whose frame is tilted from its
    sole would keep only its heel along its own axis (docs/robots.md, "Soles, floor, URDF"). ``points_along(up)``:
    the foot's ground points (k, 3) read along ``up`` (:func:`geom_sole_points` of its geoms), in the frame of both
    vectors."""
    body_up, vertical = np.asarray(body_up, dtype=float), np.asarray(vertical, dtype=float)
    if np.allclose(body_up, vertical):
        return line_up(points_along, body_up)
    along_body = tread_spread(points_along(body_up), body_up)
    if along_body == 0.0 and tread_spread(points_along(vertical), vertical) == 0.0:
        return line_up(points_along, body_up)
    return vertical if tread_spread(points_along(vertical), vertical) > 1.01 * along_body else body_up


def tread_length(points: FloatArray, up: FloatArray) -> float:
    """The largest distance [m] between two of the ground points (k, 3) on the sole along ``up`` (:func:`on_sole`)."""
    on = np.asarray(points, dtype=float)[on_sole(points, up)]
    if len(on) < 2:
        return 0.0
    return float(np.max(np.linalg.norm(on[:, None, :] - on[None, :, :], axis=-1)))


def line_up(points_along: Callable[[FloatArray], FloatArray], body_up: FloatArray) -> FloatArray:
    """The up (3,) of a sole that spans no area (a capsule, a row of spheres: a line foot): ``body_up`` turned
    perpendicular to the line of its ground points u' = (u − (u·d) d) / ‖·‖ (d the unit direction between the two
    farthest points read along u), so that the whole line lies on the sole — a capsule is round about its axis, and
    along a foot axis tilted from its sole only one end of it is on the sole. ``body_up`` itself when the points
    are on a line along it already, or are not on one (turned, other points reach the sole: a heel raised above a
    toe line)."""
    pts = np.asarray(points_along(body_up), dtype=float)
    if len(pts) < 2:
        return body_up
    dist = np.linalg.norm(pts[:, None, :] - pts[None, :, :], axis=-1)
    i, k = np.unravel_index(int(np.argmax(dist)), dist.shape)
    if dist[i, k] <= 0.0:
        return body_up
    d = (pts[k] - pts[i]) / dist[i, k]
    up = body_up - float(body_up @ d) * d
    norm = float(np.linalg.norm(up))
    if norm < 1e-6:
        return body_up
    up = up / norm
    turned = points_along(up)
    if tread_spread(turned, up) > 0.0:  # turned, other points reach the sole (a raised heel): not a line foot
        return body_up
    return up if tread_length(turned, up) > 1.01 * tread_length(pts, body_up) else body_up


def sole_slopes(along: FloatArray, across: FloatArray, height: FloatArray) -> tuple[float, float]:
    """The sole's plane through its ground points: the least-squares slopes (a, b) of height = c + a·along + b·across
    (points (k,) in a frame whose third axis is up, [m]); a direction the points do not span (a line of points, one
    point) gets slope 0."""
    slopes = [0.0, 0.0]
    axes = (along, across)
    spanned = [i for i in (0, 1) if float(np.ptp(axes[i])) > 1e-6]
    if spanned:
        fit = np.column_stack([np.ones_like(height), *(axes[i] - axes[i].mean() for i in spanned)])
        coef = np.linalg.lstsq(fit, height, rcond=None)[0]
        for i, c in zip(spanned, coef[1:], strict=True):
            slopes[i] = float(c)
    return slopes[0], slopes[1]


def along_line(points: FloatArray, up: FloatArray, forward: FloatArray) -> FloatArray:
    """The toe direction (3,) of a sole: for ground points (k, 3) that lie on one line across ``up`` (a line foot, no
    area: :func:`tread_spread` 0), the line's unit direction perpendicular to ``up``, pointing the way of ``forward``;
    ``forward`` (3,) itself otherwise."""
    if len(points) < 2 or tread_spread(points, up) > 0.0:
        return forward
    dist = np.linalg.norm(points[:, None, :] - points[None, :, :], axis=-1)
    i, k = np.unravel_index(int(np.argmax(dist)), dist.shape)
    d = points[k] - points[i]
    d = d - float(d @ up) * up
    norm = float(np.linalg.norm(d))
    if norm < 1e-6:
        return forward
    d = d / norm
    return d if float(d @ forward) >= 0.0 else -d


class SoleRectangle(NamedTuple):
    """A foot's sole as a box in the foot body's frame (:func:`sole_rectangle`): ``centre`` (3,), ``rot`` (3, 3)
    whose columns are the box's x (toe), y (left) and z (up) axes, ``half`` sizes (3,) [m], and the ``tread``: the
    ground points on the sole (k, 2), (toe, left) [m]."""

    centre: FloatArray
    rot: FloatArray
    half: FloatArray
    tread: FloatArray


def tread_fill(points: FloatArray) -> float:
    """The share of the rectangle around planar points (k, 2) [m] that their convex hull covers, in [0, 1]: 1 for a
    rectangle's corners, 0.5 for a triangle; 0 when they span no area."""
    from scipy.spatial import ConvexHull, QhullError

    pts = np.asarray(points, dtype=float)
    box = float(np.prod(np.ptp(pts, axis=0))) if len(pts) else 0.0
    if box <= 0.0 or len(pts) < 3:
        return 0.0
    try:
        return min(1.0, float(ConvexHull(pts).volume) / box)  # a 2-D hull's volume is its area
    except QhullError:  # collinear points
        return 0.0


class Chord(NamedTuple):
    """A segment along the toe axis in a sole's (toe, left) plane [m]: from ``start`` to ``end`` along the toe axis,
    at ``across`` to the left."""

    start: float
    end: float
    across: float

    @property
    def length(self) -> float:
        return self.end - self.start


def line_chord(points: FloatArray, samples: int = 201) -> Chord:
    """The line a tread (its ground points (k, 2), (toe, left) [m]) is planned as a line foot on: the longest chord
    of its convex hull along the toe axis, at the lateral offset y* = argmax_y L(y), L(y) the length of the hull's
    section {(x, y)} (``samples`` offsets across its width; of equally long ones, the nearest the middle). It lies
    inside the contact polygon over its whole length, so a centre of pressure on it is one the foot supports: for
    Unitree H1's heel point and toe bar (a triangle), the line from the heel to the toe bar's middle. Points that
    span no area (a capsule along the foot) give their own extent along the toe axis."""
    from scipy.spatial import ConvexHull, QhullError

    pts = np.asarray(points, dtype=float)
    mid = float(pts[:, 1].min() + pts[:, 1].max()) / 2.0
    try:
        hull = ConvexHull(pts)
    except QhullError:  # collinear points: the line itself
        return Chord(float(pts[:, 0].min()), float(pts[:, 0].max()), mid)
    a, b, c = hull.equations[:, 0], hull.equations[:, 1], hull.equations[:, 2]  # a x + b y + c <= 0 inside
    best = Chord(0.0, 0.0, mid)
    offsets = np.linspace(pts[:, 1].min(), pts[:, 1].max(), samples)
    for y in sorted(offsets, key=lambda v: abs(v - mid)):  # the middle first: it keeps ties
        rhs = -(b * y + c)
        lo = max((float(r / q) for q, r in zip(a, rhs, strict=True) if q < -1e-12), default=-np.inf)
        hi = min((float(r / q) for q, r in zip(a, rhs, strict=True) if q > 1e-12), default=np.inf)
        if np.all(rhs[np.abs(a) <= 1e-12] >= -1e-12) and hi - lo > best.length + 1e-9:
            best = Chord(lo, hi, float(y))
    return best


def tread_problem(side: str, what: str, points: FloatArray) -> str | None:
    """The one-line refusal of a sole whose tread (its ground points (k, 2) [m]) covers less than
    :data:`MIN_TREAD_FILL` of the rectangle around it (:func:`tread_fill`), naming the sole (``what``) and what to
    change; None when it is a sole robustgait can bound."""
    fill = tread_fill(points)
    if fill <= 0.0 or fill >= MIN_TREAD_FILL:
        return None
    size = np.ptp(np.asarray(points, dtype=float), axis=0)
    return (f"the {side} sole ({what}) is not a rectangle: its contact polygon covers {100 * fill:.0f} % of the "
            f"{size[0]:.3g} × {size[1]:.3g} m rectangle around it (a triangle of a heel point and a toe bar covers "
            f"50 %), and robustgait keeps the centre of pressure inside that rectangle: add a box geom under the foot "
            f"spanning its tread, or a sphere at each of its four corners, and name it as the sole "
            f"(legs.{side}.sole_geom); or plan it as a line foot on its longest chord along the foot "
            f"(legs.{side}.foot = \"line\")")


def sole_rectangle(model: mujoco.MjModel, data: mujoco.MjData, geoms: list[int], forward: FloatArray,
                   line: bool = False) -> SoleRectangle:
    """The sole of a foot's geoms as a box in the foot body's frame (:class:`SoleRectangle`), at the posture of
    ``data``.

    Up is the body axis closest to the world's vertical (:func:`foot_up`) and toe the remaining body axis closest
    to ``forward`` (the base's x axis in the world), so the box is aligned with the foot. The sole's points are the
    geoms' ground points (:func:`geom_sole_points`) that are on the sole (:func:`on_sole`) across the geoms; when
    their plane (:func:`sole_slopes`) is tilted from the body's axes (a foot plate's geoms rotated 90.5°), the box is
    turned onto it, so that the box lies flat where the geoms do. The rectangle spans the points; the box is
    :data:`VIRTUAL_SOLE_THICKNESS` thick above the lowest. ``line``: a line foot's sole, its toe axis along the line
    (:func:`along_line`).
    """
    body = int(model.geom_bodyid[geoms[0]])
    rb = data.xmat[body].reshape(3, 3)  # body axes in the world (columns)

    def points_along(up: FloatArray) -> FloatArray:  # the geoms' ground points in the body's frame
        return np.concatenate([geom_sole_points(model, g, model.geom_pos[g], quat_to_mat(model.geom_quat[g]), up)
                               for g in geoms])

    up = sole_up(points_along, foot_up(rb), rb.T @ np.array([0.0, 0.0, 1.0]))
    up_k = int(np.argmax(np.abs(up)))
    if np.allclose(np.abs(up), np.eye(3)[up_k]):  # a body axis: the box's axes are the body's
        rest = [k for k in range(3) if k != up_k]
        fwd_k = max(rest, key=lambda k: abs(float(rb[:, k] @ forward)))
        fwd = np.eye(3)[fwd_k] * (1.0 if float(rb[:, fwd_k] @ forward) >= 0 else -1.0)
    else:  # the vertical: forward within the plane normal to it
        fwd = rb.T @ forward - float((rb.T @ forward) @ up) * up
        fwd /= float(np.linalg.norm(fwd))
    points = points_along(up)
    on = on_sole(points, up)
    if line:
        fwd = along_line(points[on], up, fwd)
    left = np.cross(up, fwd)
    height = points @ up
    bottom = float(height[on].min())
    a, b = sole_slopes(points[on] @ fwd, points[on] @ left, height[on])
    if max(abs(a), abs(b)) > 1e-9:  # the plane's normal (−a, −b, 1) in (toe, left, up): the box's axes turned onto it
        up = (up - a * fwd - b * left) / float(np.sqrt(1.0 + a * a + b * b))
        fwd = fwd - float(fwd @ up) * up
        fwd /= float(np.linalg.norm(fwd))
        left = np.cross(up, fwd)
        bottom = float((points[on] @ up).min())
    along, across = points[on] @ fwd, points[on] @ left
    half = np.array([(along.max() - along.min()) / 2, (across.max() - across.min()) / 2,
                     VIRTUAL_SOLE_THICKNESS / 2])
    centre = ((along.max() + along.min()) / 2 * fwd + (across.max() + across.min()) / 2 * left
              + (bottom + half[2]) * up)
    return SoleRectangle(centre, np.column_stack([fwd, left, up]), half, np.column_stack([along, across]))


def loader_rectangle(model: mujoco.MjModel, geoms: Sequence[int], base: int, line: bool = False) -> SoleRectangle:
    """The rectangle a foot's virtual sole box is built on (:func:`resolve_sole`): :func:`sole_rectangle` of its
    ``geoms`` in ``model``'s zero posture (qpos0), toe the way of body ``base``'s x axis there; ``line``: a line
    foot's. ``robot init`` reads a sole of several geoms through it (:func:`robustgait.inspection.discover.find_sole`),
    so the sole size it scales a spec's values with is the size of the sole the spec loads with."""
    data = mujoco.MjData(model)
    mujoco.mj_kinematics(model, data)
    return sole_rectangle(model, data, list(geoms), data.xmat[base].reshape(3, 3)[:, 0], line)


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
    if one_box(model, ids):
        if not name:  # an unnamed box (named by its body): our sensors need a name
            name = virtual_sole_name(side)
            geoms[ids[0]].name = name
        return ResolvedSole(name, (mujoco.mjtObj.mjOBJ_GEOM, name), tuple(ids), virtual=False)
    base = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, spec.base_body)
    line = spec.feet.get(side) == "line"
    centre, rot, half, tread = loader_rectangle(model, ids, base, line)
    if line and half[0] > LINE_HALF_WIDTH and half[1] <= LINE_HALF_WIDTH:  # a line foot: its box as wide as nothing
        half[1] = LINE_HALF_WIDTH
    elif min(half[0], half[1]) <= LINE_HALF_WIDTH:
        raise input_error(src, f"the {side} sole ({leg.describe()}) spans no area ({2 * half[0]:.3g} × "
                          f"{2 * half[1]:.3g} m): name geoms that cover the foot's support"
                          + ("" if line else ", or say that it is a line foot (foot = \"line\")"))
    elif line:  # a tread with an area planned as a line foot: its box on the longest chord inside it
        chord = line_chord(tread)
        shift = np.array([(chord.start + chord.end) / 2 - (tread[:, 0].min() + tread[:, 0].max()) / 2,
                          chord.across - (tread[:, 1].min() + tread[:, 1].max()) / 2, 0.0])
        centre = centre + rot @ shift
        half[0], half[1] = chord.length / 2, LINE_HALF_WIDTH
    if not line and (problem := tread_problem(side, leg.describe(), tread)) is not None:
        raise input_error(src, problem)
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
    :data:`ADDED_FLOOR` added to the world body, colliding with the soles' geoms (their contype/conaffinity bits; soles
    that touch only through ``<pair>`` elements are an input error: no pair names the added plane); or the world
    body's only plane, named :data:`ADDED_FLOOR` if unnamed. ``soles``: the real sole geoms."""
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
        if soles and not contype | conaffinity:  # no pair can name a floor the MJCF does not have
            raise input_error(src, "add_floor: the soles' geoms touch only what a <pair> names (contype = conaffinity "
                              "= 0): add the floor plane and its pairs with the soles to the MJCF")
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
