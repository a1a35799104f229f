"""Closed-chain legs (robustgait.robots.legs.closed_chain; docs/robots.md, "Your robot: robot init and robot
check"): an ankle driven through a rod — an equality constraint that ties a body or joint of a leg — is refused in
one line naming the constraint and what a user changes, by robot init and by the loader; an equality elsewhere (the
arms) is a note."""

from __future__ import annotations

import re
from pathlib import Path

import mujoco
import pytest

from robustgait import load_robot
from robustgait.errors import RobustGaitError
from robustgait.robots.legs import closed_chain, subtree
from tests.inspection.test_inspection import SERVO_RULE, biped_xml, run, write


def with_equality(xml: str, equality: str, bodies: str = "") -> str:
    """The test biped with ``equality`` (MJCF elements) in an ``<equality>`` block, and ``bodies`` (MJCF, with
    ``{s}`` for the side) inside each shin."""
    if bodies:
        for s in ("left", "right"):
            xml = re.sub(rf'(<body name="{s}_shin"[^>]*>)', lambda m, s=s: m.group(1) + bodies.format(s=s), xml)
    return xml.replace("</mujoco>", f"<equality>{equality}</equality></mujoco>")


CRANK = ('<body name="{s}_crank" pos="0 0 -0.1"><joint name="{s}_crank_joint" axis="0 1 0"/>'
         '<geom type="capsule" fromto="0 0 0 0.03 0 0" size="0.01" mass="0.05"/></body>')
RODS = ''.join(f'<connect name="{s}_ankle_rod" body1="{s}_crank" body2="{s}_foot" anchor="0.03 0 0"/>'
               for s in ("left", "right"))
COUPLED = '<joint name="knee_to_ankle" joint1="left_ankle_pitch" joint2="left_knee" polycoef="0 -0.5 0 0 0"/>'


def test_a_rod_driven_ankle_is_refused_by_robot_init_in_one_line(tmp_path: Path,
                                                                 capsys: pytest.CaptureFixture[str]) -> None:
    model = write(tmp_path, with_equality(biped_xml(keyframe=False), RODS, CRANK))  # the cranks shift its qpos
    spec = tmp_path / "biped.toml"
    code, _, err = run(capsys, "robot", "init", model, "-o", spec, *SERVO_RULE)
    assert code == 2 and not spec.exists()
    line = err.strip()
    assert "\n" not in line and line.startswith("robustgait: error:")
    assert ("the left leg is a closed chain: equality constraint 'left_ankle_rod' (connect) ties 'left_crank' to "
            "'left_foot'") in line
    assert "model the leg as a serial chain" in line


def test_the_constraint_is_found_in_the_leg_it_ties_and_nowhere_else(tmp_path: Path) -> None:
    m = mujoco.MjModel.from_xml_path(str(write(tmp_path, with_equality(biped_xml(), COUPLED))))
    left, right, torso = m.body("left_hip").id, m.body("right_hip").id, m.body("torso").id
    assert m.body("left_foot").id in subtree(m, left) and m.body("right_foot").id not in subtree(m, left)
    assert closed_chain(m, left) == ("equality constraint 'knee_to_ankle' (joint) ties 'left_ankle_pitch' to "
                                     "'left_knee'")
    assert closed_chain(m, right) is None and torso not in subtree(m, left)
    serial = mujoco.MjModel.from_xml_path(str(write(tmp_path, biped_xml(), "serial.xml")))
    assert closed_chain(serial, serial.body("left_hip").id) is None


def test_the_loader_refuses_a_spec_whose_model_ties_a_leg(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    model = write(tmp_path, biped_xml())
    spec = tmp_path / "biped.toml"
    code, _, err = run(capsys, "robot", "init", model, "-o", spec, *SERVO_RULE)
    assert code == 0, err
    load_robot(spec)  # the serial legs load
    write(tmp_path, with_equality(biped_xml(), COUPLED))  # the same file, its left knee now drives the ankle
    with pytest.raises(RobustGaitError, match="the left leg is a closed chain: equality constraint 'knee_to_ankle'"):
        load_robot(spec)


def test_an_equality_outside_the_legs_is_a_note(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    arms = '<joint name="elbows" joint1="left_elbow" joint2="right_elbow" polycoef="0 1 0 0 0"/>'
    model = write(tmp_path, with_equality(biped_xml(), arms))
    code, out, err = run(capsys, "robot", "init", model, "-o", tmp_path / "b.toml", *SERVO_RULE)
    assert code == 0, err
    assert "note: the model has 1 equality constraint (closed linkages?)" in out
