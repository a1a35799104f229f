"""Discrete-time barrier functions (DTBF) on a Poincaré section, r* from samples, confidence bound.

Reference: N. Tucker, K. Li, A. D. Ames, "Synthesizing Robust Walking Gaits via Discrete-Time Barrier
Functions with Application to Multi-Contact Exoskeleton Locomotion", arXiv:2310.06169 (the paper).
See ``docs/certificate.md``.

Barrier. ``ball`` (default): H(x) = r² − ‖x − x*‖² on the reduced state x ∈ R^n. The paper writes
H = r − ‖x − x*‖² while defining the safe set as the ball B_r; we use r² so that {H ≥ 0} = B_r exactly (the
closed ball). ``paper``: the paper's literal H = r − ‖x − x*‖², still required on the ball B_r.

DTBF condition for the return map P: H(P(x)) − H(x) ≥ −α H(x), 0 < α < 1. For one sample with
d = ‖x − x*‖ and p = ‖P(x) − x*‖ it reads α r² ≥ p² − (1 − α) d² (``ball``) or α r ≥ p² − (1 − α) d²
(``paper``); a fall is p = ∞ (never satisfied). The estimators built on this (the paper's uniform one and a
sequential one) are in :mod:`.estimators`.

Conventions: arrays of states have the state in the last axis; a row of images with a NaN (or any
non-finite entry) is a fall. Problems caused by input raise :class:`RobustGaitError` (one line).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import asdict, dataclass
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from robustgait.config import Barrier, CertifyConfig
from robustgait.errors import RobustGaitError
from robustgait.io.logs import load_reduced_log  # re-exported: the log readers live in robustgait.io

__all__ = [
    "BarrierTrace",
    "Certificate",
    "RadiusSolution",
    "Round",
    "barrier_along",
    "barrier_margin",
    "barrier_value",
    "certificate_from_samples",
    "certify_map",
    "distances",
    "evaluate_map",
    "invariant_radius",
    "load_reduced_log",
    "radius_threshold_sq",
    "sample_ball",
    "solve_radius",
    "violation_bound",
    "violation_end",
]

FloatArray = NDArray[np.float64]
BatchedMap = Callable[[FloatArray], ArrayLike]


# --------------------------------------------------------------------------------------- validation
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
def barrier_value(x: ArrayLike, x_star: ArrayLike, r: float, barrier: Barrier = "ball") -> FloatArray:
    """Barrier H(x) = r² − ‖x − x*‖² (``ball``) or r − ‖x − x*‖² (``paper``)  (docs/design.md §6).

    Shapes: x (..., n), x_star (n,) → (...). The paper writes H = r − ‖x − x*‖² while defining the
    safe set as the ball B_r; ``ball`` uses r² so that {H ≥ 0} = B_r = {‖x − x*‖ ≤ r} exactly.
    """
    xa = np.asarray(x, dtype=np.float64)
    diff = xa - np.asarray(x_star, dtype=np.float64)
    level = float(r) ** 2 if barrier == "ball" else float(r)
    return np.asarray(level - np.sum(diff * diff, axis=-1), dtype=np.float64)


def barrier_margin(x0: ArrayLike, x1: ArrayLike, x_star: ArrayLike, r: float, alpha: float,
                   barrier: Barrier = "ball") -> FloatArray:
    """DTBF margin m(x) = H(P(x)) − H(x) + α H(x)  (paper: the DTBF condition, ΔH ≥ −α H).

    Shapes: x0 (..., n) states, x1 (..., n) their images P(x0), x_star (n,) → (...). m ≥ 0 means the
    condition holds; equivalently m = α r² − p² + (1 − α) d² (``ball``; α r − … for ``paper``) with
    d = ‖x0 − x*‖, p = ‖x1 − x*‖. An image row with NaN (or inf) — the sample fell — gives m = −inf.
    """
    a = float(alpha)
    h0 = barrier_value(x0, x_star, r, barrier)
    h1 = barrier_value(x1, x_star, r, barrier)
    m = np.asarray(h1 - h0 + a * h0, dtype=np.float64)
    fell = _fell_rows(np.asarray(x1, dtype=np.float64))
    return np.where(fell, -np.inf, m)


def radius_threshold_sq(d: ArrayLike, p: ArrayLike, alpha: float) -> FloatArray:
    """Threshold c = (p² − (1 − α) d²) / α of the condition's left side (r² for ``ball``, r for ``paper``).

    Shapes: d (N,) distances ‖x_i − x*‖, p (N,) distances ‖P(x_i) − x*‖ (inf or NaN = fell) → (N,).
    Sample i satisfies α r² ≥ p² − (1 − α) d² iff r² ≥ c_i, and α r ≥ p² − (1 − α) d² iff r ≥ c_i
    (c_i = inf for a fall; c_i ≤ 0: always).
    """
    a = float(alpha)
    da = np.asarray(d, dtype=np.float64)
    pa = np.asarray(p, dtype=np.float64)
    with np.errstate(over="ignore", invalid="ignore"):
        c = (pa * pa - (1.0 - a) * da * da) / a
    return np.where(np.isnan(pa) | np.isinf(pa), np.inf, c)


def violation_end(d: ArrayLike, p: ArrayLike, alpha: float, barrier: Barrier = "ball") -> FloatArray:
    """s_i: sample i (distance d_i, image distance p_i) is violated exactly for r ∈ [d_i, s_i).

    s = √max(c, 0) (``ball``) or max(c, 0) (``paper``), c = :func:`radius_threshold_sq`; s = inf for a fall.
    Shapes: d (N,), p (N,) → (N,). The interval is empty (never violated) when s ≤ d.
    """
    c = np.maximum(radius_threshold_sq(d, p, alpha), 0.0)
    return np.sqrt(c) if barrier == "ball" else c


class RadiusSolution(NamedTuple):
    """r* (the supremum of the feasible radii in [0, r_max]) and whether r* itself is feasible."""

    radius: float
    attained: bool


def solve_radius(d: ArrayLike, p: ArrayLike, *, alpha: float, r_max: float,
                 barrier: Barrier = "ball") -> RadiusSolution:
    """Exact r* = sup{r ∈ [0, r_max] : every i with d_i ≤ r has α r² ≥ p_i² − (1 − α) d_i²}  (α r for ``paper``).

    Shapes: d (N,), p (N,) (inf = fell). docs/design.md §6; the paper's r* search, made exact for the sample.
    Sample i is violated exactly for r ∈ [d_i, s_i) with s_i = √max(c_i, 0) (``ball``) or max(c_i, 0)
    (``paper``) (see :func:`violation_end`): it is inactive below d_i and satisfied from s_i on, so the feasible
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
    r_max_f = float(r_max)
    da = np.asarray(d, dtype=np.float64)
    pa = np.asarray(p, dtype=np.float64)
    if da.ndim != 1 or da.size < 1 or pa.shape != da.shape:
        raise RobustGaitError(f"d and p must both have shape (N,) with N >= 1, got {da.shape}, {pa.shape}")
    if not np.all(np.isfinite(da) & (da >= 0.0)):
        raise RobustGaitError("distances d must be finite and >= 0")
    s = violation_end(da, pa, alpha, barrier)
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
    b = float(beta)
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
    rad = float(radius)
    if not (math.isfinite(rad) and rad > 0.0):
        raise RobustGaitError(f"radius must be a finite number > 0, got {radius!r}")
    c = _check_point("center", center, int(dim))
    n, k = int(n_samples), int(dim)
    g = rng.standard_normal((n, k))
    norm = np.linalg.norm(g, axis=1, keepdims=True)
    g[norm[:, 0] == 0.0, 0] = 1.0  # probability zero; keeps the direction defined
    norm = np.linalg.norm(g, axis=1, keepdims=True)
    rho = rad * rng.random(n) ** (1.0 / k)
    return np.asarray(c + g / norm * rho[:, None], dtype=np.float64)


def invariant_radius(x0: ArrayLike, x1: ArrayLike, x_star: ArrayLike, *, alpha: float, r_max: float,
                     barrier: Barrier = "ball") -> float:
    """r* for a sample set: the supremum of the feasible radii in [0, r_max] (docs/design.md §6).

    Shapes: x0 (N, n) samples, x1 (N, n) their images (a NaN row = fell), x_star (n,). With
    d_i = ‖x_i − x*‖ and p_i = ‖P(x_i) − x*‖ (∞ if fell), r is feasible iff every i with d_i ≤ r has
    α r² ≥ p_i² − (1 − α) d_i². Returns the supremum; it is attained unless a violating or fell sample
    sits at distance r* (then only the open ball of radius r* is certified) — use
    :func:`solve_radius` or :class:`Certificate` (``attained``) to tell the two apart.
    """
    a0, a1, xs = _check_samples(x0, x1, x_star)
    d, p = distances(a0, a1, xs)
    return solve_radius(d, p, alpha=alpha, r_max=r_max, barrier=barrier).radius


def distances(x0: FloatArray, x1: FloatArray, x_star: FloatArray) -> tuple[FloatArray, FloatArray]:
    """d_i = ‖x0_i − x*‖ and p_i = ‖x1_i − x*‖ (inf where the image row is not finite: fell)."""
    d = np.linalg.norm(x0 - x_star, axis=1)
    with np.errstate(invalid="ignore", over="ignore"):
        p = np.linalg.norm(x1 - x_star, axis=1)
    p = np.where(_fell_rows(x1), np.inf, p)
    return d, p


# -------------------------------------------------------------------------------------- certificate
@dataclass(frozen=True)
class Round:
    """One round of samples of an estimator (:mod:`.estimators`).

    kind: ``uniform`` (i.i.d. uniform in B(x*, radius): the paper's draw), ``explore`` (proposals of the
    sequential estimator inside B(radius), any distribution), ``verify`` (fresh i.i.d. uniform in B(radius),
    drawn after radius = r̂ was fixed); n_samples in it; samples_used: in all rounds so far; r_hat: the exact
    r* of all samples so far (:func:`solve_radius`); passed: for ``verify``, whether r̂ survived the batch.
    """

    kind: str
    radius: float
    n_samples: int
    samples_used: int
    r_hat: float
    passed: bool | None = None


@dataclass(frozen=True, eq=False)
class Certificate:
    """A DTBF certificate of the ball B_{r*}(x*) from sampled images of the return map.

    Fields: radius (r* of a state certificate, J* of a push certificate: the supremum of feasible radii), attained (r*
    itself feasible; if False the certified set is the open ball, see :func:`solve_radius`), x_star (n,), alpha,
    r_max, samples (N, n), images (N, n) (NaN rows where fell), fell (N,), margins (N,) = :func:`barrier_margin` at r*
    (−inf where fell), n_inside (samples in the certified ball: d_i ≤ r* if attained else d_i < r*;
    all have margin ≥ 0), seed (None if the samples were supplied), confidence = 1 − β and
    violation_bound = ε (1 when there is no statement). barrier: ``ball`` or ``paper``; method: the
    estimator (``uniform``, ``sequential``); rounds: its rounds; sample_round (N,): the round of each sample
    (index into rounds); basis: why the bound holds (empty: the uniform union bound of
    :func:`violation_bound`); budget_exhausted: the sequential estimator ran out of samples before a
    verification batch passed (then there is no statement). estimate: the sequential estimator's r̂ after its
    exploration, before any verification (None for ``uniform``); verified: false for the sequential estimator's
    exploration alone (``verify=False``: r* is then the estimate, with no statement). curve: a push certificate's
    fitted fall curve at the end (:meth:`.fallcurve.FallCurve.summary`: pushes, falls, s₅₀, slope, floor and Ĵ); its
    exploration pushes inside J* may have fallen (the statement rests on the verification batch alone,
    :mod:`.estimators`).
    """

    radius: float
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
    barrier: Barrier = "ball"
    method: str = "uniform"
    rounds: tuple[Round, ...] = ()
    sample_round: NDArray[np.int64] | None = None
    basis: str = ""
    budget_exhausted: bool = False
    estimate: float | None = None
    verified: bool = True
    curve: dict[str, float | int] | None = None

    @property
    def n_samples(self) -> int:
        return int(self.samples.shape[0])

    @property
    def vacuous(self) -> bool:
        """No sample lies in the certified ball: nothing is certified (r* = 0 included)."""
        return self.n_inside == 0

    @property
    def round_of_sample(self) -> NDArray[np.int64]:
        """(N,) index into ``rounds`` of each sample's round (all 0 for a single draw)."""
        if self.sample_round is None:
            return np.zeros(self.n_samples, dtype=np.int64)
        return self.sample_round

    def statement(self) -> str:
        """One readable sentence with the confidence statement (or why there is none)."""
        ball = "closed" if self.attained else "open"
        where = f"the {ball} ball of radius r* = {self.radius:.6g} around x*"
        cond = f"the DTBF condition (alpha = {self.alpha:g}" + (", paper barrier H = r − ‖x − x*‖²)"
                                                                if self.barrier == "paper" else ")")
        if not self.verified:
            return (f"r̂ = {self.radius:.6g} is an estimate from {self.n_samples} exploration samples, not verified: "
                    "no confidence statement.")
        if self.vacuous:
            return (f"No sample lies in {where}: the certificate is vacuous (no confidence statement; "
                    f"{self.n_samples} samples, method {self.method}).")
        if self.budget_exhausted:
            return (f"The sample budget was spent ({self.n_samples} samples) before a verification batch passed: "
                    f"r* = {self.radius:.6g} is the exact supremum of the feasible radii for these samples under "
                    f"{cond}, but there is no confidence statement.")
        basis = self.basis or (
            f"{self.n_inside} of {self.n_samples} uniform samples in B(x*, r_max = {self.r_max:g}) lie in it and "
            f"all satisfy it (union bound over the {self.n_samples + 1} possible choices of r*)")
        return (f"With confidence {100.0 * self.confidence:g}%, at most {100.0 * self.violation_bound:.3g}% of the "
                f"volume of {where} violates {cond}: {basis}.")

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dict (lists and floats; fell images and their −inf margins are None). ``value`` is the certified
        radius, 0 unless ``verified`` (an exploration alone certifies nothing: its radius is ``estimate``)."""
        return {
            "value": float(self.radius) if self.verified else 0.0,
            "attained": bool(self.attained),
            "x_star": [float(v) for v in self.x_star],
            "alpha": float(self.alpha),
            "r_max": float(self.r_max),
            "barrier": self.barrier,
            "method": self.method,
            "n_samples": self.n_samples,
            "n_inside": int(self.n_inside),
            "n_fell": int(np.count_nonzero(self.fell)),
            "seed": self.seed,
            "confidence": float(self.confidence),
            "violation_bound": float(self.violation_bound),
            "vacuous": self.vacuous,
            "budget_exhausted": bool(self.budget_exhausted),
            "estimate": None if self.estimate is None else float(self.estimate),
            "verified": bool(self.verified),
            "curve": self.curve,
            "statement": self.statement(),
            "basis": self.basis,
            "rounds": [asdict(r) for r in self.rounds],
            "samples": [[float(v) for v in row] for row in self.samples],
            "images": [None if f else [float(v) for v in row] for row, f in zip(self.images, self.fell, strict=True)],
            "fell": [bool(f) for f in self.fell],
            "margins": [None if f else float(m) for m, f in zip(self.margins, self.fell, strict=True)],
            "sample_round": [int(k) for k in self.round_of_sample],
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
    alpha: float,
    r_max: float,
    beta: float,
    barrier: Barrier,
    seed: int | None = None,
    solution: RadiusSolution | None = None,
) -> Certificate:
    """Certificate from given samples x0 (N, n) and images x1 (N, n) (NaN row = fell), x_star (n,).

    r* is the exact :func:`solve_radius` of the samples in [0, r_max], or ``solution`` when given (the radius a
    sequential verification batch certified, at most that). The confidence statement assumes x0 i.i.d. uniform on
    B_{r_max}(x*) (see :func:`violation_bound`); the sequential estimator replaces it with its own
    (:mod:`.estimators`).
    """
    a0, a1, xs = _check_samples(x0, x1, x_star)
    a, b = float(alpha), float(beta)
    d, p = distances(a0, a1, xs)
    sol = solution if solution is not None else solve_radius(d, p, alpha=a, r_max=r_max, barrier=barrier)
    fell = _fell_rows(a1)
    images = np.where(fell[:, None], np.nan, a1)
    inside = d <= sol.radius if sol.attained else d < sol.radius
    n_inside = int(np.count_nonzero(inside))
    n = a0.shape[0]
    return Certificate(
        radius=sol.radius,
        attained=sol.attained,
        x_star=_frozen(xs),
        alpha=a,
        r_max=float(r_max),
        samples=_frozen(a0),
        images=_frozen(images),
        fell=_frozen(fell),
        margins=_frozen(barrier_margin(a0, images, xs, sol.radius, a, barrier)),
        n_inside=n_inside,
        seed=seed,
        confidence=1.0 - b,
        violation_bound=violation_bound(n_inside, n, b),
        barrier=barrier,
        rounds=(Round("uniform", float(r_max), n, n, sol.radius),),
        sample_round=_frozen(np.zeros(n, dtype=np.int64)),
    )


def evaluate_map(P: BatchedMap, x0: FloatArray) -> FloatArray:
    """P applied to a batch x0 (N, n) (on a copy), checked to return a numeric (N, n) array (NaN rows = fell)."""
    out = P(x0.copy())
    try:
        x1 = np.asarray(out, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise RobustGaitError(f"the map's output is not a numeric array: {exc}") from exc
    if x1.shape != x0.shape:
        raise RobustGaitError(f"the map returned shape {x1.shape}, expected {x0.shape}")
    return x1


def certify_map(P: BatchedMap, x_star: ArrayLike, config: CertifyConfig | None = None) -> Certificate:
    """The paper's estimator (``uniform``): certify a batched map P: (N, n) → (N, n) (NaN rows = fell)
    around its fixed point x_star (n,) with ``config`` (its ``n_samples``, ``r_max``, ``alpha``, ``beta``,
    ``seed``, ``barrier``).

    Draws N points uniform in B_{r_max}(x*) with ``np.random.default_rng(seed)`` (:func:`sample_ball`),
    evaluates P once on the batch and returns :func:`certificate_from_samples`. The sequential estimator is
    :func:`.estimators.certify_map_sequential`.
    """
    cfg = config or CertifyConfig(method="uniform")
    xs = _check_point("x_star", x_star)
    x0 = sample_ball(cfg.n_samples, xs.shape[0], cfg.radius, xs, np.random.default_rng(cfg.seed))
    x1 = evaluate_map(P, x0)
    return certificate_from_samples(x0, x1, xs, alpha=cfg.alpha, r_max=cfg.radius, beta=cfg.beta, seed=cfg.seed,
                                    barrier=cfg.barrier)


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
    rr, al = float(r), float(alpha)
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
