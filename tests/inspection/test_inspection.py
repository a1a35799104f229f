"""Robot inspection (robustgait.inspection, `robot init` / `robot check`): discovery of legs, soles, floor and
mirror on synthetic bipeds written here (MJCF and URDF) and on exo, Booster T1 when ../shared/robots is beside the
repository; the gain rule's inertias against rigid-body sums; the scaling rules against exo's spec; bad input."""

from __future__ import annotations

import dataclasses
import json
import sys
import textwrap
from pathlib import Path

import mujoco
import numpy as np
import pytest

from robustgait import load_robot
from robustgait.cli import main
from robustgait.config import RobotConfig, ScaleRules
from robustgait.errors import RobustGaitError
from robustgait.inspection.check import run_checks
from robustgait.inspection.discover import find_legs, torque_limits
from robustgait.inspection.gains import (
    joint_loads,
    nice_floor,
    pd_gains,
    servo_timestep,
    spectral_radius,
    static_torques,
)
from robustgait.inspection.mirror import Mirror, find_mirror, fk_residual, mass_asymmetry, name_partner
from robustgait.inspection.model import open_model
from robustgait.inspection.scale import RobotSize, axis_range, nice_step, scale
from robustgait.robotinit.draft import draft_spec
from robustgait.robots.soles import sole_points

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover - exercised on 3.10 only
    import tomli as tomllib

REPO = Path(__file__).resolve().parents[2]
T1 = REPO.parent / "shared" / "robots" / "booster_t1" / "t1.xml"
EXO_XML = REPO / "src" / "robustgait" / "robots" / "exo" / "exo.xml"
# robot init's servo timestep rule, which walks no gait (the accuracy rule's tests: tests/robotinit/test_timestep.py),
# and robot check without the timestep check (which generates the default gait)
SERVO_RULE = ("--timestep-rule", "servo")
needs_t1 = pytest.mark.skipif(not T1.is_file(), reason="../shared/robots/booster_t1 (Booster T1) is not beside the "
                              "repository")

FEET = {
    "box": '<geom name="{s}_sole" type="box" size="0.1 0.05 0.01" pos="0.03 0 -0.05"/>',
    "unnamed_box": '<geom type="box" size="0.1 0.05 0.01" pos="0.03 0 -0.05"/>',
    "spheres": "".join(f'<geom class="foot" type="sphere" size="0.01" pos="{x} {y} -0.05"/>'
                       for x in (-0.06, 0.12) for y in (-0.04, 0.04)),
    "capsules": "".join(f'<geom class="foot" type="capsule" size="0.01" fromto="-0.06 {y} -0.05 0.12 {y} -0.05"/>'
                        for y in (-0.04, 0.04)),
    # two cylinders lying along the foot (PNDbotics Adam Lite's feet): their lowest lines are the sole
    "cylinders": "".join(f'<geom class="foot" type="cylinder" size="0.01" fromto="-0.06 {y} -0.05 0.12 {y} -0.05"/>'
                         for y in (-0.04, 0.04)),
    # one cylinder standing on its end: its bottom disk is the sole
    "puck": '<geom class="foot" type="cylinder" size="0.05 0.01" pos="0.03 0 -0.05"/>',
    # a box sole and a higher cylinder (an ankle guard) of another class: the sole is the box's class
    "box_and_cylinder": ('<geom class="foot" type="box" size="0.1 0.05 0.01" pos="0.03 0 -0.05"/>'
                         '<geom type="cylinder" size="0.03 0.02" pos="0 0 0"/>'),
    # a mesh (a pyramid on its base): the sole is its convex hull's bottom face
    "mesh": '<geom type="mesh" mesh="footmesh"/>',
    "ellipsoid": '<geom type="ellipsoid" size="0.1 0.05 0.01" pos="0.03 0 -0.05"/>',
    # the box sole pitched 0.01 rad in its foot's frame (a CAD export's foot plate)
    "tilted_box": '<geom name="{s}_sole" type="box" size="0.1 0.05 0.01" pos="0.03 0 -0.05" euler="0 0.01 0"/>',
    # a toe on its own hinge, its box level with the foot's
    "toe": ('<geom name="{s}_sole" type="box" size="0.06 0.05 0.01" pos="-0.01 0 -0.05"/>'
            '<body name="{s}_toe" pos="0.05 0 0"><joint name="{s}_toe" axis="0 1 0" range="-0.5 0.5"/>'
            '<inertial pos="0.03 0 -0.05" mass="0.1" diaginertia="0.0001 0.0001 0.0001"/>'
            '<geom type="box" size="0.04 0.05 0.01" pos="0.04 0 -0.05"/></body>'),
    "none": "",
}


def body(name: str, joint: str, axis: str, limits: str, mass: float, com: str, inertia: str, inner: str = "",
         pos: str = "0 0 0", extra: str = "") -> str:
    """One MJCF body on one hinge: its inertial, then ``inner`` (geoms, child bodies)."""
    return (f'<body name="{name}" pos="{pos}"><joint name="{joint}" axis="{axis}" range="{limits}" {extra}/>'
            f'<inertial pos="{com}" mass="{mass}" diaginertia="{inertia}"/>{inner}</body>')


def leg(s: str, y: float, foot: str, roll_axis: str, short: float = 0.0, ankle_roll: bool = True) -> str:
    """A 6-joint leg (hip yaw, roll, pitch, knee, ankle pitch, roll) hanging from the waist at lateral offset y;
    without ``ankle_roll`` 5 joints, the foot on the ankle pitch (its body and the foot's as one, 1 kg)."""
    def frc(limit: int) -> str:
        return f'actuatorfrcrange="-{limit} {limit}"'

    if ankle_roll:
        foot_body = body(f"{s}_foot", f"{s}_ankle_roll", "1 0 0", "-0.5 0.5", 0.8, "0.02 0 -0.03",
                         "0.002 0.004 0.004", FEET[foot].format(s=s), extra=frc(40))
        ankle = body(f"{s}_ankle", f"{s}_ankle_pitch", "0 1 0", "-1 1", 0.2, "0 0 0", "0.0002 0.0002 0.0002",
                     foot_body, pos="0 0 -0.3", extra=frc(50))
    else:
        ankle = body(f"{s}_ankle", f"{s}_ankle_pitch", "0 1 0", "-1 1", 1.0, "0.02 0 -0.03", "0.002 0.004 0.004",
                     FEET[foot].format(s=s), pos="0 0 -0.3", extra=frc(50))
    shin = body(f"{s}_shin", f"{s}_knee", "0 1 0", "0 2.2", 2.0, "0 0 -0.15", "0.02 0.02 0.002",
                '<geom type="capsule" fromto="0 0 -0.02 0 0 -0.26" size="0.035"/>' + ankle, pos=f"0 0 {-0.3 + short}",
                extra=frc(100))
    thigh = body(f"{s}_thigh", f"{s}_hip_pitch", "0 1 0", "-1.5 1.5", 3.0, "0 0 -0.15", "0.03 0.03 0.004",
                 '<geom type="capsule" fromto="0 0 0 0 0 -0.3" size="0.04"/>' + shin,
                 extra=frc(80) + ' armature="0.01"')
    hip2 = body(f"{s}_hip2", f"{s}_hip_roll", roll_axis, "-0.5 0.5", 0.5, "0 0 0", "0.001 0.001 0.001", thigh,
                extra=frc(80))
    return body(f"{s}_hip", f"{s}_hip_yaw", "0 0 1", "-0.5 0.5", 1.0, "0 0 0", "0.002 0.002 0.002", hip2,
                pos=f"0 {y} -0.05", extra=frc(60))


def arm(s: str, y: float) -> str:
    forearm = body(f"{s}_forearm", f"{s}_elbow", "0 1 0", "-2 0", 0.6, "0 0 -0.1", "0.002 0.002 0.0005",
                   '<geom type="capsule" fromto="0 0 0 0 0 -0.2" size="0.025"/>', pos="0 0 -0.25")
    return body(f"{s}_upper_arm", f"{s}_shoulder", "0 1 0", "-2 2", 1.0, "0 0 -0.12", "0.005 0.005 0.001",
                '<geom type="capsule" fromto="0 0 0 0 0 -0.24" size="0.03"/>' + forearm, pos=f"0 {y} 0.25")


def biped_xml(*, foot: str = "box", floor: bool = True, keyframe: bool = True, freejoint: bool = True,
              legs: tuple[str, ...] = ("left", "right"), right_short: float = 0.0, waist: float = 0.0,
              collide: bool = True, ankle_roll: bool = True) -> str:
    """A 20 kg humanoid: torso with a head (neck yaw) and two 2-joint arms, a waist (yaw) carrying two 6-joint legs
    (``ankle_roll`` false: 5-joint legs, as Unitree H1's). The right hip roll's axis points the other way (-x), as
    some models have it. Torque limits: the legs' from actuatorfrcrange, the arms' and neck's from motors' ctrlrange,
    the waist's from a position actuator's forcerange × gear."""
    sides = {"left": 0.09, "right": -0.09}
    axes = {"left": "1 0 0", "right": "-1 0 0"}
    legs_xml = "".join(leg(s, sides[s], foot, axes[s], right_short if s == "right" else 0.0, ankle_roll)
                       for s in legs)
    pose = "0 0 -0.3 0.6 -0.3" + (" 0" if ankle_roll else "")
    key = (f'<keyframe><key name="stand" qpos="0 0 0.9 1 0 0 0  0  0.3 -0.5 0.3 -0.5  {waist}  '
           f'{pose}  {pose}"/></keyframe>') if keyframe and len(legs) == 2 else ""
    return textwrap.dedent(f"""\
        <mujoco model="Test Biped">
          <compiler angle="radian" autolimits="true"/>
          <option timestep="0.002" integrator="implicitfast"/>
          <asset><mesh name="footmesh" vertex="-0.08 -0.05 -0.06 0.12 -0.05 -0.06 0.12 0.05 -0.06 -0.08 0.05 -0.06
                                              0 0 -0.01"/></asset>
          <default>{'' if collide else '<geom contype="0" conaffinity="0"/>'}
            <default class="foot"><geom friction="1 0.005 0.0001"/></default></default>
          <worldbody>
            {'<geom name="ground" type="plane" size="0 0 0.05"/>' if floor else ''}
            <body name="torso" pos="0 0 0.9">
              {'<freejoint name="root"/>' if freejoint else ''}
              <inertial pos="0 0 0.15" mass="8.0" diaginertia="0.15 0.12 0.08"/>
              <geom type="box" size="0.08 0.12 0.15" pos="0 0 0.15"/>
              {body("head", "neck_yaw", "0 0 1", "-1 1", 1.0, "0 0 0.08", "0.004 0.004 0.004",
                    '<geom type="sphere" size="0.08" pos="0 0 0.08"/>', pos="0 0 0.32")}
              {arm("left", 0.15)}{arm("right", -0.15)}
              {body("waist", "waist_yaw", "0 0 1", "-1 1", 2.0, "0 0 0", "0.01 0.01 0.01", legs_xml,
                    pos="0 0 -0.05")}
            </body>
          </worldbody>
          <actuator>
            <motor joint="neck_yaw" ctrlrange="-5 5"/>
            <motor joint="left_shoulder" ctrlrange="-20 20"/>
            <motor joint="right_shoulder" ctrlrange="-20 20"/>
            <motor joint="left_elbow" ctrlrange="-10 10" gear="2"/>
            <motor joint="right_elbow" ctrlrange="-10 10" gear="2"/>
            <position joint="waist_yaw" kp="100" forcerange="-30 30"/>
          </actuator>
          {key}
        </mujoco>""")


def write(tmp_path: Path, text: str, name: str = "biped.xml") -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


def run(capsys: pytest.CaptureFixture[str], *argv: str | Path) -> tuple[int, str, str]:
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


LEFT_LEG = ["left_hip_yaw", "left_hip_roll", "left_hip_pitch", "left_knee", "left_ankle_pitch", "left_ankle_roll"]


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
    # the loader's sole box spans the same footprint
    assert sorted(2 * robot.model.geom_size[g][:2]) == pytest.approx(sorted([sole.length, sole.width]), abs=1e-9)


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


def test_name_partners() -> None:
    names = ["Left_Hip_Pitch", "Right_Hip_Pitch", "LL_HR", "LR_HR", "leg_left_1_joint", "leg_right_1_joint",
             "l_hip", "r_hip", "AL1", "AR1", "waist"]
    assert name_partner("Left_Hip_Pitch", names) == ("Right_Hip_Pitch", "left")
    assert name_partner("LR_HR", names) == ("LL_HR", "right")
    assert name_partner("leg_left_1_joint", names) == ("leg_right_1_joint", "left")
    assert name_partner("r_hip", names) == ("l_hip", "right")
    assert name_partner("AL1", names) == ("AR1", "left")
    assert name_partner("waist", names) is None


def test_a_model_files_rounding_is_not_an_asymmetry(tmp_path: Path) -> None:
    """Both legs 0.7 mm to the left (PNDbotics Adam Lite's torso sits 0.5 mm off the plane): each hip roll's axis line
    1.4 mm from the other's reflection, within robot.mirror_tolerance (2 mm); 5 mm is refused, saying the
    tolerance."""
    def shifted(dy: float) -> str:
        return biped_xml().replace('pos="0 0.09 -0.05"', f'pos="0 {0.09 + dy:g} -0.05"').replace(
            'pos="0 -0.09 -0.05"', f'pos="0 {-0.09 + dy:g} -0.05"')
    assert 'pos="0 0.0907 -0.05"' in shifted(0.0007)
    draft_spec(write(tmp_path, shifted(0.0007)), RobotConfig())
    with pytest.raises(RobustGaitError, match=r"anchor 10.00 mm from the reflected one, tolerance 2 mm"):
        draft_spec(write(tmp_path, shifted(0.005), "far.xml"), RobotConfig())


def test_mirror_signs_follow_the_axes_and_reflect_the_model(tmp_path: Path) -> None:
    r = open_model(write(tmp_path, biped_xml()))
    mirror = find_mirror(r, 1e-3)
    sign = {r.joint_name(j): mirror.sign[j] for j in r.joints}
    partner = {r.joint_name(j): r.joint_name(k) for j, k in mirror.partner.items()}
    # yaw: a z axis reflects to −S z = −z, the partner's axis is +z: −1; the right roll axis is −x = −S x: +1
    assert sign["left_hip_yaw"] == -1 and sign["left_hip_roll"] == 1 and sign["left_hip_pitch"] == 1
    assert sign["waist_yaw"] == -1 and partner["waist_yaw"] == "waist_yaw" and sign["left_shoulder"] == 1
    assert partner["left_knee"] == "right_knee" and partner["right_elbow"] == "left_elbow"
    res = fk_residual(r, mirror, 10, 0)
    assert res.position < 1e-12 and res.angle < 1e-6
    # a wrong sign moves bodies far from their partners' reflections
    knee = next(j for j in r.joints if r.joint_name(j) == "left_knee")
    bad = Mirror(mirror.partner, {**mirror.sign, knee: -1.0, mirror.partner[knee]: -1.0}, mirror.body_partner)
    assert fk_residual(r, bad, 10, 0).position > 0.05


def test_a_joint_on_the_plane_is_its_own_partner_wherever_its_frame_sits(tmp_path: Path) -> None:
    """A head's tilt hinge mounted on one side of its bracket (Robotis OP3): its frame 2 cm off the sagittal plane,
    its axis along y — the line S maps onto itself, so the joint is its own partner, and the reflection is verified
    (the frame's offset is a constant of the body); a wrong sign is still caught. The neck's yaw shares its vertical
    line with the waist's: each is its own partner, not the other's."""
    tilt = body("head_tilt_link", "head_tilt", "0 -1 0", "-1 1", 0.3, "0 -0.019 0.03", "0.001 0.001 0.001",
                '<geom type="sphere" size="0.06" pos="0 -0.019 0.03"/>', pos="0.01 0.019 0.03")
    r = open_model(write(tmp_path, biped_xml().replace('<geom type="sphere" size="0.08" pos="0 0 0.08"/>', tilt)))
    mirror = find_mirror(r, 1e-3)
    ids = {r.joint_name(j): j for j in r.joints}
    assert mirror.partner[ids["head_tilt"]] == ids["head_tilt"] and mirror.sign[ids["head_tilt"]] == 1
    assert mirror.partner[ids["neck_yaw"]] == ids["neck_yaw"] and mirror.partner[ids["waist_yaw"]] == ids["waist_yaw"]
    res = fk_residual(r, mirror, 10, 0)
    assert res.position < 1e-9 and res.angle < 1e-6
    bad = Mirror(mirror.partner, {**mirror.sign, ids["head_tilt"]: -1.0}, mirror.body_partner)
    assert fk_residual(r, bad, 10, 0).angle > 0.1                   # tilted the other way


def test_mass_asymmetry_finds_the_side_that_differs(tmp_path: Path) -> None:
    """A model whose kinematics reflect exactly can still differ left to right in its masses (T1's shanks, 60 g):
    found pair by pair, the lighter body named — and a difference at the level of a model file's rounding (half a
    milligram, an inertia 0.5 % apart) is not a difference: certified on the step map."""
    tol = (RobotConfig().side_mass_tolerance, RobotConfig().side_inertia_tolerance)
    xml = biped_xml()
    r = open_model(write(tmp_path, xml))
    same = mass_asymmetry(r, find_mirror(r, 1e-3))
    assert same.mass == 0 and same.inertia == 0 and "same masses" in same.describe(r, *tol)
    assert not same.differs(*tol)
    at = xml.index('name="right_shin"')
    at = xml.index('mass="2.0"', at)
    rounding = xml[:at] + 'mass="2.0000005" diaginertia="0.0201 0.02 0.002"' + xml[
        at + len('mass="2.0" diaginertia="0.02 0.02 0.002"'):]
    r = open_model(write(tmp_path, rounding, "rounding.xml"))
    tiny = mass_asymmetry(r, find_mirror(r, 1e-3))
    assert tiny.mass == pytest.approx(5e-7) and tiny.inertia == pytest.approx(0.0001 / 0.0201)
    assert not tiny.differs(*tol) and "the same within the tolerance" in tiny.describe(r, *tol)
    assert "certified on the step map" in tiny.describe(r, *tol)
    at = xml.index('name="right_shin"')
    at = xml.index('mass="2.0"', at)
    heavier = xml[:at] + 'mass="2.06" diaginertia="0.021 0.02 0.002"' + xml[at + len('mass="2.0" diaginertia="0.02 '
                                                                                       '0.02 0.002"'):]
    r = open_model(write(tmp_path, heavier, "heavier.xml"))
    asym = mass_asymmetry(r, find_mirror(r, 1e-3))
    assert asym.mass == pytest.approx(0.06) and asym.inertia == pytest.approx(0.001 / 0.021)
    assert r.body_name(asym.body) == "left_shin" and r.body_name(asym.partner) == "right_shin"
    assert asym.differs(*tol) and "'left_shin' is 60 g lighter than 'right_shin'" in asym.describe(r, *tol)
    assert "certified on the stride map" in asym.describe(r, *tol)


# ----------------------------------------------------------------------------------------------- gains
def test_stance_inertia_is_the_robot_about_the_ankle(tmp_path: Path) -> None:
    """With the left foot welded and every other joint held, the left ankle roll turns the rest of the robot as one
    rigid body about its axis: I = Σ (aᵀ I_b a + m_b |a × (c_b − p)|²) over the bodies above it, plus armature."""
    r = open_model(write(tmp_path, biped_xml()))
    legs = find_legs(r, 0.1, 0.005)
    q = r.qpos(height=legs.standing_height)
    loads = joint_loads(r, q, {"left": legs.left.foot, "right": legs.right.foot})
    m = r.model
    d = r.kinematics(q)
    j = next(j for j in r.joints if r.joint_name(j) == "left_ankle_roll")
    a, p = d.xaxis[j], d.xanchor[j]
    foot = legs.left.foot
    rigid = 0.0
    for b in range(1, m.nbody):
        if b == foot:
            continue
        rot = d.ximat[b].reshape(3, 3)
        inertia = rot @ np.diag(m.body_inertia[b]) @ rot.T
        arm_ = np.cross(a, d.xipos[b] - p)
        rigid += float(a @ inertia @ a + m.body_mass[b] * arm_ @ arm_)
    assert loads[j].stance == pytest.approx(rigid + m.dof_armature[m.jnt_dofadr[j]], rel=1e-9)
    # the swing value is the mass matrix's diagonal: the foot alone (its inertia about the roll axis)
    assert loads[j].swing < 0.01 * loads[j].stance


def test_pd_gains_respect_the_cap_and_the_timestep(tmp_path: Path) -> None:
    d = draft_spec(write(tmp_path, biped_xml()), RobotConfig())
    c = d.config
    for j in d.robot.joints:
        g, load, tau = d.gains[j], d.loads[j], d.torque[j].value or 0.0
        assert 0 < g.kp <= tau / c.tracking_error * (1 + 1e-12) and g.kd > 0
        assert g.kp == pytest.approx(min(load.stance * (2 * np.pi * c.bandwidth) ** 2, tau / c.tracking_error))
        assert g.kd == pytest.approx(2 * c.damping_ratio * np.sqrt(g.kp * load.swing)) and g.radius < 1
    # partners get the same servo
    for j, k in d.mirror.partner.items():
        assert (d.gains[j].kp, d.gains[j].kd) == (d.gains[k].kp, d.gains[k].kd)


def test_spectral_radius_of_the_discrete_servo() -> None:
    # semi-implicit Euler: stable while h kd / I < 2 and (h ω)² < 4 − 2 h kd / I
    assert spectral_radius(100.0, 1.0, 1.0, 0.01, "euler") < 1
    assert spectral_radius(100.0, 250.0, 1.0, 0.01, "euler") > 1
    assert spectral_radius(1e6, 10.0, 1.0, 0.01, "euler") > 1
    # implicit damping: any damping contracts
    assert spectral_radius(100.0, 1e5, 1.0, 0.01, "implicitfast") < 1
    # continuous decay e^{-ζω h} for the critically damped servo at a small step
    assert spectral_radius(100.0, 20.0, 1.0, 1e-4, "rk4") == pytest.approx(np.exp(-10 * 1e-4), rel=1e-3)
    # a servo that would not contract at its step is lowered until it does
    from robustgait.inspection.gains import JointLoad

    g = pd_gains(JointLoad(1e-4, 1.0, "left"), 1e4, 50.0, 1.0, 0.01, 0.002, "euler")
    assert g.bound == "stability" and g.radius < 1


def test_the_timestep_resolves_the_fastest_servo(tmp_path: Path) -> None:
    assert [nice_floor(x) for x in (0.0014, 0.001, 0.00099, 0.0049, 0.07)] == [0.001, 0.001, 0.0005, 0.002, 0.05]
    # at least `steps` physics steps per period of the fastest servo, at most a fraction of √(l/g), never above the
    # model's step
    assert servo_timestep(0.002, 57.3, 12.0, 1.0, 1.0) == 0.001  # Booster T1's ankle (model: 2 ms)
    assert servo_timestep(0.002, 57.3, 12.0, 0.238, 0.0035) == 0.0005  # ... and its leg: 0.83 ms
    assert servo_timestep(0.001, 66.7, 12.0, 0.308, 0.0035) == 0.001  # exo's ankle (rule gains) and leg: 1.08 ms
    assert servo_timestep(0.0005, 10.0, 12.0, 1.0, 0.0035) == 0.0005
    d = draft_spec(write(tmp_path, biped_xml()), RobotConfig())
    f = max(g.frequency for g in d.gains.values())
    assert d.timestep <= float(d.robot.model.opt.timestep) and d.timestep * f <= 1 / d.config.servo_steps + 1e-12
    assert d.timestep <= d.config.scale.timestep * np.sqrt(d.size.leg_length / d.size.gravity)
    assert d.servo_frequency >= f * (1 - 1e-9)  # measured before any lowering for stability


def test_static_torques_balance_gravity(tmp_path: Path) -> None:
    r = open_model(write(tmp_path, biped_xml()))
    legs = find_legs(r, 0.1, 0.005)
    q = r.qpos(height=legs.standing_height)
    one = static_torques(r, q, [legs.left.foot])
    m = r.model
    d = r.kinematics(q)
    # standing on the left foot, the left leg carries everything but itself below the joint: the knee's torque is
    # the weight above it times its lever arm — checked through the virtual-work identity g = Jᵀ w + τ
    jac = np.zeros((6, m.nv))
    mujoco.mj_jacBody(m, d, jac[:3], jac[3:], legs.left.foot)
    w = np.linalg.lstsq(jac[:, :6].T, d.qfrc_bias[:6], rcond=None)[0]
    assert np.allclose(one, np.r_[np.zeros(6), (d.qfrc_bias - jac.T @ w)[6:]], atol=1e-9)
    both = static_torques(r, q, [legs.left.foot, legs.right.foot])
    knee = m.jnt_dofadr[next(j for j in r.joints if r.joint_name(j) == "left_knee")]
    assert abs(both[knee]) < abs(one[knee])  # two feet share the weight


# ----------------------------------------------------------------------------------------------- scaling
def test_the_rules_give_back_exos_spec() -> None:
    size = RobotSize(leg_length=0.93, standing_height=0.921, mass=126.0, gravity=9.81, hip_spacing=0.25,
                     sole_length=0.27, sole_width=0.12)
    s = scale(size, ScaleRules())
    spec = tomllib.loads((REPO / "src" / "robustgait" / "robots" / "exo" / "spec.toml").read_text())
    for axis, value in spec["action_space"].items():
        if axis != "multicontact":
            assert s.action_space[axis] == pytest.approx(tuple(value)), axis
    for axis, value in spec["action_space"]["multicontact"].items():
        assert s.multicontact_action_space[axis] == pytest.approx(tuple(value)), axis
    q = spec["gait_quality"]
    assert s.angular_velocity == pytest.approx(q["pelvis_angular_velocity"], rel=0.03)
    assert s.joint_velocity == pytest.approx(q["joint_velocity"], rel=0.03)
    assert s.pelvis_height == pytest.approx(tuple(q["pelvis_height"]), rel=0.03)
    assert s.fall_height == pytest.approx(spec["fall"]["min_base_height"], rel=0.03)
    rules = ScaleRules()  # the gait-quality angles are exo's (scale-free)
    for k in ("pelvis_roll", "pelvis_yaw", "swing_tilt", "swing_yaw"):
        assert getattr(rules, k) == q[k], k
    assert rules.pelvis_pitch == tuple(q["pelvis_pitch"])
    assert s.gait == pytest.approx({"step_length": 0.15, "step_duration": 0.7, "step_width": 0.25,
                                    "step_height": 0.07}, rel=0.03)
    assert [nice_step(x) for x in (0.019, 0.11, 0.0024, 3.3)] == [0.02, 0.1, 0.0025, 2.5]


def test_narrow_soles_get_shorter_default_steps_and_a_shorter_grid() -> None:
    """PNDbotics Adam Lite's size (sole 0.05 m on a 0.896 m leg: narrow): the default step is 2.0 √(l/g), where the
    same robot with 0.12 m soles gets 2.3 √(l/g); the narrow grid ends at 3.0 √(l/g)."""
    import math

    narrow = RobotSize(leg_length=0.896, standing_height=0.929, mass=58.2, gravity=9.81, hip_spacing=0.234,
                       sole_length=0.22, sole_width=0.05)
    wide = dataclasses.replace(narrow, sole_width=0.12)
    t = math.sqrt(0.896 / 9.81)
    assert scale(narrow, ScaleRules()).gait["step_duration"] == pytest.approx(2.0 * t, rel=1e-2)
    assert scale(wide, ScaleRules()).gait["step_duration"] == pytest.approx(2.3 * t, rel=1e-2)
    assert scale(narrow, ScaleRules()).action_space["step_duration"][1] <= 3.0 * t + 1e-9
    assert scale(narrow, ScaleRules()).multicontact_action_space == scale(wide, ScaleRules()).multicontact_action_space


def test_a_point_foot_walker_steps_end_at_its_lambda_t() -> None:
    """Adam Lite's size: a walk that balances by foot placement (κ ≥ ``point_foot_share``) ends its step durations at
    λT = ``point_foot_step`` — never below the default step, which walked; an ankle that holds the centre of mass
    (κ below it), or no measurement, leaves the narrow-sole grid as it is, and nothing else of the spec moves."""
    import math

    from robustgait.inspection.scale import Balance

    size = RobotSize(leg_length=0.896, standing_height=0.929, mass=58.2, gravity=9.81, hip_spacing=0.234,
                     sole_length=0.22, sole_width=0.05)
    rules = ScaleRules()
    plain = scale(size, rules)
    assert scale(size, rules, Balance(share=0.49, rate=3.3)) == plain
    assert scale(size, rules, Balance(share=0.5, rate=3.3)) == scale(size, rules, Balance(share=1.0, rate=3.3))
    capped = scale(size, rules, Balance(share=1.0, rate=3.3))
    low, high, step = capped.action_space["step_duration"]
    assert high * 3.3 == pytest.approx(rules.point_foot_step, abs=3.3 * step / 2 + 1e-9)  # the nearest grid point
    default = plain.gait["step_duration"]
    assert abs(low - rules.action_step_duration[0] * default) <= step / 2 + 1e-9  # the same low multiple, finer step
    assert high < plain.action_space["step_duration"][1]
    assert {k: v for k, v in capped.action_space.items() if k != "step_duration"} == {
        k: v for k, v in plain.action_space.items() if k != "step_duration"}
    assert dataclasses.replace(capped, action_space=plain.action_space) == plain
    fast = scale(size, rules, Balance(share=1.0, rate=1.5 * rules.point_foot_step / default))  # default's λT 1.5 × cap
    assert fast.action_space["step_duration"][1] >= default - fast.action_space["step_duration"][2] / 2
    assert default == pytest.approx(2.0 * math.sqrt(0.896 / 9.81), rel=1e-2)


def test_a_point_foot_walker_whose_tried_end_fails_stops_that_axis_at_its_default() -> None:
    """Adam Lite's size: when the window's narrowest step (or its longest) does not pass gait generate, a point-foot
    walker's widths start (its lengths end) at the grid point nearest the default, which walked, and the other end
    stays; the failure moves nothing for an ankle that holds (κ below ``point_foot_share``), and nothing but that
    axis moves."""
    from robustgait.inspection.scale import Balance

    size = RobotSize(leg_length=0.896, standing_height=0.929, mass=58.2, gravity=9.81, hip_spacing=0.192,
                     sole_length=0.22, sole_width=0.05)
    rules = ScaleRules()
    walks = scale(size, rules, Balance(share=1.0, rate=3.3))
    for axis, end in (("step_width", 0), ("step_length", 1)):
        fails = scale(size, rules, Balance(share=1.0, rate=3.3, ends_fail=(axis,)))
        default = walks.gait[axis]
        moved, step = fails.action_space[axis][end], fails.action_space[axis][2]
        assert abs(walks.action_space[axis][end] - default) > step  # the rule reaches past the default there
        assert abs(moved - default) <= step / 2 + 1e-9
        other = fails.action_space[axis][1 - end]
        assert other == pytest.approx(walks.action_space[axis][1 - end], abs=step)
        assert {k: v for k, v in fails.action_space.items() if k != axis} == {
            k: v for k, v in walks.action_space.items() if k != axis}
        assert scale(size, rules, Balance(share=0.49, rate=3.3, ends_fail=(axis,))) == scale(size, rules)


def test_the_width_axis_starts_where_the_feet_do_not_touch() -> None:
    """Robotis OP3's size: 0.88 × its 0.104 m default width rounds to a 0.09 m grid point, narrower than its 0.078 m
    soles and their 0.013 m gap allow (gait generation refuses 0.09); the axis starts at the next grid point, for the
    flat-foot and the multi-contact grids, and nothing else moves."""
    from robustgait.inspection.scale import above_least, least_width

    size = RobotSize(leg_length=0.279, standing_height=0.3, mass=3.15, gravity=9.81, hip_spacing=0.104,
                     sole_length=0.12, sole_width=0.078)
    out = scale(size, ScaleRules())
    least = least_width(size)
    assert least == pytest.approx(0.078 + 0.013, abs=1e-9)
    for space in (out.action_space, out.multicontact_action_space):
        assert space is not None
        low, high, step = space["step_width"]
        assert least <= low < least + step and low <= high
    assert above_least((0.2, 0.3, 0.02), 0.15) == (0.2, 0.3, 0.02)  # already clear: unchanged
    assert above_least((0.09, 0.1, 0.01), 0.2) == (0.1, 0.1, 0.01)  # none clears: the high end only


def test_a_grid_stops_at_the_grid_point_nearest_its_high_multiple() -> None:
    # Booster T1's durations: 0.86–1.57 × 0.548 s = 0.47–0.86 s; the nice step 0.1 (not 0.078) must not stretch the
    # five steps to 1.0 s: the grid stops at 0.9 s, the grid point nearest 0.86 s
    assert axis_range("step_duration", 0.548, (0.86, 1.57, 5)) == (0.5, 0.9, 0.1)
    assert axis_range("step_duration", 0.708, (0.86, 1.57, 5)) == (0.6, 1.1, 0.1)  # exo's: all five steps
    assert axis_range("step_length", 0.1, (1.0, 1.05, 4))[1] > 0.1  # at least one step


# ----------------------------------------------------------------------------------------------- robot init / check
def test_init_writes_a_spec_that_loads_and_passes_check(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    model = write(tmp_path, biped_xml())
    spec = tmp_path / "out" / "biped.toml"
    spec.parent.mkdir()
    code, out, err = run(capsys, "robot", "init", model, "-o", spec, *SERVO_RULE)
    assert code == 0 and err == "" and "mirror: verified" in out and f"wrote {spec}" in out
    text = spec.read_text()
    raw = tomllib.loads(text)
    assert raw["mjcf"] == "../biped.xml" and raw["floor_geom"] == "ground" and raw["name"] == "test_biped"
    assert raw["joints"]["names"][:6] == LEFT_LEG
    assert set(raw["joints"]["held"]) == {"neck_yaw", "left_shoulder", "left_elbow", "right_shoulder",
                                          "right_elbow", "waist_yaw"}
    assert raw["joints"]["held"]["left_shoulder"] == 0.3 and raw["joints"]["held"]["right_elbow"] == -0.5
    assert raw["mirror"]["joint_perm"] == [6, 7, 8, 9, 10, 11, 0, 1, 2, 3, 4, 5]
    assert raw["mirror"]["joint_sign"] == [-1, 1, 1, 1, 1, -1] * 2
    assert raw["mirror"]["held"]["waist_yaw"] == ["waist_yaw", -1]
    assert raw["posture"]["left_knee"] == 0.6 and raw["legs"]["left"] == {"sole_geom": "left_sole"}
    # every value line carries a comment (but table headers and the names' closing brackets)
    # (a table's values that share one comment line above them: held angles, posture, mirror, action spaces)
    shared = {*raw["joints"]["held"], *raw["posture"], *raw["mirror"].get("held", {}), "joint_perm", "joint_sign",
              *raw["action_space"]["multicontact"], "name", "description"}
    for line in text.splitlines():
        if "=" in line and not line.startswith("#") and not line.endswith("= ["):
            assert "#" in line or line.split("=")[0].strip() in shared, line
    robot = load_robot(spec)
    assert robot.n_joints == 12 and len(robot.spec.held) == 6
    results = run_checks(robot, RobotConfig())
    assert all(r.passed for r in results), [r.line for r in results]
    code, out, _ = run(capsys, "robot", "check", spec, "--no-timestep", "--json")
    report = json.loads(out)
    assert code == 0 and report["passed"] and [c["name"] for c in report["checks"]] == [
        "mirror", "soles", "torques", "stiffness", "stand", "tracking"]


def test_an_asymmetric_keyframe_is_made_symmetric(tmp_path: Path) -> None:
    d = draft_spec(write(tmp_path, biped_xml(waist=0.1)), RobotConfig())
    waist = next(j for j in d.robot.joints if d.robot.joint_name(j) == "waist_yaw")
    assert d.angles[waist] == 0.0 and d.asymmetry == pytest.approx(0.1) and "made symmetric" in d.notes[-1]


def test_plan_all_plans_every_joint(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    spec = tmp_path / "all.toml"
    code, _, _ = run(capsys, "robot", "init", write(tmp_path, biped_xml()), "-o", spec, *SERVO_RULE, "--plan", "all",
                     "--bandwidth", "3")
    raw = tomllib.loads(spec.read_text())
    assert code == 0 and len(raw["joints"]["names"]) == 18 and "held" not in raw["joints"]
    perm = raw["mirror"]["joint_perm"]
    assert sorted(perm) == list(range(18)) and all(perm[perm[i]] == i for i in range(18))
    assert "(2π × 3 Hz)²" in spec.read_text()


def test_a_broken_mirror_fails_check(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    spec = tmp_path / "spec.toml"
    run(capsys, "robot", "init", write(tmp_path, biped_xml()), "-o", spec, *SERVO_RULE)
    text = spec.read_text().replace("joint_sign = [-1, 1, 1, 1, 1, -1, -1, 1, 1, 1, 1, -1]",
                                    "joint_sign = [-1, 1, 1, -1, 1, -1, -1, 1, 1, -1, 1, -1]")
    spec.write_text(text)
    code, out, _ = run(capsys, "robot", "check", spec, "--no-timestep")
    assert code == 1 and "mirror: FAIL" in out and "1 of 6 checks failed (mirror)" in out


def test_a_servo_weaker_than_gravity_fails_stiffness(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """kp capped at τ_max / 1 rad: the stance ankle is softer than the robot tipping over it (m g h)."""
    spec = tmp_path / "spec.toml"
    run(capsys, "robot", "init", write(tmp_path, biped_xml()), "-o", spec, *SERVO_RULE, "--tracking-error", "1")
    robot = load_robot(spec)
    result = next(r for r in run_checks(robot, RobotConfig()) if r.name == "stiffness")
    assert not result.passed and result.values["ratio"] < 1 and "ankle" in result.line


def test_soft_gains_fail_stand_and_tracking(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    spec = tmp_path / "spec.toml"
    run(capsys, "robot", "init", write(tmp_path, biped_xml()), "-o", spec, *SERVO_RULE, "--bandwidth", "0.2",
        "--damping-ratio", "0.2")
    code, out, _ = run(capsys, "robot", "check", spec, "--no-timestep")
    lines = {line.split(":")[0]: line for line in out.splitlines()}
    assert code == 1 and "FAIL" in lines["tracking"] and ("FELL" in lines["stand"] or "FAIL" in lines["stand"])


URDF_LEG = [("hip_yaw", "0 0 1", "0 {y} -0.05"), ("hip_roll", "1 0 0", "0 0 0"), ("hip_pitch", "0 1 0", "0 0 0"),
            ("knee", "0 1 0", "0 0 -0.3"), ("ankle_pitch", "0 1 0", "0 0 -0.3"), ("ankle_roll", "1 0 0", "0 0 0")]


def biped_urdf() -> str:
    """The synthetic biped as a URDF: a pelvis and two 6-joint legs with box feet (collision names kept)."""
    inertia = '<inertia ixx="{i}" iyy="{i}" izz="{i}" ixy="0" ixz="0" iyz="0"/>'
    links = [f'<link name="pelvis"><inertial><mass value="10"/>{inertia.format(i=0.1)}</inertial>'
             '<collision><origin xyz="0 0 0.1"/><geometry><box size="0.2 0.3 0.2"/></geometry></collision></link>']
    joints = []
    for s, y in (("left", 0.09), ("right", -0.09)):
        parent = "pelvis"
        for j, axis, xyz in URDF_LEG:
            link = f"{s}_{j}_link"
            sole = (f'<collision name="{s}_sole"><origin xyz="0.03 0 -0.05"/><geometry><box size="0.2 0.1 0.02"/>'
                    "</geometry></collision>" if j == "ankle_roll" else "")
            mass = {"hip_pitch": 3.0, "knee": 2.0, "ankle_roll": 0.8}.get(j, 0.5)
            links.append(f'<link name="{link}"><inertial><origin xyz="0 0 {-0.15 if mass > 1 else 0}"/>'
                         f'<mass value="{mass}"/>{inertia.format(i=0.01)}</inertial>{sole}</link>')
            joints.append(f'<joint name="{s}_{j}" type="revolute"><parent link="{parent}"/><child link="{link}"/>'
                          f'<origin xyz="{xyz.format(y=y)}"/><axis xyz="{axis}"/>'
                          f'<limit lower="-1" upper="{2.2 if j == "knee" else 1}" effort="80" velocity="10"/></joint>')
            parent = link
    return f'<robot name="urdf_biped">{"".join(links)}{"".join(joints)}</robot>'


def test_init_on_a_urdf(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    model = write(tmp_path, biped_urdf(), "biped.urdf")
    spec = tmp_path / "spec.toml"
    code, _, err = run(capsys, "robot", "init", model, "-o", spec, *SERVO_RULE)
    assert code == 0, err
    raw = tomllib.loads(spec.read_text())
    assert raw["base_body"] == "pelvis" and raw["mjcf"] == "biped.urdf" and raw["add_floor"] is True
    assert raw["legs"]["left"] == {"sole_geom": "left_sole"} and len(raw["joints"]["names"]) == 12
    assert raw["joints"]["torque_limit"] == [80.0] * 12 and "held" not in raw["joints"]
    assert raw["mirror"]["joint_sign"] == [-1, -1, 1, 1, 1, -1] * 2
    robot = load_robot(spec)
    results = run_checks(robot, RobotConfig())
    assert all(r.passed for r in results), [r.line for r in results]


def test_init_on_exo_finds_its_spec(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    spec = tmp_path / "exo.toml"
    code, out, _ = run(capsys, "robot", "init", EXO_XML, "-o", spec, *SERVO_RULE)
    raw = tomllib.loads(spec.read_text())
    shipped = tomllib.loads(EXO_XML.with_name("spec.toml").read_text())
    assert code == 0 and "no torque limit in the model: estimated" in out
    for k in ("names",):
        assert raw["joints"][k] == shipped["joints"][k]
    assert raw["mirror"] == {**shipped["mirror"]}
    assert raw["legs"] == shipped["legs"] and raw["base_body"] == "pelvis" and raw["floor_geom"] == "floor"
    assert all(r.passed for r in run_checks(load_robot(spec), RobotConfig()))


@needs_t1
def test_init_and_check_on_booster_t1(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    spec = tmp_path / "t1.toml"
    code, out, _ = run(capsys, "robot", "init", T1, "-o", spec, *SERVO_RULE)
    assert code == 0
    raw = tomllib.loads(spec.read_text())
    j = raw["joints"]
    assert j["names"][:6] == ["Left_Hip_Pitch", "Left_Hip_Roll", "Left_Hip_Yaw", "Left_Knee_Pitch",
                              "Left_Ankle_Pitch", "Left_Ankle_Roll"]
    assert len(j["held"]) == 11 and j["held"]["Left_Shoulder_Roll"] == -1.4 and j["held"]["Waist"] == 0.0
    assert raw["mirror"]["joint_sign"] == [1, -1, -1, 1, 1, -1] * 2
    assert raw["mirror"]["held"]["Left_Elbow_Yaw"] == ["Right_Elbow_Yaw", -1]
    limits = dict(zip(j["names"], j["torque_limit"], strict=True))
    assert all(0 < kp <= 50 * limits[n] for n, kp in zip(j["names"], j["kp"], strict=True))
    assert raw["legs"]["left"] == {"sole_geom": "left_foot_box"} and raw["floor_geom"] == "floor"
    # its model asks for 2 ms; its ankle servos (57 Hz on the swing inertia) need 1 ms, its leg 0.83 ms (exo's 1 ms
    # of √(l/g)): 0.5 ms (docs/robots.md)
    assert raw["sim"]["timestep"] == 0.0005
    assert raw["gait_quality"]["pelvis_roll"] == 0.05 and raw["gait_quality"]["pelvis_pitch"] == [-0.05, 0.15]
    code, out, _ = run(capsys, "robot", "check", spec, "--no-timestep")
    assert code == 0 and "t1: all 6 checks passed" in out


@needs_t1
def test_init_on_booster_t1_as_the_menagerie_has_it(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """The Menagerie's t1.xml has unnamed foot boxes and no floor (our copy names them and adds one)."""
    xml = T1.read_text().replace(' name="left_foot_box"', "").replace(' name="right_foot_box"', "")
    xml = xml.replace('<geom name="floor" type="plane" size="0 0 0.05" rgba="0.8 0.8 0.8 1"/>', "")
    assert 'type="plane"' not in xml and 'name="left_foot_box"' not in xml
    spec = tmp_path / "t1.toml"
    code, out, err = run(capsys, "robot", "init", write(tmp_path, xml, "t1.xml"), "-o", spec, *SERVO_RULE)
    raw = tomllib.loads(spec.read_text())
    assert code == 0, err
    assert raw["legs"]["left"] == {"sole_body": "left_foot_link"} and raw["add_floor"] is True
    code, out, _ = run(capsys, "robot", "check", spec, "--no-timestep")
    assert code == 0 and "t1: all 6 checks passed" in out


# ----------------------------------------------------------------------------------------------- bad input
BAD_MODELS = {
    "no free joint": (lambda: biped_xml(freejoint=False, keyframe=False), "no free joint"),
    "one leg": (lambda: biped_xml(legs=("left",)), "one leg"),
    "no collision geom": (lambda: biped_xml(collide=False), "no sole found"),
    "no foot geom": (lambda: biped_xml(foot="none"), "no area to stand on"),
    "ellipsoid sole": (lambda: biped_xml(foot="ellipsoid"), "is an ellipsoid, whose contact patch robustgait "
                       "cannot bound: make it a box or a mesh"),
    "two-body foot": (lambda: biped_xml(foot="toe", keyframe=False), "foot stands on 2 bodies"),
    # the right shin 3 cm shorter: the feet still stand level within the tolerance, the mirror cannot be right
    "asymmetric": (lambda: biped_xml(right_short=0.03), "the mirror does not reflect the model"),
    "unparsable": (lambda: "<mujoco><worldbody><body></mujoco>", "could not parse"),
}


@pytest.mark.parametrize("case", sorted(BAD_MODELS))
def test_bad_models_are_refused_in_one_line(tmp_path: Path, capsys: pytest.CaptureFixture[str], case: str) -> None:
    make, message = BAD_MODELS[case]
    spec = tmp_path / "spec.toml"
    code, out, err = run(capsys, "robot", "init", write(tmp_path, make()), "-o", spec)
    assert code == 2 and out == "" and err.count("\n") == 1 and err.startswith("robustgait: error: ")
    assert message in err and not spec.exists() and list(tmp_path.iterdir()) == [tmp_path / "biped.xml"]


def test_bad_paths_are_refused(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    model = write(tmp_path, biped_xml())
    cases = [(("robot", "init", tmp_path / "missing.xml", "-o", tmp_path / "a.toml"), "not found"),
             (("robot", "init", tmp_path / "model.obj", "-o", tmp_path / "a.toml"), "unknown robot model format"),
             (("robot", "init", tmp_path, "-o", tmp_path / "a.toml"), "unknown robot model format"),
             (("robot", "init", model, "-o", tmp_path), "is a directory"),
             (("robot", "init", model, "-o", tmp_path / "a.json"), "expected .toml"),
             (("robot", "init", model, "-o", tmp_path / "a.toml", "--keyframe", "sit"), "no keyframe named 'sit'"),
             (("robot", "check", tmp_path / "missing.toml"), "missing.toml")]
    for argv, message in cases:
        code, _, err = run(capsys, *argv)
        assert code == 2 and err.count("\n") == 1 and message in err, (argv, err)
    assert not (tmp_path / "a.toml").exists()


def test_check_refuses_a_held_joint_that_does_not_exist(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    spec = tmp_path / "spec.toml"
    run(capsys, "robot", "init", write(tmp_path, biped_xml()), "-o", spec, *SERVO_RULE)
    spec.write_text(spec.read_text().replace("neck_yaw", "neck_roll"))
    code, out, err = run(capsys, "robot", "check", spec)
    assert code == 2 and out == "" and "unknown held joint name 'neck_roll'" in err


def test_draft_errors_are_input_errors(tmp_path: Path) -> None:
    with pytest.raises(RobustGaitError, match="no free joint"):
        draft_spec(write(tmp_path, biped_xml(freejoint=False, keyframe=False)), RobotConfig())


@needs_t1
def test_a_robot_of_collision_geoms_only_is_rendered(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """T1 without its visual meshes has only collision geoms, in group 3, which MuJoCo hides by default: videos and
    tiles show that group (sim.walk.scene_option), so that the robot is in the picture; exo's are unchanged."""
    import mujoco

    from robustgait import load_robot
    from robustgait.sim.walk import offscreen_renderer, scene_option

    spec = tmp_path / "t1.toml"
    assert run(capsys, "robot", "init", T1, "-o", spec, *SERVO_RULE)[0] == 0
    for robot, groups in ((load_robot(spec), [1, 1, 1, 1, 0, 0]), (load_robot("exo"), [1, 1, 1, 0, 0, 0])):
        option = scene_option(robot)
        assert list(option.geomgroup) == groups
        m = robot.model
        d = mujoco.MjData(m)
        d.qpos[2] = 1.0
        mujoco.mj_forward(m, d)
        renderer = offscreen_renderer(robot, 160, 120)
        cam = mujoco.MjvCamera()
        cam.type, cam.trackbodyid, cam.distance = mujoco.mjtCamera.mjCAMERA_TRACKING, robot.base_body_id, 2.5
        renderer.update_scene(d, cam)
        default = renderer.render().astype(int)
        renderer.update_scene(d, cam, scene_option=option)
        shown = renderer.render().astype(int)
        renderer.close()
        changed = int((np.abs(default - shown).sum(axis=2) > 30).sum())
        assert (changed > 200) if groups[3] else (changed == 0)
