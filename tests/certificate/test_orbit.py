"""The orbit a map settles on, from its iterates (robustgait.certificate.orbit) — on maps whose answer is known
(robustgait.certificate.synthetic): a contraction, a noisy attractor, a slow drift, an expansion that wanders beyond
its band, period-two and period-four orbits — and the numerics of the linearization diagnostic (finite differences of
piecewise-smooth maps, spectral radii, the event's flow projection)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from robustgait import RobustGaitError
from robustgait.certificate import Iterated, find_orbit
from robustgait.certificate.barrier import certify_map
from robustgait.certificate.numerics import fd_jacobian, flow_projection, spectral_radius
from robustgait.certificate.orbit import Status, classify, periods, settle_window
from robustgait.certificate.synthetic import DriftMap, LinearMap, NoisyMap, QuadraticMap, iterates
from robustgait.config import CertifyConfig

CFG = CertifyConfig()  # the shipped orbit options and recovery band
ORBIT = CFG.orbit
START = np.r_[0.3, 0.2, -0.1]


def search(F, x0=START, **kw):  # type: ignore[no-untyped-def]
    """The orbit search on a synthetic map, probing with perturbations of 0.1 (outside the band's floor 0.03)."""
    return find_orbit(Iterated(F, x0, kw.pop("perturbation", 0.1), **kw), CFG)


def test_a_contraction_is_accepted_on_its_fixed_point():
    """A linear map of spectral radius 0.8 from 0.3 away: settled, period 1, x* within the band of the true fixed point,
    σ far below the floor; every perturbed state comes back (and each left the band first: the probe tested
    something)."""
    F = LinearMap.with_spectrum((0.8, 0.5, -0.3), np.array([0.1, 0.2, 0.3]), skew=0.2)
    o = search(F)
    assert o.status == Status.OK and o.ok and o.period == 1 and o.band is not None
    assert o.sigma is not None and o.sigma < ORBIT.floor and o.held == ORBIT.hold_steps
    assert o.steps == o.band_steps[1] < ORBIT.max_steps + ORBIT.hold_steps
    np.testing.assert_allclose(o.band.centres[0], F.x_star, atol=1e-3)
    assert o.probe is not None and o.probe.ok and sum(o.probe.left) >= len(o.probe.left) // 2
    assert "settled at step" in o.describe() and o.to_dict()["period"] == 1


def test_a_noisy_contraction_is_accepted_with_its_scatter():
    """The same contraction plus uniform noise of ±0.01: no point attractor, a band — accepted, σ reported, of the
    noise's order (at most amplitude / (1 − 0.8) = 0.05 in a coordinate, at least the amplitude's half)."""
    F = NoisyMap(LinearMap.with_spectrum((0.8, 0.5, -0.3), np.zeros(3)), 0.01, seed=4)
    o = search(F)
    assert o.ok and o.period == 1 and o.sigma is not None and 0.005 < o.sigma < 0.05
    assert o.to_dict()["sigma"] == o.sigma and f"σ = {o.sigma:.2g}" in o.describe()


@pytest.mark.parametrize("velocity", [0.002, 2e-4])
def test_a_slow_drift_is_refused(velocity):
    """Every coordinate follows the first, which advances a little each map: the iterates never settle — the last
    window leaves the band of the one before, or its centre moves by more than its own scatter."""
    o = search(DriftMap(velocity))
    assert o.status == Status.UNSETTLED and not o.ok
    assert "keeps growing" in o.reason or "keeps moving" in o.reason or "then left that band" in o.reason


@pytest.mark.parametrize("seed", range(5))
def test_a_map_that_wanders_beyond_its_band_is_refused(seed):
    """A slow expansion (eigenvalue 1.08) with noise: from 0.01 off its fixed point the iterates leave every band they
    were in (a growing band); from the noise floor they first look settled, and the probe's perturbed states do not
    come back (unstable). Refused either way, whatever the noise's draw."""
    F = NoisyMap(LinearMap.with_spectrum((1.08, 0.5, 0.2), np.zeros(3)), 1e-4, seed=seed)
    o = search(F, np.r_[0.01, 0.0, 0.0])
    assert o.status == Status.UNSETTLED and "keeps growing" in o.reason, o.reason
    quiet = search(F, np.zeros(3))
    assert quiet.status in (Status.UNSETTLED, Status.UNSTABLE) and not quiet.ok


def test_a_settled_walk_that_does_not_come_back_is_unstable():
    """A band with a repelling direction beyond it: x ↦ x* + 0.5 (x − x*) inside |x_0 − x*_0| < 0.05, expanding
    ×1.5 outside — the iterates settle on x*, but perturbations of 0.1 never return: unstable."""
    inner = LinearMap.with_spectrum((0.5, 0.5, 0.5), np.zeros(3))

    def F(x):  # type: ignore[no-untyped-def]
        out = inner(x)
        far = np.abs(np.asarray(x)[:, 0]) >= 0.05
        out[far, 0] = 1.5 * np.asarray(x)[far, 0]
        return out

    o = search(F, np.array([0.02, 0.1, 0.1]))
    assert o.status == Status.UNSTABLE and o.band is not None and o.probe is not None and not o.probe.ok
    assert "moved away from its band" in o.reason and any(o.probe.diverging) and not any(o.probe.fell)
    assert search(F, np.array([0.02, 0.1, 0.1]), perturbation=0.04).ok  # within the basin: they come back


def test_a_probe_that_settles_on_another_orbit_of_the_gait_is_not_a_divergence():
    """Two attractors, x_0 = 0 and x_0 = 0.2 (a gait that walks two orbits, as Atalante's L 0.18 T 0.6 does: period 2,
    and period 1 once pushed): perturbed states that land in the other one stay near it without entering the band —
    they do not move away, and the orbit is stable; a state that falls is not."""
    inner = LinearMap.with_spectrum((0.5, 0.5, 0.5), np.zeros(3))

    def F(x):  # type: ignore[no-untyped-def]
        out = inner(x)
        far = np.asarray(x)[:, 0] > 0.06
        out[far, 0] = 0.2 + 0.5 * (np.asarray(x)[far, 0] - 0.2)
        return out

    o = search(F, np.array([0.02, 0.1, 0.1]))
    assert o.ok and o.probe is not None and not all(o.probe.recovered) and not any(o.probe.diverging)
    assert "stayed near it" in o.describe()


@pytest.mark.parametrize("r, k", [(3.2, 2), (3.5, 4)])
def test_period_two_and_four_orbits_are_recognised_and_certified_on_their_own_map(r, k):
    """The logistic map at r = 3.2 settles on a period-two orbit, at 3.5 on a period-four one: recognised with that
    period (not refused), x* on the orbit; the k-fold map has x* as a fixed point and a barrier certificate around it,
    the map itself none (it moves x* to the orbit's next point)."""
    F = QuadraticMap(r)
    # probes of 0.01 (a band of 0.003): 0.05 off the period-four orbit lies near the unstable period-two one, which a
    # perturbed state leaves only slowly
    fine = dataclasses.replace(CFG, push=dataclasses.replace(CFG.push, recovery_radius=0.003))
    o = find_orbit(Iterated(F, START, 0.01), fine)
    assert o.ok and o.period == k and o.probe is not None and any(o.probe.left), o.describe()
    x_star = o.band.centres[0]
    if k == 2:
        assert min(abs(x_star[0] - p) for p in F.period_two) < 1e-6

    def Fk(x):  # type: ignore[no-untyped-def]
        for _ in range(k):
            x = F(x)
        return x

    np.testing.assert_allclose(Fk(x_star[None])[0], x_star, atol=1e-6)
    cfg = CertifyConfig(disturbance="state", method="uniform", r_max=0.05, n_samples=200)
    own = certify_map(Fk, x_star, cfg)
    assert own.radius > 0.0 and not own.vacuous
    assert certify_map(F, x_star, cfg).vacuous  # every sample's image is the orbit's next point, far away


def test_a_robot_whose_sides_differ_is_searched_from_period_two():
    """min_period 2 (the stride map: a robot whose left and right differ) finds a period-2 orbit even where period 1
    explains the iterates as well — the map certified is the walk's two steps."""
    F = LinearMap.with_spectrum((0.7, 0.5, 0.2), np.zeros(3))
    assert search(F).period == 1 and search(F, min_period=2).period == 2
    assert periods(4) == (1, 2, 4) and periods(4, 2) == (2, 4) and periods(1) == (1,)


def test_a_band_that_moves_after_it_settled_is_refused():
    """Settled on its fixed point, then the map starts drifting (a slope that turns the walk: a gait that falls after
    hundreds of steps looks settled for dozens): the hold sees the band's centre move and refuses it."""
    inner = LinearMap.with_spectrum((0.5, 0.5, 0.5), np.zeros(3))
    calls = {"n": 0}

    def F(x):  # type: ignore[no-untyped-def]
        calls["n"] += 1
        out = inner(x)
        if calls["n"] > 40:
            out[:, 0] += 0.002 * (calls["n"] - 40) / 40  # a drift that starts after the walk settled
        return out

    o = search(F)
    assert o.status == Status.UNSETTLED and "then left that band" in o.reason and o.settled is not None
    assert o.held < ORBIT.hold_steps


def test_a_fall_and_a_short_walk_are_said_as_such():
    """A map whose image is not finite after 12 maps: the orbit is 'fell', with the step; a sequence shorter than
    two windows cannot be told."""
    calls = {"n": 0}

    def F(x):  # type: ignore[no-untyped-def]
        calls["n"] += 1
        out = 0.5 * np.asarray(x)
        return out if calls["n"] < 12 else np.full_like(out, np.nan)

    o = search(F)
    assert o.status == Status.FELL and "fell in step 12" in o.reason and o.steps == 11
    z = iterates(QuadraticMap(2.8), START, 10)[1:]
    short, i = classify(z, ORBIT, min_period=1, radius=0.03, multiple=3.0)
    assert i is None and short.status == Status.UNDECIDED and "before its switching states settled" in short.reason


def test_the_settling_test_compares_the_last_window_with_the_one_before():
    """Two windows of a constant sequence settle at once; a jump in the last window larger than settle_multiple × the
    window before's scatter (or the floor) is a growing band; a centre that moved by more than drift × the last
    window's scatter is a moving band."""
    w = ORBIT.window
    z = np.zeros((2 * w, 2))
    assert settle_window(z, 1, ORBIT, 1, 0.03, 3.0).__class__.__name__ == "Settling"
    z[-1, 0] = 2 * ORBIT.floor
    out = settle_window(z, 1, ORBIT, 1, 0.03, 3.0)
    assert out.__class__.__name__ == "Unsettled" and out.why == "growing"
    z[:w, 0] = 0.005 * (-1.0) ** np.arange(w)  # the window before scatters 0.005: the jump is now inside its band
    assert settle_window(z, 1, ORBIT, 1, 0.03, 3.0).__class__.__name__ == "Settling"
    cfg = dataclasses.replace(ORBIT, settle_multiple=0.1)
    assert settle_window(z, 1, cfg, 1, 0.03, 3.0).__class__.__name__ == "Unsettled"
    z[w:, 1] = 0.004  # B moved from A's centre by 0.004 > its own scatter (the floor, 0.001)
    out = settle_window(z, 1, ORBIT, 1, 0.03, 3.0)
    assert out.__class__.__name__ == "Unsettled" and out.why == "moving"


@pytest.mark.parametrize("eigenvalues", [(0.98, 0.5, -0.3, 0.1), (1.02, 0.5, -0.3, 0.1), (-1.05, 0.2, 0.0, 0.0)])
@pytest.mark.parametrize("skew", [0.0, 0.4])
def test_linear_maps_have_their_spectral_radius(eigenvalues, skew):
    """ρ of a linear map (normal, or not: skew) from one finite-difference batch, within 1e-7 (the map is linear: only
    rounding)."""
    F = LinearMap.with_spectrum(eigenvalues, np.array([0.3, -0.2, 1.0, 0.5]), skew=skew, seed=1)
    x = F.x_star + 1e-3 * np.array([1.0, 1.0, -1.0, 0.5])
    j = fd_jacobian(F, x, ORBIT.fd_step, ORBIT.fd_jump)
    np.testing.assert_allclose(j.matrix, F.a, atol=1e-8)
    rho, moduli = spectral_radius(j.matrix)
    assert rho == pytest.approx(F.rho, abs=1e-7) and moduli[0] == rho and np.all(np.diff(moduli) <= 0)
    np.testing.assert_allclose(sorted(moduli), sorted(np.abs(eigenvalues)), atol=1e-7)


def test_a_column_with_a_jump_on_one_side_is_taken_from_the_other():
    """x sits 0.3 h below a jump of the staircase: the central difference along x_0 would be off by jump / 2h; the
    robust column is the backward difference, exact for the linear pieces, and says it was one-sided."""
    h = ORBIT.fd_step
    F = LinearMap.with_spectrum((0.7, -0.4, 0.2), np.zeros(3), skew=0.3, jump=2e-3, width=1e-2)
    x = np.array([5e-3 - 0.3 * h, 0.01, -0.02])
    j = fd_jacobian(F, x, h, ORBIT.fd_jump)
    assert j.one_sided == (0,)
    np.testing.assert_allclose(j.matrix, F.a, atol=1e-7)
    central = (F(x + h * np.eye(3)[0]) - F(x - h * np.eye(3)[0]))[0] / (2 * h)
    assert abs(central[0] - F.a[0, 0]) > 100  # what the rule avoids
    np.testing.assert_allclose(fd_jacobian(F, np.zeros(3), h, ORBIT.fd_jump).matrix, F.a, atol=1e-8)


def test_a_side_that_falls_is_left_out_and_both_sides_falling_raise():
    a = LinearMap.with_spectrum((0.5, 0.1), np.zeros(2))

    def falls_right(x):  # type: ignore[no-untyped-def]
        out = a(x)
        out[np.asarray(x)[:, 1] > 1e-7] = np.nan
        return out

    j = fd_jacobian(falls_right, np.zeros(2), 1e-6, ORBIT.fd_jump)
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


def test_the_linearization_says_what_a_repelling_point_means_and_when_it_is_not_defined() -> None:
    from robustgait.certificate.orbit import Linearization

    stable = Linearization(True, 0.8, 0.82, 0.7).describe()
    assert stable.startswith("ρ = 0.8 ") and "repels" not in stable
    repelling = Linearization(True, 1.23, 1.227, 1.32).describe()
    assert "ρ = 1.23" in repelling and "repels tiny perturbations" in repelling and "band's scale" in repelling
    undefined = Linearization(False, 1.31, 0.81, None, reason="1.31 and 0.81 more than 10 % apart").describe()
    assert undefined.startswith("linearization not defined (contact events)") and "0.81" in undefined


def test_a_probe_that_falls_measures_the_basin_and_one_that_moves_away_the_orbit() -> None:
    """Stable: none of the probes moved away and not all fell (a fall is J*'s business); unstable: one moved away, or
    every one fell."""
    from robustgait.certificate.orbit import Probe

    def probe(recovered, fell, diverging):  # type: ignore[no-untyped-def]
        n = len(recovered)
        return Probe(1.0, 20, tuple(recovered), tuple(3 if r else 0 for r in recovered), tuple(fell), (True,) * n,
                     tuple(diverging))

    assert probe([True, True, False], [False, False, True], [False] * 3).ok
    assert not probe([True, True, False], [False, False, False], [False, False, True]).ok
    assert not probe([False] * 3, [True] * 3, [False] * 3).ok
    assert probe([False] * 3, [False] * 3, [False] * 3).ok  # near the band without entering it: not a divergence
