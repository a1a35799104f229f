"""Periodic orbits of a batched map F: (N, d) → (N, d) (NaN rows: the sample fell), whatever the map is: whether its
iterates have settled (a window of them within a tolerance; a period-two orbit), its finite-difference Jacobian (ONE
call of F on 2d + 1 states), the spectral radius ρ of a linearization, and damped Newton on F(x) = x
(``docs/certificate.md``, "Fixed point"; :mod:`.poincare` gives the return map in section
coordinates).

F need only be piecewise smooth: the simulated step map jumps where a touchdown or a contact crosses a physics step,
so the Jacobian takes a column one-sided, from the side without a jump, when its forward and backward differences
disagree (:func:`fd_jacobian`). Maps with known answers: :mod:`.synthetic`.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from robustgait.errors import RobustGaitError

FloatArray = NDArray[np.float64]
BatchMap = Callable[[FloatArray], FloatArray]


def window_residual(xs: ArrayLike, window: int, period: int = 1) -> float:
    """max_{i = 1 … W} ‖x_{k − i p} − x_k‖ of the newest iterate x_k of ``xs`` (K, d): how far the last W iterates of
    period p (p = 2: every other one) lie from it; inf while there are fewer than W p + 1 iterates."""
    a = np.asarray(xs, dtype=float)
    if window < 1 or period < 1:
        raise RobustGaitError(f"window and period must be ≥ 1, got {window} and {period}")
    if a.shape[0] < window * period + 1:
        return float("inf")
    past = a[-1 - period * np.arange(1, window + 1)]
    return float(np.max(np.linalg.norm(past - a[-1], axis=1)))


def settled_at(xs: ArrayLike, window: int, tol: float, min_index: int = 0, period: int = 1) -> int | None:
    """The first index k ≥ ``min_index`` whose window (:func:`window_residual` of xs[:k + 1]) is ≤ tol, or None."""
    a = np.asarray(xs, dtype=float)
    for k in range(max(min_index, window * period), a.shape[0]):
        if window_residual(a[:k + 1], window, period) <= tol:
            return k
    return None


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


@dataclass(frozen=True)
class NewtonResult:
    """Damped Newton on F(x) = x: the last point ``x`` (d,), ‖F(x_i) − x_i‖ per iterate (``residuals``, the start
    first), whether the last is ≤ the tolerance, the Jacobians at the last point and at the start (None where F
    fell within the step), and the states F was evaluated on."""

    x: FloatArray
    residuals: tuple[float, ...]
    converged: bool
    jacobian: Jacobian | None
    first: Jacobian | None
    evaluations: int


def newton(F: BatchMap, x0: ArrayLike, *, step: float | ArrayLike, jump: float, tol: float, iterations: int,
           damping: Sequence[float], jacobian: Callable[[FloatArray], Jacobian] | None = None) -> NewtonResult:
    """Damped Newton on G(x) = F(x) − x from x0 (d,): per iteration one finite-difference batch (:func:`fd_jacobian`,
    2d + 1 states: F(x) and J), the step δ solving (I − J) δ = F(x) − x (least squares if I − J is singular), then ONE
    batch of x + s δ for s in ``damping``; the s with the smallest residual is taken if it lowers the residual, else
    Newton stops (stalled: F jumps across x*, or the linearization is wrong). Stops when ‖F(x) − x‖ ≤ tol or after
    ``iterations`` iterations. ``jacobian``: the Jacobian to use at a point (default: :func:`fd_jacobian` of F).
    """
    jac = jacobian or (lambda x: fd_jacobian(F, x, step, jump))
    x = np.asarray(x0, dtype=float).copy()
    d = x.shape[0]
    evaluations = 0
    residuals: list[float] = []
    j: Jacobian | None = None
    first: Jacobian | None = None
    for it in range(iterations + 1):
        try:
            j = jac(x)
        except RobustGaitError:
            j = None
            break
        first = first or j
        evaluations += 2 * d + 1
        g = j.value - x
        residuals.append(float(np.linalg.norm(g)))
        if residuals[-1] <= tol or it == iterations:
            break
        delta = np.linalg.lstsq(np.eye(d) - j.matrix, g, rcond=None)[0]
        trial = x + np.asarray(damping, dtype=float)[:, None] * delta
        img = np.asarray(F(trial), dtype=float)
        evaluations += len(damping)
        res = np.linalg.norm(img - trial, axis=1)
        res[~np.isfinite(res)] = np.inf
        best = int(np.argmin(res))
        if not res[best] < residuals[-1]:
            break
        x = trial[best]
    converged = bool(residuals) and residuals[-1] <= tol
    return NewtonResult(x, tuple(residuals), converged, j, first, evaluations)


def residual_summary(residuals: Sequence[float], window: int) -> dict[str, Any]:
    """A search's successive residuals ‖x_k − x_{k−1}‖ in a few numbers: their count, the last, the smallest, and the
    median and largest of the last ``window``."""
    r = np.asarray(residuals, dtype=float)
    if r.size == 0:
        return {"steps": 0, "last": None, "min": None, "median_last_window": None, "max_last_window": None}
    tail = r[-window:]
    return {"steps": int(r.size), "last": float(r[-1]), "min": float(r.min()),
            "median_last_window": float(np.median(tail)), "max_last_window": float(tail.max())}


@dataclass(frozen=True)
class OrbitReport:
    """What a fixed-point search (or a walk) learned of the orbit of a map: the distance ``metric`` of its iterates
    and their successive residuals ‖x_k − x_{k−1}‖ (``residuals``; ``period`` steps per iterate); the step at which a
    window of ``window`` iterates first lay within ``tol`` of the newest (``settled``, None if never) and that window's
    residual (at the end if it never held); ``steps``: walked until it held, or in all; ``period_two``: it never
    held, but iterates two apart lay within ``tol`` (P∘P settled, P not); then, at x*: the Newton residuals and
    whether Newton converged, ‖F(x*) − x*‖, the spectral radius ρ of the linearized map and the moduli of its
    eigenvalues, ρ at a fixed event time, and the Jacobian columns taken one-sided."""

    metric: str
    window: int
    tol: float
    period: int
    residuals: tuple[float, ...]
    settled: int | None
    window_residual: float
    steps: int
    period_two: bool = False
    newton: tuple[float, ...] = ()
    newton_converged: bool | None = None
    map_residual: float | None = None
    rho: float | None = None
    moduli: tuple[float, ...] = ()
    rho_fixed_event: float | None = None
    one_sided: int = 0

    @property
    def converged(self) -> bool:
        return self.settled is not None

    def describe(self) -> str:
        """One line: settled or not, the window, ρ."""
        w = f"{self.window} iterates within {self.tol:g}"
        if self.settled is None and not np.isfinite(self.window_residual):
            line = f"NOT converged (too few iterates for a window of {self.window}: {self.steps} steps)"
        elif self.settled is None:
            what = "period two: iterates two apart settle, successive ones do not" if self.period_two else "wandering"
            line = (f"NOT converged ({what}; window residual {self.window_residual:.2e} over the last {self.window} "
                    f"iterates, {w} needed, {self.steps} steps)")
        else:
            line = f"converged at step {self.settled} ({w}: window residual {self.window_residual:.2e})"
            if self.period == 2:
                line = "stride map (two steps): " + line
        if self.newton:
            line += f"; Newton {' → '.join(f'{r:.1e}' for r in self.newton)}" + (
                "" if self.newton_converged else " (not converged)")
        if self.rho is not None:
            line += f"; ρ = {self.rho:.3g}" + (" (UNSTABLE: ≥ 1)" if self.rho >= 1 else "")
        return line

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready; the residuals as :func:`residual_summary`."""
        return {"metric": self.metric, "window": self.window, "tol": self.tol, "period": self.period,
                "converged": self.converged,
                "settled_at_step": self.settled, "window_residual": _finite(self.window_residual),
                "period_two": self.period_two, "residuals": residual_summary(self.residuals, self.window),
                "newton_residuals": list(self.newton), "newton_converged": self.newton_converged,
                "map_residual": self.map_residual, "rho": self.rho, "moduli": list(self.moduli),
                "rho_fixed_event": self.rho_fixed_event, "one_sided_columns": self.one_sided}


def _finite(v: float) -> float | None:
    return float(v) if np.isfinite(v) else None


def search_report(xs: ArrayLike, *, metric: str, window: int, tol: float, min_index: int, period: int = 1,
                  first_step: int = 0) -> OrbitReport:
    """The window search over a finished sequence of iterates ``xs`` (K, d): successive residuals, the first settled
    iterate at index ≥ ``min_index`` (reported in steps: ``first_step`` + index × ``period``, x_0 being the state
    after ``first_step`` steps), and, if none, whether iterates two apart settled at the end (a period-two orbit)."""
    a = np.asarray(xs, dtype=float)
    res = tuple(float(v) for v in np.linalg.norm(np.diff(a, axis=0), axis=1)) if a.shape[0] > 1 else ()
    k = settled_at(a, window, tol, min_index)
    if k is not None:
        step = first_step + k * period
        return OrbitReport(metric, window, tol, period, res[:k], step, window_residual(a[:k + 1], window), step)
    two = window_residual(a, window, 2) <= tol
    return OrbitReport(metric, window, tol, period, res, None, window_residual(a, window),
                       first_step + len(res) * period if a.shape[0] else 0, period_two=bool(two))


def orbit_status(report: OrbitReport, rho_max: float | None) -> str:
    """``ok``, or why the orbit of ``report`` gives no fixed point to certify: ``no_stable_orbit`` (no window of its
    iterates settled), ``period_two_orbit`` (none did, but iterates two apart did), ``unstable_orbit`` (it settled, but
    ρ ≥ ``rho_max``; None: ρ is not asked for)."""
    if report.settled is None:
        return "period_two_orbit" if report.period_two else "no_stable_orbit"
    if rho_max is not None and report.rho is not None and report.rho >= rho_max:
        return "unstable_orbit"
    return "ok"
