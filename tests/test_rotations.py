import mujoco
import numpy as np

from robustgait.rotations import quat_to_mat


def test_quat_to_mat_matches_mujoco():
    q = np.random.default_rng(1).normal(size=4)
    q /= np.linalg.norm(q)
    ref = np.zeros(9)
    mujoco.mju_quat2Mat(ref, q)
    np.testing.assert_allclose(quat_to_mat(q), ref.reshape(3, 3), atol=1e-15)


def test_quat_to_mat_is_batched_and_normalizes():
    q = np.random.default_rng(2).normal(size=(5, 3, 4))
    r = quat_to_mat(q)
    assert r.shape == (5, 3, 3, 3)
    np.testing.assert_allclose(r @ np.swapaxes(r, -1, -2), np.broadcast_to(np.eye(3), r.shape), atol=1e-14)
    np.testing.assert_allclose(np.linalg.det(r), 1.0, atol=1e-14)
