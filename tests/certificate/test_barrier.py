"""Tests for robustgait.certificate.barrier: DTBF, exact r* from samples, confidence bound, logged trajectories."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays
from scipy import stats

from robustgait.certificate.barrier import (
    barrier_along,
    barrier_margin,
    barrier_value,
    certificate_from_samples,
    certify_map,
    invariant_radius,
    load_reduced_log,
    sample_ball,
    solve_radius,
    violation_bound,
    violation_end,
)
from robustgait.config import CertifyConfig
from robustgait.errors import RobustGaitError


def uniform(**kw: object) -> CertifyConfig:
    """The paper's estimator with these options (a state certificate unless told)."""
    return CertifyConfig(method="uniform", **{"disturbance": "state", **kw})  # type: ignore[arg-type]

# ------------------------------------------------------------------------------ brute-force reference


def _feasible(r: float, d: np.ndarray, p: np.ndarray, alpha: float, slack: float, barrier: str = "ball") -> bool:
    """Definition of docs/certificate.md, checked directly: every sample with d_i ≤ r has α r² ≥ p_i² − (1−α) d_i²
    (α r ≥ … for the paper's barrier)."""
    act = d <= r
    with np.errstate(over="ignore", invalid="ignore"):
        rhs = p[act] ** 2 - (1.0 - alpha) * d[act] ** 2
    level = r * r if barrier == "ball" else r
    return bool(np.all(alpha * level >= rhs + slack))


def _reference(d: np.ndarray, p: np.ndarray, alpha: float, r_max: float, slack: float, barrier: str = "ball") -> float:
    """Largest feasible radius on a dense set: a grid, every candidate and points just below/above."""
    with np.errstate(over="ignore", invalid="ignore"):
        c = (p**2 - (1.0 - alpha) * d**2) / alpha
    ends = c[np.isfinite(c) & (c > 0)]
    cands = np.concatenate([[r_max], d, np.sqrt(ends) if barrier == "ball" else ends])
    radii = np.concatenate([np.linspace(0.0, r_max, 401), cands, cands * (1 - 1e-9), cands * (1 + 1e-9), cands - 1e-12])
    radii = np.unique(radii[(radii >= 0) & (radii <= r_max)])
    best = 0.0
    for r in radii[::-1]:
        if _feasible(float(r), d, p, alpha, slack, barrier):
            best = float(r)
            break
    return best


coord = st.floats(-2.0, 2.0, allow_nan=False, allow_subnormal=False)


@st.composite
def random_sample_sets(draw: st.DrawFn) -> tuple[np.ndarray, np.ndarray, np.ndarray, float, float]:
    """Generic sets from a seeded generator: points in a ball, images x* + g (x − x*) + noise, some falls."""
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    n, N = int(rng.integers(1, 4)), int(rng.integers(1, 60))
    r_max = float(rng.uniform(0.1, 3.0))
    x_star = rng.uniform(-1, 1, n)
    x0 = sample_ball(N, n, r_max * rng.uniform(0.5, 1.5), x_star, rng)
    low = rng.uniform(0.0, 1.1)  # gains near 1 give short bad intervals, hence gaps (non-interval sets)
    gains = rng.uniform(low, low + rng.uniform(0.0, 0.6), N)
    x1 = x_star + gains[:, None] * (x0 - x_star) + rng.normal(0, rng.uniform(0, 0.1), (N, n))
    d = np.linalg.norm(x0 - x_star, axis=1)
    fell = rng.random(N) < rng.uniform(0, 0.3) if rng.random() < 0.5 else d > rng.uniform(0, r_max)
    x1[fell, 0] = np.nan
    return x0, x1, x_star, float(rng.uniform(0.01, 0.5)), r_max


@st.composite
def sample_sets(draw: st.DrawFn) -> tuple[np.ndarray, np.ndarray, np.ndarray, float, float]:
    """Sets drawn element-wise by hypothesis (edge cases: zeros, repeated rows, identity images)."""
    n = draw(st.integers(1, 3))
    N = draw(st.integers(1, 25))
    x_star = draw(arrays(np.float64, n, elements=st.floats(-1, 1, allow_subnormal=False)))
    x0 = draw(arrays(np.float64, (N, n), elements=coord))
    gains = draw(arrays(np.float64, N, elements=st.floats(0.0, 1.6, allow_subnormal=False)))
    noise = draw(arrays(np.float64, (N, n), elements=st.floats(-0.3, 0.3, allow_subnormal=False)))
    x1 = x_star + gains[:, None] * (x0 - x_star) + noise * draw(st.sampled_from([0.0, 1.0]))
    fell = draw(arrays(np.bool_, N))
    x1[fell, draw(st.integers(0, n - 1))] = np.nan
    alpha = draw(st.floats(0.01, 0.99))
    r_max = draw(st.floats(0.05, 4.0))
    return x0, x1, x_star, alpha, r_max


@pytest.mark.slow  # keeps plain pytest within 60 s; CI runs it
@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.one_of(sample_sets(), random_sample_sets()), st.sampled_from(["ball", "paper"]))
def test_invariant_radius_matches_brute_force(case: tuple[np.ndarray, np.ndarray, np.ndarray, float, float],
                                              barrier: str) -> None:
    x0, x1, x_star, alpha, r_max = case
    r_star = invariant_radius(x0, x1, x_star, alpha=alpha, r_max=r_max, barrier=barrier)  # type: ignore[arg-type]
    assert 0.0 <= r_star <= r_max
    d = np.linalg.norm(x0 - x_star, axis=1)
    p = np.linalg.norm(x1 - x_star, axis=1)
    p[np.isnan(p)] = np.inf
    # strict (slack > 0) / lenient (slack < 0) versions absorb rounding exactly at a candidate radius
    ref_strict = _reference(d, p, alpha, r_max, slack=1e-12, barrier=barrier)
    ref_lenient = _reference(d, p, alpha, r_max, slack=-1e-12, barrier=barrier)
    assert ref_strict - 1e-7 <= r_star <= ref_lenient + 1e-7

    cert = certificate_from_samples(x0, x1, x_star, alpha=alpha, r_max=r_max, beta=0.05, barrier=barrier)  # type: ignore[arg-type]
    assert cert.radius == r_star
    inside = d <= r_star if cert.attained else d < r_star
    assert cert.n_inside == int(inside.sum())
    assert np.all(cert.margins[inside] >= -1e-12)
    if cert.attained:
        assert r_star == r_max
    else:  # the supremum is the distance of a sample that violates there (or fell)
        assert np.any(d == r_star)
        assert np.min(cert.margins[d == r_star]) < 1e-12


# ------------------------------------------------------------------------------------ exact small sets


def test_feasible_set_need_not_be_an_interval() -> None:
    # one 1-D sample at d = 0.5 with image at p = sqrt(0.25 + 0.05·0.49): violated for r ∈ [0.5, 0.7)
    # (c = (p² − 0.95·0.25)/0.05 = 0.49), satisfied again from 0.7 on, so r_max = 1 is feasible.
    alpha = 0.05
    p = math.sqrt(0.95 * 0.25 + alpha * 0.49)
    sol = solve_radius(np.array([0.5]), np.array([p]), alpha=alpha, r_max=1.0)
    assert sol == (1.0, True)
    # with r_max inside the bad interval, the supremum is 0.5, not attained
    sol = solve_radius(np.array([0.5]), np.array([p]), alpha=alpha, r_max=0.6)
    assert sol.radius == 0.5 and not sol.attained
    # a fall at 0.8 after the gap [0.7, 0.8): radii just below 0.8 are feasible, so r* = 0.8 (not 0.5)
    sol = solve_radius(np.array([0.5, 0.8]), np.array([p, np.inf]), alpha=alpha, r_max=1.0)
    assert sol.radius == 0.8 and not sol.attained


def test_paper_barrier_condition_and_interval() -> None:
    # the paper's H = r − ‖x − x*‖²: sample i must satisfy α r ≥ p² − (1 − α) d², violated for r ∈ [d, c)
    # (c = (p² − (1 − α) d²)/α, not √c). α = 1/2, d = 1/8, p = 5/8: c = 2p² − d² = 49/64.
    d, p = np.array([0.125]), np.array([0.625])
    assert violation_end(d, p, 0.5, "paper")[0] == 49 / 64 and violation_end(d, p, 0.5)[0] == 7 / 8
    assert solve_radius(d, p, alpha=0.5, r_max=49 / 64, barrier="paper") == (49 / 64, True)
    assert solve_radius(d, p, alpha=0.5, r_max=0.7, barrier="paper") == (0.125, False)
    assert solve_radius(d, p, alpha=0.5, r_max=0.8) == (0.125, False)  # ball: bad up to 7/8
    # values and margins: H = r − ‖x − x*‖² and m = α r − p² + (1 − α) d²
    assert barrier_value(np.array([[0.5, 0.0]]), [0, 0], 0.5, "paper")[0] == 0.25
    m = barrier_margin(np.array([[0.125]]), np.array([[0.625]]), [0.0], 0.7, 0.5, "paper")[0]
    assert m == pytest.approx(0.5 * 0.7 - 0.625**2 + 0.5 * 0.125**2)
    with pytest.raises(RobustGaitError, match="barrier: must be one of 'ball', 'paper'"):
        uniform(barrier="hat")
    # for r < 1 the paper's condition is weaker: its r* is at least the ball's on the same samples
    x_star = np.zeros(3)
    cb = certify_map(lambda x: 1.02 * x + 0.02 * x**2, x_star, uniform(r_max=0.9, seed=3))
    cp = certify_map(lambda x: 1.02 * x + 0.02 * x**2, x_star, uniform(r_max=0.9, seed=3, barrier="paper"))
    assert cp.radius > cb.radius and cp.barrier == "paper" and "paper barrier" in cp.statement()


def test_touching_intervals_and_boundary_at_r_max() -> None:
    # exact dyadic arithmetic: α = 1/2, d = 1/8, p = 5/8 → c = 2p² − d² = 49/64, bad on [1/8, 7/8)
    d, p = np.array([0.125]), np.array([0.625])
    assert solve_radius(d, p, alpha=0.5, r_max=0.875) == (0.875, True)  # satisfied exactly at r_max
    assert solve_radius(d, p, alpha=0.5, r_max=0.8) == (0.125, False)
    # a fall exactly at 7/8 touches [1/8, 7/8): no feasible radius in between, r* = 1/8
    sol = solve_radius(np.array([0.125, 0.875]), np.array([0.625, np.inf]), alpha=0.5, r_max=1.0)
    assert sol == (0.125, False)


def test_fell_sample_gives_unattained_supremum() -> None:
    x0 = np.array([[0.2], [-0.5], [0.8], [1.5]])
    x1 = np.array([[0.1], [-0.25], [np.nan], [0.0]])  # the sample at 0.8 fell
    assert invariant_radius(x0, x1, [0.0], alpha=0.05, r_max=2.0) == 0.8
    cert = certificate_from_samples(x0, x1, [0.0], alpha=0.05, r_max=2.0, beta=0.05, barrier="ball")
    assert not cert.attained and cert.n_inside == 2  # the open ball: 0.2 and 0.5
    assert cert.fell.tolist() == [False, False, True, False]
    assert cert.margins[2] == -np.inf
    # chained bad intervals: 0.3 violated on [0.3, 0.9), overlapping the fall at 0.8 → r* = 0.3
    p03 = math.sqrt(0.95 * 0.09 + 0.05 * 0.81)
    x0 = np.vstack([x0, [[0.3]]])
    x1 = np.vstack([x1, [[p03]]])
    assert invariant_radius(x0, x1, [0.0], alpha=0.05, r_max=2.0) == pytest.approx(0.3, abs=1e-15)


# ----------------------------------------------------------------------------------- known answers


def test_linear_contraction_gives_r_max() -> None:
    x_star = np.array([0.3, -0.2, 1.0])
    cert = certify_map(lambda x: x_star + 0.5 * (x - x_star), x_star, uniform(r_max=1.5, n_samples=500, seed=1))
    assert cert.radius == 1.5 and cert.attained
    assert cert.n_inside == 500 and not cert.fell.any()
    assert np.all(cert.margins >= 0)


def test_expanding_direction_drives_r_star_to_zero() -> None:
    # P(x) = diag(0.5, 0.5, 1.5) x: points on the third axis leave every ball, so the true r* is 0.
    D = np.diag([0.5, 0.5, 1.5])
    radii = [certify_map(lambda x: x @ D, np.zeros(3), uniform(n_samples=N, seed=0)).radius for N in (50, 500, 5000)]
    assert radii[0] > radii[1] > radii[2]
    assert radii[2] < 0.25


def test_cubic_map_hand_derived_radius() -> None:
    # P(x) = x³, x* = 0 (1-D; fixed points ±1). For a sample with d = |x|: p = d³ and the condition at
    # r reads α r² ≥ d⁶ − (1−α) d². If d ≤ 1 then d⁶ − (1−α)d² ≤ α d² ≤ α r² for every r ≥ d: never
    # violated. If d > 1 it fails at r = d (needs d⁴ ≤ 1). True r* (all x): max over |x| ≤ r of
    # x⁶ − (1−α)x² is r⁶ − (1−α)r² (convex in x²), so α r² ≥ r⁶ − (1−α) r² ⇔ r ≤ 1: r* = 1. From samples
    # r* = the smallest d_i > 1 (the bad intervals [d, d·√((d⁴−1+α)/α)) chain up to r_max for dense
    # samples), i.e. 1 ≤ r* ≤ 1 + t with P(no d_i in (1, 1+t)) = (1 − t/2)^N ≈ e^{−Nt/2}: t = 24/N.
    for N in (400, 4000):
        cert = certify_map(lambda x: x**3, np.zeros(1), uniform(r_max=2.0, n_samples=N, seed=2))
        assert 1.0 <= cert.radius <= 1.0 + 24.0 / N
        assert not cert.attained


def test_fell_region_hand_derived_radius() -> None:
    # 2-D: P(x) = 0.5 x if ‖x‖ ≤ a, else a fall. Samples with d ≤ a contract (never violated), samples
    # with d > a fell (violated for all r ≥ d). So r* = min{d_i > a} ≥ a, and with N uniform samples in
    # B_2, P(r* > a + t) = (1 − ((a+t)² − a²)/4)^N ≤ e^{−N·a·t/2}: t = 24/(a N).
    a = 0.7

    def P(x: np.ndarray) -> np.ndarray:
        return np.where(np.linalg.norm(x, axis=1, keepdims=True) <= a, 0.5 * x, np.nan)

    for N in (300, 3000):
        cert = certify_map(P, np.zeros(2), uniform(r_max=2.0, n_samples=N, seed=3))
        assert a <= cert.radius <= a + 24.0 / (a * N)
        assert not cert.attained
        assert cert.n_inside == int(np.sum(np.linalg.norm(cert.samples, axis=1) <= a))


# ------------------------------------------------------------------------------------ sampling, bound


def test_sample_ball_is_uniform() -> None:
    rng = np.random.default_rng(7)
    center = np.array([1.0, -2.0, 0.5])
    x = sample_ball(4000, 3, 1.5, center, rng)
    assert x.shape == (4000, 3)
    rho = np.linalg.norm(x - center, axis=1) / 1.5
    assert rho.max() <= 1.0
    # radial law P(ρ ≤ q) = q³  ⇔  ρ³ ~ U(0, 1)
    assert stats.kstest(rho**3, "uniform").pvalue > 1e-3
    # direction: on S², each coordinate of the unit vector is U(−1, 1) (Archimedes)
    u = (x - center) / (1.5 * rho[:, None])
    for k in range(3):
        assert stats.kstest(u[:, k], stats.uniform(loc=-1, scale=2).cdf).pvalue > 1e-3
    # binomial check of one fraction: inside half the radius ≈ 1/8
    frac = np.mean(rho <= 0.5)
    assert abs(frac - 0.125) < 5 * math.sqrt(0.125 * 0.875 / 4000)


def test_violation_bound_formula() -> None:
    assert violation_bound(0, 200, 0.05) == 1.0
    assert violation_bound(200, 200, 0.05) == pytest.approx(1 - (0.05 / 201) ** (1 / 200), rel=1e-12)
    assert violation_bound(50, 200, 0.05) > violation_bound(100, 200, 0.05)
    eps = violation_bound(37, 100, 0.1)
    assert (1 - eps) ** 37 == pytest.approx(0.1 / 101, rel=1e-9)


def test_certificate_statement_and_json() -> None:
    P = lambda x: np.where(np.abs(x) > 1.2, np.nan, 0.5 * x)  # noqa: E731
    cert = certify_map(P, np.zeros(1), uniform(n_samples=100, seed=4))
    assert cert.confidence == 0.95
    assert cert.violation_bound == violation_bound(cert.n_inside, 100, 0.05)
    text = cert.statement()
    assert "95%" in text and f"{100 * cert.violation_bound:.3g}%" in text and "\n" not in text
    d = json.loads(json.dumps(cert.to_dict(), allow_nan=False))
    assert d["value"] == cert.radius and d["verified"] and d["n_inside"] == cert.n_inside
    fell = np.asarray(d["fell"])
    assert fell.any() and all(d["images"][i] is None for i in np.flatnonzero(fell))
    assert all(d["margins"][i] is None for i in np.flatnonzero(fell))
    assert all(d["images"][i] is not None for i in np.flatnonzero(~fell))


def test_same_seed_same_certificate() -> None:
    def P(x: np.ndarray) -> np.ndarray:
        return 0.9 * x + 0.2 * x**2

    a = certify_map(P, np.zeros(2), uniform(n_samples=150, seed=11))
    b = certify_map(P, np.zeros(2), uniform(n_samples=150, seed=11))
    c = certify_map(P, np.zeros(2), uniform(n_samples=150, seed=12))
    assert a.to_dict() == b.to_dict()
    assert np.array_equal(a.samples, b.samples) and a.seed == 11
    assert not np.array_equal(a.samples, c.samples)


@pytest.mark.parametrize(
    "kwargs",
    [
        {"r_max": 0.0},
        {"r_max": -1.0},
        {"r_max": math.inf},
        {"r_max": math.nan},
        {"alpha": 0.0},
        {"alpha": 1.0},
        {"alpha": -0.1},
        {"n_samples": 0},
        {"beta": 0.0},
        {"x_star": [0.0, math.nan]},
        {"P": lambda x: x[:, :1]},
        {"P": lambda x: x.T},
        {"P": lambda x: x[0]},
    ],
)
def test_certify_map_bad_inputs(kwargs: dict) -> None:
    args: dict = {"P": lambda x: 0.5 * x, "x_star": [0.0, 0.0], **kwargs}
    with pytest.raises(RobustGaitError) as err:
        certify_map(args.pop("P"), args.pop("x_star"), uniform(**args))
    assert "\n" not in str(err.value)


def test_invariant_radius_bad_inputs() -> None:
    x = np.zeros((4, 2))
    good = {"alpha": 0.05, "r_max": 1.0}
    cases: list[tuple[np.ndarray, np.ndarray, list[float], dict[str, float]]] = [
        (np.zeros((0, 2)), np.zeros((0, 2)), [0, 0], good),
        (x, np.zeros((4, 3)), [0, 0], good),
        (x, x, [0, 0, 0], good),
        (np.full((4, 2), np.nan), x, [0, 0], good),
        (x, x, [np.nan, 0], good),
    ]
    for x0, x1, xs, kw in cases:
        with pytest.raises(RobustGaitError):
            invariant_radius(x0, x1, xs, **kw)


# ------------------------------------------------------------------------- barrier along trajectories


def test_barrier_value_uses_r_squared() -> None:
    x = np.array([[1.5, 0.0], [0.0, 2.0], [3.0, 0.0]])
    h = barrier_value(x, [0.0, 0.0], 2.0)
    assert h.tolist() == [4.0 - 2.25, 0.0, 4.0 - 9.0]  # {H ≥ 0} = B_2 (with H = r − ‖·‖², 1.5 fails)


def test_barrier_margin_formula_and_falls() -> None:
    x0 = np.array([[1.0, 0.0], [0.0, 0.5], [0.3, 0.3]])
    x1 = np.array([[0.5, 0.0], [0.0, 1.2], [np.nan, np.nan]])
    m = barrier_margin(x0, x1, [0.0, 0.0], 1.0, 0.1)
    assert m[0] == pytest.approx(0.1 - 0.25 + 0.9 * 1.0)
    assert m[1] == pytest.approx(0.1 - 1.44 + 0.9 * 0.25)
    assert m[2] == -np.inf


def test_barrier_along_contracting_and_expanding() -> None:
    x_star = np.array([0.1, -0.3, 0.2])
    x0 = x_star + np.array([0.4, 0.2, -0.3])
    contract = np.array([x_star + 0.6**k * (x0 - x_star) for k in range(12)])
    tr = barrier_along(contract, x_star, 1.0, 0.05)
    assert tr.h.shape == (12,) and tr.margins.shape == (11,)
    assert np.all(tr.margins >= 0) and tr.ok and tr.first_violation is None
    assert tr.h[0] == pytest.approx(1.0 - 0.29)
    expand = np.array([x_star + 1.3**k * (x0 - x_star) for k in range(12)])
    tr = barrier_along(expand, x_star, 1.0, 0.05)
    assert not tr.ok and tr.first_violation == 0
    assert np.all(tr.margins < 0) and np.all(np.diff(tr.h) < 0)
    with pytest.raises(RobustGaitError):
        barrier_along(expand[:1], x_star, 1.0, 0.05)


def test_load_csv(tmp_path: Path) -> None:
    f = tmp_path / "log.csv"
    f.write_text("step,wx,wy,wz,phase\n0,0.1,0.2,0.3,L\n1,0.05,0.1,0.15,R\n2,0.02,0.04,0.06,L\n")
    assert load_reduced_log(f).shape == (3, 4)  # every numeric column, 'phase' is text
    x = load_reduced_log(f, columns=["wx", "wy", "wz"])
    assert x.tolist() == [[0.1, 0.2, 0.3], [0.05, 0.1, 0.15], [0.02, 0.04, 0.06]]
    assert load_reduced_log(str(f), columns=["wz", "wx"])[0].tolist() == [0.3, 0.1]
    assert barrier_along(x, [0, 0, 0], 1.0, 0.05).ok


@pytest.mark.parametrize(
    ("content", "columns"),
    [
        ("wx,wy\n0.1,0.2\n0.3\n", None),  # ragged
        ("wx,wy\n0.1,nan\n0.3,0.4\n", None),  # NaN
        ("wx,wy\n0.1,\n0.3,0.4\n", None),  # empty value
        ("wx,wy\n", None),  # no data
        ("a,b\nx,y\n", None),  # nothing numeric
        ("wx,wy\n0.1,0.2\n", ["wz"]),  # missing column
        ("wx,tag\n0.1,a\n", ["tag"]),  # text column selected
    ],
)
def test_load_csv_errors(tmp_path: Path, content: str, columns: list[str] | None) -> None:
    f = tmp_path / "bad.csv"
    f.write_text(content)
    with pytest.raises(RobustGaitError, match=r"bad\.csv"):
        load_reduced_log(f, columns)


def test_load_npz(tmp_path: Path) -> None:
    xs = np.arange(12.0).reshape(4, 3)
    np.savez(tmp_path / "a.npz", x=xs, t=np.arange(4.0))
    np.savez(tmp_path / "b.npz", states=xs)
    assert np.array_equal(load_reduced_log(tmp_path / "a.npz"), xs)
    assert np.array_equal(load_reduced_log(tmp_path / "b.npz"), xs)
    np.savez(tmp_path / "two.npz", u=xs, v=xs)
    np.savez(tmp_path / "flat.npz", x=np.arange(3.0))
    np.savez(tmp_path / "nan.npz", x=np.array([[0.0, np.nan]]))
    (tmp_path / "junk.npz").write_bytes(b"not a zip file")
    for name in ("two.npz", "flat.npz", "nan.npz", "junk.npz", "missing.npz", "missing.csv"):
        with pytest.raises(RobustGaitError, match=name.replace(".", r"\.")):
            load_reduced_log(tmp_path / name)
