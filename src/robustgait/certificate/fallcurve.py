"""The fall curve of a gait: how the share of pushes that make it fall grows with the push's size
(``docs/certificate.md``, "Where the verification batch is drawn: the fall curve").

A push of impulse J = s u (s = |J| [N s], u a direction, its phase in the validation's range) makes the gait fall
with probability p(s), the share of directions and phases whose threshold lies below s. The model is a log-logistic
curve above a floor s₀ below which no push falls,

    p(s; μ, b, s₀) = σ(b (ln(s − s₀) − μ)) for s > s₀, 0 below,   σ(z) = 1 / (1 + e^{−z}),             (1)

s₀ + e^μ the push size at which half fall (s₅₀) and b > 0 the slope (:func:`fall_probability`). A batch of pushes
uniform in the disk |J| ≤ r (the certificate's statement) falls in the share

    V(r) = (2 / r²) ∫₀^r p(s) s ds                                                                       (2)

(:func:`disk_fall_fraction`, from two tabulated functions of one variable per slope). The parameters get a posterior
on a grid (flat in μ, ln b and s₀) from pushes and whether each fell (:func:`fit_fall_curve`, :class:`FallCurve`):

* the estimate Ĵ is the push size r_ε whose disk has the predicted share ε of falls, E[V(r_ε)] = ε
  (:meth:`FallCurve.estimate`); it moves smoothly with every push, so two gaits share it only when their curves agree;
* the verification radius is the largest r whose posterior-predictive probability that a batch of n fresh pushes
  uniform in the disk has none that falls, E[(1 − V(r))^n], is at least a level (:meth:`FallCurve.verification_radius`).

The exploration that feeds it (:mod:`.estimators`) searches around the falls nearest the origin, so its directions
are not uniform: the curve it fits leans towards the weakest directions, the ones a batch meets first. The posterior
is exact on its grid (no sampling), so a fit is a deterministic function of its pushes.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import brentq

from robustgait.errors import RobustGaitError

FloatArray = NDArray[np.float64]

# the grids of the posterior: ln of the rise's scale relative to the largest push size considered, the slope b, and
# the floor s₀ as a fraction of the smallest push that fell
MU_SPAN = (-7.0, 1.0)
MU_STEP = 0.08
SLOPES = np.geomspace(0.7, 70.0, 28)
FLOORS = np.linspace(0.0, 0.98, 36)
# grid points whose posterior mass together is below this are dropped after a fit
NEGLIGIBLE = 1e-6
# the tables of G_b and H_b: x on a uniform grid; below it, their first-order tails
_X = np.linspace(-30.0, 30.0, 601)


def fall_probability(s: ArrayLike, mu: ArrayLike, b: ArrayLike, floor: ArrayLike = 0.0) -> FloatArray:
    """p(s; μ, b, s₀) = σ(b (ln(s − s₀) − μ)) for s > s₀, 0 below (1): the share of pushes of size s [N s] (uniform
    direction and phase) that make the gait fall; broadcast over s, μ, b and s₀."""
    t = np.asarray(s, dtype=float) - np.asarray(floor, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        z = np.asarray(b, dtype=float) * (np.log(np.where(t > 0.0, t, 1.0)) - np.asarray(mu, dtype=float))
    return np.asarray(np.where(t > 0.0, 0.5 * (1.0 + np.tanh(0.5 * z)), 0.0))


@functools.cache
def _table(b: float, k: int) -> FloatArray:
    """ln of (k/b) ∫₀^∞ σ(x − τ) e^{−kτ/b} dτ on the grid :data:`_X`: G_b (k = 2, the disk average) and H_b (k = 1,
    the average along a segment), by composite Gauss–Legendre (unit panels, 6 nodes) on τ ∈ [0, max(x, 0) + 40]
    (beyond it σ(x − τ) < e^{−40})."""
    nodes, weights = np.polynomial.legendre.leggauss(6)
    panels = np.arange(0.0, float(_X[-1]) + 40.0, 1.0)
    tau = (panels[:, None] + 0.5 * (nodes[None, :] + 1.0)).ravel()
    w = np.tile(0.5 * weights, panels.size)
    log_sigma = -np.logaddexp(0.0, tau[None, :] - _X[:, None])
    g = (k / b) * (np.exp(log_sigma - k * tau[None, :] / b) @ w)
    return np.asarray(np.log(np.minimum(g, 1.0)))


def _average(x: FloatArray, b: float, k: int) -> FloatArray:
    """G_b(x) (k = 2) or H_b(x) (k = 1), from the table; below it the tail k e^x / (b + k) (relative error
    < e^{−30}); above it 1 − (1 − G(x₁)) e^{−k (x − x₁)/b} from the table's end x₁ (exact but for σ(−x₁) < e^{−30}:
    beyond x₁ the curve is 1 over the part of the disk it shifts in)."""
    table = _table(float(b), k)
    top = float(_X[-1])
    inside = np.interp(x, _X, table)
    below = math.log(k / (b + k)) + x
    gap = -math.expm1(float(table[-1]))  # 1 − G at the table's end
    above = np.log1p(-gap * np.exp(-k * (np.maximum(x, top) - top) / b))
    return np.asarray(np.exp(np.where(x < _X[0], below, np.where(x > top, above, inside))))


def disk_fall_fraction(r: float, mu: ArrayLike, b: float, floor: ArrayLike = 0.0) -> FloatArray:
    """V(r) (2) of the curves (μ, b, s₀) (μ and s₀ broadcast; one slope b): with t = r − s₀ and x = b (ln t − μ),

        V(r) = (t / r)² G_b(x) + 2 s₀ t / r² H_b(x)   (0 for r ≤ s₀),

    G_b(x) = (2/b) ∫₀^∞ σ(x − τ) e^{−2τ/b} dτ the average of p over the disk of radius t around no floor and
    H_b(x) = (1/b) ∫₀^∞ σ(x − τ) e^{−τ/b} dτ its average along the segment [0, t] (substituting s = s₀ + t e^{−τ/b})."""
    mu_a = np.asarray(mu, dtype=float)
    s0 = np.broadcast_to(np.asarray(floor, dtype=float), np.broadcast_shapes(mu_a.shape, np.shape(floor)))
    t = r - s0
    above = t > 0.0
    x = b * (np.log(np.where(above, t, 1.0)) - mu_a)
    v = (t / r) ** 2 * _average(x, b, 2) + 2.0 * s0 * t / r**2 * _average(x, b, 1)
    return np.asarray(np.where(above, np.minimum(v, 1.0), 0.0))


@dataclass(frozen=True)
class FallCurve:
    """The posterior of the fall curve (1) on a grid, as its P points of non-negligible mass: ``mu``, ``slopes`` (b),
    ``floors`` (s₀ [N s]) and ``weights`` (P,) (sum 1), from ``n_pushes`` pushes of which ``n_fell`` fell; sizes in
    N s; ``cap`` the largest radius any answer may take (the certificate's r_max)."""

    mu: FloatArray
    slopes: FloatArray
    floors: FloatArray
    weights: FloatArray
    n_pushes: int
    n_fell: int
    cap: float

    def __post_init__(self) -> None:
        # the points grouped by slope (one table each): (b, first, end) over the points sorted by b
        order = np.argsort(self.slopes, kind="stable")
        for name in ("mu", "slopes", "floors", "weights"):
            object.__setattr__(self, name, np.asarray(getattr(self, name), dtype=float)[order])
        edges = np.flatnonzero(np.diff(self.slopes)) + 1
        starts = np.concatenate([[0], edges]).astype(int)
        ends = np.concatenate([edges, [self.slopes.size]]).astype(int)
        object.__setattr__(self, "_groups", [(float(self.slopes[a]), int(a), int(e)) for a, e in zip(starts, ends,
                                                                                                      strict=True)])

    def disk_fraction(self, r: float) -> FloatArray:
        """V(r) (2) at every point (P,), in the points' order (sorted by slope)."""
        out = np.empty(self.weights.size)
        for b, a, e in self._groups:  # type: ignore[attr-defined]
            out[a:e] = disk_fall_fraction(r, self.mu[a:e], b, self.floors[a:e])
        return out

    def fall_share(self, r: float) -> float:
        """E[V(r)]: the predicted share of pushes uniform in the disk of radius r [N s] that fall."""
        return float(self.weights @ self.disk_fraction(r)) if r > 0.0 else 0.0

    def pass_probability(self, r: float, n: int) -> float:
        """E[(1 − V(r))^n]: the posterior-predictive probability that none of n fresh pushes uniform in the disk of
        radius r [N s] falls."""
        if r <= 0.0:
            return 1.0
        v = np.minimum(self.disk_fraction(r), 1.0)
        with np.errstate(divide="ignore"):
            return float(self.weights @ np.exp(n * np.log1p(-v)))

    def _largest(self, excess: Callable[[float], float]) -> float:
        """The largest r ≤ ``cap`` with excess(r) ≤ 0, excess increasing in r: Brent's method in ln r to 1e-6 (0 when
        excess stays positive down to 1e-9 of ``cap``)."""
        hi = self.cap
        if excess(hi) <= 0.0:
            return hi
        lo = hi
        while excess(lo) > 0.0:
            lo *= 0.25
            if lo < hi * 1e-9:
                return 0.0
        root = brentq(lambda x: excess(math.exp(x)), math.log(lo), math.log(hi), xtol=1e-6)
        return math.exp(float(root))

    def estimate(self, epsilon: float) -> float:
        """Ĵ: the push size r_ε whose disk has the predicted share ε of falls, E[V(r_ε)] = ε (at most ``cap``)."""
        return self._largest(lambda r: self.fall_share(r) - epsilon)

    def verification_radius(self, n: int, level: float) -> float:
        """The largest r ≤ ``cap`` whose :meth:`pass_probability` for a batch of n is at least ``level``."""
        return self._largest(lambda r: level - self.pass_probability(r, n))

    def slope(self) -> float:
        """The posterior mean of b."""
        return float(self.weights @ self.slopes)

    def floor(self) -> float:
        """The posterior mean of the floor s₀ [N s]: below it no push falls."""
        return float(self.weights @ self.floors)

    def s50(self) -> float:
        """The posterior mean of the push size at which half fall, s₀ + e^μ [N s]."""
        return float(self.weights @ (self.floors + np.exp(self.mu)))

    def summary(self, epsilon: float) -> dict[str, float | int]:
        """JSON-ready: pushes and falls fitted, the posterior means of s₅₀, b and s₀, and Ĵ."""
        return {"pushes": self.n_pushes, "fell": self.n_fell, "s50": self.s50(), "slope": self.slope(),
                "floor": self.floor(), "estimate": self.estimate(epsilon)}


def fit_fall_curve(sizes: ArrayLike, fell: ArrayLike, cap: float) -> FallCurve:
    """The posterior of (1) on a grid — μ ∈ ln cap + [−7, 1] (step 0.08), b ∈ [0.7, 70] (28 log-spaced), s₀ ∈ [0,
    0.98] × the smallest size that fell (36 steps; × cap when none fell) — with a flat prior in μ, ln b and s₀, from
    pushes of sizes s (N,) [N s] > 0 with uniform directions and phases and whether each fell (N,): the Bernoulli
    likelihood Π p(s_i)^{y_i} (1 − p(s_i))^{1 − y_i} (a push at or below the floor never falls). Points whose
    posterior mass together is below :data:`NEGLIGIBLE` are dropped. ``cap`` > 0: the largest push size considered
    (r_max). With no pushes the posterior is the prior."""
    s = np.asarray(sizes, dtype=float).ravel()
    y = np.asarray(fell, dtype=bool).ravel()
    if s.shape != y.shape:
        raise RobustGaitError(f"the fall curve needs one outcome per push size, got {s.shape} and {y.shape}")
    if not (math.isfinite(cap) and cap > 0.0):
        raise RobustGaitError(f"the fall curve's cap must be a finite size > 0, got {cap!r}")
    if s.size and not np.all(np.isfinite(s) & (s > 0.0)):
        raise RobustGaitError("push sizes must be finite and > 0 to fit the fall curve")
    mu = math.log(cap) + np.arange(MU_SPAN[0], MU_SPAN[1] + 1e-9, MU_STEP)
    floors = FLOORS * (float(s[y].min()) if y.any() else cap)
    loglik = np.zeros((mu.size, SLOPES.size, floors.size))
    for f, s0 in enumerate(floors):
        above = s > s0
        lt = np.log(s[above] - s0)
        sign = np.where(y[above], 1.0, -1.0)
        z = SLOPES[None, :, None] * (lt[None, None, :] - mu[:, None, None]) * sign
        loglik[:, :, f] = -np.logaddexp(0.0, -z).sum(axis=2)
    w = np.exp(loglik - loglik.max()).ravel()
    w /= w.sum()
    order = np.argsort(w)
    keep = np.sort(order[np.cumsum(w[order]) > NEGLIGIBLE])
    i, j, m = np.unravel_index(keep, loglik.shape)
    return FallCurve(mu[i], SLOPES[j], floors[m], w[keep] / w[keep].sum(), int(s.size), int(np.count_nonzero(y)),
                     float(cap))
