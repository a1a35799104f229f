"""The shipped robot ``exo``: its spec, geometry, mirror symmetry, contacts, and standing with PD servos."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from robustgait.dynamics import Dynamics
from robustgait.io.robotfile import load_robot, shipped_robots
from robustgait.robots import Robot
from robustgait.robots.model import CONTACT_SENSORS

# Nominal standing posture, per leg: hip roll, hip yaw, hip pitch, knee, ankle pitch, ankle roll.
# hip + knee + ankle pitch = 0 keeps the soles flat under an upright pelvis.
STAND = np.array([0.0, 0.0, -0.1, 0.2, -0.1, 0.0] * 2)
SIDES = ("left", "right")


@pytest.fixture(scope="module")
def robot() -> Robot:
    return load_robot("exo")


def standing_state(robot: Robot, drop: float = 0.001) -> mujoco.MjData:
    """Standing posture with both soles flat, ``drop`` metres above the floor, at rest."""
    m = robot.model
    d = mujoco.MjData(m)
    d.qpos[:] = m.qpos0
    d.qpos[robot.qpos_idx] = STAND
    mujoco.mj_kinematics(m, d)
    lowest = min(d.xpos[m.body(f"{s}_sole_frame").id][2] for s in SIDES)
    d.qpos[2] += drop - lowest
    d.ctrl[:] = STAND
    mujoco.mj_forward(m, d)
    return d


def test_exo_is_shipped_and_loads(robot: Robot) -> None:
    assert "exo" in shipped_robots()
    m = robot.model
    assert robot.n_joints == 12
    legs = ["hip_roll", "hip_yaw", "hip_pitch", "knee", "ankle_pitch", "ankle_roll"]
    assert robot.spec.joints == tuple(f"{s}_{j}" for s in SIDES for j in legs)
    assert m.jnt_type[0] == mujoco.mjtJoint.mjJNT_FREE and m.jnt_bodyid[0] == m.body("pelvis").id
    assert (m.nq, m.nv, m.nu) == (19, 18, 12)
    assert 100.0 <= robot.mass <= 135.0
    assert m.opt.timestep == 0.001 and np.allclose(m.opt.gravity, [0.0, 0.0, -9.81])
    assert robot.spec.fall.min_base_height == pytest.approx(0.6) and robot.spec.fall.max_tilt == pytest.approx(0.8)
    assert robot.spec.description
    # every moving body has a positive mass and inertia; frame bodies are massless leaves
    for b in range(1, m.nbody):
        if m.body_jntnum[b] > 0:
            assert m.body_mass[b] > 0.5 and np.all(m.body_inertia[b] > 1e-4), m.body(b).name
    for s in SIDES:
        for kind in ("sole", "toe", "heel"):
            b = m.body(f"{s}_{kind}_frame")
            assert b.mass[0] == 0.0 and b.jntnum[0] == 0 and not np.any(m.body_parentid[1:] == b.id)


def test_joint_limits_gains_and_mirror(robot: Robot) -> None:
    lo, hi = robot.joint_range.T
    for side in (0, 6):
        assert -0.35 <= lo[side] and hi[side] <= 0.35  # hip roll
        assert lo[side + 2] == pytest.approx(-2.0) and 0.2 <= hi[side + 2] <= 0.5  # hip pitch (flexion < 0)
        assert (lo[side + 3], hi[side + 3]) == pytest.approx((0.0, 1.9))  # knee
    assert np.all(lo < STAND) and np.all(STAND < hi)
    assert np.all((robot.kp >= 1000) & (robot.kp <= 50000)) and np.all((robot.kd >= 10) & (robot.kd <= 600))
    assert np.all((robot.torque_limit >= 100) & (robot.torque_limit <= 350))
    assert robot.spec.mirror_perm == (6, 7, 8, 9, 10, 11, 0, 1, 2, 3, 4, 5)
    assert robot.spec.mirror_sign == (-1, -1, 1, 1, 1, -1) * 2
    assert robot.spec.base_mirror_sign == (1, -1, 1, -1, 1, -1)
    # the limits are mirror images: relabeling maps the range onto itself
    mirrored = np.sort(robot.mirror_joints(robot.joint_range.T), axis=0)
    np.testing.assert_allclose(mirrored, robot.joint_range.T)
    perm = list(robot.spec.mirror_perm)
    for gains in (robot.kp, robot.kd, robot.torque_limit):
        np.testing.assert_array_equal(gains[perm], gains)


def test_mirror_relabeling_is_a_reflection(robot: Robot) -> None:
    """A configuration and its relabeling are mirror images about the sagittal plane (y -> -y)."""
    m = robot.model
    rng = np.random.default_rng(3)
    d, dm = mujoco.MjData(m), mujoco.MjData(m)
    pairs = [(m.body(f"left_{n}").id, m.body(f"right_{n}").id)
             for n in ("hip_roll_link", "thigh", "shank", "foot", "sole_frame", "toe_frame", "heel_frame")]
    for _ in range(5):
        q = rng.uniform(*robot.joint_range.T)
        d.qpos[:] = m.qpos0
        dm.qpos[:] = m.qpos0
        d.qpos[robot.qpos_idx] = q
        dm.qpos[robot.qpos_idx] = robot.mirror_joints(q)
        mujoco.mj_kinematics(m, d)
        mujoco.mj_kinematics(m, dm)
        flip = np.array([1.0, -1.0, 1.0])
        for left, right in pairs:
            np.testing.assert_allclose(dm.xpos[right], flip * d.xpos[left], atol=1e-12)
            np.testing.assert_allclose(dm.xipos[right], flip * d.xipos[left], atol=1e-12)
        np.testing.assert_allclose(dm.subtree_com[robot.base_body_id], flip * d.subtree_com[robot.base_body_id],
                                   atol=1e-12)


def test_standing_geometry(robot: Robot) -> None:
    m = robot.model
    d = standing_state(robot, drop=0.0)
    assert 0.90 <= d.qpos[2] <= 0.95  # pelvis height
    sole = {s: d.xpos[m.body(f"{s}_sole_frame").id] for s in SIDES}
    assert sole["left"][1] - sole["right"][1] == pytest.approx(0.25, abs=0.01)  # step width
    assert sole["left"][0] == pytest.approx(sole["right"][0])
    for s in SIDES:
        g = robot.sole_geom_id[s]
        assert m.geom_type[g] == mujoco.mjtGeom.mjGEOM_BOX
        assert 0.26 <= 2 * m.geom_size[g][0] <= 0.28 and 2 * m.geom_size[g][1] == pytest.approx(0.12)
        R = d.geom_xmat[g].reshape(3, 3)
        assert R[2, 2] == pytest.approx(1.0)  # flat sole
        bottom = d.geom_xpos[g][2] - m.geom_size[g][2]
        assert bottom == pytest.approx(0.0, abs=1e-12)
        toe, heel = (d.xpos[m.body(f"{s}_{k}_frame").id] for k in ("toe", "heel"))
        assert toe[0] - heel[0] == pytest.approx(2 * m.geom_size[g][0]) and toe[2] == heel[2] == pytest.approx(0.0)
    # leg segments: hip -> knee -> ankle -> sole
    hip, knee, ankle = (d.xpos[m.body(n).id] for n in ("left_thigh", "left_shank", "left_foot"))
    assert 0.38 <= np.linalg.norm(knee - hip) <= 0.42
    assert np.linalg.norm(ankle - knee) == pytest.approx(0.41)
    assert 0.10 <= ankle[2] - sole["left"][2] <= 0.16


def test_only_floor_contacts_and_no_self_collision(robot: Robot) -> None:
    m = robot.model
    floor = robot.floor_geom_id
    robot_geoms = [g for g in range(m.ngeom) if m.geom_bodyid[g] != 0]
    colliding = [g for g in robot_geoms if m.geom_contype[g] & m.geom_conaffinity[floor]
                 or m.geom_contype[floor] & m.geom_conaffinity[g]]
    names = {m.geom(g).name for g in colliding}
    assert {"left_sole", "right_sole", "pelvis_collision"} <= names
    assert any("thigh" in n for n in names) and any("shank" in n for n in names)
    for i in robot_geoms:  # the robot never collides with itself
        for j in robot_geoms:
            assert not (m.geom_contype[i] & m.geom_conaffinity[j]), (m.geom(i).name, m.geom(j).name)
    assert m.npair == 0 and m.nexclude == 0


def test_a_fall_registers_a_non_foot_contact(robot: Robot) -> None:
    """The robot lying on its back touches the floor with the trunk/pelvis, seen by the floor sensor."""
    m = robot.model
    d = mujoco.MjData(m)
    d.qpos[:] = m.qpos0
    d.qpos[robot.qpos_idx] = STAND
    d.qpos[2] = 0.3
    d.qpos[3:7] = [np.cos(-np.pi / 4), 0.0, np.sin(-np.pi / 4), 0.0]  # pitched back by 90 degrees
    d.ctrl[:] = STAND
    for _ in range(500):
        mujoco.mj_step(m, d)
    adr = robot.sensor_adr
    left, right, floor = (d.sensordata[adr[n]] for n in CONTACT_SENSORS)
    assert floor - left - right > 0


def test_total_mass_equals_adam(robot: Robot) -> None:
    dyn = Dynamics(robot)
    assert dyn.total_mass == pytest.approx(robot.mass, rel=1e-9)
    assert dyn.total_mass == pytest.approx(float(np.sum(robot.model.body_mass)), rel=1e-12)


def test_stands_for_10_seconds_with_pd_servos(robot: Robot) -> None:
    m = robot.model
    d = standing_state(robot)
    frame_ids = {s: m.body(f"{s}_sole_frame").id for s in SIDES}
    z0 = d.qpos[2]
    n = round(10.0 / m.opt.timestep)
    z = np.empty(n)
    tilt = np.empty(n)
    soles = np.empty((n, 2, 3))
    non_foot = np.empty(n)
    adr = robot.sensor_adr
    for k in range(n):
        mujoco.mj_step(m, d)
        z[k] = d.qpos[2]
        tilt[k] = np.arccos(np.clip(d.xmat[robot.base_body_id][8], -1.0, 1.0))
        soles[k] = [d.xpos[frame_ids[s]] for s in SIDES]
        left, right, floor = (d.sensordata[adr[c]] for c in CONTACT_SENSORS)
        non_foot[k] = floor - left - right
    assert np.all(np.abs(z - z0) < 0.02) and z.min() > robot.spec.fall.min_base_height
    assert tilt.max() < 0.05
    landed = soles[200:]  # after the 1 mm drop has settled
    slide = np.linalg.norm(landed[:, :, :2] - landed[0, :, :2], axis=-1)
    assert slide.max() < 0.01
    assert np.all(np.abs(soles[:, :, 2]) < 0.005)  # no sinking, no lift-off
    assert np.all(non_foot == 0)
    assert d.sensordata[adr[CONTACT_SENSORS[0]]] > 0 and d.sensordata[adr[CONTACT_SENSORS[1]]] > 0
    assert np.abs(d.qvel).max() < 1e-3
    assert np.abs(d.qpos[robot.qpos_idx] - STAND).max() < 0.01
    assert np.all(np.abs(d.actuator_force) < 0.5 * robot.torque_limit)  # far from saturation
