"""Legs without an ankle roll (robustgait.robots.legs, docs/robots.md "Legs without an ankle roll"): an H1-like biped
— the biped of tests/inspection/biped.py with 5-joint legs (hip yaw, roll, pitch, knee, ankle pitch) — is
read as such: robot init writes the gait its legs allow (the step width of parallel legs, the hips'
roll), generation refuses what they do not, and the default gait walks 300 steps and is certified."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from robustgait import load_robot
from robustgait.config import RobotConfig, RobotScale, ScaleRules
from robustgait.inspection.scale import hip_roll_angle, scale
from robustgait.robots.legs import ankle_roll_joint
from tests.inspection.biped import EXO_XML, SERVO_RULE, biped_xml, run, write


def h1_like_xml() -> str:
    """The test biped with 5-joint legs (no ankle roll), on its 0.2 × 0.1 m box soles."""
    return biped_xml(ankle_roll=False)


@pytest.fixture(scope="module")
def h1_spec(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The H1-like biped's spec as robot init writes it with the servo timestep rule (no walk)."""
    from robustgait.cli import main

    d = tmp_path_factory.mktemp("h1")
    xml = write(d, h1_like_xml(), "h1.xml")
    assert main(["robot", "init", str(xml), "-o", str(d / "h1.toml"), *SERVO_RULE]) == 0
    return d / "h1.toml"


def test_the_ankle_roll_is_a_roll_joint_below_the_knee():
    """exo's legs end in an ankle roll; the H1-like legs end in the ankle pitch: no ankle roll, whose spec says so."""
    exo = load_robot("exo")
    assert exo.has_ankle_roll
    assert {s: exo.model.joint(j).name for s, j in exo.ankle_rolls.items() if j is not None} == {
        "left": "left_ankle_roll", "right": "right_ankle_roll"}
    chain = exo.leg_joints["left"]
    assert ankle_roll_joint(exo.model, chain[:-1]) is None  # the same leg cut above its ankle roll


def test_robot_init_writes_the_gait_parallel_legs_allow(h1_spec: Path):
    text = h1_spec.read_text()
    robot = load_robot(h1_spec)
    assert not robot.has_ankle_roll and robot.ankle_rolls == {"left": None, "right": None}
    assert robot.sole_spacing == pytest.approx(0.18, abs=1e-9)
    assert robot.default_params.step_width == pytest.approx(robot.sole_spacing, abs=1e-4)
    space = robot.spec.action_space
    assert space is not None and list(space["step_width"].grid()) == [robot.default_params.step_width]
    assert robot.spec.multicontact_action_space is None and "\n[action_space.multicontact]\n" not in text
    q = robot.spec.gait_quality
    assert q.pelvis_roll == pytest.approx(math.atan(0.09 / 0.2174), abs=2e-3) and q.pelvis_roll > 0.05
    assert q.pelvis_angular_velocity is not None
    assert q.pelvis_angular_velocity >= 2 * math.pi * q.pelvis_roll / robot.default_params.step_duration - 0.01
    assert "no ankle roll" in text


def test_a_width_of_four_digits_is_the_one_value_its_axis_holds(tmp_path: Path) -> None:
    """Legs 0.1807 m apart (Unitree H1's are 0.4057 m): the action space's one width is the [gait] width to the digit,
    not 3 digits of it, which parallel legs could not land at (every grid gait failed to solve)."""
    from robustgait.cli import main

    xml = h1_like_xml().replace('pos="0 0.09 -0.05"', 'pos="0 0.09035 -0.05"').replace(
        'pos="0 -0.09 -0.05"', 'pos="0 -0.09035 -0.05"')
    assert main(["robot", "init", str(write(tmp_path, xml, "h1.xml")), "-o", str(tmp_path / "h1.toml"),
                 *SERVO_RULE]) == 0
    robot = load_robot(tmp_path / "h1.toml")
    assert robot.default_params.step_width == pytest.approx(0.1807, abs=1e-9)
    space = robot.spec.action_space
    assert space is not None and list(space["step_width"].grid()) == [robot.default_params.step_width]


def test_generation_refuses_what_the_legs_cannot_do(h1_spec: Path, capsys: pytest.CaptureFixture[str],
                                                   no_work: None):
    """Another step width, or a multi-contact gait: one line naming the legs' reason, exit 2, nothing written, before
    any gait problem is built (no_work)."""
    out = h1_spec.parent / "g.json"
    code, _, err = run(capsys, "gait", "generate", "--robot", h1_spec, "--step-width", "0.17", "-o", out)
    assert code == 2 and "no ankle roll" in err and "0.18 m apart" in err and len(err.strip().splitlines()) == 1
    code, _, err = run(capsys, "gait", "generate", "--robot", h1_spec, "--domains", "multicontact", "-o", out)
    assert code == 2 and "has no ankle roll" in err and len(err.strip().splitlines()) == 1
    assert not out.exists()


def test_the_scale_rules_of_legs_without_an_ankle_roll():
    """Step width the soles' spacing (one grid value), pelvis roll atan((w/2)/h_u), its rate 2π φ / T; legs with an
    ankle roll keep exo's rules."""
    base: dict[str, float] = dict(leg_length=0.66, standing_height=0.73, mass=29.2, gravity=9.81, hip_spacing=0.18,
                                  sole_length=0.2, sole_width=0.1)
    with_roll = scale(RobotScale(**base), ScaleRules())
    size = RobotScale(**base, ankle_roll=False, sole_spacing=0.1834, upper_body_height=0.22)
    s = scale(size, ScaleRules())
    assert s.gait["step_width"] == 0.1834 and s.action_space["step_width"][:2] == (0.1834, 0.1834)
    assert s.multicontact_action_space is None and with_roll.multicontact_action_space is not None
    assert s.pelvis_roll == pytest.approx(hip_roll_angle(size), rel=1e-2) == pytest.approx(math.atan(0.0917 / 0.22),
                                                                                           rel=1e-2)
    assert with_roll.pelvis_roll == 0.05 and with_roll.gait["step_width"] == 0.18
    assert s.angular_velocity == pytest.approx(2 * math.pi * s.pelvis_roll / s.gait["step_duration"], rel=2e-2)


def test_line_feet_balance_by_foot_placement_not_by_the_hips():
    """Legs without an ankle roll on line feet: a line foot takes no roll moment, so the hip rule (the pelvis rolled
    over the stance foot) does not apply: exo's pelvis roll and its rate; the step width stays the soles' spacing. A
    tread with an area planned as a line (H1's) keeps the hip rule: measured, H1's default gait walks 300 steps with
    it and falls in step 7 without it (docs/robots.md)."""
    base: dict[str, float] = dict(leg_length=1.02, standing_height=1.01, mass=33.3, gravity=9.81, hip_spacing=0.27,
                                  sole_length=0.16, sole_width=0.0, ankle_roll=False, sole_spacing=0.2701,
                                  upper_body_height=0.0284)
    hips = scale(RobotScale(**base), ScaleRules())  # flat soles as narrow: the hips balance sideways
    line = scale(RobotScale(**base, line_feet=True, roll_support=False), ScaleRules())
    assert hips.pelvis_roll > 1.0 and line.pelvis_roll == ScaleRules().pelvis_roll
    # a heel point and a toe bar planned as a line (Unitree H1) take a roll moment: the hips still balance it
    tread = scale(RobotScale(**base, line_feet=True), ScaleRules())
    assert tread.pelvis_roll == hips.pelvis_roll  # its rate 2π φ / T at its own (line feet's) default step
    assert tread.angular_velocity == pytest.approx(2 * math.pi * tread.pelvis_roll / tread.gait["step_duration"],
                                                   rel=2e-2)
    rate = ScaleRules().angular_velocity * math.sqrt(9.81 / 1.02)
    assert hips.angular_velocity > 2 * rate and line.angular_velocity == pytest.approx(rate, rel=1e-2)
    assert line.gait["step_width"] == 0.2701 and line.action_space["step_width"][:2] == (0.2701, 0.2701)


@pytest.mark.slow
def test_the_h1_like_biped_walks_300_steps_and_is_certified(tmp_path: Path, capsys: pytest.CaptureFixture[str]):
    """robot init with its defaults (the timestep by accuracy: the default gait generated and walked at each step),
    robot check passes (its timestep check is that same walk, skipped), the default gait walks 300 steps and is
    certified."""
    from robustgait import certify_gait, generate_gait, walk
    from robustgait.config import SimConfig

    xml = write(tmp_path, h1_like_xml(), "h1.xml")
    code, _, err = run(capsys, "robot", "init", xml, "-o", tmp_path / "h1.toml")
    assert code == 0, err
    code, out, err = run(capsys, "robot", "check", tmp_path / "h1.toml", "--no-timestep")  # init walked it
    assert code == 0, out + err
    robot = load_robot(tmp_path / "h1.toml")
    res = generate_gait(robot, robot.default_params)
    assert res.success and res.gait is not None, res.reason
    walked = walk(robot, res.gait, SimConfig(step_cap=300))
    assert walked.steps_taken == 300 and not walked.fell
    cert = certify_gait(robot, res.gait)
    assert cert.ok and cert.j_star > 0.0, cert.reason


def test_exo_model_is_read_with_its_ankle_roll(tmp_path: Path):
    """The exo MJCF as robot init reads it: both legs end in an ankle roll (nothing of this file applies)."""
    from robustgait.inspection.discover import find_legs
    from robustgait.inspection.model import open_model

    cfg = RobotConfig()
    legs = find_legs(open_model(EXO_XML), cfg.foot_level, cfg.sole_tolerance)
    assert legs.ankle_roll and legs.left.ankle_roll is not None
