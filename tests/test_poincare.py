import numpy as np
import pytest

from robustgait import CertifyConfig, RobustGaitError
from robustgait.poincare import ReturnMap
from robustgait.reduced import reduce_state, stance_jacobian


@pytest.fixture(scope="module")
def step_map(robot_gait):
    with ReturnMap(*robot_gait) as pmap:
        pmap.find_fixed_point()
        yield pmap


def test_fixed_point_is_a_fixed_point_of_the_map(step_map):
    fp = step_map.fixed_point
    assert fp.residual < 5e-3 and fp.steps >= 10 and len(fp.residuals) == fp.steps
    img = step_map(fp.omega[None])[0]
    assert np.linalg.norm(img - fp.omega) < 0.02


def test_holonomic_reconstruction_keeps_the_stance_sole_twist(step_map):
    robot = step_map.robot
    fp = step_map.fixed_point
    xbar = fp.omega + np.array([[0.3, -0.2, 0.1], [0.0, 0.0, 0.0]])
    qpos, qvel = step_map.reconstruct(xbar)
    np.testing.assert_array_equal(qvel[1], fp.qvel)  # ι(x̄*) = x* exactly
    np.testing.assert_allclose(reduce_state(qpos, qvel, "heading")[0], xbar[0], atol=1e-12)
    js = stance_jacobian(robot, qpos[0], step_map.stance)
    np.testing.assert_allclose(js @ qvel[0], js @ fp.qvel, atol=1e-10)


def test_horizon_maps_k_steps_and_a_fall_in_any_is_a_fall(step_map):
    """P^k: k maps on full states (ι once, Φ at the end — not P ∘ P ∘ P of reduced states, which would rebuild the
    state at every step); a sample that falls in step 1 is NaN at every later iterate."""
    fp = step_map.fixed_point
    x = fp.omega + np.array([[0.05, -0.03, 0.02], [4.0, 0.0, 0.0]])
    one = step_map(x)
    with ReturnMap(step_map.robot, step_map.gait, CertifyConfig(disturbance="state", horizon=3)) as p3:
        p3.set_fixed_point(fp)
        three = p3(x)
        path = p3.last_path
    assert path.shape == (3, 2, 3)
    np.testing.assert_allclose(path[0], one, atol=1e-12)
    np.testing.assert_allclose(three, path[-1])
    q, v = step_map.reconstruct(x[:1])
    for _ in range(3):
        q, v, _ = step_map._advance(q, v)
    np.testing.assert_allclose(reduce_state(q, v, "heading"), three[:1], atol=1e-12)
    assert np.isnan(path[:, 1]).all()


def test_angular_only_changes_only_the_angular_velocity(step_map):
    with ReturnMap(step_map.robot, step_map.gait, CertifyConfig(reconstruction="angular-only")) as pmap:
        fp = pmap.set_fixed_point(step_map.fixed_point)
        qpos, qvel = pmap.reconstruct(fp.omega[None] + 0.25)
    changed = np.flatnonzero(qvel[0] != fp.qvel)
    assert set(changed) <= {3, 4, 5} and np.array_equal(qpos[0], fp.qpos)


@pytest.mark.slow  # rendering / a second map: keeps plain pytest ≤ 60 s; CI runs it
def test_stride_map_fixed_point(robot_gait):
    with ReturnMap(*robot_gait, CertifyConfig(map="stride")) as pmap:
        fp = pmap.find_fixed_point()
        assert fp.steps % 2 == 0 and fp.residual < 5e-3
        out = pmap(np.vstack([fp.omega, fp.omega + np.array([3.0, 0, 0])]))
    assert np.linalg.norm(out[0] - fp.omega) < 0.02 and np.isnan(out[1]).all()


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
