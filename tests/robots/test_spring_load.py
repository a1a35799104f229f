"""A posture as it stands on springs (robustgait.inspection.gains.settle_springs, robotinit.posture.level_under_load,
robot check's loaded posture; docs/robots.md, "Closed chains, springs and line feet"), on the inline closed-chain
biped of tests/robots/test_loops.py with its knees bent, so that its shin springs carry the weight."""

from __future__ import annotations

from pathlib import Path

import mujoco
import numpy as np
import pytest

from robustgait import load_robot
from robustgait.config import RobotCheckConfig
from robustgait.inspection.check import check_soles, check_stand, inspected, loaded, standing_qpos
from robustgait.inspection.gains import settle_springs, standing_loads, static_torques
from robustgait.inspection.model import open_model
from robustgait.robots.spec import SIDES
from tests.inspection.biped import SERVO_RULE, run, write
from tests.robots.test_loops import chain_xml

LEG = "0 -0.3 1 0 0 0 0.6 0 0 -0.3"  # hip roll, hip pitch, rod quaternion, knee, spring, tarsus, foot


def bent_xml(stiffness: float = 200.0, spring_range: str = "-0.3 0.3") -> str:
    """The chain biped standing on bent knees (keyframe ``home``), its shin springs ``stiffness`` [N m/rad]."""
    return (chain_xml(keyframe=f"0 0 0.9 1 0 0 0  {LEG}  {LEG}")
            .replace('stiffness="800" range="-0.3 0.3"', f'stiffness="{stiffness:g}" range="{spring_range}"'))


def test_standing_loads_split_the_weight_without_internal_forces(tmp_path: Path) -> None:
    r = open_model(write(tmp_path, bent_xml(), "bent.xml"), "home")
    m = r.model
    feet = [m.body(f"{s}_foot").id for s in SIDES]
    q = r.qpos(height=0.9)
    tau = standing_loads(r, q, feet)
    spring = {s: m.jnt_dofadr[m.joint(f"{s}_shin_spring").id] for s in SIDES}
    # a symmetric stance: each spring holds the same torque, the half weight's on its leg
    assert tau[spring["left"]] == pytest.approx(tau[spring["right"]], rel=1e-6)
    assert abs(tau[spring["left"]]) > 1.0
    assert np.allclose(tau[:6], 0.0)
    # the passive joints that are not springs hold nothing: the loops do
    assert abs(tau[m.jnt_dofadr[m.joint("left_tarsus").id]]) < 1e-8
    # the servos' least torques (static_torques) let the feet push against each other and unload the springs
    assert abs(static_torques(r, q, feet)[spring["left"]]) < abs(tau[spring["left"]])


def test_settled_springs_are_where_the_robot_stands_still(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    model = write(tmp_path, bent_xml(), "bent.xml")
    spec = tmp_path / "bent.toml"
    code, out, err = run(capsys, "robot", "init", model, "-o", spec, *SERVO_RULE)
    assert code == 0, err
    assert "the springs deflect under the robot's weight standing on both feet (left_shin_spring" in out
    robot = load_robot(spec)
    m = robot.model
    adr = [m.jnt_qposadr[m.joint(f"{s}_shin_spring").id] for s in SIDES]

    def moved(rm_qpos: np.ndarray) -> float:
        """How far the springs move in the first 50 ms standing under the servos."""
        d = mujoco.MjData(m)
        d.qpos[:] = rm_qpos
        d.ctrl[:] = robot.servo_controls(np.asarray(robot.spec.posture))
        start = d.qpos[adr].copy()
        for _ in range(round(0.05 / robot.dt)):
            mujoco.mj_step(m, d)
        return float(np.abs(d.qpos[adr] - start).max())

    rigid, settled = inspected(robot), loaded(robot)
    deflection = float(abs(settled.qpos()[adr[0]] - rigid.qpos()[adr[0]]))
    assert deflection > 0.02
    assert moved(standing_qpos(robot, settled)) < 0.2 * deflection  # in equilibrium: it barely moves
    assert moved(standing_qpos(robot, rigid)) > 0.5 * deflection  # undeflected: it drops onto its springs


def test_robot_init_levels_the_soles_as_the_robot_stands_on_its_springs(tmp_path: Path,
                                                                        capsys: pytest.CaptureFixture[str]) -> None:
    model = write(tmp_path, bent_xml(), "bent.xml")
    spec = tmp_path / "bent.toml"
    assert run(capsys, "robot", "init", model, "-o", spec, *SERVO_RULE)[0] == 0
    robot = load_robot(spec)
    rm = inspected(robot)  # the posture with its springs rigid: the weight would turn its feet
    d = rm.kinematics(standing_qpos(robot, rm))
    assert min(robot.sole_boxes[s].tilt(d) for s in SIDES) > 0.02
    soles = check_soles(robot, RobotCheckConfig())
    assert soles.passed and soles.values["tilt"] < 1e-4  # as it stands: level
    assert check_stand(robot, RobotCheckConfig()).passed


def test_settling_moves_only_the_springs_and_closes_the_loops(tmp_path: Path) -> None:
    r = open_model(write(tmp_path, bent_xml(), "bent.xml"), "home")
    m = r.model
    before = dict(r.angles)
    angles = settle_springs(r, [m.body(f"{s}_foot").id for s in SIDES])
    assert set(angles) == {m.joint(f"{s}_shin_spring").id for s in SIDES}
    for j in r.joints:  # planned joints stay
        assert r.angles[j] == before[j]
    assert max(r.loop_residuals().values()) < 1e-6
    # settled: the spring's torque k (ref − q) is the load at its own deflection
    tau = standing_loads(r, r.qpos(), [m.body(f"{s}_foot").id for s in SIDES])
    for s in r.springs:
        assert s.stiffness * (s.springref - r.angles[s.joint]) == pytest.approx(tau[m.jnt_dofadr[s.joint]], rel=1e-6)


def test_a_spring_the_weight_would_push_out_of_its_range_is_one_line(tmp_path: Path,
                                                                     capsys: pytest.CaptureFixture[str]) -> None:
    model = write(tmp_path, bent_xml(spring_range="-0.005 0.005"), "bent.xml")
    code, _, err = run(capsys, "robot", "init", model, "-o", tmp_path / "b.toml", *SERVO_RULE)
    line = err.strip()
    assert code == 2 and "\n" not in line and not (tmp_path / "b.toml").exists()
    assert "spring 'left_shin_spring' (200 N m/rad) would deflect to" in line
    assert "outside its range [-0.005, 0.005]" in line
