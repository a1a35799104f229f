"""Linearizing a batched map F: (N, d) → (N, d) (NaN rows: the sample fell), whatever the map is: its finite-difference
Jacobian (ONE call of F on 2d + 1 states), the spectral radius ρ of a linearization, and the correction of a map whose
event is found in continuous time (``docs/certificate.md``, "ρ, a diagnostic"; :mod:`.returnmap` gives the return
map in section coordinates, :mod:`.linearization` uses these).

F need only be piecewise smooth: the simulated step map jumps where a touchdown or a contact crosses a physics step,
so the Jacobian takes a column one-sided, from the side without a jump, when its forward and backward differences
disagree (:func:`fd_jacobian`). Maps with known answers: :mod:`.synthetic`.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from robustgait.errors import RobustGaitError

FloatArray = NDArray[np.float64]
BatchMap = Callable[[FloatArray], FloatArray]


@dataclass(frozen=True)
class Jacobian:
    """A finite-difference Jacobian: ``matrix`` (d, d), ∂F_i/∂x_j; ``value`` F(x) (d,); ``one_sided``: the columns taken
    from one side (the other side's difference jumped); ``step`` the step per coordinate (d,)."""

    matrix: FloatArray
    value: FloatArray
    one_sided: tuple[int, ...]
    step: FloatArray


def fd_jacobian(F: BatchMap, x: ArrayLike, step: float | ArrayLike, jump: float) -> Jacobian:
    """∂F/∂x at x (d,) from ONE call of F on the 2d + 1 states x, x + h_j e_j, x − h_j e_j.

    Column j is the central difference (F(x + h_j e_j) − F(x − h_j e_j)) / 2h_j, unless the forward and backward
    differences D⁺_j, D⁻_j disagree, ‖D⁺_j − D⁻_j‖ > ``jump`` · min(‖D⁺_j‖, ‖D⁻_j‖): then F jumps between x and one of
    the two states (the jump s inflates that side's difference to ≈ s/h) and the column is the one-sided difference of
    smaller norm — first-order accurate, O(h), where the central one is O(h²). A perturbed state that fell (NaN row)
    leaves the other side; both fallen, or F(x) itself, raise :class:`RobustGaitError`.
    """
    x = np.asarray(x, dtype=float)
    d = x.shape[0]
    h = np.broadcast_to(np.asarray(step, dtype=float), (d,)).copy()
    if not np.all(h > 0):
        raise RobustGaitError("finite-difference steps must be positive")
    e = np.diag(h)
    y = np.asarray(F(np.vstack([x[None], x + e, x - e])), dtype=float)
    f0, fp, fm = y[0], y[1:d + 1], y[d + 1:]
    if not np.all(np.isfinite(f0)):
        raise RobustGaitError("the map falls from the point its Jacobian is taken at")
    dp, dm = (fp - f0) / h[:, None], (f0 - fm) / h[:, None]  # row j: the difference along coordinate j
    ok_p, ok_m = np.isfinite(dp).all(axis=1), np.isfinite(dm).all(axis=1)
    if not np.all(ok_p | ok_m):
        raise RobustGaitError(f"the map falls on both sides of coordinate(s) {np.flatnonzero(~(ok_p | ok_m)).tolist()} "
                              "within the finite-difference step")
    dp, dm = np.where(ok_p[:, None], dp, dm), np.where(ok_m[:, None], dm, dp)
    np_, nm = np.linalg.norm(dp, axis=1), np.linalg.norm(dm, axis=1)
    one = (np.linalg.norm(dp - dm, axis=1) > jump * np.minimum(np_, nm)) | ~ok_p | ~ok_m
    cols = np.where(one[:, None], np.where((np_ <= nm)[:, None], dp, dm), 0.5 * (dp + dm))
    return Jacobian(cols.T.copy(), f0, tuple(int(j) for j in np.flatnonzero(one)), h)


def spectral_radius(a: ArrayLike) -> tuple[float, FloatArray]:
    """ρ(A) = max |λ_i| and the moduli |λ_i| of the eigenvalues of A (d, d), largest first."""
    moduli = np.sort(np.abs(np.linalg.eigvals(np.asarray(a, dtype=float))))[::-1]
    return float(moduli[0]), moduli


def flow_projection(flow: ArrayLike, guard_gradient: ArrayLike) -> FloatArray | None:
    """Π = I − f ∇gᵀ / (∇g · f) (d, d): moves a change of the image along the flow f onto the tangent space of the
    guard g = 0 — the linearization of a map whose event is found in continuous time, Π ∂Φ/∂x, from ∂Φ/∂x at a fixed
    event time (the event time's derivative −∇g · ∂Φ/∂x / (∇g · f), as in the trajectory sensitivities of hybrid
    systems: Hiskens & Pai, IEEE Trans. Circuits Syst. I 47(2), 2000). None when
    the flow is tangent to the guard (|∇g · f| ≤ 1e-9 ‖∇g‖ ‖f‖): the event time is then not defined by the state."""
    f, g = np.asarray(flow, dtype=float), np.asarray(guard_gradient, dtype=float)
    gf = float(g @ f)
    if abs(gf) <= 1e-9 * float(np.linalg.norm(g) * np.linalg.norm(f)):
        return None
    return np.asarray(np.eye(f.shape[0]) - np.outer(f, g) / gf)
