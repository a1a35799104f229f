"""The posture robot init writes (robustgait.robotinit.posture): a model whose centre of mass stands over the soles'
rear edge (a keyframe-less model on straight legs, as Menagerie's H1) is leaned at the ankles until the mass stands
over the middle of its soles, the pelvis and soles kept level; a model standing well over its soles keeps its
posture."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from robustgait.config import RobotConfig
from robustgait.inspection.discover import find_legs
from robustgait.inspection.mirror import find_mirror
from robustgait.inspection.model import open_model
from robustgait.robotinit.posture import centre_over_soles, com_over_soles
from tests.inspection.biped import SERVO_RULE, biped_xml, run, write


def heel_heavy_xml() -> str:
    """The test biped with its sole boxes moved 7 cm forward: its centre of mass stands over their rear tenth."""
    return biped_xml().replace('size="0.1 0.05 0.01" pos="0.03 0 -0.05"', 'size="0.1 0.05 0.01" pos="0.1 0 -0.05"')


def test_a_mass_over_the_heels_is_brought_over_the_middle_of_the_soles(tmp_path: Path):
    cfg = RobotConfig()
    robot = open_model(write(tmp_path, heel_heavy_xml()))
    legs = find_legs(robot, cfg.foot_level, cfg.sole_tolerance)
    com, rear, front = com_over_soles(robot, legs, robot.angles)
    assert (com - rear) / (front - rear) < (1 - cfg.stand_fraction) / 2  # the case this is for
    before = dict(robot.angles)
    lean = centre_over_soles(robot, legs, find_mirror(robot, cfg.mirror_tolerance), cfg.stand_fraction)
    assert 0.0 < lean < 0.5
    com, rear, front = com_over_soles(robot, legs, robot.angles)
    assert com == pytest.approx((rear + front) / 2, abs=2e-4)
    changed = {robot.joint_name(j) for j in robot.angles if robot.angles[j] != before[j]}
    assert changed == {f"{s}_{j}" for s in ("left", "right") for j in ("hip_pitch", "ankle_pitch")}
    # soles and pelvis keep their orientation: ankle and hip pitch turned by opposite angles, the knees unchanged
    left = {robot.joint_name(j): robot.angles[j] - before[j] for j in robot.angles}
    assert left["left_ankle_pitch"] == pytest.approx(-left["left_hip_pitch"], abs=1e-12)
    assert left["right_ankle_pitch"] == pytest.approx(left["left_ankle_pitch"], abs=1e-12)


def test_robot_init_says_it_and_the_leaned_biped_stands(tmp_path: Path, capsys: pytest.CaptureFixture[str]):
    xml = write(tmp_path, heel_heavy_xml())
    code, out, err = run(capsys, "robot", "init", xml, "-o", tmp_path / "b.toml", *SERVO_RULE)
    assert code == 0, err
    assert "legs leaned by" in out and "legs leaned at the ankles" in (tmp_path / "b.toml").read_text()
    code, out, err = run(capsys, "robot", "check", tmp_path / "b.toml", "--no-timestep")
    assert "stand: ok" in out, out + err


def test_a_model_standing_over_its_soles_keeps_its_posture(tmp_path: Path):
    cfg = RobotConfig()
    robot = open_model(write(tmp_path, biped_xml()))
    legs = find_legs(robot, cfg.foot_level, cfg.sole_tolerance)
    before = dict(robot.angles)
    assert centre_over_soles(robot, legs, find_mirror(robot, cfg.mirror_tolerance), cfg.stand_fraction) == 0.0
    assert robot.angles == before and np.isfinite(list(before.values())).all()
