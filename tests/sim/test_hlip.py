"""The H-LIP equations (robustgait.sim.hlip) against their definitions: matrix exponentials, fixed points, deadbeat."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.linalg import expm

from robustgait.sim import hlip

CASES = [(0.55, 0.548, 0.0), (0.55, 0.40, 0.1), (0.9, 0.6, 0.0), (1.0, 0.35, 0.05)]


@pytest.mark.parametrize(("z0", "ts", "td"), CASES)
def test_s2s_matrices_are_the_flows_of_ssp_then_dsp_and_the_foot_switch(z0: float, ts: float, td: float) -> None:
    lam = hlip.pendulum_rate(z0, 9.81)
    a, b = hlip.s2s_matrices(lam, ts, td)
    a_ssp = np.array([[0.0, 1.0], [lam**2, 0.0]])
    a_dsp = np.array([[0.0, 1.0], [0.0, 0.0]])
    np.testing.assert_allclose(a, expm(a_ssp * ts) @ expm(a_dsp * td), rtol=1e-12)
    np.testing.assert_allclose(b, expm(a_ssp * ts) @ [-1.0, 0.0], rtol=1e-12)
    np.testing.assert_allclose(hlip.ssp_flow(lam, np.array([ts, 0.0]))[1], np.eye(2))


@pytest.mark.parametrize(("z0", "ts", "td"), CASES)
def test_deadbeat_gain_kills_any_error_in_two_steps(z0: float, ts: float, td: float) -> None:
    lam = hlip.pendulum_rate(z0, 9.81)
    a, b = hlip.s2s_matrices(lam, ts, td)
    k = hlip.deadbeat_gain(lam, ts, td)
    closed = a + np.outer(b, k)
    np.testing.assert_allclose(closed @ closed, 0.0, atol=1e-9)
    assert hlip.closed_loop_radius(a, b, k) < 1e-4
    # det(A + BK) = 1 − k1 and tr(A + BK) = c (2 − k1) + λ s (T_D − k2), for any K
    c, s = np.cosh(lam * ts), np.sinh(lam * ts)
    for k1, k2 in [(0.5, k[1]), (1.0, 0.8 * k[1]), (1.3, 0.1)]:
        m = a + np.outer(b, [k1, k2])
        assert np.linalg.det(m) == pytest.approx(1 - k1, abs=1e-9)
        assert np.trace(m) == pytest.approx(c * (2 - k1) + lam * s * (td - k2), abs=1e-9)


@pytest.mark.parametrize(("z0", "ts", "td"), CASES)
def test_lqr_gain_stabilizes_the_s2s_dynamics(z0: float, ts: float, td: float) -> None:
    lam = hlip.pendulum_rate(z0, 9.81)
    a, b = hlip.s2s_matrices(lam, ts, td)
    assert hlip.closed_loop_radius(a, b, hlip.lqr_gain(a, b, z0, lam)) < 1.0
    assert hlip.closed_loop_radius(a, b, np.zeros(2)) > 1.0  # the open loop diverges


@pytest.mark.parametrize(("z0", "ts", "td"), CASES)
def test_orbits_are_fixed_points_of_the_s2s_map(z0: float, ts: float, td: float) -> None:
    lam = hlip.pendulum_rate(z0, 9.81)
    a, b = hlip.s2s_matrices(lam, ts, td)
    x1, u1 = hlip.period1_orbit(lam, ts, td, 0.2)
    np.testing.assert_allclose(a @ x1 + b * u1, x1, atol=1e-12)
    assert u1 == pytest.approx(0.2 * (ts + td))
    x_left, x_right, u_left, u_right = hlip.period2_orbit(lam, ts, td, 0.1, -0.2)
    np.testing.assert_allclose(a @ x_left + b * u_left, x_right, atol=1e-12)
    np.testing.assert_allclose(a @ x_right + b * u_right, x_left, atol=1e-12)
    assert u_left + u_right == pytest.approx(2 * 0.1 * (ts + td))


def test_step_correction_predicts_the_error_at_the_preimpact_instant() -> None:
    lam, ts, td = hlip.pendulum_rate(0.6, 9.81), 0.5, 0.0
    k = hlip.deadbeat_gain(lam, ts, td)
    err = np.array([[0.01, -0.02], [0.0, 0.0]])
    t_left = np.array([0.3, 0.1])
    want = [(expm(np.array([[0.0, 1.0], [lam**2, 0.0]]) * 0.3) @ err[0]) @ k, 0.0]
    np.testing.assert_allclose(hlip.step_correction(k, lam, err, t_left), want, atol=1e-12)
    # past the nominal pre-impact instant the error is taken as it is
    assert hlip.step_correction(k, lam, err[0], -0.1) == pytest.approx(err[0] @ k)
    with pytest.raises(ValueError, match="z0 > 0"):
        hlip.pendulum_rate(0.0, 9.81)
