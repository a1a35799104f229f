"""The gain rule (robustgait.inspection.gains): the stance inertia against rigid-body sums, the PD gains' cap and the
timestep, static torques."""

from __future__ import annotations

import sys
from pathlib import Path

import mujoco
import numpy as np
import pytest

from robustgait.config import RobotConfig
from robustgait.inspection.discover import find_legs
from robustgait.inspection.gains import (
    joint_loads,
    nice_floor,
    pd_gains,
    servo_timestep,
    spectral_radius,
    static_torques,
)
from robustgait.inspection.model import open_model
from robustgait.robotinit.draft import draft_spec

if sys.version_info >= (3, 11):
    pass
else:  # pragma: no cover - exercised on 3.10 only
    pass
from tests.inspection.biped import biped_xml, write


# ----------------------------------------------------------------------------------------------- gains
def test_stance_inertia_is_the_robot_about_the_ankle(tmp_path: Path) -> None:
    """With the left foot welded and every other joint held, the left ankle roll turns the rest of the robot as one
    rigid body about its axis: I = Σ (aᵀ I_b a + m_b |a × (c_b − p)|²) over the bodies above it, plus armature."""
    r = open_model(write(tmp_path, biped_xml()))
    legs = find_legs(r, 0.1, 0.005)
    q = r.qpos(height=legs.standing_height)
    loads = joint_loads(r, q, {"left": legs.left.foot, "right": legs.right.foot})
    m = r.model
    d = r.kinematics(q)
    j = next(j for j in r.joints if r.joint_name(j) == "left_ankle_roll")
    a, p = d.xaxis[j], d.xanchor[j]
    foot = legs.left.foot
    rigid = 0.0
    for b in range(1, m.nbody):
        if b == foot:
            continue
        rot = d.ximat[b].reshape(3, 3)
        inertia = rot @ np.diag(m.body_inertia[b]) @ rot.T
        arm_ = np.cross(a, d.xipos[b] - p)
        rigid += float(a @ inertia @ a + m.body_mass[b] * arm_ @ arm_)
    assert loads[j].stance == pytest.approx(rigid + m.dof_armature[m.jnt_dofadr[j]], rel=1e-9)
    # the swing value is the mass matrix's diagonal: the foot alone (its inertia about the roll axis)
    assert loads[j].swing < 0.01 * loads[j].stance


def test_pd_gains_respect_the_cap_and_the_timestep(tmp_path: Path) -> None:
    d = draft_spec(write(tmp_path, biped_xml()), RobotConfig())
    c = d.config
    for j in d.robot.joints:
        g, load, tau = d.gains[j], d.loads[j], d.torque[j].value or 0.0
        assert 0 < g.kp <= tau / c.tracking_error * (1 + 1e-12) and g.kd > 0
        assert g.kp == pytest.approx(min(load.stance * (2 * np.pi * c.bandwidth) ** 2, tau / c.tracking_error))
        assert g.kd == pytest.approx(2 * c.damping_ratio * np.sqrt(g.kp * load.swing)) and g.radius < 1
    # partners get the same servo
    for j, k in d.mirror.partner.items():
        assert (d.gains[j].kp, d.gains[j].kd) == (d.gains[k].kp, d.gains[k].kd)


def test_spectral_radius_of_the_discrete_servo() -> None:
    # semi-implicit Euler: stable while h kd / I < 2 and (h ω)² < 4 − 2 h kd / I
    assert spectral_radius(100.0, 1.0, 1.0, 0.01, "euler") < 1
    assert spectral_radius(100.0, 250.0, 1.0, 0.01, "euler") > 1
    assert spectral_radius(1e6, 10.0, 1.0, 0.01, "euler") > 1
    # implicit damping: any damping contracts
    assert spectral_radius(100.0, 1e5, 1.0, 0.01, "implicitfast") < 1
    # continuous decay e^{-ζω h} for the critically damped servo at a small step
    assert spectral_radius(100.0, 20.0, 1.0, 1e-4, "rk4") == pytest.approx(np.exp(-10 * 1e-4), rel=1e-3)
    # a servo that would not contract at its step is lowered until it does
    from robustgait.inspection.gains import JointLoad

    g = pd_gains(JointLoad(1e-4, 1.0, "left"), 1e4, 50.0, 1.0, 0.01, 0.002, "euler")
    assert g.bound == "stability" and g.radius < 1


def test_the_timestep_resolves_the_fastest_servo(tmp_path: Path) -> None:
    assert [nice_floor(x) for x in (0.0014, 0.001, 0.00099, 0.0049, 0.07)] == [0.001, 0.001, 0.0005, 0.002, 0.05]
    # at least `steps` physics steps per period of the fastest servo, at most a fraction of √(l/g), never above the
    # model's step
    assert servo_timestep(0.002, 57.3, 12.0, 1.0, 1.0) == 0.001  # Booster T1's ankle (model: 2 ms)
    assert servo_timestep(0.002, 57.3, 12.0, 0.238, 0.0035) == 0.0005  # ... and its leg: 0.83 ms
    assert servo_timestep(0.001, 66.7, 12.0, 0.308, 0.0035) == 0.001  # exo's ankle (rule gains) and leg: 1.08 ms
    assert servo_timestep(0.0005, 10.0, 12.0, 1.0, 0.0035) == 0.0005
    d = draft_spec(write(tmp_path, biped_xml()), RobotConfig())
    f = max(g.frequency for g in d.gains.values())
    assert d.timestep <= float(d.robot.model.opt.timestep) and d.timestep * f <= 1 / d.config.servo_steps + 1e-12
    assert d.timestep <= d.config.scale.timestep * np.sqrt(d.size.leg_length / d.size.gravity)
    assert d.servo_frequency >= f * (1 - 1e-9)  # measured before any lowering for stability


def test_static_torques_balance_gravity(tmp_path: Path) -> None:
    r = open_model(write(tmp_path, biped_xml()))
    legs = find_legs(r, 0.1, 0.005)
    q = r.qpos(height=legs.standing_height)
    one = static_torques(r, q, [legs.left.foot])
    m = r.model
    d = r.kinematics(q)
    # standing on the left foot, the left leg carries everything but itself below the joint: the knee's torque is
    # the weight above it times its lever arm — checked through the virtual-work identity g = Jᵀ w + τ
    jac = np.zeros((6, m.nv))
    mujoco.mj_jacBody(m, d, jac[:3], jac[3:], legs.left.foot)
    w = np.linalg.lstsq(jac[:, :6].T, d.qfrc_bias[:6], rcond=None)[0]
    assert np.allclose(one, np.r_[np.zeros(6), (d.qfrc_bias - jac.T @ w)[6:]], atol=1e-9)
    both = static_torques(r, q, [legs.left.foot, legs.right.foot])
    knee = m.jnt_dofadr[next(j for j in r.joints if r.joint_name(j) == "left_knee")]
    assert abs(both[knee]) < abs(one[knee])  # two feet share the weight


def test_static_torques_of_a_closed_chain_are_the_gradient_of_its_weight_through_the_loops(tmp_path: Path) -> None:
    # the inline biped of tests/robots/test_loops.py: its knee holds the leg through a rod on a ball joint and a passive
    # tarsus. Standing on its left foot, each planned joint's static torque is ∂V/∂q of the weight's potential with the
    # foot fixed, the loops closed (the passive joints solved, the springs held): virtual work, by finite differences
    from robustgait.robots.loops import close_loops
    from tests.robots.test_loops import chain_xml

    r = open_model(write(tmp_path, chain_xml(), "chain.xml"))
    m = r.model
    foot = m.body("left_foot").id
    q0 = r.qpos(height=0.9)
    for s in ("left", "right"):
        q0[m.jnt_qposadr[m.joint(f"{s}_knee").id]] = 0.4
        q0[m.jnt_qposadr[m.joint(f"{s}_hip_pitch").id]] = -0.2
    q0 = close_loops(m, q0, r.loops, r.solved, 1e-12)
    d0 = r.kinematics(q0)
    p_f0, r_f0 = d0.xpos[foot].copy(), d0.xmat[foot].reshape(3, 3).copy()

    def potential(q: np.ndarray) -> float:
        q = close_loops(m, q, r.loops, r.solved, 1e-12)
        q[:7] = [0, 0, 0, 1, 0, 0, 0]
        d = r.kinematics(q)
        rot = r_f0 @ d.xmat[foot].reshape(3, 3).T  # the base turned and moved so that the foot stays where it was
        q[:3] = p_f0 - rot @ d.xpos[foot]
        mujoco.mju_mat2Quat(q[3:7], rot.ravel())
        d = r.kinematics(q)
        return float(-m.opt.gravity[2] * sum(m.body_mass) * d.subtree_com[0][2])

    tau = static_torques(r, q0, [foot])
    h = 1e-6
    for name in ("left_hip_roll", "left_hip_pitch", "left_knee", "right_knee", "left_foot"):
        adr, dof = m.jnt_qposadr[m.joint(name).id], m.jnt_dofadr[m.joint(name).id]
        up, down = q0.copy(), q0.copy()
        up[adr] += h
        down[adr] -= h
        assert tau[dof] == pytest.approx((potential(up) - potential(down)) / (2 * h), abs=1e-4 * sum(m.body_mass))
    tarsus = m.jnt_dofadr[m.joint("left_tarsus").id]
    assert abs(tau[tarsus]) < 1e-8  # a passive joint holds nothing; the loop does
    assert abs(tau[m.jnt_dofadr[m.joint("left_knee").id]]) > 1.0  # and the knee holds the leg through it
