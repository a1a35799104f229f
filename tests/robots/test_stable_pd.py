"""Stable PD servos (robot spec ``[sim] stable_pd``): the damping kd + h kp in the actuators, the references and the
tracking statistics alike, and the same walk as the explicit servo when the step is small."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from robustgait import load_gait, load_robot
from robustgait.certificate.band import band_coordinates
from robustgait.io.robotfile import read_mjcf
from robustgait.robots import Robot
from robustgait.robots.model import servo_damping
from robustgait.sim import walk
from robustgait.sim.controller import desired_outputs, step_controls
from robustgait.sim.engine import StepEngine
from tests.conftest import EXO_GAIT, REPO


def variant(robot: Robot, **spec: object) -> Robot:
    s = replace(robot.spec, **spec)  # type: ignore[arg-type]
    return Robot(s, read_mjcf(s))


def test_damping_formula() -> None:
    assert servo_damping(1000.0, 20.0, 0.001, True) == pytest.approx(21.0)
    assert servo_damping(1000.0, 20.0, 0.001, False) == 20.0


def test_actuators_references_and_gains_agree() -> None:
    exo = load_robot("exo")
    stable = variant(exo, stable_pd=True)
    h = stable.dt
    assert np.allclose(stable.kd, exo.kd + h * exo.kp) and np.allclose(stable.servo_kd, exo.servo_kd + h * exo.servo_kp)
    # the model's servos apply u = kp (c − q) − (kd + h kp) q̇
    assert np.allclose(stable.model.actuator_biasprm[:, 2], -stable.servo_kd)
    assert np.allclose(stable.model.actuator_gainprm[:, 0], stable.servo_kp)
    # the references carry the same damping: c − y_d differs by h ẏ_d exactly
    gait = load_gait(EXO_GAIT, exo)
    c0, c1 = step_controls(exo, gait, 50), step_controls(stable, gait, 50)
    n = exo.n_joints
    tau = np.arange(50) * (h / gait.domains[0].duration)
    _, dy = desired_outputs(gait, tau, 0)
    assert np.allclose(c1[:, :n] - c0[:, :n], h * dy, atol=1e-12)


def test_converges_to_the_explicit_servo_as_the_step_shrinks() -> None:
    """One step from the settled switching state at h = 0.25 ms: the stable servo's switching state differs from
    the explicit one's by well under the recovery band's floor (0.03 band units); at 1 ms by more (its h kp is 4×)."""
    exo = load_robot("exo")
    gait = load_gait(EXO_GAIT, exo)
    start = walk(exo, gait, steps=6).events[-1]
    q0, v0 = np.array(start.qpos), np.array(start.qvel)
    stance = "left" if start.stance == "right" else "right"
    gaps = []
    for h in (0.00025, 0.001):
        ends = []
        for stable in (False, True):
            robot = variant(exo, stable_pd=stable, timestep=h)
            with StepEngine(robot, load_gait(EXO_GAIT, robot)) as eng:
                b = eng.step(q0[None], v0[None], stance)
            assert not b.fell[0]
            ends.append(band_coordinates(robot, b.qpos, b.qvel)[0])
        gaps.append(float(np.max(np.abs(ends[1] - ends[0]))))
    assert gaps[0] < 0.005 and gaps[0] < gaps[1]


def spec_file(tmp_path, line: str):  # type: ignore[no-untyped-def]
    exo = REPO / "src" / "robustgait" / "robots" / "exo"
    text = (exo / "spec.toml").read_text().replace('mjcf = "exo.xml"', f'mjcf = "{exo / "exo.xml"}"')
    text = text.replace('integrator = "implicitfast"', f'integrator = "implicitfast"\n{line}')
    path = tmp_path / "spec.toml"
    path.write_text(text)
    return path


def test_the_spec_turns_it_on_and_refuses_a_bad_value(tmp_path) -> None:  # type: ignore[no-untyped-def]
    robot = load_robot(spec_file(tmp_path, "stable_pd = true"))
    assert robot.spec.stable_pd and np.allclose(robot.kd, np.asarray(robot.spec.kd) + robot.dt * robot.kp)
    assert not load_robot("exo").spec.stable_pd
    from robustgait.cli import main

    bad = spec_file(tmp_path, 'stable_pd = "often"')
    assert main(["robot", "check", str(bad)]) == 2
