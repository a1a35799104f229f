"""Robots nobody here tuned (docs/robots.md, "Soles and floor", "Held joints"): soles named by geoms, bodies or
classes (virtual soles over sphere feet), floors found or added, held joints welded for planning, URDF input, the
robot-scaled generation defaults — on a small synthetic biped written here."""

from __future__ import annotations

import textwrap
from pathlib import Path

import mujoco
import numpy as np
import pytest

from robustgait import load_robot
from robustgait.config import GenerationConfig, relative_generation_defaults
from robustgait.errors import RobustGaitError

LEG = """
      <body name="{s}_hip" pos="0 {y} -0.05">
        <joint name="{s}_hip_roll" axis="1 0 0" range="-0.5 0.5"/>
        <inertial pos="0 0 0" mass="0.5" diaginertia="0.001 0.001 0.001"/>
        <body name="{s}_thigh" pos="0 0 -0.02">
          <joint name="{s}_hip_pitch" axis="0 1 0" range="-1.5 1.5"/>
          <inertial pos="0 0 -0.1" mass="1.0" diaginertia="0.005 0.005 0.001"/>
          <geom type="capsule" fromto="0 0 0 0 0 -0.2" size="0.02" contype="0" conaffinity="0"/>
          <body name="{s}_shin" pos="0 0 -0.2">
            <joint name="{s}_knee" axis="0 1 0" range="0 2"/>
            <inertial pos="0 0 -0.1" mass="0.8" diaginertia="0.004 0.004 0.001"/>
            <body name="{s}_ankle" pos="0 0 -0.2">
              <joint name="{s}_ankle_pitch" axis="0 1 0" range="-1 1"/>
              <inertial pos="0 0 0" mass="0.1" diaginertia="0.0001 0.0001 0.0001"/>
              <body {footname} pos="0 0 -0.02">
                <joint name="{s}_ankle_roll" axis="1 0 0" range="-0.5 0.5"/>
                <inertial pos="0 0 -0.02" mass="0.3" diaginertia="0.0005 0.001 0.001"/>
                {foot}
              </body>
            </body>
          </body>
        </body>
      </body>
      <body name="{s}_arm" pos="0 {arm_y} 0.15">
        <joint name="{s}_shoulder" axis="0 1 0" range="-2 2"/>
        <inertial pos="0 0 -0.1" mass="0.4" diaginertia="0.002 0.002 0.0005"/>
      </body>"""
BOX_FOOT = '<geom name="{s}_sole" type="box" size="0.08 0.04 0.01" pos="0.02 0 -0.03"/>'
SPHERE_FOOT = "".join(f'<geom class="foot" type="sphere" size="0.01" pos="{x} {y} -0.03"/>'
                      for x in (-0.05, 0.09) for y in (-0.03, 0.03))


def biped_xml(*, spheres: bool = False, floor: bool = True, named_feet: bool = True) -> str:
    """A 10-joint biped with two shoulder joints (to hold), 5 kg; box soles, or four spheres of class ``foot``."""
    legs = "".join(LEG.format(s=s, y=y, arm_y=2 * y, footname=f'name="{s}_foot"' if named_feet else "",
                              foot=SPHERE_FOOT if spheres else BOX_FOOT.format(s=s))
                   for s, y in (("left", 0.06), ("right", -0.06)))
    return textwrap.dedent(f"""\
        <mujoco model="biped">
          <default><default class="foot"><geom friction="1 0.005 0.0001"/></default></default>
          <worldbody>
            {'<geom name="ground" type="plane" size="0 0 0.05"/>' if floor else ''}
            <body name="torso" pos="0 0 0.5">
              <freejoint/>
              <inertial pos="0 0 0.05" mass="2.0" diaginertia="0.02 0.015 0.01"/>
              {legs}
            </body>
          </worldbody>
        </mujoco>""")


JOINTS = [f"{s}_{j}" for s in ("left", "right") for j in ("hip_roll", "hip_pitch", "knee", "ankle_pitch", "ankle_roll")]


def biped_spec(tmp_path: Path, *, legs: str | None = None, extra: str = "", xml: str | None = None,
               held: str | None = None, mjcf: str = "biped.xml") -> Path:
    if xml is not None:
        (tmp_path / mjcf).write_text(xml)
    legs = legs or '[legs.left]\nsole_geom = "left_sole"\n[legs.right]\nsole_geom = "right_sole"\n'
    held = held if held is not None else textwrap.dedent("""\
        [joints.held]
        left_shoulder = 0.3
        right_shoulder = 0.3
        [joints.held_servo]
        left_shoulder = [40.0, 1.0, 10.0]
        right_shoulder = [40.0, 1.0, 10.0]
        [mirror.held]
        left_shoulder = ["right_shoulder", 1]
        right_shoulder = ["left_shoulder", 1]
        """)
    text = textwrap.dedent(f"""\
        name = "biped"
        mjcf = "{mjcf}"
        base_body = "torso"
        {extra}
        [joints]
        names = {JOINTS}
        kp = {[200.0] * 10}
        kd = {[4.0] * 10}
        torque_limit = {[40.0] * 10}
        """).replace("'", '"') + held + legs + textwrap.dedent("""\
        [mirror]
        joint_perm = [5, 6, 7, 8, 9, 0, 1, 2, 3, 4]
        joint_sign = [-1, 1, 1, 1, -1, -1, 1, 1, 1, -1]
        [fall]
        min_base_height = 0.2
        """)
    (tmp_path / "spec.toml").write_text(text)
    return tmp_path / "spec.toml"


def test_held_joints_are_servos_in_sim_and_welded_for_planning(tmp_path: Path) -> None:
    robot = load_robot(biped_spec(tmp_path, xml=biped_xml()))
    assert robot.model.nu == 12 and robot.n_joints == 10 and robot.model.nq == 7 + 12
    plan = robot.planned
    assert plan.model.nq == 7 + 10 and plan.model.nu == 10 and plan.spec.held == ()
    assert plan.mass == pytest.approx(robot.mass, abs=1e-12)  # welded bodies keep their mass
    # forward kinematics of the welded model = the full model's with the held joints at their angles
    rng = np.random.default_rng(1)
    qp = plan.model.qpos0.copy()
    qp[plan.qpos_idx] = rng.uniform(-0.4, 0.4, 10)
    full, vel = robot.expand_state(qp, np.zeros(plan.model.nv))
    assert np.array_equal(full[robot.held_qpos_idx], [0.3, 0.3]) and not vel.any()
    d, dp = mujoco.MjData(robot.model), mujoco.MjData(plan.model)
    d.qpos[:], dp.qpos[:] = full, qp
    mujoco.mj_fwdPosition(robot.model, d)
    mujoco.mj_fwdPosition(plan.model, dp)
    for b in range(1, plan.model.nbody):
        i = robot.model.body(plan.model.body(b).name).id
        assert np.allclose(d.xipos[i], dp.xipos[b], atol=1e-12) and np.allclose(d.ximat[i], dp.ximat[b], atol=1e-12)
    # the servo controls of a step hold the held joints at their angles
    c = robot.servo_controls(np.zeros((5, 10)))
    assert c.shape == (5, 12) and np.all(c[:, 10:] == 0.3)
    # mirroring twice is the identity, and swaps the two shoulders
    qv = rng.normal(size=robot.model.nv)
    full[robot.held_qpos_idx] = [0.1, 0.2]
    mq, mv = robot.mirror_state(full, qv)
    assert np.array_equal(mq[robot.held_qpos_idx], [0.2, 0.1])
    back = robot.mirror_state(mq, mv)
    assert np.allclose(back[0], full) and np.allclose(back[1], qv)


def test_sphere_feet_get_a_virtual_sole_box(tmp_path: Path) -> None:
    legs = '[legs.left]\nsole_body = "left_foot"\nsole_class = "foot"\n[legs.right]\nsole_body = "right_foot"\n'
    robot = load_robot(biped_spec(tmp_path, xml=biped_xml(spheres=True), legs=legs))
    m = robot.model
    for side in ("left", "right"):
        g = robot.sole_geom_id[side]
        assert m.geom(g).name == f"robustgait_{side}_sole" and m.geom_contype[g] == 0 and m.geom_conaffinity[g] == 0
        # spans the sphere bottoms: 0.14 m × 0.06 m, bottom face at the spheres' lowest point
        assert sorted(m.geom_size[g][:2] * 2) == pytest.approx([0.06, 0.14])
        d = mujoco.MjData(m)
        mujoco.mj_kinematics(m, d)
        bottom = d.geom_xpos[g][2] - m.geom_size[g][2]
        spheres = [i for i in range(m.ngeom) if m.geom_bodyid[i] == m.geom_bodyid[g] and m.geom_type[i] == 2]
        assert len(spheres) == 4
        assert bottom == pytest.approx(min(d.geom_xpos[i][2] - 0.01 for i in spheres), abs=1e-12)
    # standing on the spheres, each sole's contact sensor counts its foot's contacts (4 spheres each)
    d = mujoco.MjData(m)
    mujoco.mj_forward(m, d)
    lowest = min(d.geom_xpos[robot.sole_geom_id[s]][2] - m.geom_size[robot.sole_geom_id[s]][2]
                 for s in ("left", "right"))
    d.qpos[2] -= lowest + 1e-4
    mujoco.mj_forward(m, d)
    for name in ("robustgait_contact_left", "robustgait_contact_right"):
        assert d.sensordata[robot.sensor_adr[name]] == 4


def test_unnamed_box_feet_named_by_body_and_a_floor_added(tmp_path: Path) -> None:
    xml = biped_xml(floor=False).replace('name="left_sole" ', "").replace('name="right_sole" ', "")
    legs = '[legs.left]\nsole_body = "left_foot"\n[legs.right]\nsole_body = "right_foot"\n'
    robot = load_robot(biped_spec(tmp_path, xml=xml, legs=legs, extra="add_floor = true"))
    assert robot.floor_name == "robustgait_floor" and robot.model.geom_type[robot.floor_geom_id] == 0  # a plane
    for side in ("left", "right"):  # a single box is the sole itself, given a name
        g = robot.sole_geom_id[side]
        assert robot.model.geom(g).name == f"robustgait_{side}_sole" and robot.model.geom_contype[g] == 1


def test_the_only_plane_is_the_floor(tmp_path: Path) -> None:
    robot = load_robot(biped_spec(tmp_path, xml=biped_xml()))
    assert robot.floor_name == "ground"


@pytest.mark.parametrize(("change", "message"), [
    ("held:no-servo", "joints.held_servo.left_shoulder: missing"),
    ("held:asym", "joints.held.left_shoulder: the held posture is not left/right symmetric"),
    ("held:unknown", "unknown held joint name 'left_elbow'"),
    ("held:planned", "joints.held.left_knee: is also in joints.names"),
    ("held:missing", "every non-base joint must be in joints.names or joints.held (missing: left_shoulder, "
                     "right_shoulder)"),
    ("legs:two", "legs.left: name the sole with exactly one of sole_geom, sole_geoms or sole_body"),
    ("legs:ellipsoid", "the left sole (geom 'lell') has an ellipsoid geom"),
    ("legs:nofoot", "no sole found for the left leg: body 'left_foot' has no colliding geom of class 'hand'"),
    ("floor:none", "the MJCF's world body has 0 plane geoms: name the floor with floor_geom, or set add_floor"),
    ("floor:twice", "add_floor: the MJCF already has a floor ('ground')"),
])
def test_bad_any_robot_specs(tmp_path: Path, change: str, message: str) -> None:
    xml, legs, extra = biped_xml(), None, ""
    held = None
    servo = "[joints.held_servo]\nleft_shoulder = [40.0, 1.0, 10.0]\nright_shoulder = [40.0, 1.0, 10.0]\n"
    mirror = '[mirror.held]\nleft_shoulder = ["right_shoulder", 1]\nright_shoulder = ["left_shoulder", 1]\n'
    if change == "held:no-servo":
        held = "[joints.held]\nleft_shoulder = 0.3\nright_shoulder = 0.3\n" + mirror
    elif change == "held:asym":
        held = "[joints.held]\nleft_shoulder = 0.3\nright_shoulder = 0.2\n" + servo + mirror
    elif change == "held:unknown":
        held = ("[joints.held]\nleft_elbow = 0.0\nleft_shoulder = 0.0\nright_shoulder = 0.0\n"
                + servo + "left_elbow = [1.0, 1.0, 1.0]\n" + mirror + 'left_elbow = ["left_elbow", 1]\n')
    elif change == "held:planned":
        held = ("[joints.held]\nleft_knee = 0.0\n[joints.held_servo]\nleft_knee = [1.0, 1.0, 1.0]\n"
                '[mirror.held]\nleft_knee = ["left_knee", 1]\n')
    elif change == "held:missing":
        held = ""
    elif change == "legs:two":
        legs = '[legs.left]\nsole_geom = "left_sole"\nsole_body = "left_foot"\n[legs.right]\nsole_geom = "right_sole"\n'
    elif change == "legs:ellipsoid":
        xml = xml.replace('<geom name="left_sole" type="box"', '<geom name="lell" type="ellipsoid"')
        legs = '[legs.left]\nsole_geom = "lell"\n[legs.right]\nsole_geom = "right_sole"\n'
    elif change == "legs:nofoot":
        legs = '[legs.left]\nsole_body = "left_foot"\nsole_class = "hand"\n[legs.right]\nsole_geom = "right_sole"\n'
    elif change == "floor:none":
        xml = biped_xml(floor=False)
    elif change == "floor:twice":
        extra = "add_floor = true"
    with pytest.raises(RobustGaitError) as err:
        load_robot(biped_spec(tmp_path, xml=xml, legs=legs, extra=extra, held=held))
    assert message in str(err.value) and "\n" not in str(err.value)


def test_a_urdf_gets_a_floating_base(tmp_path: Path) -> None:
    # MuJoCo compiles the URDF; its root link is attached to the world, so the loader adds the free joint
    urdf = textwrap.dedent("""\
        <robot name="biped">
          <link name="torso"><inertial><mass value="2"/><inertia ixx="0.02" iyy="0.015" izz="0.01" ixy="0" ixz="0"
            iyz="0"/></inertial></link>""")
    links, joints = [], []
    for s, y in (("left", 0.06), ("right", -0.06)):
        parent = "torso"
        chain = [("hip_roll", "1 0 0", f"0 {y} -0.05"), ("hip_pitch", "0 1 0", "0 0 -0.02"),
                 ("knee", "0 1 0", "0 0 -0.2"), ("ankle_pitch", "0 1 0", "0 0 -0.2"),
                 ("ankle_roll", "1 0 0", "0 0 -0.02")]
        for j, axis, xyz in chain:
            link = f"{s}_{j}_link"
            geom = ('<collision><origin xyz="0.02 0 -0.03"/><geometry><box size="0.16 0.08 0.02"/></geometry>'
                    "</collision>" if j == "ankle_roll" else "")
            links.append(f'<link name="{link}"><inertial><mass value="0.5"/><inertia ixx="0.001" iyy="0.001" '
                         f'izz="0.001" ixy="0" ixz="0" iyz="0"/></inertial>{geom}</link>')
            joints.append(f'<joint name="{s}_{j}" type="revolute"><parent link="{parent}"/><child link="{link}"/>'
                          f'<origin xyz="{xyz}"/><axis xyz="{axis}"/><limit lower="-2" upper="2" effort="40" '
                          'velocity="10"/></joint>')
            parent = link
    urdf += "".join(links) + "".join(joints) + "</robot>"
    (tmp_path / "biped.urdf").write_text(urdf)
    legs = ('[legs.left]\nsole_body = "left_ankle_roll_link"\n[legs.right]\nsole_body = "right_ankle_roll_link"\n')
    robot = load_robot(biped_spec(tmp_path, legs=legs, mjcf="biped.urdf", held="", extra="add_floor = true"))
    assert robot.model.jnt_type[0] == mujoco.mjtJoint.mjJNT_FREE and robot.model.nq == 7 + 10
    assert robot.mass == pytest.approx(2.0 + 10 * 0.5)


def test_generation_options_scale_with_the_robot(tmp_path: Path) -> None:
    robot = load_robot(biped_spec(tmp_path, xml=biped_xml()))
    rules = relative_generation_defaults(robot.scale)
    assert rules["min_normal_force"] == pytest.approx(0.04 * robot.mass * 9.81)
    assert rules["cop_margin"] == pytest.approx(0.04 / 3)  # a third of the sole's half-width
    resolved = GenerationConfig().for_robot(robot.scale, robot.spec.generation)
    assert resolved.min_normal_force == rules["min_normal_force"]
    assert GenerationConfig(min_normal_force=7.0).for_robot(robot.scale).min_normal_force == 7.0  # config wins
    exo = load_robot("exo")  # exo's spec keeps the values its published gaits were made with
    assert GenerationConfig().for_robot(exo.scale, exo.spec.generation).min_normal_force == 50.0
    assert relative_generation_defaults(exo.scale)["min_normal_force"] == pytest.approx(50.0, rel=0.02)
