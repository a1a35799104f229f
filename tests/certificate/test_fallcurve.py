"""Tests for robustgait.certificate.fallcurve: the fall curve's disk average against quadrature, the posterior's
estimate and verification radius on curves whose answer is known, and the design of exploration pushes."""

from __future__ import annotations

import math

import numpy as np
import pytest

from robustgait.certificate.fallcurve import (
    disk_fall_fraction,
    fall_probability,
    fit_fall_curve,
)
from robustgait.errors import RobustGaitError


@pytest.mark.parametrize("b", [0.8, 4.0, 15.0, 60.0])
@pytest.mark.parametrize("floor", [0.0, 0.4])
@pytest.mark.parametrize("r", [0.5, 0.9, 1.6])
def test_the_disk_average_is_the_integral_of_the_curve(b: float, floor: float, r: float) -> None:
    """V(r) = (2/r²) ∫₀^r p(s) s ds, by the tables of G_b and H_b, against the trapezoid rule on 400 001 points."""
    mu = math.log(0.5)
    s = np.linspace(0.0, r, 400_001)[1:]
    direct = np.trapezoid(fall_probability(s, mu, b, floor) * s, s) * 2.0 / r**2
    assert float(disk_fall_fraction(r, mu, b, floor)) == pytest.approx(direct, rel=2e-3, abs=1e-12)


def test_the_curve_is_zero_at_and_below_its_floor_and_half_at_its_scale() -> None:
    assert fall_probability(np.array([0.5, 1.0]), 0.0, 3.0, 1.0).tolist() == [0.0, 0.0]
    assert float(fall_probability(2.0, 0.0, 3.0, 1.0)) == pytest.approx(0.5)
    assert float(disk_fall_fraction(1.0, 0.0, 3.0, 1.0)) == 0.0
    # far below s₅₀ without a floor, V is the tail 2 e^x / (b + 2) of the disk's average
    assert float(disk_fall_fraction(math.exp(-40.0 / 3.0), 0.0, 3.0)) == pytest.approx(0.4 * math.exp(-40.0), rel=1e-9)


def _pushes(rng: np.random.Generator, n: int, s0: float, s50: float, b: float, top: float) -> tuple[np.ndarray,
                                                                                                   np.ndarray]:
    s = rng.uniform(0.05, top, n)
    return s, rng.random(n) < fall_probability(s, math.log(s50 - s0), b, s0)


def test_the_fit_finds_a_known_curve_and_its_answers_follow_it() -> None:
    """800 pushes from a curve with a floor at 8, s₅₀ 15 and slope 4: the posterior's means lie near the truth, Ĵ is
    near the true r_ε, and the verification radius is below Ĵ, where the true pass probability of a batch of 154 is
    high."""
    s0, s50, b = 8.0, 15.0, 4.0
    s, y = _pushes(np.random.default_rng(0), 800, s0, s50, b, 30.0)
    c = fit_fall_curve(s, y, 40.0)
    assert c.weights.sum() == pytest.approx(1.0) and c.n_pushes == 800 and c.n_fell == int(y.sum())
    # the floor is seen only through the curve's slow onset above it: below the truth, not above it
    assert c.s50() == pytest.approx(s50, rel=0.1) and 0.5 * s0 < c.floor() < 1.1 * s0
    truth = [float(disk_fall_fraction(r, math.log(s50 - s0), b, s0)) for r in (9.0, 11.0, 13.0)]
    assert [c.fall_share(r) for r in (9.0, 11.0, 13.0)] == pytest.approx(truth, abs=0.01)
    j_hat = c.estimate(0.02)
    assert float(disk_fall_fraction(j_hat, math.log(s50 - s0), b, s0)) == pytest.approx(0.02, abs=0.008)
    r_v = c.verification_radius(154, 0.9)
    assert r_v < j_hat and c.pass_probability(r_v, 154) == pytest.approx(0.9, abs=1e-3)
    assert (1.0 - float(disk_fall_fraction(r_v, math.log(s50 - s0), b, s0))) ** 154 > 0.5
    # the predictive probability decreases with the radius and the batch
    assert c.pass_probability(0.5 * r_v, 154) >= c.pass_probability(r_v, 154) >= c.pass_probability(r_v, 300)


def test_the_estimate_moves_smoothly_with_one_push() -> None:
    """Ĵ is a function of every push: moving one push that fell changes it a little, not by a jump to another push's
    size (the nearest fall's estimator tied gaits whose nearest fall was the same push)."""
    s, y = _pushes(np.random.default_rng(1), 120, 5.0, 12.0, 5.0, 25.0)
    base = fit_fall_curve(s, y, 30.0).estimate(0.02)
    k = int(np.flatnonzero(y)[np.argmin(np.abs(s[y] - 12.0))])  # the push that fell nearest s₅₀
    moved = s.copy()
    moved[k] *= 1.01
    other = fit_fall_curve(moved, y, 30.0).estimate(0.02)
    assert other != base and abs(other / base - 1.0) < 0.01


def test_falls_among_small_pushes_lower_the_estimate() -> None:
    s, y = _pushes(np.random.default_rng(2), 150, 5.0, 12.0, 5.0, 25.0)
    more = y | ((s > 6.0) & (s < 8.0))
    assert fit_fall_curve(s, more, 30.0).estimate(0.02) < fit_fall_curve(s, y, 30.0).estimate(0.02)


def test_no_falls_leave_the_curve_above_the_pushes() -> None:
    s = np.geomspace(0.1, 10.0, 60)
    c = fit_fall_curve(s, np.zeros(60, dtype=bool), 20.0)
    assert c.n_fell == 0 and c.estimate(0.02) > 5.0


@pytest.mark.parametrize(("sizes", "fell", "cap", "match"), [
    ([1.0, 2.0], [True], 10.0, "one outcome per push size"),
    ([1.0, -2.0], [True, False], 10.0, "finite and > 0"),
    ([1.0], [True], 0.0, "cap must be a finite size"),
])
def test_bad_input_is_one_line(sizes: list[float], fell: list[bool], cap: float, match: str) -> None:
    with pytest.raises(RobustGaitError, match=match):
        fit_fall_curve(sizes, fell, cap)
