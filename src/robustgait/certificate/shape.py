"""Shaped certified sets: an ellipsoid {δ : δᵀ S δ ≤ r²} whose shape S comes from the return map's linearization at
its fixed point (``docs/certificate.md``, "Shaped sets").

The ball of the DTBF H = r² − ‖δ‖² asks every sample to come back *in the Euclidean norm of the coordinates*. A
contracting map whose linearization A is not normal (eigenvalues inside the unit circle, but ‖A‖ > 1) expands some
directions for one step and is refused by any ball; the quadratic Lyapunov function of A is not. Its sublevel sets
are ellipsoids, the set this module shapes:

1. :func:`fit_linearization` — A (k, k) by least squares on the images of samples uniform in a small ball around x*
   (finite differences of a simulated map with touchdown events are noisy; a fit over a ball averages them);
2. :func:`lyapunov_shape` — S from AᵀSA − S = −I (positive definite iff A is Schur stable), scaled to det S = 1, so
   the ellipsoid of "radius" r has the volume of the ball of radius r;
3. :func:`ellipsoid_transform` — coordinates in which that ellipsoid is the ball: z = Cᵀ δ with S = C Cᵀ, so the
   estimators (:mod:`.barrier`, :mod:`.estimators`) certify it unchanged.

A gait whose fitted A is not Schur stable has no quadratic Lyapunov function of its linearization: the ellipsoid
falls back to the ball (S = I) and says so (``fallback``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.linalg
from numpy.typing import NDArray

from robustgait.errors import RobustGaitError

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class LinearFit:
    """P(x* + δ) ≈ x* + b + A δ on the fit samples: A (k, k), offset b (k,), the samples used (finite images) and the
    residual RMS of the fit relative to the RMS of the images' deviations (0: exactly linear)."""

    a: FloatArray
    offset: FloatArray
    used: int
    relative_residual: float

    @property
    def spectral_radius(self) -> float:
        return float(np.max(np.abs(np.linalg.eigvals(self.a))))


def fit_linearization(samples: FloatArray, images: FloatArray, x_star: FloatArray) -> LinearFit:
    """Least-squares linearization of a map at x*: minimize Σ_i ‖(P(x_i) − x*) − b − A (x_i − x*)‖² over A, b.

    Shapes: samples (N, k), images (N, k) (rows with a NaN — falls — are left out), x_star (k,). Needs at least
    k + 1 finite rows. Returns :class:`LinearFit`.
    """
    x0 = np.asarray(samples, dtype=float)
    x1 = np.asarray(images, dtype=float)
    ok = np.isfinite(x1).all(axis=1)
    k = x0.shape[1]
    if ok.sum() < k + 1:
        raise RobustGaitError(f"the linearization needs at least {k + 1} samples that do not fall, got {int(ok.sum())}")
    d0, d1 = x0[ok] - x_star, x1[ok] - x_star
    design = np.hstack([d0, np.ones((d0.shape[0], 1))])
    coef, *_ = np.linalg.lstsq(design, d1, rcond=None)
    a, b = coef[:k].T, coef[k]
    resid = d1 - design @ coef
    scale = float(np.sqrt(np.mean(d1 * d1)))
    rel = float(np.sqrt(np.mean(resid * resid)) / scale) if scale > 0 else 0.0
    return LinearFit(np.asarray(a), np.asarray(b), int(ok.sum()), rel)


def lyapunov_shape(a: FloatArray) -> FloatArray:
    """S (k, k): the solution of the discrete Lyapunov equation AᵀSA − S = −I, scaled to det S = 1.

    V(δ) = δᵀSδ then decreases along the linearization, V(Aδ) − V(δ) = −‖δ‖²/det(S₀)^{1/k} < 0 (S₀ the unscaled
    solution). Positive definite iff A is Schur stable (spectral radius < 1); raises :class:`RobustGaitError`
    otherwise.
    """
    a = np.asarray(a, dtype=float)
    rho = float(np.max(np.abs(np.linalg.eigvals(a))))
    if not rho < 1.0:
        raise RobustGaitError(f"the linearization is not contracting (spectral radius {rho:.3g} ≥ 1): no ellipsoid")
    s = scipy.linalg.solve_discrete_lyapunov(a.T, np.eye(a.shape[0]))
    s = 0.5 * (s + s.T)
    sign, logdet = np.linalg.slogdet(s)
    if sign <= 0:
        raise RobustGaitError("the Lyapunov solution is not positive definite")
    return np.asarray(s / math.exp(logdet / a.shape[0]))


def ellipsoid_transform(s: FloatArray) -> FloatArray:
    """Cᵀ (k, k) with S = C Cᵀ (Cholesky): δᵀ S δ = ‖Cᵀ δ‖², so {δᵀ S δ ≤ r²} is the ball of radius r in z = Cᵀ δ."""
    return np.asarray(np.linalg.cholesky(np.asarray(s, dtype=float)).T)


def volume_ratio(r_ellipsoid: float, r_ball: float, dim: int) -> float:
    """vol{δᵀSδ ≤ r_e²} / vol{‖δ‖ ≤ r_b} = (r_e / r_b)^k for det S = 1 (inf if r_b = 0 < r_e; 1 if both are 0)."""
    if r_ball <= 0.0:
        return 1.0 if r_ellipsoid <= 0.0 else math.inf
    return float((r_ellipsoid / r_ball) ** dim)


@dataclass(frozen=True)
class Shape:
    """The shape of a certified set in the state's metric coordinates: S (k, k) (identity for the ball), the fit it
    came from (None for the ball), and ``fallback``: why an ellipsoid fell back to the ball ("" if it did not)."""

    s: FloatArray
    fit: LinearFit | None = None
    fallback: str = ""

    @property
    def transform(self) -> FloatArray:
        return ellipsoid_transform(self.s)

    @property
    def axes(self) -> FloatArray:
        """Semi-axes (k,) of the ellipsoid of radius 1, longest first (1/√ of S's eigenvalues)."""
        return np.asarray(np.sort(1.0 / np.sqrt(np.linalg.eigvalsh(self.s)))[::-1])

    def inner_radius(self, r: float) -> float:
        """The radius of the largest ball inside {δᵀSδ ≤ r²}: r / √λ_max(S)."""
        return float(r / math.sqrt(float(np.linalg.eigvalsh(self.s)[-1])))

    def to_dict(self) -> dict[str, Any]:
        out: dict[str, Any] = {"S": self.s.tolist(), "axes": self.axes.tolist(), "fallback": self.fallback}
        if self.fit is not None:
            out.update({"A": self.fit.a.tolist(), "offset": self.fit.offset.tolist(), "fit_samples": self.fit.used,
                        "fit_relative_residual": self.fit.relative_residual,
                        "spectral_radius": self.fit.spectral_radius})
        return out


def shape_from_fit(fit: LinearFit) -> Shape:
    """The ellipsoid of a fitted linearization, or the ball with the reason if A is not contracting."""
    try:
        return Shape(lyapunov_shape(fit.a), fit)
    except RobustGaitError as exc:
        return Shape(np.eye(fit.a.shape[0]), fit, fallback=str(exc))
