"""Bézier polynomials for the virtual-constraint outputs (docs/design.md §3).

A gait's desired joint trajectory is y_d(τ) = Σ_k β_k b_{k,M}(τ), τ ∈ [0, 1], with the Bernstein basis
b_{k,M}(τ) = C(M, k) τ^k (1 − τ)^(M−k) of degree M (M = 7 for 8 coefficients per output). Functions are
vectorized over time (τ of any shape) and over outputs (β of shape (m, M+1)). Derivatives are with respect
to τ; divide by the step duration T (per derivative order) for time derivatives.

Reference: Westervelt, Grizzle, Chevallereau, Choi, Morris, *Feedback Control of Dynamic Bipedal Robot
Locomotion* (2007), §6.3 (Bézier polynomials and their derivatives).
"""

from __future__ import annotations

from math import comb

import numpy as np
from numpy.typing import ArrayLike, NDArray


def bernstein_basis(degree: int, tau: ArrayLike) -> NDArray[np.float64]:
    """Bernstein basis b_{k,M}(τ) = C(M, k) τ^k (1 − τ)^(M − k), k = 0..M.

    τ: any shape S → returns shape S + (M + 1,).
    """
    t = np.asarray(tau, dtype=float)[..., None]
    k = np.arange(degree + 1)
    binom = np.array([comb(degree, int(i)) for i in k], dtype=float)
    return binom * t**k * (1.0 - t) ** (degree - k)


def bezier(coeffs: ArrayLike, tau: ArrayLike) -> NDArray[np.float64]:
    """y(τ) = Σ_k β_k b_{k,M}(τ).

    coeffs: (m, M+1) (or (M+1,) for one output); τ: shape S → returns S + (m,) (or S).
    """
    b = np.asarray(coeffs, dtype=float)
    basis = bernstein_basis(b.shape[-1] - 1, tau)
    return basis @ b.T if b.ndim == 2 else basis @ b


def bezier_derivative_coeffs(coeffs: ArrayLike, order: int = 1) -> NDArray[np.float64]:
    """Coefficients of d^j y/dτ^j, a Bézier of degree M − j: β' = M (β_{k+1} − β_k), applied j times.

    coeffs: (..., M+1) → (..., M+1−j). Raises ValueError when j exceeds the degree.
    """
    b = np.asarray(coeffs, dtype=float)
    if order < 0 or order > b.shape[-1] - 1:
        raise ValueError(f"derivative order {order} not in [0, {b.shape[-1] - 1}]")
    for _ in range(order):
        b = (b.shape[-1] - 1) * np.diff(b, axis=-1)
    return b


def bezier_derivative(coeffs: ArrayLike, tau: ArrayLike, order: int = 1) -> NDArray[np.float64]:
    """d^j y/dτ^j at τ (same shapes as :func:`bezier`)."""
    return bezier(bezier_derivative_coeffs(coeffs, order), tau)
