"""robot init and robot check end to end (robustgait.robotinit, robustgait.inspection.check) on synthetic bipeds
(MJCF and URDF, tests/inspection/biped.py), on exo and on Booster T1 when ../shared/robots is beside the
repository; bad input refused in one line."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import mujoco
import numpy as np
import pytest

from robustgait import load_robot
from robustgait.config import RobotConfig
from robustgait.errors import RobustGaitError
from robustgait.inspection.check import run_checks
from robustgait.robotinit.draft import draft_spec

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover - exercised on 3.10 only
    import tomli as tomllib

from tests.inspection.biped import EXO_XML, LEFT_LEG, SERVO_RULE, T1, biped_xml, needs_t1, run, write


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
