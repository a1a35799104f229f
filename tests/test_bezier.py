import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from robustgait.bezier import bernstein_basis, bezier, bezier_derivative, bezier_derivative_coeffs

coeffs = arrays(np.float64, (3, 8), elements=st.floats(-2, 2))


def test_basis_partition_of_unity_and_endpoints():
    tau = np.linspace(0, 1, 41)
    b = bernstein_basis(7, tau)
    assert b.shape == (41, 8)
    np.testing.assert_allclose(b.sum(axis=1), 1.0, atol=1e-14)
    beta = np.arange(24.0).reshape(3, 8)
    np.testing.assert_allclose(bezier(beta, 0.0), beta[:, 0])
    np.testing.assert_allclose(bezier(beta, 1.0), beta[:, -1])


@settings(max_examples=50, deadline=None)
@given(coeffs, st.floats(0.05, 0.95), st.integers(1, 3))
def test_derivatives_match_finite_differences(beta, tau, order):
    h = 1e-4
    def f(t):
        return bezier_derivative(beta, t, order - 1) if order > 1 else bezier(beta, t)
    fd = (f(tau + h) - f(tau - h)) / (2 * h)
    np.testing.assert_allclose(bezier_derivative(beta, tau, order), fd, rtol=1e-5, atol=1e-5 * 7**order)


def test_derivative_endpoints_and_shapes():
    beta = np.random.default_rng(0).normal(size=(12, 8))
    d = bezier_derivative(beta, np.array([0.0, 1.0]))
    np.testing.assert_allclose(d[0], 7 * (beta[:, 1] - beta[:, 0]))
    np.testing.assert_allclose(d[1], 7 * (beta[:, 7] - beta[:, 6]))
    assert bezier(beta, np.zeros((4, 5))).shape == (4, 5, 12)
    assert bezier(beta[0], np.zeros(5)).shape == (5,)
    with pytest.raises(ValueError):
        bezier_derivative_coeffs(beta, 8)
