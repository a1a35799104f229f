"""The orbit check's numerics (robustgait.certificate.numerics) on maps with known orbits
(robustgait.certificate.synthetic): a window of iterates, period two, finite-difference Jacobians of piecewise-smooth
maps, spectral radii, damped Newton, and the verdict."""

from __future__ import annotations

import numpy as np
import pytest

from robustgait import RobustGaitError
from robustgait.certificate.numerics import (
    OrbitReport,
    fd_jacobian,
    flow_projection,
    newton,
    orbit_status,
    residual_summary,
    search_report,
    settled_at,
    spectral_radius,
    window_residual,
)
from robustgait.certificate.synthetic import LinearMap, QuadraticMap, iterates
from robustgait.config import CertifyConfig
from robustgait.config.certify import NEWTON_DAMPING

CFG = CertifyConfig()  # the shipped window, tolerance, finite-difference step and ρ bound


def search(xs: np.ndarray, window: int = CFG.fp_window) -> OrbitReport:
    return search_report(xs, metric="section", window=window, tol=CFG.fp_tol, min_index=CFG.fp_min_steps)


def with_rho(report: OrbitReport, F, x) -> OrbitReport:  # type: ignore[no-untyped-def]
    import dataclasses

    j = fd_jacobian(F, x, CFG.fp_fd_step, CFG.fp_fd_jump)
    rho, moduli = spectral_radius(j.matrix)
    return dataclasses.replace(report, rho=rho, moduli=tuple(moduli))


def test_window_residual_measures_the_last_iterates_from_the_newest():
    xs = np.array([[0.0], [5.0], [1.0], [1.2], [0.9], [1.0]])
    assert window_residual(xs, 3) == pytest.approx(0.2) and window_residual(xs, 4) == pytest.approx(4.0)
    assert window_residual(xs, 2, period=2) == pytest.approx(4.0) and window_residual(xs, 6) == np.inf
    assert settled_at(xs, 1, 0.25) == 3 and settled_at(xs, 1, 0.25, min_index=4) == 5
    assert settled_at(xs, 2, 0.25) == 5 and settled_at(xs, 5, 0.25) is None
    with pytest.raises(RobustGaitError, match="window and period must be ≥ 1"):
        window_residual(xs, 0)
    assert residual_summary([], 3)["steps"] == 0
    s = residual_summary([3.0, 1.0, 2.0, 0.5], 2)
    assert s == {"steps": 4, "last": 0.5, "min": 0.5, "median_last_window": 1.25, "max_last_window": 2.0}


def test_a_wandering_map_that_dips_below_the_tolerance_once_is_refused():
    """The chaotic logistic map (r = 3.9) passes once close to its repelling fixed point: one successive residual
    below fp_tol at step 31, none before or after. The rule before the check (a window of 1) took that iterate for x*;
    the shipped window of 20 refuses the orbit, and Newton from the dip finds x* with ρ = 1.9: unstable."""
    F = QuadraticMap(3.9)
    xs = iterates(F, np.r_[F.preimage(F.x_star[0] + 3e-3, 30), 0.0, 0.0], 100)
    dips = np.flatnonzero(np.linalg.norm(np.diff(xs, axis=0), axis=1) < CFG.fp_tol) + 1
    assert dips.tolist() == [31]
    assert search(xs, window=1).settled == 31  # the old rule: a certificate
    report = search(xs)
    assert report.settled is None and not report.period_two and report.window_residual > 0.5
    assert orbit_status(report, CFG.fp_rho_max) == "no_stable_orbit"
    nr = newton(F, xs[31], step=CFG.fp_fd_step, jump=CFG.fp_fd_jump, tol=1e-12, iterations=8, damping=NEWTON_DAMPING)
    assert nr.converged and np.allclose(nr.x, F.x_star, atol=1e-12)
    settled = search(xs[:32], window=1)
    assert orbit_status(with_rho(settled, F, nr.x), CFG.fp_rho_max) == "unstable_orbit"
    assert with_rho(settled, F, nr.x).rho == pytest.approx(1.9, abs=1e-6)


@pytest.mark.parametrize("eigenvalues, status", [((0.98, 0.5, -0.3, 0.1), "ok"), ((1.02, 0.5, -0.3, 0.1),
                                                                                   "unstable_orbit"),
                                                 ((-1.05, 0.2, 0.0, 0.0), "unstable_orbit")])
@pytest.mark.parametrize("skew", [0.0, 0.4])
def test_linear_maps_have_their_spectral_radius(eigenvalues, status, skew):
    """ρ of a linear map (normal, or not: skew) from one finite-difference batch, within 1e-7 (the map is linear: only
    rounding); ρ 0.98 is accepted, 1.02 and 1.05 (a flip) refused."""
    F = LinearMap.with_spectrum(eigenvalues, np.array([0.3, -0.2, 1.0, 0.5]), skew=skew, seed=1)
    x = F.x_star + 1e-3 * np.array([1.0, 1.0, -1.0, 0.5])
    j = fd_jacobian(F, x, CFG.fp_fd_step, CFG.fp_fd_jump)
    np.testing.assert_allclose(j.matrix, F.a, atol=1e-8)
    rho, moduli = spectral_radius(j.matrix)
    assert rho == pytest.approx(F.rho, abs=1e-7) and moduli[0] == rho and np.all(np.diff(moduli) <= 0)
    np.testing.assert_allclose(sorted(moduli), sorted(np.abs(eigenvalues)), atol=1e-7)
    settled = search(np.repeat(x[None], 25, axis=0))  # an orbit that sits still: only ρ decides
    assert orbit_status(with_rho(settled, F, x), CFG.fp_rho_max) == status
    assert orbit_status(with_rho(settled, F, x), None) == "ok"  # ρ not asked for


def test_a_period_two_map_is_refused_with_that_reason():
    """The logistic map at r = 3.2 settles on a period-two orbit: successive iterates never settle, iterates two apart
    do, at the two known points; P∘P's own window settles."""
    F = QuadraticMap(3.2)
    xs = iterates(F, np.r_[0.3, 0.2, -0.1], 100)
    report = search(xs)
    assert report.settled is None and report.period_two and orbit_status(report, 1.0) == "period_two_orbit"
    np.testing.assert_allclose(sorted(xs[-2:, 0]), F.period_two, atol=1e-9)
    assert search(xs[::2]).settled is not None  # the stride map
    assert search(iterates(QuadraticMap(2.8), np.r_[0.3, 0.2, -0.1], 100)).period_two is False


@pytest.mark.parametrize("r", [2.8, 3.9])
def test_newton_converges_on_a_smooth_nonlinear_map(r):
    """Damped Newton on the logistic map from 0.05 off its fixed point: quadratic convergence to it (stable or not),
    the Jacobian there of spectral radius |2 − r|."""
    F = QuadraticMap(r, dim=4, gain=0.3)
    nr = newton(F, F.x_star + np.array([0.05, 0.1, -0.1, 0.2]), step=CFG.fp_fd_step, jump=CFG.fp_fd_jump, tol=1e-12,
                iterations=10, damping=NEWTON_DAMPING)
    assert nr.converged and np.allclose(nr.x, F.x_star, atol=1e-12) and len(nr.residuals) <= 7
    r_ = np.asarray(nr.residuals)
    assert np.all(np.diff(r_) < 0)
    big = r_[:-1] > 1e-6  # quadratic while above the finite-difference error
    assert np.all(r_[1:][big] <= 10 * r_[:-1][big] ** 2)
    assert nr.jacobian is not None and spectral_radius(nr.jacobian.matrix)[0] == pytest.approx(F.rho, abs=1e-6)
    assert nr.evaluations == len(nr.residuals) * (2 * 4 + 1) + (len(nr.residuals) - 1) * len(NEWTON_DAMPING)


def test_newton_does_not_claim_a_fixed_point_the_map_jumps_across():
    """A staircase map that jumps across the diagonal has no fixed point: its residual is nowhere below the gap at the
    jump, and Newton stops there (no damped step lowers it) without claiming convergence."""
    F = LinearMap.with_spectrum((0.5, 0.5), np.zeros(2), jump=-0.5e-4, width=1e-4, bias=0.4e-4)
    probe = np.linspace(-3e-4, 3e-4, 60001)[:, None] * np.array([1.0, 0.0])
    assert np.min(np.linalg.norm(F(probe) - probe, axis=1)) > 1e-5  # the residual's smallest value: at the jump
    nr = newton(F, np.array([1e-5, 0.0]), step=1e-7, jump=CFG.fp_fd_jump, tol=CFG.fp_newton_tol, iterations=10,
                damping=NEWTON_DAMPING)
    assert not nr.converged and nr.residuals[-1] > 1e-5


def test_a_column_with_a_jump_on_one_side_is_taken_from_the_other():
    """x sits 0.3 h below a jump of the staircase: the central difference along x_0 would be off by jump / 2h; the
    robust column is the backward difference, exact for the linear pieces, and says it was one-sided."""
    h = CFG.fp_fd_step
    F = LinearMap.with_spectrum((0.7, -0.4, 0.2), np.zeros(3), skew=0.3, jump=2e-3, width=1e-2)
    x = np.array([5e-3 - 0.3 * h, 0.01, -0.02])
    j = fd_jacobian(F, x, h, CFG.fp_fd_jump)
    assert j.one_sided == (0,)
    np.testing.assert_allclose(j.matrix, F.a, atol=1e-7)
    central = (F(x + h * np.eye(3)[0]) - F(x - h * np.eye(3)[0]))[0] / (2 * h)
    assert abs(central[0] - F.a[0, 0]) > 100  # what the rule avoids
    np.testing.assert_allclose(fd_jacobian(F, np.zeros(3), h, CFG.fp_fd_jump).matrix, F.a, atol=1e-8)


def test_a_side_that_falls_is_left_out_and_both_sides_falling_raise():
    a = LinearMap.with_spectrum((0.5, 0.1), np.zeros(2))

    def falls_right(x):  # type: ignore[no-untyped-def]
        out = a(x)
        out[np.asarray(x)[:, 1] > 1e-7] = np.nan
        return out

    j = fd_jacobian(falls_right, np.zeros(2), 1e-6, CFG.fp_fd_jump)
    assert j.one_sided == (1,) and np.allclose(j.matrix, a.a, atol=1e-8)
    with pytest.raises(RobustGaitError, match="falls on both sides of coordinate"):
        fd_jacobian(lambda x: np.where(np.abs(np.asarray(x)[:, :1]) > 0, np.nan, a(x)), np.zeros(2), 1e-6, 0.5)
    with pytest.raises(RobustGaitError, match="falls from the point"):
        fd_jacobian(lambda x: np.full_like(np.asarray(x), np.nan), np.zeros(2), 1e-6, 0.5)


def test_flow_projection_moves_the_event_onto_the_guard():
    """Π = I − f ∇gᵀ/(∇g·f): the image of Π lies in the guard's tangent space and the flow is its kernel — the
    linearization of a map whose event is found in continuous time (a change along the flow is only a change of the
    event's time)."""
    rng = np.random.default_rng(3)
    f, g = rng.standard_normal(5), rng.standard_normal(5)
    p = flow_projection(f, g)
    assert p is not None
    np.testing.assert_allclose(g @ p, 0.0, atol=1e-12)
    np.testing.assert_allclose(p @ f, 0.0, atol=1e-12)
    np.testing.assert_allclose(p @ p, p, atol=1e-12)
    assert flow_projection(np.array([1.0, 0.0]), np.array([0.0, 1.0])) is None  # the flow along the guard


def test_the_report_says_what_it_saw():
    xs = iterates(QuadraticMap(2.8), np.r_[0.3, 0.2, -0.1], 60)
    report = search(xs)
    assert report.converged and report.settled is not None and report.steps == report.settled
    assert report.window_residual <= CFG.fp_tol and len(report.residuals) == report.settled
    d = report.to_dict()
    assert d["converged"] and d["settled_at_step"] == report.settled and d["residuals"]["steps"] == report.settled
    assert "converged at step" in report.describe()
    wander = search(iterates(QuadraticMap(3.9), np.r_[0.3, 0.0, 0.0], 40))
    assert "NOT converged (wandering" in wander.describe() and wander.to_dict()["settled_at_step"] is None
    assert "period two" in search(iterates(QuadraticMap(3.2), np.r_[0.3, 0.0, 0.0], 60)).describe()
    short = search(iterates(QuadraticMap(2.8), np.r_[0.3, 0.0, 0.0], 4))
    assert "too few iterates for a window of 20: 4 steps" in short.describe()
    assert short.to_dict()["window_residual"] is None
    assert search(np.empty((0, 3))).steps == 0
