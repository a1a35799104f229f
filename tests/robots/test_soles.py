"""Where a foot stands (robustgait.robots.soles.sole_up): a foot body whose frame is tilted from its sole — Berkeley
Humanoid's is 10° off its level foot plate — is read along the vertical, not along its own axis (which kept only the
heel's edge and refused the foot), by robot init and by the loader's virtual sole alike."""

from __future__ import annotations

import math
import re
from pathlib import Path

import mujoco
import numpy as np
import pytest

from robustgait import load_robot
from tests.inspection.biped import SERVO_RULE, biped_xml, run, write

TILT = 0.17  # [rad] the foot body's frame pitched from its sole, about Berkeley Humanoid's 10°


def tilted_frame_xml() -> str:
    """The test biped whose foot bodies are pitched by TILT while their unnamed box soles are turned back level, at
    the same place in the world (the box a virtual sole of the foot body's geoms)."""
    c, s = math.cos(TILT), math.sin(TILT)
    x, z = 0.03, -0.05
    gx, gz = c * x - s * z, s * x + c * z  # R_y(TILT)ᵀ (x, 0, z): the box's place in the pitched frame
    xml = biped_xml(foot="unnamed_box")
    for side in ("left", "right"):
        xml = xml.replace(f'<body name="{side}_foot" pos="0 0 0">', f'<body name="{side}_foot" pos="0 0 0" '
                          f'euler="0 {TILT} 0">')
    return xml.replace('<geom type="box" size="0.1 0.05 0.01" pos="0.03 0 -0.05"/>',
                       f'<geom type="box" size="0.1 0.05 0.01" pos="{gx:.9f} 0 {gz:.9f}" euler="0 {-TILT} 0"/>')


def test_a_foot_frame_tilted_from_its_sole_stands_on_the_whole_sole(tmp_path: Path,
                                                                   capsys: pytest.CaptureFixture[str]):
    xml = tilted_frame_xml()
    assert xml.count(f'euler="0 {TILT} 0"') == 2 and xml.count(f'euler="0 {-TILT} 0"') == 2  # the case this is for
    code, out, err = run(capsys, "robot", "init", write(tmp_path, xml), "-o", tmp_path / "b.toml", *SERVO_RULE)
    assert code == 0, err
    lengths = [float(v) for v in re.findall(r"sole 1 unnamed geoms of '\w+', ([0-9.]+) × 0.1 m", out)]
    assert len(lengths) == 2 and min(lengths) > 0.19, out  # the whole box (its length along the tilted frame)
    robot = load_robot(tmp_path / "b.toml")
    d = mujoco.MjData(robot.model)
    d.qpos[robot.qpos_idx] = robot.spec.posture
    mujoco.mj_kinematics(robot.model, d)
    for side, sole in robot.sole_boxes.items():
        assert (sole.half_length, sole.half_width) == (pytest.approx(0.1, abs=1e-3), pytest.approx(0.05, abs=1e-3))
        assert sole.tilt(d) < 1e-3, side  # the virtual sole lies on the box's face, level
    code, out, _ = run(capsys, "robot", "check", tmp_path / "b.toml", "--no-timestep")
    assert "soles: ok" in out and "stand: ok" in out, out
    assert np.isfinite(robot.mass)


def test_a_box_sole_the_keyframe_tilts_is_read_on_its_face(tmp_path: Path, capsys: pytest.CaptureFixture[str]):
    """Apptronik Apollo's case: the foot frame pitched from its box sole (as above) and a keyframe that stands the box
    2.5° off level. Read along the foot's axis or the vertical, only an edge of the box was on the sole ("spans 0 × 0
    m"); a sole that is one box is read along its own face, and robot init levels it."""
    tilt = 0.044  # [rad] ≈ 2.5°
    xml = tilted_frame_xml().replace("0.6 -0.3 0", f"0.6 {-0.3 + tilt:g} 0")
    assert xml.count(f"0.6 {-0.3 + tilt:g} 0") == 2  # both legs' keyframe ankles
    code, out, err = run(capsys, "robot", "init", write(tmp_path, xml), "-o", tmp_path / "b.toml", *SERVO_RULE)
    assert code == 0, err
    lengths = [float(v) for v in re.findall(r"sole 1 unnamed geoms of '\w+', ([0-9.]+) × 0.1 m", out)]
    assert len(lengths) == 2 and min(lengths) > 0.19, out
    assert "the soles were not level in the posture: each ankle turned by up to 0.04" in out
    robot = load_robot(tmp_path / "b.toml")
    d = mujoco.MjData(robot.model)
    d.qpos[robot.qpos_idx] = robot.spec.posture
    mujoco.mj_kinematics(robot.model, d)
    assert all(sole.tilt(d) < 1e-3 for sole in robot.sole_boxes.values())


def test_a_box_sole_turned_in_its_foot_is_measured_as_the_loader_reads_it(tmp_path: Path,
                                                                         capsys: pytest.CaptureFixture[str]):
    """Apptronik Apollo's box sole lies 17° from its foot body's axes. Robot init measured its extent along those
    axes (wider and longer than the box), so its sole width, and what followed from it (the regulator's rule in its
    notes), differed from the loaded robot's box. A sole that is one box is measured by its own sizes."""
    turn = 0.3  # [rad] about the foot's vertical
    xml = biped_xml(foot="box").replace('pos="0.03 0 -0.05"/>', f'pos="0.03 0 -0.05" euler="0 0 {turn}"/>')
    assert xml.count(f'euler="0 0 {turn}"') == 2
    code, _, err = run(capsys, "robot", "init", write(tmp_path, xml), "-o", tmp_path / "b.toml", *SERVO_RULE)
    assert code == 0, err
    sizes = re.findall(r"a box, sole ([0-9.]+) × ([0-9.]+) m", (tmp_path / "b.toml").read_text())
    assert sizes == [("0.2", "0.1")] * 2, sizes  # along the foot's axes: 0.221 × 0.155 m
    robot = load_robot(tmp_path / "b.toml")
    for sole in robot.sole_boxes.values():
        assert (2 * sole.half_length, 2 * sole.half_width) == (pytest.approx(0.2), pytest.approx(0.1))
