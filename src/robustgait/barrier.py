"""Discrete-time barrier functions (DTBF) on a Poincaré section, r* from samples, confidence bound.

Reference: N. Tucker, K. Li, A. D. Ames, "Synthesizing Robust Walking Gaits via Discrete-Time Barrier
Functions with Application to Multi-Contact Exoskeleton Locomotion", arXiv:2310.06169 (the paper).
See DESIGN §6.

Barrier. H(x) = r² − ‖x − x*‖² on the reduced state x ∈ R^n. The paper writes H = r − ‖x − x*‖² while
defining the safe set as the ball B_r; we use r² so that {H ≥ 0} = B_r exactly (the closed ball).

DTBF condition for the return map P: H(P(x)) − H(x) ≥ −α H(x), 0 < α < 1. For one sample with
d = ‖x − x*‖ and p = ‖P(x) − x*‖ it reads α r² ≥ p² − (1 − α) d²; a fall is p = ∞ (never satisfied).

Conventions: arrays of states have the state in the last axis; a row of images with a NaN (or any
non-finite entry) is a fall. Problems caused by input raise :class:`RobustGaitError` (one line).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from robustgait.errors import RobustGaitError
from robustgait.io.logs import load_reduced_log  # re-exported: the log readers live in robustgait.io

__all__ = [
    "BarrierTrace",
    "Certificate",
    "RadiusSolution",
    "barrier_along",
    "barrier_margin",
    "barrier_value",
    "certificate_from_samples",
    "certify_map",
    "invariant_radius",
    "load_reduced_log",
    "radius_threshold_sq",
    "sample_ball",
    "solve_radius",
    "violation_bound",
]

FloatArray = NDArray[np.float64]
BatchedMap = Callable[[FloatArray], ArrayLike]


# --------------------------------------------------------------------------------------- validation
def _check_unit(name: str, value: float) -> float:
    v = float(value)
    if not 0.0 < v < 1.0:
        raise RobustGaitError(f"{name} must satisfy 0 < {name} < 1, got {value!r}")
    return v


def _check_alpha(alpha: float) -> float:
    return _check_unit("alpha", alpha)


def _check_beta(beta: float) -> float:
    return _check_unit("beta", beta)


def _check_positive(name: str, value: float) -> float:
    v = float(value)
    if not (math.isfinite(v) and v > 0.0):
        raise RobustGaitError(f"{name} must be a finite number > 0, got {value!r}")
    return v


def _check_point(name: str, x: ArrayLike, n: int | None = None) -> FloatArray:
    a = np.asarray(x, dtype=np.float64)
    if a.ndim != 1 or a.size == 0 or (n is not None and a.shape[0] != n):
        want = f"({n},)" if n is not None else "(n,) with n >= 1"
        raise RobustGaitError(f"{name} must have shape {want}, got {a.shape}")
    if not np.all(np.isfinite(a)):
        raise RobustGaitError(f"{name} contains NaN or inf")
    return a


def _check_samples(x0: ArrayLike, x1: ArrayLike, x_star: ArrayLike) -> tuple[FloatArray, FloatArray, FloatArray]:
    a0 = np.asarray(x0, dtype=np.float64)
    a1 = np.asarray(x1, dtype=np.float64)
    if a0.ndim != 2 or a0.shape[0] < 1 or a0.shape[1] < 1:
        raise RobustGaitError(f"samples must have shape (N, n) with N >= 1, n >= 1, got {a0.shape}")
    if a1.shape != a0.shape:
        raise RobustGaitError(f"images must have the samples' shape {a0.shape}, got {a1.shape}")
    if not np.all(np.isfinite(a0)):
        raise RobustGaitError("samples contain NaN or inf")
    return a0, a1, _check_point("x_star", x_star, a0.shape[1])


def _fell_rows(x1: FloatArray) -> NDArray[np.bool_]:
    """Rows of images with any non-finite entry (NaN = fell; ±inf is treated the same)."""
    return ~np.all(np.isfinite(x1), axis=-1)


# ---------------------------------------------------------------------------------------- equations
def barrier_value(x: ArrayLike, x_star: ArrayLike, r: float) -> FloatArray:
    """Barrier H(x) = r² − ‖x − x*‖²  (the paper's barrier on the reduced state; DESIGN §6).

    Shapes: x (..., n), x_star (n,) → (...). The paper writes H = r − ‖x − x*‖² while defining the
    safe set as the ball B_r; we use r² so that {H ≥ 0} = B_r = {‖x − x*‖ ≤ r} exactly.
    """
    xa = np.asarray(x, dtype=np.float64)
    diff = xa - np.asarray(x_star, dtype=np.float64)
    return np.asarray(float(r) ** 2 - np.sum(diff * diff, axis=-1), dtype=np.float64)


def barrier_margin(x0: ArrayLike, x1: ArrayLike, x_star: ArrayLike, r: float, alpha: float) -> FloatArray:
    """DTBF margin m(x) = H(P(x)) − H(x) + α H(x)  (paper: the DTBF condition, ΔH ≥ −α H).

    Shapes: x0 (..., n) states, x1 (..., n) their images P(x0), x_star (n,) → (...). m ≥ 0 means the
    condition holds; equivalently m = α r² − p² + (1 − α) d² with d = ‖x0 − x*‖, p = ‖x1 − x*‖.
    An image row with NaN (or inf) — the sample fell — gives m = −inf.
    """
    a = _check_alpha(alpha)
    h0 = barrier_value(x0, x_star, r)
    h1 = barrier_value(x1, x_star, r)
    m = np.asarray(h1 - h0 + a * h0, dtype=np.float64)
    fell = _fell_rows(np.asarray(x1, dtype=np.float64))
    return np.where(fell, -np.inf, m)


def radius_threshold_sq(d: ArrayLike, p: ArrayLike, alpha: float) -> FloatArray:
    """Squared radius from which a sample satisfies the condition: c = (p² − (1 − α) d²) / α.

    Shapes: d (N,) distances ‖x_i − x*‖, p (N,) distances ‖P(x_i) − x*‖ (inf or NaN = fell) → (N,).
    Sample i satisfies α r² ≥ p² − (1 − α) d² iff r² ≥ c_i (c_i = inf for a fall; c_i ≤ 0: always).
    """
    a = _check_alpha(alpha)
    da = np.asarray(d, dtype=np.float64)
    pa = np.asarray(p, dtype=np.float64)
    with np.errstate(over="ignore", invalid="ignore"):
        c = (pa * pa - (1.0 - a) * da * da) / a
    return np.where(np.isnan(pa) | np.isinf(pa), np.inf, c)


class RadiusSolution(NamedTuple):
    """r* (the supremum of the feasible radii in [0, r_max]) and whether r* itself is feasible."""

    r_star: float
    attained: bool


def solve_radius(d: ArrayLike, p: ArrayLike, *, alpha: float, r_max: float) -> RadiusSolution:
    """Exact r* = sup{r ∈ [0, r_max] : every i with d_i ≤ r has α r² ≥ p_i² − (1 − α) d_i²}.

    Shapes: d (N,), p (N,) (inf = fell). DESIGN §6; the paper's r* search, made exact for the sample.
    Sample i is violated exactly for r ∈ [d_i, s_i) with s_i = √max(c_i, 0) (see
    :func:`radius_threshold_sq`): it is inactive below d_i and satisfied from s_i on, so the feasible
    set is [0, r_max] minus a union of half-open intervals — not an interval in general. Hence:

    * r_max feasible (in no bad interval) → r* = r_max, attained.
    * otherwise r_max lies in a connected component [A, B) of the union of bad intervals, with A = d_j
      for some violating/fell sample j. Radii just below A are feasible, A is not: r* = A is the
      supremum, *not attained* (``attained=False``); the certified set is then the open ball of radius
      r*, i.e. the samples with d_i < r*. If A = 0 (a violating sample exactly at x*) nothing is
      feasible and r* = 0, not attained.

    The candidates are r_max, the d_i and the s_i (= √c_i); sorting the bad intervals by start and
    sweeping a running maximum of their ends finds the component in O(N log N). No grid.
    """
    r_max_f = _check_positive("r_max", r_max)
    da = np.asarray(d, dtype=np.float64)
    pa = np.asarray(p, dtype=np.float64)
    if da.ndim != 1 or da.size < 1 or pa.shape != da.shape:
        raise RobustGaitError(f"d and p must both have shape (N,) with N >= 1, got {da.shape}, {pa.shape}")
    if not np.all(np.isfinite(da) & (da >= 0.0)):
        raise RobustGaitError("distances d must be finite and >= 0")
    s = np.sqrt(np.maximum(radius_threshold_sq(da, pa, alpha), 0.0))
    bad = (s > da) & (da <= r_max_f)  # nonempty bad intervals that can reach [0, r_max]
    starts, ends = da[bad], s[bad]
    if starts.size == 0:
        return RadiusSolution(r_max_f, True)
    order = np.argsort(starts, kind="stable")
    starts, ends = starts[order], ends[order]
    reach = np.maximum.accumulate(ends)  # right end of the union of the intervals so far
    if reach[-1] <= r_max_f:  # r_max is at or beyond every bad interval's (open) end
        return RadiusSolution(r_max_f, True)
    new_component = np.empty(starts.size, dtype=bool)
    new_component[0] = True
    new_component[1:] = starts[1:] > reach[:-1]  # a gap before this start (touching = connected)
    first = int(np.flatnonzero(new_component)[-1])
    return RadiusSolution(float(starts[first]), False)


def violation_bound(n_inside: int, n_samples: int, beta: float) -> float:
    """ε = 1 − (β / (N + 1))^(1 / n_r)  (ε = 1 if n_r = 0): the certified violating volume fraction.

    n_inside = n_r samples in the certified ball, all satisfying the condition; n_samples = N.
    Claim: with probability ≥ 1 − β over the draw of the samples, the fraction of the volume of the
    certified ball B_{r*} where the DTBF condition at radius r* fails (including falls) is ≤ ε.

    Assumptions: the N samples are i.i.d. uniform on B_{r_max}(x*); the map is deterministic; the
    condition is evaluated exactly at the sampled points. It says nothing about violating sets of
    measure zero (or of volume fraction ≤ ε), and it is not a proof of invariance.

    Why: for a fixed radius ρ, the samples falling in B_ρ are i.i.d. uniform on B_ρ, so if the violating
    fraction V(ρ) exceeds ε then m of them all satisfy the condition with probability ≤ (1 − ε)^m.
    r* is chosen after seeing the samples, but it is one of N + 1 values: r_max (then n_r = N) or
    the k-th smallest distance d_(k) (certified open ball, n_r = k − 1). Given d_(k), the k − 1 closer
    samples are i.i.d. uniform on B_{d_(k)} (order statistics), so each of the N + 1 events
    "pick this one, all n_r satisfy, V > ε" has probability ≤ (1 − ε)^{n_r} = β / (N + 1); a union
    bound gives β. (Solving (1 − ε)^{n_r} = β without the N + 1 would ignore the selection.)
    """
    if n_inside < 0 or n_samples < 1 or n_inside > n_samples:
        raise RobustGaitError(f"need 0 <= n_inside <= n_samples, n_samples >= 1; got {n_inside}, {n_samples}")
    b = _check_beta(beta)
    if n_inside == 0:
        return 1.0
    return float(-math.expm1(math.log(b / (n_samples + 1)) / n_inside))


def sample_ball(n_samples: int, dim: int, radius: float, center: ArrayLike, rng: np.random.Generator) -> FloatArray:
    """N i.i.d. points uniform in the closed n-ball: x = c + R · U^(1/n) · g / ‖g‖, g ~ N(0, I_n).

    Shapes: center (dim,) → (n_samples, dim). Gaussian direction (uniform on the sphere) and the
    radius law P(‖x − c‖ ≤ ρ R) = ρ^n, i.e. ‖x − c‖ = R U^(1/n), U ~ U(0, 1).
    """
    if int(n_samples) != n_samples or n_samples < 1:
        raise RobustGaitError(f"n_samples must be an integer >= 1, got {n_samples!r}")
    if int(dim) != dim or dim < 1:
        raise RobustGaitError(f"dim must be an integer >= 1, got {dim!r}")
    rad = _check_positive("radius", radius)
    c = _check_point("center", center, int(dim))
    n, k = int(n_samples), int(dim)
    g = rng.standard_normal((n, k))
    norm = np.linalg.norm(g, axis=1, keepdims=True)
    g[norm[:, 0] == 0.0, 0] = 1.0  # probability zero; keeps the direction defined
    norm = np.linalg.norm(g, axis=1, keepdims=True)
    rho = rad * rng.random(n) ** (1.0 / k)
    return np.asarray(c + g / norm * rho[:, None], dtype=np.float64)


def invariant_radius(x0: ArrayLike, x1: ArrayLike, x_star: ArrayLike, *, alpha: float, r_max: float) -> float:
    """r* for a sample set: the supremum of the feasible radii in [0, r_max] (DESIGN §6).

    Shapes: x0 (N, n) samples, x1 (N, n) their images (a NaN row = fell), x_star (n,). With
    d_i = ‖x_i − x*‖ and p_i = ‖P(x_i) − x*‖ (∞ if fell), r is feasible iff every i with d_i ≤ r has
    α r² ≥ p_i² − (1 − α) d_i². Returns the supremum; it is attained unless a violating or fell sample
    sits at distance r* (then only the open ball of radius r* is certified) — use
    :func:`solve_radius` or :class:`Certificate` (``attained``) to tell the two apart.
    """
    a0, a1, xs = _check_samples(x0, x1, x_star)
    _check_alpha(alpha)
    d, p = _distances(a0, a1, xs)
    return solve_radius(d, p, alpha=alpha, r_max=r_max).r_star


def _distances(x0: FloatArray, x1: FloatArray, x_star: FloatArray) -> tuple[FloatArray, FloatArray]:
    d = np.linalg.norm(x0 - x_star, axis=1)
    with np.errstate(invalid="ignore", over="ignore"):
        p = np.linalg.norm(x1 - x_star, axis=1)
    p = np.where(_fell_rows(x1), np.inf, p)
    return d, p


# -------------------------------------------------------------------------------------- certificate
@dataclass(frozen=True, eq=False)
class Certificate:
    """A DTBF certificate of the ball B_{r*}(x*) from sampled images of the return map.

    Fields: r_star (supremum of feasible radii), attained (r* itself feasible; if False the certified
    set is the open ball, see :func:`solve_radius`), x_star (n,), alpha, r_max, samples (N, n),
    images (N, n) (NaN rows where fell), fell (N,), margins (N,) = :func:`barrier_margin` at r*
    (−inf where fell), n_inside (samples in the certified ball: d_i ≤ r* if attained else d_i < r*;
    all have margin ≥ 0), seed (None if the samples were supplied), confidence = 1 − β and
    violation_bound = ε of :func:`violation_bound`.
    """

    r_star: float
    attained: bool
    x_star: FloatArray
    alpha: float
    r_max: float
    samples: FloatArray
    images: FloatArray
    fell: NDArray[np.bool_]
    margins: FloatArray
    n_inside: int
    seed: int | None
    confidence: float
    violation_bound: float

    @property
    def n_samples(self) -> int:
        return int(self.samples.shape[0])

    def statement(self) -> str:
        """One readable sentence with the confidence statement."""
        ball = "closed" if self.attained else "open"
        pct = 100.0 * self.violation_bound
        return (
            f"With confidence {100.0 * self.confidence:g}%, at most {pct:.3g}% of the volume of the {ball} "
            f"ball of radius r* = {self.r_star:.6g} around x* violates the DTBF condition (alpha = "
            f"{self.alpha:g}): {self.n_inside} of {self.n_samples} uniform samples in B(x*, r_max = {self.r_max:g}) "
            f"lie in it and all satisfy it (union bound over the {self.n_samples + 1} possible choices of r*)."
        )

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dict (lists and floats; fell images and their −inf margins are None)."""
        return {
            "r_star": float(self.r_star),
            "attained": bool(self.attained),
            "x_star": [float(v) for v in self.x_star],
            "alpha": float(self.alpha),
            "r_max": float(self.r_max),
            "n_samples": self.n_samples,
            "n_inside": int(self.n_inside),
            "n_fell": int(np.count_nonzero(self.fell)),
            "seed": self.seed,
            "confidence": float(self.confidence),
            "violation_bound": float(self.violation_bound),
            "statement": self.statement(),
            "samples": [[float(v) for v in row] for row in self.samples],
            "images": [None if f else [float(v) for v in row] for row, f in zip(self.images, self.fell, strict=True)],
            "fell": [bool(f) for f in self.fell],
            "margins": [None if f else float(m) for m, f in zip(self.margins, self.fell, strict=True)],
        }


def _frozen(a: NDArray[Any]) -> NDArray[Any]:
    out = np.array(a, copy=True)
    out.setflags(write=False)
    return out


def certificate_from_samples(
    x0: ArrayLike,
    x1: ArrayLike,
    x_star: ArrayLike,
    *,
    alpha: float = 0.05,
    r_max: float = 2.0,
    beta: float = 0.05,
    seed: int | None = None,
) -> Certificate:
    """Certificate from given samples x0 (N, n) and images x1 (N, n) (NaN row = fell), x_star (n,).

    The confidence statement assumes x0 i.i.d. uniform on B_{r_max}(x*) (see :func:`violation_bound`).
    """
    a0, a1, xs = _check_samples(x0, x1, x_star)
    a = _check_alpha(alpha)
    b = _check_beta(beta)
    d, p = _distances(a0, a1, xs)
    sol = solve_radius(d, p, alpha=a, r_max=r_max)
    fell = _fell_rows(a1)
    images = np.where(fell[:, None], np.nan, a1)
    inside = d <= sol.r_star if sol.attained else d < sol.r_star
    n_inside = int(np.count_nonzero(inside))
    return Certificate(
        r_star=sol.r_star,
        attained=sol.attained,
        x_star=_frozen(xs),
        alpha=a,
        r_max=float(r_max),
        samples=_frozen(a0),
        images=_frozen(images),
        fell=_frozen(fell),
        margins=_frozen(barrier_margin(a0, images, xs, sol.r_star, a)),
        n_inside=n_inside,
        seed=seed,
        confidence=1.0 - b,
        violation_bound=violation_bound(n_inside, a0.shape[0], b),
    )


def certify_map(
    P: BatchedMap,
    x_star: ArrayLike,
    *,
    r_max: float = 2.0,
    alpha: float = 0.05,
    n_samples: int = 200,
    seed: int = 0,
    beta: float = 0.05,
) -> Certificate:
    """Certify a batched map P: (N, n) → (N, n) (NaN rows = fell) around its fixed point x_star (n,).

    Draws n_samples points uniform in B_{r_max}(x*) with ``np.random.default_rng(seed)``
    (:func:`sample_ball`), evaluates P once on the batch and returns :func:`certificate_from_samples`.
    """
    xs = _check_point("x_star", x_star)
    r = _check_positive("r_max", r_max)
    _check_alpha(alpha)
    _check_beta(beta)
    x0 = sample_ball(n_samples, xs.shape[0], r, xs, np.random.default_rng(seed))
    out = P(x0.copy())
    try:
        x1 = np.asarray(out, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise RobustGaitError(f"the map's output is not a numeric array: {exc}") from exc
    if x1.shape != x0.shape:
        raise RobustGaitError(f"the map returned shape {x1.shape}, expected {x0.shape}")
    return certificate_from_samples(x0, x1, xs, alpha=alpha, r_max=r, beta=beta, seed=seed)


# ------------------------------------------------------------------------------ logged trajectories
@dataclass(frozen=True, eq=False)
class BarrierTrace:
    """H along a recorded sequence of section states (paper Fig. 5).

    h (T,) = H(x_k); margins (T−1,) = H(x_{k+1}) − H(x_k) + α H(x_k); ok = all margins ≥ 0;
    first_violation = first k whose pair (k, k+1) violates, or None.
    """

    h: FloatArray
    margins: FloatArray
    ok: bool
    first_violation: int | None
    r: float
    alpha: float


def barrier_along(xs: ArrayLike, x_star: ArrayLike, r: float, alpha: float) -> BarrierTrace:
    """H(x_k) = r² − ‖x_k − x*‖² and the DTBF margins H(x_{k+1}) − (1 − α) H(x_k) along a sequence.

    Shapes: xs (T, n) consecutive states on the section (T ≥ 2), x_star (n,) → h (T,), margins (T−1,).
    """
    a = np.asarray(xs, dtype=np.float64)
    if a.ndim != 2 or a.shape[0] < 2 or a.shape[1] < 1:
        raise RobustGaitError(f"states must have shape (T, n) with T >= 2, got {a.shape}")
    if not np.all(np.isfinite(a)):
        raise RobustGaitError("states contain NaN or inf")
    x0 = _check_point("x_star", x_star, a.shape[1])
    rr = _check_positive("r", r)
    al = _check_alpha(alpha)
    h = barrier_value(a, x0, rr)
    m = barrier_margin(a[:-1], a[1:], x0, rr, al)
    bad = np.flatnonzero(m < 0.0)
    return BarrierTrace(
        h=_frozen(h),
        margins=_frozen(m),
        ok=bad.size == 0,
        first_violation=int(bad[0]) if bad.size else None,
        r=rr,
        alpha=al,
    )
