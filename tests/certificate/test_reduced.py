"""Tests for robustgait.certificate.reduced: the reduced states of a certificate (omega, centroidal, velocity) —
frames, the reconstruction ι (stance sole kept still, Φ(ι(x̄)) = x̄, ι(x̄*) = x*), the metrics (kinetic energy), the
centroidal momentum against MuJoCo's physics (a push's Δh is its impulse), and the certificate's coordinates."""

import mujoco
import numpy as np
import pytest
from scipy import stats

from robustgait import CertifyConfig
from robustgait.certificate.barrier import sample_ball
from robustgait.certificate.reduced import (
    Coordinates,
    ReducedState,
    centroidal_momentum,
    frame_rotation,
    holonomic_reconstruction,
    reduce_state,
    stance_jacobian,
)
from robustgait.certificate.shape import Shape
from robustgait.robots.model import mass_matrix
from robustgait.rotations import quat_to_mat
from tests.conftest import ORBITS, walked_orbit

# one worker runs the modules of the group, so their module fixtures are made once and the orbit searches of one gait
# shared (tests.conftest.walked_orbit)
pytestmark = pytest.mark.xdist_group(ORBITS)

STATES = ("omega", "centroidal", "velocity")


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
def fixed_point(exo, exo_gait):
    return walked_orbit(exo, exo_gait).fixed_point("heading")


def _state(name, exo, exo_gait, fp, **kw):
    cfg = CertifyConfig(**{"disturbance": "state", **kw})
    return ReducedState.at(name, exo, fp.qpos, fp.qvel, exo_gait.stance, cfg)


def test_holonomic_reconstruction_is_the_least_joint_velocity_change(exo, exo_gait, fixed_point):
    fp = fixed_point
    js = stance_jacobian(exo, fp.qpos, exo_gait.stance)
    g = holonomic_reconstruction(exo, fp.qpos, exo_gait.stance)
    assert g.shape == (exo.model.nv, 3)
    np.testing.assert_allclose(js @ g, 0, atol=1e-10)
    # any other admissible change (G plus a constraint-null-space direction with δω = 0) moves the joints more
    a = np.hstack([js[:, :3], js[:, 6:]])
    null = np.linalg.svd(a)[2][6:].T
    rng = np.random.default_rng(0)
    for _ in range(20):
        z = null @ rng.normal(size=null.shape[1])
        assert np.linalg.norm(g[6:, 0] + 0.1 * z[3:]) >= np.linalg.norm(g[6:, 0]) - 1e-12


@pytest.mark.parametrize("name", STATES)
def test_iota_keeps_the_stance_sole_still_and_phi_inverts_it(exo, exo_gait, fixed_point, name):
    fp = fixed_point
    red = _state(name, exo, exo_gait, fp)
    assert red.dim == {"omega": 3, "centroidal": 6, "velocity": exo.model.nv - 6}[name]
    rng = np.random.default_rng(1)
    xbar = red.x_star + rng.normal(size=(5, red.dim)) * (0.3 if name == "omega" else 2.0)
    qpos, qvel = red.iota(np.vstack([xbar, red.x_star]))
    np.testing.assert_array_equal(qvel[-1], fp.qvel)  # ι(x̄*) = x* exactly
    np.testing.assert_array_equal(qpos, np.tile(fp.qpos, (6, 1)))
    np.testing.assert_allclose(red.phi(qpos, qvel)[:-1], xbar, atol=1e-9 * max(1.0, float(np.abs(xbar).max())))
    js = stance_jacobian(exo, fp.qpos, exo_gait.stance)
    np.testing.assert_allclose((qvel - fp.qvel) @ js.T, 0, atol=1e-9)


@pytest.mark.parametrize("name", ["centroidal", "velocity"])
def test_energy_metric_is_the_kinetic_energy(exo, exo_gait, fixed_point, name):
    fp = fixed_point
    red = _state(name, exo, exo_gait, fp)
    assert red.energy and red.unit == "√J"
    m = mass_matrix(exo.model, fp.qpos)[1]
    np.testing.assert_allclose(m, m.T, atol=1e-12)
    rng = np.random.default_rng(2)
    for _ in range(3):
        delta = rng.normal(size=red.dim)
        qpos, qvel = red.iota((red.x_star + delta)[None])
        dq = qvel[0] - fp.qvel
        ke = 0.5 * dq @ m @ dq
        metric = float(delta @ red.metric @ delta)
        if name == "velocity":  # every contact-consistent velocity: the metric is twice its kinetic energy
            np.testing.assert_allclose(metric, 2 * ke, rtol=1e-9)
        else:  # the least-energy change producing δh: its kinetic energy is at least the centroidal one
            assert 2 * ke >= metric * (1 - 1e-9)
        np.testing.assert_allclose(red.kinetic_energy(qpos, qvel)[0], ke, rtol=1e-9)
    # centroidal metric: ‖h‖²_W = ‖p‖²/m + Lᵀ I_c⁻¹ L for a rigid translation of the whole robot (L = 0)
    if name == "centroidal":
        v = np.zeros(exo.model.nv)
        v[0] = 0.4  # base linear velocity, world x: every body moves at 0.4 m/s
        h = centroidal_momentum(exo, fp.qpos[None], v[None])[0]
        np.testing.assert_allclose(h[:3] @ h[:3] / exo.mass, exo.mass * 0.4**2, rtol=1e-9)
        np.testing.assert_allclose(h[3:], 0, atol=1e-9)


def test_a_push_changes_the_centroidal_momentum_by_its_impulse(exo, exo_gait, fixed_point):
    """Physics, not algebra: MuJoCo steps the robot in the air (no gravity, no constraint, servos off) from the fixed
    point's state for 20 ms, once under a force on the base and once without; the difference of the changes of
    h = (p, L) is (J, r × J), r from the whole centre of mass to the base's (RK4: the default implicitfast integrator
    drifts ≈ 2e-3 N s in 20 ms at these joint speeds; the unforced run cancels what remains)."""
    m = exo.model
    saved = (m.opt.gravity.copy(), m.opt.disableflags, m.actuator_gainprm.copy(), m.actuator_biasprm.copy(),
             m.opt.integrator)
    b = exo.base_body_id
    force, n = np.array([120.0, -60.0, 30.0]), 20
    changes, arms = [], []
    try:
        m.opt.gravity[:] = 0
        m.opt.disableflags |= mujoco.mjtDisableBit.mjDSBL_CONSTRAINT  # no contact, no joint limit
        m.actuator_gainprm[:] = 0
        m.actuator_biasprm[:] = 0
        m.opt.integrator = mujoco.mjtIntegrator.mjINT_RK4  # conserves momentum far better than implicitfast
        for f in (force, np.zeros(3)):
            d = mujoco.MjData(m)
            d.qpos[:] = fixed_point.qpos
            d.qpos[2] += 2.0
            d.qvel[:] = fixed_point.qvel
            mujoco.mj_forward(m, d)
            q0 = d.qpos.copy()
            h0 = centroidal_momentum(exo, q0[None], d.qvel[None].copy())[0]
            for _ in range(n):
                d.xfrc_applied[b, :3] = f
                if f.any():
                    arms.append(d.xipos[b] - d.subtree_com[b])  # the base is the root of the robot's tree
                mujoco.mj_step(m, d)
            mujoco.mj_forward(m, d)
            q1 = d.qpos.copy()
            h1 = centroidal_momentum(exo, q1[None], d.qvel[None].copy())[0]
            changes.append(world(h1, q1) - world(h0, q0))
    finally:
        m.opt.gravity[:], m.opt.disableflags, m.actuator_gainprm[:], m.actuator_biasprm[:], m.opt.integrator = saved
    impulse = force * n * m.opt.timestep
    dp, dl = changes[0] - changes[1]
    np.testing.assert_allclose(dp, impulse, atol=1e-3 * np.linalg.norm(impulse))
    np.testing.assert_allclose(dl, np.cross(np.mean(arms, axis=0), impulse), atol=0.02 * np.linalg.norm(impulse))


def world(h, qpos):
    """(p, L) of a centroidal momentum in the heading frame of ``qpos``, back in world axes."""
    r = quat_to_mat(qpos[3:7])
    psi = np.arctan2(r[1, 0], r[0, 0])
    rz = np.array([[np.cos(psi), -np.sin(psi), 0], [np.sin(psi), np.cos(psi), 0], [0, 0, 1]])
    return np.array([rz @ h[:3], rz @ h[3:]])


@pytest.mark.parametrize("name", STATES)
def test_samples_are_uniform_in_the_metric_ball(exo, exo_gait, fixed_point, name):
    """z uniform in the Euclidean ball ↦ x̄ = T⁻¹ z uniform in the metric ball: ‖x̄ − x̄*‖_W / r has CDF ρ^k."""
    red = _state(name, exo, exo_gait, fixed_point)
    co = Coordinates.of(red)
    k, r = red.dim, 3.0
    z = sample_ball(4000, k, r, co.x_star, np.random.default_rng(3))
    xbar = co.to_xbar(z)
    d = xbar - red.x_star
    rho = np.sqrt(np.einsum("ni,ij,nj->n", d, red.metric, d)) / r
    assert rho.max() <= 1 + 1e-12
    assert stats.kstest(rho, lambda x: np.clip(x, 0, 1) ** k).pvalue > 1e-3
    # and not uniform in the unweighted coordinates when the metric is not the identity (the test has power)
    if not np.allclose(red.metric, np.eye(k)):
        plain = np.linalg.norm(d, axis=1)
        assert stats.kstest(plain / plain.max(), lambda x: np.clip(x, 0, 1) ** k).pvalue < 1e-3


def test_coordinates_of_an_ellipsoid(exo, exo_gait, fixed_point):
    red = _state("omega", exo, exo_gait, fixed_point)
    s = np.array([[2.0, 0.3, 0.0], [0.3, 1.0, 0.0], [0.0, 0.0, 0.5]])
    s /= np.linalg.det(s) ** (1 / 3)
    co = Coordinates.of(red, Shape(s))
    d = np.array([[0.1, -0.2, 0.05]])
    z = co.to_z(red.x_star + d)
    np.testing.assert_allclose(np.sum((z - co.x_star) ** 2), (d @ s @ d.T)[0, 0], rtol=1e-12)
    np.testing.assert_allclose(co.to_xbar(z), red.x_star + d, atol=1e-14)
    assert co.energy(1.0) is None
