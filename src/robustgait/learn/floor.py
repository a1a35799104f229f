"""Where the gaits are predicted to clear a person study's robustness floor (docs/person.md): a model of the
certificate's figure over the action space, so that a person study proposes only where its gaits are likely to be
shown — as ROIAL (Li et al., "ROIAL: Region of Interest Active Learning for Characterizing Exoskeleton Gait
Preference Landscapes", ICRA 2021) restricts its questions to a region predicted safe — instead of drawing blindly and
discarding what falls below the floor.

The model is kernel regression (Nadaraya–Watson) shrunk towards zero: at a point x of the normalized action space
([0, 1] per axis) the predicted figure is μ(x) = Σ_i w_i(x) y_i / (w₀ + Σ_i w_i(x)), w_i(x) = exp(−‖x − x_i‖² / 2ℓ²),
over the evaluated gaits' figures y_i (a gait that fell or was refused counts 0), with a prior weight w₀ on a figure
of 0: an unexplored gait is not presumed robust. μ is a weighted mean, so it never exceeds the figures seen nor
overshoots between a robust gait and a fallen one. The grid points with μ ≥ the floor are *predicted to clear it*.
With the floor's reference alone (figure v, floor f v) the region is the ball of normalized radius
ℓ √(2 ln((1 − f) / (f w₀))) around the reference's parameters.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np
from numpy.typing import NDArray

from robustgait.learn.space import ActionSpace

FloatArray = NDArray[np.float64]


def floor_prediction(x: FloatArray, values: FloatArray, grid: FloatArray, lengthscale: float,
                     prior_weight: float) -> FloatArray:
    """μ (M,) at ``grid`` (M, d): Σ_i w_i y_i / (w₀ + Σ_i w_i) with w_i = exp(−‖grid − x_i‖² / 2ℓ²) over the points
    ``x`` (N, d) and their figures ``values`` (N,), w₀ = ``prior_weight`` (module docstring). Zeros when N = 0."""
    if x.shape[0] == 0:
        return np.zeros(grid.shape[0])
    d2 = np.sum((grid[:, None, :] - x[None, :, :]) ** 2, axis=-1)
    w = np.exp(-0.5 * d2 / lengthscale**2)
    return np.asarray(w @ values / (prior_weight + w.sum(axis=1)))


def predicted_to_clear(space: ActionSpace, observed: Sequence[tuple[Mapping[str, float], float]], floor: float,
                       lengthscale: float, prior_weight: float) -> NDArray[np.bool_]:
    """(size,): the grid points whose predicted figure μ (:func:`floor_prediction` over the gaits ``observed``,
    (parameters, figure) pairs — a gait that fell or was refused counts as 0) is at least ``floor``. All True when
    nothing is observed (no model yet) or the floor is 0."""
    if not observed or floor <= 0.0:
        return np.ones(space.size, dtype=bool)
    x = np.array([space.normalize(p) for p, _ in observed], dtype=float).reshape(len(observed), space.dim)
    y = np.array([v for _, v in observed], dtype=float)
    return np.asarray(floor_prediction(x, y, space.normalized(), lengthscale, prior_weight) >= floor)
