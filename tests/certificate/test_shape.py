"""Tests for robustgait.certificate.shape: the linearization fit, the Lyapunov ellipsoid (positive definite, det 1, the
equation), its coordinates, the fallback to the ball, and an ellipsoid certifying what no ball can (a contracting
map that is not normal)."""

import numpy as np
import pytest

from robustgait.certificate.barrier import sample_ball
from robustgait.certificate.estimators import certify_map_sequential
from robustgait.certificate.shape import (
    Shape,
    ellipsoid_transform,
    fit_linearization,
    lyapunov_shape,
    shape_from_fit,
    volume_ratio,
)
from robustgait.config import CertifyConfig, SequentialConfig
from robustgait.errors import RobustGaitError

# contracting (eigenvalues 0.5, 0.3, 0.2) but not normal: ‖A‖ ≈ 1.6 stretches some directions in one step
A = np.array([[0.5, 1.2, 0.0], [0.0, 0.3, 0.4], [0.0, 0.0, 0.2]])
X_STAR = np.array([0.4, -0.3, 0.2])


def linear(x: np.ndarray) -> np.ndarray:
    return X_STAR + (x - X_STAR) @ A.T


def test_fit_recovers_a_linear_map_and_ignores_falls() -> None:
    x = sample_ball(40, 3, 0.1, X_STAR, np.random.default_rng(0))
    y = linear(x)
    y[:5] = np.nan
    fit = fit_linearization(x, y, X_STAR)
    np.testing.assert_allclose(fit.a, A, atol=1e-12)
    np.testing.assert_allclose(fit.offset, 0, atol=1e-12)
    assert fit.used == 35 and fit.relative_residual < 1e-12
    assert fit.spectral_radius == pytest.approx(0.5)
    with pytest.raises(RobustGaitError, match="at least 4 samples"):
        fit_linearization(x[:3], y[:3], X_STAR)


def test_lyapunov_shape_is_positive_definite_with_det_1() -> None:
    s = lyapunov_shape(A)
    np.testing.assert_allclose(s, s.T)
    assert np.all(np.linalg.eigvalsh(s) > 0)
    assert np.linalg.det(s) == pytest.approx(1.0)
    # AᵀSA − S = −c I for the scaled solution (c = 1/det(S₀)^{1/3} > 0)
    lhs = A.T @ s @ A - s
    np.testing.assert_allclose(lhs, lhs[0, 0] * np.eye(3), atol=1e-12)
    assert lhs[0, 0] < 0
    c_t = ellipsoid_transform(s)
    d = np.array([0.3, -0.1, 0.2])
    assert np.sum((c_t @ d) ** 2) == pytest.approx(d @ s @ d)
    with pytest.raises(RobustGaitError, match="not contracting"):
        lyapunov_shape(np.diag([1.1, 0.5, 0.2]))


def test_fallback_and_volume_ratio() -> None:
    x = sample_ball(40, 3, 0.1, X_STAR, np.random.default_rng(1))
    expanding = fit_linearization(x, X_STAR + (x - X_STAR) * 1.2, X_STAR)
    sh = shape_from_fit(expanding)
    assert "not contracting" in sh.fallback and np.array_equal(sh.s, np.eye(3))
    assert volume_ratio(0.4, 0.2, 3) == pytest.approx(8.0)
    assert volume_ratio(0.0, 0.0, 3) == 1.0 and volume_ratio(0.1, 0.0, 3) == np.inf
    good = shape_from_fit(fit_linearization(x, linear(x), X_STAR))
    assert good.fallback == "" and good.inner_radius(1.0) <= 1.0 <= float(good.axes[0])


def test_an_ellipsoid_certifies_what_no_ball_can() -> None:
    """The ball's DTBF condition fails near x* along the stretched direction (‖A δ‖ > ‖δ‖): r* is tiny; in the
    Lyapunov ellipsoid's coordinates the same map contracts and the whole sampled ball is certified."""
    cfg = CertifyConfig(disturbance="state", r_max=1.0, sequential=SequentialConfig(budget=1500))
    ball = certify_map_sequential(linear, X_STAR, cfg)
    sh = Shape(lyapunov_shape(A))
    t = sh.transform
    z_star = t @ X_STAR

    def in_z(z: np.ndarray) -> np.ndarray:
        return linear(np.linalg.solve(t, z.T).T) @ t.T

    ell = certify_map_sequential(in_z, z_star, cfg)
    assert ball.radius < 0.05 and ell.radius == 1.0 and ell.violation_bound <= 0.02
    assert volume_ratio(ell.radius, ball.radius, 3) > 1000
