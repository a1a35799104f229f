import numpy as np
import pytest

from robustgait import RobustGaitError, load_robot
from robustgait.io.robotfile import shipped_robots
from robustgait.robots.spec import SHIPPED_DIR
from tests.conftest import ATALANTE_DIR, ATALANTE_SPEC, needs_atalante


@pytest.fixture(scope="module", params=["exo", "atalante"])
def any_robot(request):  # type: ignore[no-untyped-def]
    return request.getfixturevalue(request.param)


def test_spec_loads_with_pd_servos(any_robot):
    robot = any_robot
    assert robot.n_joints == 12 and 100.0 <= robot.mass <= 135.0
    m = robot.model
    assert m.nu == 12 and m.opt.timestep == 0.001
    np.testing.assert_array_equal(m.actuator_gainprm[:, 0], robot.kp)
    np.testing.assert_array_equal(-m.actuator_biasprm[:, 1], robot.kp)
    np.testing.assert_array_equal(-m.actuator_biasprm[:, 2], robot.kd)
    np.testing.assert_array_equal(m.actuator_forcerange[:, 1], robot.torque_limit)
    # actuator i drives joint i of the spec's output order
    np.testing.assert_array_equal(m.actuator_trnid[:, 0], [m.joint(j).id for j in robot.spec.joints])


@needs_atalante
def test_atalante_mass(atalante):
    assert abs(atalante.mass - 133.49) < 0.01


def test_pd_servo_torque_law(any_robot):
    """u = kp (c − q) − kd q̇, clamped at the torque limit."""
    import mujoco

    robot = any_robot
    d = mujoco.MjData(robot.model)
    d.qpos[2] = 2.0
    d.qvel[robot.dof_idx] = 0.3
    d.ctrl[:] = 0.001
    mujoco.mj_forward(robot.model, d)
    q = d.qpos[robot.qpos_idx]
    expect = np.clip(robot.kp * (0.001 - q) - robot.kd * 0.3, -robot.torque_limit, robot.torque_limit)
    np.testing.assert_allclose(d.actuator_force, expect, rtol=1e-12)


def spec_text(robot: str) -> str:
    """A robot's spec TOML with its MJCF path made absolute (so the text works from any directory)."""
    if robot == "exo":
        return (SHIPPED_DIR / "exo" / "spec.toml").read_text().replace(
            'mjcf = "exo.xml"', f'mjcf = "{SHIPPED_DIR / "exo" / "exo.xml"}"')
    return ATALANTE_SPEC.read_text().replace("../../../shared/atalante/", f"{ATALANTE_DIR}/")


BAD_SPECS = {
    "exo": [
        ('"left_ankle_roll"', '"left_ankle_rol"', "unknown joint name 'left_ankle_rol'"),
        ('sole_geom = "left_sole"', 'sole_geom = "left_foot"', "unknown geom name 'left_foot'"),
        ('floor_geom = "floor"', 'floor_geom = "ground"', "unknown geom name 'ground'"),
        ('base_body = "pelvis"', 'base_body = "left_thigh"', "has no free joint"),
        ("joint_perm = [6, 7, 8, 9, 10, 11, 0, 1, 2, 3, 4, 5]", "joint_perm = [6, 7, 8, 9, 10, 11, 0, 1, 2, 3, 4, 4]",
         "permutation"),
        ("kd = [400, 120,", "kd = [400,", "joints.kd: must be a list of 12 numbers"),
        ('name = "exo"\n', 'name = "exo\n', "malformed TOML"),
        ("mjcf = ", 'mjcf = "nowhere.xml"\n# ', "MJCF file not found"),
    ],
    "atalante": [
        ("LeftSagittalKneeJoint", "LeftKnee", "unknown joint name 'LeftKnee'"),
        ('floor_geom = "terrain_mesh"', 'floor_geom = "ground"', "unknown geom name 'ground'"),
        ('base_body = "torso"', 'base_body = "LeftFrontalHipLink"', "has no free joint"),
    ],
}


@pytest.mark.parametrize("robot, old, new, message", [(r, *case) for r, cases in BAD_SPECS.items() for case in cases])
def test_bad_specs(tmp_path, robot, old, new, message):
    if robot == "atalante" and not (ATALANTE_DIR / "loadedExo.xml").is_file():
        pytest.skip("../shared/atalante (AMBER lab model) is not beside the repository")
    text = spec_text(robot)
    assert old in text
    p = tmp_path / "bad.toml"
    p.write_text(text.replace(old, new))
    with pytest.raises(RobustGaitError, match=message) as err:
        load_robot(p)
    msg = str(err.value)
    assert "\n" not in msg and ("bad.toml" in msg or "nowhere.xml" in msg)


def test_unknown_robot_and_missing_spec(tmp_path):
    with pytest.raises(RobustGaitError, match="unknown robot"):
        load_robot("no-such-robot")
    with pytest.raises(RobustGaitError, match="robot spec file not found"):
        load_robot(tmp_path / "missing.toml")


def test_shipped_robots_listed():
    assert "exo" in shipped_robots()


def test_exo_spec_has_gait_quality_action_space_and_posture():
    spec = load_robot("exo").spec
    q = spec.gait_quality
    assert 0 < q.pelvis_roll < 0.2 and q.pelvis_pitch[0] < q.pelvis_pitch[1] and len(q.joint_velocity) == 12
    assert set(spec.action_space) == {"step_length", "step_duration", "step_width", "step_height"}
    assert spec.action_space["step_length"].grid() == (0.1, 0.12, 0.14, 0.16, 0.18, 0.2, 0.22)
    assert spec.posture[spec.joints.index("left_knee")] == 0.3 and len(spec.posture) == 12


@pytest.mark.parametrize("extra, message", [
    ("[gait_quality]\npelvis_roll = -0.1\n", r"gait_quality.pelvis_roll: must satisfy 0 < x ≤ π rad \(got -0.1\)"),
    ("[gait_quality]\npelvis_pitch = [0.2, 0.1]\n", "gait_quality.pelvis_pitch: must be .low, high. with low < high"),
    ("[gait_quality]\nroll = 0.1\n", r"gait_quality.roll: unknown key \(known: pelvis_roll, "),
    ("[gait_quality]\njoint_velocity = [1, 2]\n", "gait_quality.joint_velocity: must be one number or a list of 12"),
    ("[action_space]\nstep_length = [0.1, 0.2, 0.05]\n", "action_space.step_duration: required, but missing"),
    ("[posture]\nleft_elbow = 0.2\n", "posture.left_elbow: not a planned joint"),
    ("[action_space.multicontact]\nstep_length = [0.1, 0.2, 0.02]\nstep_duration = [0.8, 1.1, 0.1]\n"
     "step_width = [0.22, 0.28, 0.02]\nstep_height = [0.04, 0.1, 0.02]\nrolling_fraction = [0.01, 0.2, 0.05]\n",
     r"action_space.multicontact.rolling_fraction: .* must lie within the bounds of GaitParams.rolling_fraction"),
])
def test_bad_gait_quality_action_space_posture(tmp_path, extra, message):
    import re

    text = spec_text("exo")
    section = extra.split("]")[0] + "]"
    text = re.sub(re.escape(section) + r"\n(?:[^\[].*\n|\n)*", "", text)  # drop the shipped section
    assert section not in text
    p = tmp_path / "bad.toml"
    p.write_text(text + "\n" + extra)
    with pytest.raises(RobustGaitError, match=message):
        load_robot(p)
