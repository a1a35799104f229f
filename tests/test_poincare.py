import mujoco
import numpy as np
import pytest

from robustgait import CertifyConfig, RobustGaitError
from robustgait.poincare import ReturnMap, frame_rotation, holonomic_reconstruction, reduce_state
from robustgait.rotations import quat_to_mat


def _yaw_quat(psi):
    return np.array([np.cos(psi / 2), 0, 0, np.sin(psi / 2)])


def _qmul(a, b):
    w1, x1, y1, z1 = a
    w2, x2, y2, z2 = b
    return np.array([w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2, w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
                     w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2, w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2])


def test_reduced_frames(robot_gait):
    s = robot_gait[1].initial_state
    qpos, qvel = s.qpos[None], s.qvel[None]
    r = quat_to_mat(s.qpos[3:7])
    np.testing.assert_allclose(reduce_state(qpos, qvel, "world")[0], r @ s.qvel[3:6], atol=1e-15)
    np.testing.assert_array_equal(reduce_state(qpos, qvel, "body")[0], s.qvel[3:6])
    # heading frame: invariant under a rotation of the whole robot about the vertical
    turned = qpos.copy()
    turned[0, 3:7] = _qmul(_yaw_quat(0.7), s.qpos[3:7])
    np.testing.assert_allclose(reduce_state(turned, qvel, "heading")[0], reduce_state(qpos, qvel, "heading")[0],
                               atol=1e-12)
    assert not np.allclose(reduce_state(turned, qvel, "world"), reduce_state(qpos, qvel, "world"))
    a = frame_rotation(s.qpos, "heading")
    np.testing.assert_allclose(a @ a.T, np.eye(3), atol=1e-14)


def test_reduced_state_of_mirror_is_reflected(robot_gait):
    robot, gait = robot_gait
    s = gait.initial_state
    mq, mv = robot.mirror_state(s.qpos[None], s.qvel[None])
    np.testing.assert_allclose(reduce_state(mq, mv, "heading")[0],
                               reduce_state(s.qpos[None], s.qvel[None], "heading")[0] * [-1, 1, -1],
                               atol=1e-12)


@pytest.fixture(scope="module")
def step_map(robot_gait):
    with ReturnMap(*robot_gait) as pmap:
        pmap.find_fixed_point()
        yield pmap


def test_fixed_point_is_a_fixed_point_of_the_map(step_map):
    fp = step_map.fixed_point
    assert fp.residual < 5e-3 and fp.steps >= 10 and len(fp.residuals) == fp.steps
    img = step_map(fp.x_star[None])[0]
    assert np.linalg.norm(img - fp.x_star) < 0.02


def test_holonomic_reconstruction_keeps_the_stance_sole_twist(step_map):
    robot = step_map.robot
    fp = step_map.fixed_point
    xbar = fp.x_star + np.array([[0.3, -0.2, 0.1], [0.0, 0.0, 0.0]])
    qpos, qvel = step_map.reconstruct(xbar)
    np.testing.assert_array_equal(qvel[1], fp.qvel)  # ι(x̄*) = x* exactly
    np.testing.assert_allclose(reduce_state(qpos, qvel, "heading")[0], xbar[0], atol=1e-12)
    m, d = robot.model, mujoco.MjData(robot.model)
    d.qpos[:] = qpos[0]
    mujoco.mj_kinematics(m, d)
    mujoco.mj_comPos(m, d)
    jp, jr = np.zeros((3, m.nv)), np.zeros((3, m.nv))
    mujoco.mj_jacGeom(m, d, jp, jr, robot.sole_geom_id[step_map.stance])
    js = np.vstack([jp, jr])
    np.testing.assert_allclose(js @ qvel[0], js @ fp.qvel, atol=1e-10)
    # least change: any other admissible change (G plus a constraint-null-space direction with δω = 0)
    # changes the joint velocities more
    g = holonomic_reconstruction(robot, fp.qpos, step_map.stance)
    assert g.shape == (m.nv, 3)
    np.testing.assert_allclose(js @ g, 0, atol=1e-10)
    a = np.hstack([js[:, :3], js[:, 6:]])
    null = np.linalg.svd(a)[2][6:].T  # (15, 9): velocity changes (δv, δq̇_j) invisible to the sole
    rng = np.random.default_rng(0)
    for _ in range(20):
        z = null @ rng.normal(size=null.shape[1])
        col = g[:, 0]
        assert np.linalg.norm(col[6:] + 0.1 * z[3:]) >= np.linalg.norm(col[6:]) - 1e-12


def test_angular_only_changes_only_the_angular_velocity(step_map):
    with ReturnMap(step_map.robot, step_map.gait, CertifyConfig(reconstruction="angular-only")) as pmap:
        pmap.fixed_point = step_map.fixed_point
        fp = step_map.fixed_point
        qpos, qvel = pmap.reconstruct(fp.x_star[None] + 0.25)
    changed = np.flatnonzero(qvel[0] != fp.qvel)
    assert set(changed) <= {3, 4, 5} and np.array_equal(qpos[0], fp.qpos)


@pytest.mark.slow  # rendering / a second map: keeps plain pytest ≤ 60 s; CI runs it
def test_stride_map_fixed_point(robot_gait):
    with ReturnMap(*robot_gait, CertifyConfig(map="stride")) as pmap:
        fp = pmap.find_fixed_point()
        assert fp.steps % 2 == 0 and fp.residual < 5e-3
        out = pmap(np.vstack([fp.x_star, fp.x_star + np.array([3.0, 0, 0])]))
    assert np.linalg.norm(out[0] - fp.x_star) < 0.02 and np.isnan(out[1]).all()


def test_fixed_point_errors(robot_gait):
    import dataclasses

    from robustgait.gait import State

    robot, gait = robot_gait
    s = gait.initial_state
    kicked = dataclasses.replace(gait, initial_state=State(s.qpos, s.qvel + np.r_[0, 0, 0, 4.0, 0, 0, np.zeros(12)]))
    with ReturnMap(robot, kicked) as pmap, pytest.raises(RobustGaitError, match="fell within step"):
        pmap.find_fixed_point()
    with ReturnMap(robot, gait, CertifyConfig(fp_tol=1e-9, fp_max_steps=12)) as pmap:
        with pytest.raises(RobustGaitError, match=r"no fixed point within 12 steps.*smallest"):
            pmap.find_fixed_point()
        with pytest.raises(RobustGaitError, match="find the fixed point first"):
            pmap(np.zeros((1, 3)))
    with pytest.raises(RobustGaitError, match="map: must be one of 'step', 'stride'"):
        CertifyConfig(map="hop")  # type: ignore[arg-type]
