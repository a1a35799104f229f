"""Statistics of a validation: binomial intervals and the disturbance size at which half the trials fail."""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

Z95 = 1.959963984540054  # standard normal quantile 0.975


def wilson_interval(successes: int, n: int, z: float = Z95) -> tuple[float, float]:
    """Wilson score interval of a binomial proportion k/n (default 95 %):

        (p̂ + z²/2n ± z √(p̂(1 − p̂)/n + z²/4n²)) / (1 + z²/n),  p̂ = k/n.

    (E. B. Wilson, J. Am. Stat. Assoc. 22, 1927.) Unlike the normal (Wald) interval it stays inside [0, 1]
    and does not collapse to a point at k = 0 or k = n: 0 of 10 gives (0, 0.278). n = 0 gives (0, 1).
    """
    if n < 0 or not 0 <= successes <= n:
        raise ValueError(f"need 0 ≤ successes ≤ n, got {successes} of {n}")
    if n == 0:
        return 0.0, 1.0
    p = successes / n
    den = 1.0 + z * z / n
    center = (p + z * z / (2 * n)) / den
    half = z / den * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n))
    return max(0.0, center - half), min(1.0, center + half)


@dataclass(frozen=True)
class Rate:
    """k of n with its proportion and 95 % Wilson interval (rate = NaN when n = 0)."""

    n: int
    k: int
    rate: float
    low: float
    high: float

    @staticmethod
    def of(k: int, n: int) -> Rate:
        lo, hi = wilson_interval(k, n)
        return Rate(n=n, k=k, rate=k / n if n else math.nan, low=lo, high=hi)

    def to_dict(self) -> dict[str, Any]:
        d = asdict(self)
        if not math.isfinite(self.rate):
            d["rate"] = None
        return d


@dataclass(frozen=True)
class LogisticFit:
    """P(success | s) = 1 / (1 + exp(−(a + b s))) by maximum likelihood, and the size s₅₀ = −a/b at which
    half the trials fail with its standard error (delta method on the inverse Fisher information).

    ``s50`` is None when it is not identified: no fall or no success in the trials, the fit did not converge,
    or b ≈ 0 (success does not depend on the size). When the sizes separate successes from falls perfectly
    the maximum-likelihood estimate does not exist (``converged`` False): s₅₀ is then the middle of the gap
    between the largest size that walked and the smallest that fell (or the reverse) and ``s50_se`` half
    the gap. ``in_range``: s₅₀ lies within the sizes drawn; ``note`` explains the last two cases.
    """

    a: float
    b: float
    s50: float | None
    s50_se: float | None
    in_range: bool
    converged: bool
    note: str

    def to_dict(self) -> dict[str, Any]:
        return {k: (None if isinstance(v, float) and not math.isfinite(v) else v) for k, v in asdict(self).items()}


def logistic_fit(size: NDArray[np.float64], success: NDArray[np.bool_], *, max_iter: int = 100) -> LogisticFit:
    """Fit P(success | size) with a two-parameter logistic model by Newton's method (IRLS) on the
    log-likelihood Σ y log p + (1 − y) log(1 − p); sizes are scaled to [0, 1] for the iteration.

    Why a logistic fit: it uses every trial (no choice of bins), is monotone in the size, and gives s₅₀ with
    an uncertainty; the binned rates are reported next to it to check the model's shape.
    """
    s = np.asarray(size, dtype=float)
    y = np.asarray(success, dtype=float)
    n, k = y.size, int(y.sum())
    lo, hi = float(s.min()) if n else 0.0, float(s.max()) if n else 0.0
    if n == 0 or k == 0 or k == n:
        what = "no trials" if n == 0 else ("no trial succeeded" if k == 0 else "no trial fell")
        return LogisticFit(math.nan, math.nan, None, None, False, False, what)
    scale = hi - lo if hi > lo else 1.0
    x = np.column_stack([np.ones(n), (s - lo) / scale])
    beta = np.array([math.log(k / (n - k)), 0.0])
    converged = False
    cov = np.full((2, 2), np.nan)
    for _ in range(max_iter):
        eta = np.clip(x @ beta, -30, 30)
        p = 1.0 / (1.0 + np.exp(-eta))
        w = p * (1 - p)
        info = x.T @ (x * w[:, None])
        grad = x.T @ (y - p)
        try:
            step = np.linalg.solve(info, grad)
        except np.linalg.LinAlgError:
            break
        beta = beta + step
        if np.abs(step).max() < 1e-10:
            converged = True
            cov = np.linalg.inv(info)
            break
        if np.abs(beta).max() > 1e3:  # diverging: sizes separate successes from falls
            break
    a_s, b_s = float(beta[0]), float(beta[1])
    # back to the original size scale: a + b s = a_s + b_s (s − lo)/scale
    b = b_s / scale
    a = a_s - b * lo
    if not converged:
        ok, bad = s[y > 0], s[y == 0]
        gap = ((ok.max(), bad.min()) if ok.max() < bad.min() else (bad.max(), ok.min()) if bad.max() < ok.min()
               else None)
        if gap is None:
            return LogisticFit(a, b, None, None, False, False, "the fit did not converge")
        # perfect separation: the MLE does not exist; the crossing lies in the gap, report its middle
        return LogisticFit(a, b, float(gap[0] + gap[1]) / 2, float(gap[1] - gap[0]) / 2, True, False,
                           f"sizes separate successes from falls: half fail between {gap[0]:.4g} and {gap[1]:.4g} "
                           "(middle reported, ± half the gap)")
    if abs(b_s) < 1e-9:
        return LogisticFit(a, b, None, None, False, True, "success does not depend on the size")
    s50_scaled = -a_s / b_s
    g = np.array([-1.0 / b_s, a_s / b_s**2])
    se_scaled = math.sqrt(max(float(g @ cov @ g), 0.0))
    s50 = lo + s50_scaled * scale
    return LogisticFit(a, b, s50, se_scaled * scale, lo <= s50 <= hi, True, "")


def binned_rates(size: NDArray[np.float64], success: NDArray[np.bool_], bins: int = 8,
                 limits: tuple[float, float] | None = None) -> list[dict[str, Any]]:
    """Success rate with its Wilson interval in ``bins`` equal-width bins of the size."""
    s = np.asarray(size, dtype=float)
    ok = np.asarray(success, dtype=bool)
    lo, hi = limits if limits is not None else (float(s.min()), float(s.max()))
    edges = np.linspace(lo, hi, bins + 1)
    idx = np.clip(np.searchsorted(edges, s, side="right") - 1, 0, bins - 1)
    out = []
    for b in range(bins):
        m = idx == b
        out.append({"size_low": float(edges[b]), "size_high": float(edges[b + 1]),
                    **Rate.of(int(ok[m].sum()), int(m.sum())).to_dict()})
    return out


@dataclass(frozen=True)
class Correlation:
    """Spearman's rank correlation ρ of ``x`` and ``y`` over ``n`` gaits with its two-sided p-value (H₀: no
    monotone association), or ``defined`` False with the ``reason`` (ρ and p are then None, never NaN)."""

    x: str
    y: str
    n: int
    rho: float | None
    p: float | None
    defined: bool
    reason: str

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)

    def text(self, names: bool = True) -> str:
        return correlation_text(self.to_dict(), names)


def correlation_text(c: dict[str, Any], names: bool = True) -> str:
    """One line for a :class:`Correlation` or its JSON: ``r* vs push success: Spearman ρ = +0.512, p = 0.13
    (n = 10)`` or ``...: Spearman ρ undefined (reason)``."""
    head = f"{c['x']} vs {c['y']}: " if names else ""
    if not c["defined"]:
        return f"{head}Spearman ρ undefined ({c['reason']})"
    return f"{head}Spearman ρ = {c['rho']:+.3f}, p = {c['p']:.3g} (n = {c['n']})"


def spearman(x: NDArray[np.float64], y: NDArray[np.float64], x_name: str, y_name: str) -> Correlation:
    """Spearman's ρ = Pearson's correlation of the ranks (ties get their average rank), and the p-value of
    ``scipy.stats.spearmanr`` (t = ρ √((n − 2)/(1 − ρ²)) with n − 2 degrees of freedom: approximate for small
    n). Undefined — with the reason, instead of scipy's NaN and warning — for n < 3 (with two points ρ is
    ±1 whatever the data, and the test has no degree of freedom) or when either column is constant (a rank
    correlation needs an ordering of both)."""
    from scipy.stats import spearmanr

    a, b = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    if a.shape != b.shape or a.ndim != 1:
        raise ValueError(f"need two 1-D arrays of one length, got {a.shape} and {b.shape}")
    n = int(a.size)
    if not (np.isfinite(a).all() and np.isfinite(b).all()):
        raise ValueError("spearman: the values must be finite")

    def undefined(reason: str) -> Correlation:
        return Correlation(x_name, y_name, n, None, None, False, reason)

    if n < 3:
        return undefined(f"fewer than 3 gaits (n = {n})")
    for name, v in ((x_name, a), (y_name, b)):
        if np.ptp(v) == 0:
            return undefined(f"{name} is the same for every gait ({v[0]:g})")
    res = spearmanr(a, b)
    rho, p = float(res.statistic), float(res.pvalue)
    return Correlation(x_name, y_name, n, rho, min(max(p, 0.0), 1.0), True, "")
