"""Discovery of legs, soles, floor and torque limits (robustgait.inspection.discover, robustgait.robots.soles) on
synthetic bipeds written here (tests/inspection/biped.py)."""

from __future__ import annotations

import sys
from pathlib import Path

import mujoco
import numpy as np
import pytest

from robustgait import load_robot
from robustgait.cli import main
from robustgait.config import RobotConfig
from robustgait.inspection.check import run_checks
from robustgait.inspection.discover import find_legs, torque_limits
from robustgait.inspection.model import open_model
from robustgait.robotinit.draft import draft_spec
from robustgait.robots.soles import sole_points

if sys.version_info >= (3, 11):
    pass
else:  # pragma: no cover - exercised on 3.10 only
    pass
from tests.inspection.biped import LEFT_LEG, SERVO_RULE, biped_xml, write


# ----------------------------------------------------------------------------------------------- discovery
def test_the_biped_is_discovered(tmp_path: Path) -> None:
    r = open_model(write(tmp_path, biped_xml()))
    legs = find_legs(r, 0.1, 0.005)
    assert [r.joint_name(j) for j in legs.left.joints] == LEFT_LEG
    assert [r.joint_name(j) for j in legs.right.joints] == [n.replace("left", "right") for n in LEFT_LEG]
    assert r.body_name(legs.branch) == "waist" and r.keyframe == "stand"
    sole = legs.left.sole
    assert sole.kind == "geom" and r.geom_name(sole.geoms[0]) == "left_sole"
    assert sole.length == pytest.approx(0.2) and sole.width == pytest.approx(0.1)
    # crouched keyframe: the base stands lower than with straight legs (0.05 + 0.05 + 0.6 + 0.06 = 0.76 m)
    assert legs.leg_length == pytest.approx(0.66) and 0.6 < legs.standing_height < 0.76
    assert legs.hip_spacing == pytest.approx(0.18)


def test_torque_limits_say_where_they_came_from(tmp_path: Path) -> None:
    r = open_model(write(tmp_path, biped_xml()))
    t = {r.joint_name(j): v for j, v in torque_limits(r).items()}
    assert (t["left_knee"].value, t["left_knee"].source) == (100.0, "its actuatorfrcrange")
    assert t["left_shoulder"].value == 20.0 and "ctrlrange" in t["left_shoulder"].source
    assert t["left_elbow"].value == 20.0 and "gear" in t["left_elbow"].source  # 10 × gear 2
    assert t["waist_yaw"].value == 30.0 and "forcerange" in t["waist_yaw"].source


@pytest.mark.parametrize(("foot", "kind", "count", "sole_class", "length", "width"), [
    ("spheres", "body", 4, None, 0.18, 0.08), ("capsules", "body", 2, None, 0.18, 0.08),
    ("cylinders", "body", 2, None, 0.18, 0.08), ("puck", "body", 1, None, 0.1, 0.1),
    ("unnamed_box", "body", 1, None, 0.2, 0.1), ("box_and_cylinder", "body", 1, "foot", 0.2, 0.1),
    ("mesh", "body", 1, None, 0.2, 0.1)])
def test_soles_of_sets_and_unnamed_geoms_load_as_virtual_soles(tmp_path: Path, foot: str, kind: str, count: int,
                                                               sole_class: str | None, length: float,
                                                               width: float) -> None:
    path = write(tmp_path, biped_xml(foot=foot))
    d = draft_spec(path, RobotConfig())
    sole = d.legs.left.sole
    assert (sole.kind, len(sole.geoms), sole.sole_class) == (kind, count, sole_class)
    assert (sole.length, sole.width) == (pytest.approx(length), pytest.approx(width))
    spec = tmp_path / "spec.toml"
    assert main(["robot", "init", str(path), "-o", str(spec), *SERVO_RULE]) == 0
    robot = load_robot(spec)
    g = robot.sole_geom_id["left"]
    # the loader's sole box spans the same footprint, and the one size type carries it alike: the draft's sizes and
    # the loaded robot's scale (the regulator's rule and the generation defaults read the latter)
    assert sorted(2 * robot.model.geom_size[g][:2]) == pytest.approx(sorted([sole.length, sole.width]), abs=1e-9)
    assert robot.sole_width == robot.scale.sole_width == pytest.approx(d.size.sole_width, abs=1e-9)
    assert robot.scale.sole_half_width == robot.sole_boxes["right"].half_width


def test_a_sole_of_several_geoms_is_measured_on_the_loaders_rectangle(tmp_path: Path) -> None:
    """Four sphere soles (0.18 × 0.08 m) under a foot body whose frame is pitched 0.17 rad from them (Berkeley
    Humanoid's 10°): robot init measures the rectangle the loader spans its virtual sole on (read along the vertical),
    not the points' extent along the pitched foot axes (0.18 cos 0.17 = 0.177 m); the loaded sole box is the same."""
    tilt, c, s = 0.17, np.cos(0.17), np.sin(0.17)
    xml = biped_xml(foot="spheres")
    for side in ("left", "right"):
        xml = xml.replace(f'<body name="{side}_foot" pos="0 0 0">', f'<body name="{side}_foot" pos="0 0 0" '
                          f'euler="0 {tilt} 0">')
    for x in (-0.06, 0.12):  # each sphere where it was in the world: R_y(tilt)ᵀ (x, y, z) in the pitched frame
        for y in (-0.04, 0.04):
            xml = xml.replace(f'pos="{x} {y} -0.05"', f'pos="{c * x + s * 0.05:.9f} {y} {s * x - c * 0.05:.9f}"')
    assert xml.count(f'euler="0 {tilt} 0"') == 2 and 'pos="0.12 0.04 -0.05"' not in xml
    path = write(tmp_path, xml)
    sole = find_legs(open_model(path), 0.1, 0.005).left.sole
    assert (sole.length, sole.width) == (pytest.approx(0.18, abs=1e-6), pytest.approx(0.08, abs=1e-6))
    spec = tmp_path / "spec.toml"
    assert main(["robot", "init", str(path), "-o", str(spec), *SERVO_RULE]) == 0
    box = load_robot(spec).sole_boxes["left"]
    assert (2 * box.half_length, 2 * box.half_width) == (pytest.approx(sole.length), pytest.approx(sole.width))


def test_a_sole_its_model_tilts_is_levelled_by_the_ankle_in_the_posture(tmp_path: Path) -> None:
    """A box sole pitched 0.01 rad in its foot's frame: robot init turns each ankle pitch by 0.01 rad (symmetric)
    and says so; robot check then finds both soles level. A level sole's posture is the keyframe's, unchanged."""
    level = draft_spec(write(tmp_path, biped_xml(foot="box")), RobotConfig())
    assert level.levelled == 0.0 and not any("level" in n for n in level.notes)
    path = tmp_path / "tilted" / "robot.xml"
    path.parent.mkdir()
    path.write_text(biped_xml(foot="tilted_box"))
    d = draft_spec(path, RobotConfig())
    assert d.levelled == pytest.approx(0.01, abs=1e-6) and any("to level them" in n for n in d.notes)
    pitch = {s: d.robot.model.joint(f"{s}_ankle_pitch").id for s in ("left", "right")}
    for s, j in pitch.items():
        assert abs(d.angles[j] - level.angles[j]) == pytest.approx(0.01, abs=1e-6), s
    spec = tmp_path / "tilted" / "spec.toml"
    assert main(["robot", "init", str(path), "-o", str(spec), *SERVO_RULE]) == 0
    soles = next(r for r in run_checks(load_robot(spec), RobotConfig()) if r.name == "soles")
    assert soles.passed and soles.values["tilt"] < 1e-5


@pytest.mark.parametrize(("geoms", "length"), [
    # two cylinders of a foot plate rotated 90.5° instead of 90° (PNDbotics Adam Lite): 2 mm higher at the heel
    ("".join(f'<geom type="cylinder" size="0.015 0.11" pos="0.045 {y} -0.049" quat="0.703845 0 0.710353 0"/>'
             for y in (-0.025, 0.025)), 0.22),
    # a heel sphere raised by 1 cm is not on the sole: the sole is the two toe spheres' line
    ('<geom type="sphere" size="0.01" pos="0.1 0.03 0"/><geom type="sphere" size="0.01" pos="0.1 -0.03 0"/>'
     '<geom type="sphere" size="0.01" pos="-0.05 0 0.01"/>', 0.0)])
def test_the_sole_plane_allows_a_tilt_of_a_degree_not_a_raised_heel(geoms: str, length: float) -> None:
    from robustgait.robots.soles import sole_rectangle

    m = mujoco.MjModel.from_xml_string(f'<mujoco><worldbody><body name="foot">{geoms}</body></worldbody></mujoco>')
    d = mujoco.MjData(m)
    mujoco.mj_kinematics(m, d)
    half = sole_rectangle(m, d, list(range(m.ngeom)), np.array([1.0, 0.0, 0.0])).half
    assert 2 * half[0] == pytest.approx(length, abs=2e-3)


def test_sole_points_are_where_each_shape_meets_the_ground() -> None:
    """Known answers: up is z; a cylinder of radius 0.02 and half-length 0.1 lying along x at height 0.05 meets the
    ground along x = ±0.1 at z = 0.03; tilted 0.3 rad about y, each end's rim touches 0.02 below its end's centre,
    displaced along the tilted disk; standing, its bottom rim is 8 points of radius 0.02."""
    up, eye = np.array([0.0, 0.0, 1.0]), np.eye(3)
    box = sole_points("box", np.zeros(3), eye, np.array([0.1, 0.05, 0.01]), up)
    assert box.shape == (4, 3) and np.allclose(box[:, 2], -0.01) and np.ptp(box[:, 0]) == pytest.approx(0.2)
    lying = np.array([[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]])  # columns: the geom's z along world x
    cyl = sole_points("cylinder", np.array([0.0, 0.0, 0.05]), lying, np.array([0.02, 0.1, 0.0]), up)
    assert np.allclose(cyl, [[0.1, 0.0, 0.03], [-0.1, 0.0, 0.03]]) or np.allclose(cyl, [[-0.1, 0.0, 0.03],
                                                                                         [0.1, 0.0, 0.03]])
    a = 0.3
    tilt = np.array([[np.cos(a), 0.0, np.sin(a)], [0.0, 1.0, 0.0], [-np.sin(a), 0.0, np.cos(a)]]) @ lying
    t = sole_points("cylinder", np.zeros(3), tilt, np.array([0.02, 0.1, 0.0]), up)
    axis = tilt[:, 2]
    assert np.allclose((t - t.mean(axis=0)) @ axis, [-0.1, 0.1]) or np.allclose((t - t.mean(axis=0)) @ axis,
                                                                                  [0.1, -0.1])
    ends = np.stack([-0.1 * axis, 0.1 * axis])
    assert np.allclose(np.linalg.norm(t - ends, axis=1), 0.02)  # on each end's rim
    assert np.allclose(t[:, 2] - ends[:, 2], -0.02 * np.cos(a))  # its lowest point: the rim's radius along −z in-plane
    standing = sole_points("cylinder", np.array([0.0, 0.0, 0.05]), eye, np.array([0.02, 0.01, 0.0]), up)
    assert standing.shape == (8, 3) and np.allclose(standing[:, 2], 0.04)
    assert np.allclose(np.linalg.norm(standing[:, :2], axis=1), 0.02)
    caps = sole_points("capsule", np.zeros(3), lying, np.array([0.02, 0.1, 0.0]), up)
    assert np.allclose(np.sort(caps[:, 0]), [-0.1, 0.1]) and np.allclose(caps[:, 2], -0.02)
    assert np.allclose(sole_points("sphere", np.zeros(3), eye, np.array([0.02, 0.0, 0.0]), up), [[0.0, 0.0, -0.02]])
