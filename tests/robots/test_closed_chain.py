"""Equality constraints of a serial robot's joints (robustgait.robots.loops.find_loops; docs/robots.md, "Closed chains,
springs and line feet"): an equality none of whose joints is passive — every joint servoed — is found in the joints it
ties and kept by MuJoCo, a note of robot init; closed chains with passive joints: tests/robots/test_loops.py."""

from __future__ import annotations

import re
from pathlib import Path

import mujoco
import pytest

from robustgait import load_robot
from robustgait.robots.legs import subtree
from robustgait.robots.loops import find_loops
from tests.inspection.biped import SERVO_RULE, biped_xml, run, write


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


def test_a_rod_whose_joints_all_have_servos_is_a_note_not_a_closed_chain(tmp_path: Path,
                                                                        capsys: pytest.CaptureFixture[str]) -> None:
    """The test biped's legs have no motors and its crank collides: no joint of the rod's loop is passive
    (robots.loops.passive_joints), so the servos drive each of them and MuJoCo keeps the equality, said in a note;
    the spec loads."""
    model = write(tmp_path, with_equality(biped_xml(keyframe=False), RODS, CRANK))
    spec = tmp_path / "biped.toml"
    code, out, err = run(capsys, "robot", "init", model, "-o", spec, *SERVO_RULE)
    assert code == 0, err
    assert "note: the model has 2 equality constraints (closed linkages?)" in out
    assert "[loops]" not in spec.read_text() and "left_crank_joint" in spec.read_text()
    load_robot(spec)


def test_the_constraint_is_found_in_the_leg_it_ties_and_nowhere_else(tmp_path: Path) -> None:
    m = mujoco.MjModel.from_xml_path(str(write(tmp_path, with_equality(biped_xml(), COUPLED))))
    left, right, torso = m.body("left_hip").id, m.body("right_hip").id, m.body("torso").id
    assert m.body("left_foot").id in subtree(m, left) and m.body("right_foot").id not in subtree(m, left)
    (loop,) = find_loops(m)
    assert (loop.key, loop.kind, loop.ends) == ("knee_to_ankle", "joint", ("left_ankle_pitch", "left_knee"))
    assert {m.joint(j).name for j in loop.joints} == {"left_ankle_pitch", "left_knee"}
    assert torso not in subtree(m, left) and right not in subtree(m, left)
    serial = mujoco.MjModel.from_xml_path(str(write(tmp_path, biped_xml(), "serial.xml")))
    assert find_loops(serial) == ()


def test_an_equality_outside_the_legs_is_a_note(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    arms = '<joint name="elbows" joint1="left_elbow" joint2="right_elbow" polycoef="0 1 0 0 0"/>'
    model = write(tmp_path, with_equality(biped_xml(), arms))
    code, out, err = run(capsys, "robot", "init", model, "-o", tmp_path / "b.toml", *SERVO_RULE)
    assert code == 0, err
    assert "note: the model has 1 equality constraint (closed linkages?)" in out
