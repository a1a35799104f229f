"""Closed chains, springs and line feet read from a model (robustgait.robots.loops, robotinit; docs/robots.md, "Closed
chains, springs and line feet"), on an inline biped whose legs are Cassie's in miniature: a knee driving a passive
tarsus through a rod on a ball joint connected to the tarsus (a four-bar), a shin spring, and a line foot (one
capsule)."""

from __future__ import annotations

import re
import sys
from pathlib import Path

import mujoco
import numpy as np
import pytest

from robustgait import load_robot
from robustgait.errors import RobustGaitError
from robustgait.inspection.check import inspected
from robustgait.inspection.model import open_model
from robustgait.robots.loops import (
    close_loops,
    closed_chains,
    closed_state,
    find_springs,
    loop_residuals,
    loop_rows,
    padded_state,
    reduced_state,
    undriven_motion,
)
from tests.inspection.biped import SERVO_RULE, run, write

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib


def leg(s: str, y: float, damped: bool = False) -> str:
    """One leg: hip roll, hip pitch (motors), a knee (motor) carrying a shin spring and a passive tarsus, a rod on a
    ball joint from the thigh connected to a heel point of the tarsus, a foot (motor) with one capsule along it.
    ``damped``: joint damping and motor armature as Cassie's model has them (:data:`DAMPING`)."""
    text = _leg(s, y)
    if damped:
        for joint, extra in DAMPING.items():
            text = text.replace(f'<joint name="{s}_{joint}"', f'<joint name="{s}_{joint}" {extra}')
    return text


# what Menagerie's Cassie puts on its joints: damping 1 N m s/rad and a rotor's armature (0.05 kg m²; Cassie's
# 0.012–0.093) on the motors, 0.01 on the rod's ball (its spin about its own axis is free) and 0.1 on the spring and
# the tarsus; without them the undamped spring and the rod's spin leave the walk's switching states unconverged in the
# timestep (robot check's timestep)
DAMPING = {"hip_roll": 'damping="1" armature="0.05"', "hip_pitch": 'damping="1" armature="0.05"',
           "knee": 'damping="1" armature="0.05"', "foot": 'damping="1" armature="0.05"',
           "rod_ball": 'damping="0.01"', "shin_spring": 'damping="0.1"', "tarsus": 'damping="0.1"'}


def _leg(s: str, y: float) -> str:
    return f"""
      <body name="{s}_hip" pos="0 {y} 0">
        <joint name="{s}_hip_roll" axis="1 0 0" range="-0.5 0.5"/>
        <inertial pos="0 0 0" mass="1" diaginertia="0.01 0.01 0.01"/>
        <body name="{s}_thigh">
          <joint name="{s}_hip_pitch" axis="0 1 0" range="-1 1"/>
          <inertial pos="0 0 -0.2" mass="3" diaginertia="0.03 0.03 0.005"/>
          <geom type="capsule" fromto="0 0 0 0 0 -0.4" size="0.04"/>
          <body name="{s}_rod" pos="-0.06 0 -0.05">
            <joint name="{s}_rod_ball" type="ball"/>
            <inertial pos="0 0 -0.2" mass="0.1" diaginertia="0.001 0.001 0.00001"/>
          </body>
          <body name="{s}_knee_link" pos="0 0 -0.4">
            <joint name="{s}_knee" axis="0 1 0" range="0 1.5"/>
            <inertial pos="0 0 -0.05" mass="0.5" diaginertia="0.001 0.001 0.001"/>
            <body name="{s}_shin">
              <joint name="{s}_shin_spring" axis="0 1 0" stiffness="800" range="-0.3 0.3"/>
              <inertial pos="0 0 -0.2" mass="1" diaginertia="0.01 0.01 0.001"/>
              <geom type="capsule" fromto="0 0 0 0 0 -0.35" size="0.03"/>
              <body name="{s}_tarsus" pos="0 0 -0.35">
                <joint name="{s}_tarsus" axis="0 1 0" range="-1.5 1.5"/>
                <inertial pos="0 0 -0.05" mass="0.5" diaginertia="0.002 0.002 0.0005"/>
                <body name="{s}_foot" pos="0 0 -0.1">
                  <joint name="{s}_foot" axis="0 1 0" range="-1 1"/>
                  <inertial pos="0.02 0 -0.02" mass="0.3" diaginertia="0.001 0.001 0.001"/>
                  <geom type="capsule" fromto="-0.06 0 -0.03 0.1 0 -0.03" size="0.02"/>
                </body>
              </body>
            </body>
          </body>
        </body>
      </body>"""


# the default keyframe: every joint at 0, the legs straight
STRAIGHT = "0 0 0.95 1 0 0 0  0 0 1 0 0 0 0 0 0 0  0 0 1 0 0 0 0 0 0 0"
# a keyframe with the knees bent: the straight legs put the rod parallel to the shin, where the loop holds the tarsus
# only to second order; standing there, the tarsi turn and the robot tips (robot check's stand)
BENT = "0 0 0.95 1 0 0 0  0 -0.3 1 0 0 0 0.6 0 0 0  0 -0.3 1 0 0 0 0.6 0 0 0"


def chain_xml(keyframe: str = STRAIGHT, damped: bool = False) -> str:
    """The biped (legs of :func:`leg`; qpos per leg: hip roll, hip pitch, rod quaternion, knee, spring, tarsus, foot)
    with a connect of each rod's end (0.35 m down the rod) to its tarsus, and a keyframe ``home``. At every joint 0 the
    rod's end sits 0.05 m behind and 0.05 m above the tarsus's heel point: the keyframe's loop is open until solved.
    ``damped``: Cassie's joint damping and armature (:data:`DAMPING`)."""
    connects = "".join(f'<connect name="{s}_achilles" body1="{s}_rod" body2="{s}_tarsus" anchor="0 0 -0.35"/>'
                       for s in ("left", "right"))
    motors = "".join(f'<motor joint="{s}_{j}" ctrlrange="-50 50"/>' for s in ("left", "right")
                     for j in ("hip_roll", "hip_pitch", "knee", "foot"))
    return f"""<mujoco model="chain biped">
      <compiler angle="radian" autolimits="true"/>
      <option timestep="0.001" integrator="implicitfast"/>
      <worldbody>
        <geom name="floor" type="plane" size="0 0 0.05"/>
        <body name="pelvis" pos="0 0 0.95">
          <freejoint/>
          <inertial pos="0 0 0.05" mass="8" diaginertia="0.1 0.08 0.08"/>
          <geom type="box" size="0.08 0.14 0.06" pos="0 0 0.06"/>
          {leg("left", 0.1, damped)}{leg("right", -0.1, damped)}
        </body>
      </worldbody>
      <equality>{connects}</equality>
      <actuator>{motors}</actuator>
      <keyframe><key name="home" qpos="{keyframe}"/></keyframe>
    </mujoco>"""


def test_loops_passive_joints_and_springs_are_read(tmp_path: Path) -> None:
    m = mujoco.MjModel.from_xml_path(str(write(tmp_path, chain_xml(), "chain.xml")))
    loops, passive = closed_chains(m)
    assert [lp.key for lp in loops] == ["left_achilles", "right_achilles"]
    assert loops[0].kind == "connect" and loops[0].ends == ("left_rod", "left_tarsus")
    names = {m.joint(j).name for j in loops[0].joints}
    assert names == {"left_rod_ball", "left_knee", "left_shin_spring", "left_tarsus"}
    # the ball joint, the spring and the tarsus are passive; the knee has a motor
    assert {m.joint(j).name for j in passive} == {f"{s}_{j}" for s in ("left", "right")
                                                 for j in ("rod_ball", "shin_spring", "tarsus")}
    springs = find_springs(m, passive)
    assert [(m.joint(sp.joint).name, sp.stiffness, sp.springref) for sp in springs] == [
        ("left_shin_spring", 800.0, 0.0), ("right_shin_spring", 800.0, 0.0)]


def test_the_loop_closes_and_only_the_rods_spin_is_free(tmp_path: Path) -> None:
    m = mujoco.MjModel.from_xml_path(str(write(tmp_path, chain_xml(), "chain.xml")))
    loops, passive = closed_chains(m)
    solved = tuple(j for j in passive if m.jnt_stiffness[j] == 0)
    q0 = m.key_qpos[0].copy()
    q0[m.jnt_qposadr[m.joint("left_knee").id]] = q0[m.jnt_qposadr[m.joint("right_knee").id]] = 0.4
    before = loop_residuals(m, q0, loops)
    assert min(before.values()) > 0.01  # open by centimetres
    q = close_loops(m, q0, loops, solved, 1e-4)
    assert max(loop_residuals(m, q, loops).values()) <= 1e-6  # the tolerance / 100
    for name in ("left_knee", "left_shin_spring", "left_hip_pitch"):  # driven joints and springs stay
        adr = m.jnt_qposadr[m.joint(name).id]
        assert q[adr] == pytest.approx(q0[adr], abs=1e-12)
    assert undriven_motion(m, q, loops, solved) is None
    # with the knee solved too, the tarsus and knee turn together: a free motion, named
    knee = m.joint("left_knee").id
    assert undriven_motion(m, q, loops, (*solved, knee)) in {knee, m.joint("left_tarsus").id}


def test_robot_init_writes_loops_springs_and_a_line_foot_that_load(tmp_path: Path,
                                                                 capsys: pytest.CaptureFixture[str]) -> None:
    model = write(tmp_path, chain_xml(), "chain.xml")
    spec = tmp_path / "chain.toml"
    code, out, err = run(capsys, "robot", "init", model, "-o", spec, *SERVO_RULE)
    assert code == 0, err
    raw = tomllib.loads(spec.read_text())
    assert set(raw["joints"]["passive"]) == {f"{s}_{j}" for s in ("left", "right")
                                            for j in ("rod_ball", "shin_spring", "tarsus")}
    assert raw["loops"]["left_achilles"] == ["connect", "left_rod", "left_tarsus"]
    assert raw["springs"]["left_shin_spring"] == [800.0, 0.0]
    assert raw["legs"]["left"]["foot"] == raw["legs"]["right"]["foot"] == "line"
    assert raw["joints"]["names"] == [f"{s}_{j}" for s in ("left", "right") for j in ("hip_roll", "hip_pitch",
                                                                                       "knee", "foot")]
    assert "residual" in spec.read_text() and "4 closed chain" not in out and "2 closed chains" in out
    # line feet balance sideways by foot placement: exo's pelvis roll, not the hips' rule
    assert raw["gait_quality"]["pelvis_roll"] == 0.05 and "the robot balances sideways by foot placement" in out
    assert "the hips balance sideways" not in spec.read_text()
    robot = load_robot(spec)
    box = robot.sole_boxes["left"]
    assert box.half_length == pytest.approx(0.08, abs=1e-3) and box.half_width <= 1e-4
    rm = inspected(robot)  # the loaded robot's posture closes its loops too
    assert max(rm.loop_residuals().values()) < 1e-4


def test_a_loop_that_cannot_close_at_the_keyframe_is_one_line_naming_it(tmp_path: Path,
                                                                       capsys: pytest.CaptureFixture[str]) -> None:
    # the rods tied by sites: each rod's end 5 cm from its ball, its tarsus's point 1 m behind the tarsus's axis (0.7 m
    # below the ball): out of the rod's reach whatever the tarsus's angle
    xml = chain_xml()
    for s in ("left", "right"):
        xml = xml.replace(f'<joint name="{s}_rod_ball" type="ball"/>',
                          f'<joint name="{s}_rod_ball" type="ball"/><site name="{s}_rod_end" pos="0 0 -0.05"/>')
        tarsus = f'<joint name="{s}_tarsus" axis="0 1 0" range="-1.5 1.5"/>'
        xml = xml.replace(tarsus, tarsus + f'<site name="{s}_heel" pos="-1 0 0"/>')
        xml = xml.replace(f'body1="{s}_rod" body2="{s}_tarsus" anchor="0 0 -0.35"',
                          f'site1="{s}_rod_end" site2="{s}_heel"')
    model = write(tmp_path, xml, "chain.xml")
    code, _, err = run(capsys, "robot", "init", model, "-o", tmp_path / "c.toml", *SERVO_RULE)
    line = err.strip()
    assert code == 2 and "\n" not in line and not (tmp_path / "c.toml").exists()
    found = re.search(r"equality '(left|right)_achilles' \(connect of '\1_rod' to '\1_tarsus'\) cannot close at the "
                      r"keyframe 'home': its ends stay ([0-9.]+) mm apart with its passive joints '\1_rod_ball', "
                      r"'\1_tarsus' solved", line)
    assert found is not None, line
    assert float(found.group(2)) > 100.0  # the rod is 0.3 m short at least
    with pytest.raises(RobustGaitError, match="cannot close"):
        open_model(model)


def test_a_spec_that_forgets_a_passive_joint_is_refused(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    model = write(tmp_path, chain_xml(), "chain.xml")
    spec = tmp_path / "chain.toml"
    assert run(capsys, "robot", "init", model, "-o", spec, *SERVO_RULE)[0] == 0
    text = spec.read_text().replace('  "left_tarsus",', "", 1)
    assert text != spec.read_text()
    spec.write_text(text)
    with pytest.raises(RobustGaitError, match=r"joints\.passive: the model's closed chains leave 'left_tarsus'"):
        load_robot(spec)


def test_a_ball_joint_outside_a_loop_is_still_refused(tmp_path: Path) -> None:
    xml = chain_xml().replace("<equality>", "<!--").replace("</equality>", "-->")
    with pytest.raises(RobustGaitError, match="'left_rod_ball' is a ball joint outside any closed chain"):
        open_model(write(tmp_path, xml, "open.xml"))


def test_the_quaternion_of_the_rod_stays_unit(tmp_path: Path) -> None:
    r = open_model(write(tmp_path, chain_xml(), "chain.xml"))
    for quat in r.balls.values():
        assert float(np.linalg.norm(quat)) == pytest.approx(1.0, abs=1e-12)


def test_a_gait_files_state_drops_the_passive_joints_and_closing_it_closes_the_loops(tmp_path: Path) -> None:
    m = mujoco.MjModel.from_xml_path(str(write(tmp_path, chain_xml(), "chain.xml")))
    loops, passive = closed_chains(m)
    rng = np.random.default_rng(1)
    q, v = m.key_qpos[0].copy(), rng.normal(0.0, 0.5, m.nv)
    for s in ("left", "right"):
        q[m.jnt_qposadr[m.joint(f"{s}_knee").id]] = 0.4
    q = close_loops(m, q, loops, tuple(j for j in passive if m.jnt_stiffness[j] == 0), 1e-8)
    qr, vr = reduced_state(m, passive, q, v)
    assert qr.shape == (7 + 8,) and vr.shape == (6 + 8,)  # base, and 4 planned joints per leg
    qp, vp = padded_state(m, passive, qr, vr)
    assert np.array_equal(reduced_state(m, passive, qp, vp)[0], qr)
    qc, vc = closed_state(m, passive, qr, vr)
    assert np.allclose(reduced_state(m, passive, qc, vc)[0], qr, atol=0, rtol=0)
    assert max(loop_residuals(m, qc, loops).values()) < 1e-8
    assert np.allclose(qc[m.jnt_qposadr[[sp.joint for sp in find_springs(m, passive)]]], 0.0)  # springref, at rest
    data = mujoco.MjData(m)
    data.qpos[:] = qc
    _, jac = loop_rows(m, data, loops)
    assert np.abs(jac @ vc).max() < 1e-10  # the passive joints' rates hold the loops
    # the tarsus the loops close is the one they closed before (the same branch)
    tarsus = [m.jnt_qposadr[m.joint(f"{s}_tarsus").id] for s in ("left", "right")]
    assert np.abs(qc[tarsus] - q[tarsus]).max() < 1e-6
