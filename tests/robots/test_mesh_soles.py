"""Mesh soles: MuJoCo collides a mesh through its convex hull, so a mesh foot stands on the hull's vertices at its
bottom (its tread), which the loader's virtual sole box and ``robot init`` span (``docs/robots.md``, "Soles, floor,
URDF"). Feet of inline meshes in the shapes real feet have, on the 20 kg biped of
``tests/inspection/biped.py``, its box soles (x −0.07…0.13, y ±0.05, bottom z −0.06 in the foot's frame)
replaced by meshes with that same tread."""

from __future__ import annotations

import itertools
import sys
from pathlib import Path

import mujoco
import numpy as np
import pytest

from robustgait import load_robot
from robustgait.cli import main
from robustgait.config import RobotConfig
from robustgait.errors import RobustGaitError
from robustgait.inspection.check import check_mirror, check_soles
from robustgait.inspection.discover import find_legs
from robustgait.inspection.model import open_model
from robustgait.robotinit.draft import draft_spec
from robustgait.robots.soles import ground_face, hull_vertices, sole_points, sole_rectangle
from tests.inspection.biped import SERVO_RULE, biped_xml, write

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover - exercised on 3.10 only
    import tomli as tomllib

# the tread every foot below stands on, in the foot body's frame [m]
X0, X1, HALF_WIDTH, BOTTOM = -0.07, 0.13, 0.05, -0.06
BOX_SOLE = '<geom name="{s}_sole" type="box" size="0.1 0.05 0.01" pos="0.03 0 -0.05"/>'
MM = 1e-3


def block(x0: float, x1: float, half_width: float, z0: float, z1: float) -> list[tuple[float, float, float]]:
    """The 8 corners of an axis-aligned block."""
    return [(x, y, z) for x in (x0, x1) for y in (-half_width, half_width) for z in (z0, z1)]


def tread(z: float = BOTTOM) -> list[tuple[float, float, float]]:
    """The tread's 4 corners."""
    return [(x, y, z) for x in (X0, X1) for y in (-HALF_WIDTH, HALF_WIDTH)]


# each foot: its meshes (name → vertices in the foot's frame), left/right symmetric so that the mirror holds
SHAPES: dict[str, dict[str, list[tuple[float, float, float]]]] = {
    # a flat tread, its toe rising 8 mm over 2 cm then 2 cm over 4 cm: the toe's vertices are off the sole
    "rising_toe": {"toe": [*tread(), *[(0.15, y, -0.052) for y in (-0.05, 0.05)],
                           *[(0.17, y, -0.04) for y in (-0.05, 0.05)],
                           *[(x, y, -0.02) for x in (X0, 0.17) for y in (-0.05, 0.05)]]},
    # chamfered edges: the bottom face is the tread, the block 1 cm wider all round from 1 cm above it
    "chamfered": {"chamfer": [*tread(), *block(X0 - 0.01, X1 + 0.01, HALF_WIDTH + 0.01, BOTTOM + 0.01, -0.02)]},
    # a heel cup: a rim 2.5 cm above the tread, wider and longer than it around the heel
    "heel_cup": {"cup": [*tread(), *[(X0 - 0.015, y, -0.035) for y in (-0.065, 0.0, 0.065)],
                         *[(-0.03, y, -0.035) for y in (-0.065, 0.065)],
                         *[(x, y, -0.02) for x in (X0, X1) for y in (-0.05, 0.05)]]},
    # a heel block and a toe block on the tread and an arch between them 1 cm above it: the union's tread
    "three_meshes": {"heel": block(X0, 0.0, HALF_WIDTH, BOTTOM, -0.03),
                     "arch": block(0.0, 0.03, HALF_WIDTH, BOTTOM + 0.01, -0.03),
                     "ball": block(0.03, X1, HALF_WIDTH, BOTTOM, -0.03)},
}


def mesh_asset(name: str, vertices: list[tuple[float, float, float]]) -> str:
    return f'<mesh name="{name}" vertex="{" ".join(f"{v:g}" for v in itertools.chain(*vertices))}"/>'


def mesh_biped(meshes: dict[str, list[tuple[float, float, float]]], box: bool = False, named: bool = False) -> str:
    """The biped of ``tests/inspection/biped.py`` with ``meshes`` as each foot's collision geoms (``named``:
    geoms ``{side}_{mesh}``), beside its box sole (``box``) or instead of it."""
    xml = biped_xml(foot="box")
    for s in ("left", "right"):
        names = {n: f' name="{s}_{n}"' if named else "" for n in meshes}
        geoms = "".join(f'<geom{names[n]} type="mesh" mesh="{n}"/>' for n in meshes)
        xml = xml.replace(BOX_SOLE.format(s=s), (BOX_SOLE.format(s=s) if box else "") + geoms)
    assets = "".join(mesh_asset(n, v) for n, v in meshes.items())
    start, end = xml.index("<asset>") + len("<asset>"), xml.index("</asset>")
    return xml[:start] + assets + xml[end:]


def foot_model(meshes: dict[str, list[tuple[float, float, float]]]) -> tuple[mujoco.MjModel, mujoco.MjData]:
    """One foot body of the meshes at the origin, after the kinematics."""
    geoms = "".join(f'<geom type="mesh" mesh="{name}"/>' for name in meshes)
    m = mujoco.MjModel.from_xml_string(f"<mujoco><asset>{''.join(mesh_asset(n, v) for n, v in meshes.items())}"
                                       f'</asset><worldbody><body name="foot">{geoms}</body></worldbody></mujoco>')
    d = mujoco.MjData(m)
    mujoco.mj_kinematics(m, d)
    return m, d


def test_hull_vertices_in_the_geom_frame_are_the_authored_ones() -> None:
    """MuJoCo recentres, rotates and scales a mesh's vertices into its mesh frame and folds that frame into the geom's
    pos/quat: hull_vertices placed by geom_xpos/xmat after mj_forward are the authored vertices (scaled) placed by the
    body's and the geom's pos/euler. A vertex inside the hull is not one of its vertices."""
    from scipy.spatial.transform import Rotation

    corners = np.array(block(0.3, 0.5, 0.05, 0.0, 0.1))
    inner = np.array([[0.4, 0.0, 0.05]])
    scale = np.array([1.0, 2.0, 0.5])
    m = mujoco.MjModel.from_xml_string(
        f'<mujoco><compiler angle="radian"/><asset><mesh name="m" scale="1 2 0.5" vertex="'
        f'{" ".join(f"{v:g}" for v in np.vstack([corners, inner]).ravel())}"/></asset><worldbody>'
        '<body pos="1 2 3" euler="0.1 0.2 0.3"><geom type="mesh" mesh="m" pos="0.01 0.02 0.03" euler="0.4 0.5 0.6"/>'
        "</body></worldbody></mujoco>")
    d = mujoco.MjData(m)
    mujoco.mj_forward(m, d)
    body, geom = (Rotation.from_euler("XYZ", a).as_matrix() for a in ([0.1, 0.2, 0.3], [0.4, 0.5, 0.6]))
    expected = np.array([1.0, 2.0, 3.0]) + (np.array([0.01, 0.02, 0.03]) + (corners * scale) @ geom.T) @ body.T
    got = d.geom_xpos[0] + hull_vertices(m, 0) @ d.geom_xmat[0].reshape(3, 3).T
    assert len(got) == 8
    assert np.abs(np.sort(got, axis=0) - np.sort(expected, axis=0)).max() < 1e-6


def test_a_mesh_meets_the_ground_at_its_tread() -> None:
    """sole_points of a mesh: its hull's vertices within the tolerance of the lowest, here the tread's 4 corners."""
    m, d = foot_model(SHAPES["chamfered"])
    points = sole_points("mesh", d.geom_xpos[0], d.geom_xmat[0].reshape(3, 3), m.geom_size[0],
                         np.array([0.0, 0.0, 1.0]), hull_vertices(m, 0))
    assert points.shape == (4, 3) and np.allclose(points[:, 2], BOTTOM, atol=1e-6)
    with pytest.raises(ValueError, match="hull"):
        sole_points("mesh", np.zeros(3), np.eye(3), np.zeros(3), np.array([0.0, 0.0, 1.0]))


@pytest.mark.parametrize("shape", sorted(SHAPES))
def test_the_loaders_sole_box_is_the_tread(shape: str) -> None:
    """The virtual sole box over a mesh foot spans its tread (0.2 × 0.1 m centred at x 0.03), to 1 mm, whatever
    rises above it (toe, chamfer, heel cup, arch)."""
    m, d = foot_model(SHAPES[shape])
    centre, rot, half, _ = sole_rectangle(m, d, list(range(m.ngeom)), np.array([1.0, 0.0, 0.0]))
    assert np.allclose(rot, np.eye(3), atol=1e-6)
    assert 2 * half[0] == pytest.approx(X1 - X0, abs=MM) and 2 * half[1] == pytest.approx(2 * HALF_WIDTH, abs=MM)
    assert np.allclose(centre[:2], [(X0 + X1) / 2, 0.0], atol=MM)
    assert centre[2] - half[2] == pytest.approx(BOTTOM, abs=MM)


@pytest.mark.parametrize("shape", sorted(SHAPES))
def test_robot_init_finds_the_tread(tmp_path: Path, shape: str) -> None:
    """robot init's discovery (find_legs) finds the same tread on each foot of the biped, and counts the mesh
    vertices on it (4 corners; the three-mesh foot, its geoms named as a foot with a geom off the sole must have
    them: 4 of the heel's and 4 of the ball's, the arch not on the sole)."""
    several = shape == "three_meshes"
    r = open_model(write(tmp_path, mesh_biped(SHAPES[shape], named=several)))
    for side in ("left", "right"):
        sole = find_legs(r, 0.1, 0.005)[side].sole
        assert sole.kind == ("geoms" if several else "body") and r.body_name(sole.body) == f"{side}_foot"
        assert sole.length == pytest.approx(X1 - X0, abs=MM) and sole.width == pytest.approx(2 * HALF_WIDTH, abs=MM)
        counts = {mujoco.mj_id2name(r.model, mujoco.mjtObj.mjOBJ_MESH, int(r.model.geom_dataid[g])): n
                  for g, n in sole.tread}
        expected = {"heel": 4, "ball": 4} if several else {next(iter(SHAPES[shape])): 4}
        assert counts == expected


def test_a_visual_mesh_beside_a_collision_box_is_not_the_sole(tmp_path: Path) -> None:
    """A visual mesh (contype = conaffinity = 0) longer than the box and reaching below it: the box is the sole."""
    xml = mesh_biped({"shoe": block(-0.1, 0.16, 0.07, -0.08, -0.02)}, box=True)
    visual = '<geom type="mesh" mesh="shoe" contype="0" conaffinity="0"/>'
    r = open_model(write(tmp_path, xml.replace('<geom type="mesh" mesh="shoe"/>', visual)))
    assert sum(1 for g in range(r.model.ngeom) if int(r.model.geom_type[g]) == int(mujoco.mjtGeom.mjGEOM_MESH)) == 2
    sole = find_legs(r, 0.1, 0.005).left.sole
    assert sole.kind == "geom" and r.geom_name(sole.geoms[0]) == "left_sole" and sole.tread == ()
    assert (sole.length, sole.width) == (pytest.approx(0.2), pytest.approx(0.1))


def test_init_on_mesh_feet_writes_a_spec_whose_soles_check(tmp_path: Path, capsys: pytest.CaptureFixture[str]
                                                          ) -> None:
    """End to end: robot init on the biped with rising-toe mesh feet writes sole_body with a comment naming the mesh
    and its vertices on the sole; the spec loads with a 0.2 × 0.1 m virtual sole on the tread, and robot check's
    mirror and soles checks pass."""
    model = write(tmp_path, mesh_biped(SHAPES["rising_toe"]))
    spec = tmp_path / "spec.toml"
    assert main(["robot", "init", str(model), "-o", str(spec), *SERVO_RULE]) == 0
    capsys.readouterr()
    text = spec.read_text()
    raw = tomllib.loads(text)
    assert raw["legs"]["left"] == {"sole_body": "left_foot"} and raw["legs"]["right"] == {"sole_body": "right_foot"}
    assert text.count("# mesh sole:") == 2 and "of 'toe' (4 vertices)" in text
    robot = load_robot(spec)
    for side in ("left", "right"):
        g = robot.sole_geom_id[side]
        assert 2 * robot.model.geom_size[g][0] == pytest.approx(X1 - X0, abs=MM)
        assert 2 * robot.model.geom_size[g][1] == pytest.approx(2 * HALF_WIDTH, abs=MM)
    config = RobotConfig()
    for check in (check_mirror(robot, config), check_soles(robot, config.check)):
        assert check.passed, check.line
    # the loader still refuses a sole it cannot bound, in one line naming the geom type
    model.write_text(model.read_text().replace('type="mesh" mesh="toe"', 'type="ellipsoid" size="0.1 0.05 0.02"'))
    with pytest.raises(RobustGaitError, match=r"the left sole .* has an ellipsoid geom: a sole is one box or a set"):
        load_robot(spec)


def test_a_mesh_sole_its_model_tilts_is_levelled(tmp_path: Path) -> None:
    """The chamfered mesh pitched 0.01 rad in its foot's frame (as tests/inspection/biped.py's tilted box):
    robot init turns each ankle pitch by 0.01 rad, as for a box, and the loaded soles are level in the posture."""
    xml = mesh_biped(SHAPES["chamfered"]).replace('mesh="chamfer"/>', 'mesh="chamfer" euler="0 0.01 0"/>')
    assert xml.count('euler="0 0.01 0"') == 2
    model = write(tmp_path, xml)
    d = draft_spec(model, RobotConfig())
    assert d.levelled == pytest.approx(0.01, abs=1e-5) and any("to level them" in n for n in d.notes)
    assert d.legs.left.sole.length == pytest.approx(X1 - X0, abs=MM)
    spec = tmp_path / "spec.toml"
    assert main(["robot", "init", str(model), "-o", str(spec), *SERVO_RULE]) == 0
    soles = check_soles(load_robot(spec), RobotConfig().check)
    assert soles.passed and soles.values["tilt"] < 1e-5


# a narrow humanoid's mesh foot: a ground face 0.034 m wide along the tread's length, with 4 mm chamfers (45°) all round
FACE_HALF_WIDTH, CHAMFER = 0.017, 0.004
NARROW_CHAMFERED = {"narrow": [*[(x, y, BOTTOM) for x in (X0, X1) for y in (-FACE_HALF_WIDTH, FACE_HALF_WIDTH)],
                               *block(X0 - CHAMFER, X1 + CHAMFER, FACE_HALF_WIDTH + CHAMFER, BOTTOM + CHAMFER, -0.02)]}


def test_a_mesh_tread_is_its_ground_face_not_the_chamfers_above_it(tmp_path: Path) -> None:
    """The chamfers' lower edges, 4 mm above the 0.034 m face, are not on the sole however far they lie from the
    lowest vertex (on_sole's band of 2 mm + 1.75 % of that distance took them: 0.042 m): the loader's sole box and
    robot init both measure the face, 0.034 ± 1 mm wide, and the face pitched 0.01 rad in its foot keeps its 4
    corners."""
    m, d = foot_model(NARROW_CHAMFERED)
    _, _, half, _ = sole_rectangle(m, d, [0], np.array([1.0, 0.0, 0.0]))
    assert 2 * half[1] == pytest.approx(2 * FACE_HALF_WIDTH, abs=MM) and 2 * half[0] == pytest.approx(X1 - X0, abs=MM)
    verts = d.geom_xpos[0] + hull_vertices(m, 0) @ d.geom_xmat[0].reshape(3, 3).T
    pitch = np.array([[np.cos(0.01), 0.0, np.sin(0.01)], [0.0, 1.0, 0.0], [-np.sin(0.01), 0.0, np.cos(0.01)]])
    for rot in (np.eye(3), pitch):
        assert ground_face(verts @ rot.T, np.array([0.0, 0.0, 1.0])).sum() == 4
    r = open_model(write(tmp_path, mesh_biped(NARROW_CHAMFERED)))
    for side in ("left", "right"):
        sole = find_legs(r, 0.1, 0.005)[side].sole
        assert sole.width == pytest.approx(2 * FACE_HALF_WIDTH, abs=MM)
        assert sole.length == pytest.approx(X1 - X0, abs=MM)
