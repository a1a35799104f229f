"""Figures: the certified invariant set (paper Fig. 4) and the barrier along a walk or a log (Fig. 5)."""

from __future__ import annotations

import itertools
from pathlib import Path

import matplotlib

matplotlib.use("Agg")  # files only; no display on the machines this runs on

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from numpy.typing import NDArray

from robustgait.certificate.barrier import BarrierTrace, Certificate
from robustgait.certificate.reduced import Coordinates
from robustgait.io.output import atomic_output, check_output

FloatArray = NDArray[np.float64]

OMEGA_LABELS = ("ω_x", "ω_y", "ω_z")
COLORS = {"satisfies": "tab:green", "violates": "tab:orange", "fell": "tab:red"}


def outcome_masks(cert: Certificate) -> dict[str, np.ndarray]:
    """Per sample: fell; violates (margin < 0 at r*, did not fall); satisfies (margin ≥ 0)."""
    fell = np.asarray(cert.fell)
    viol = ~fell & (np.asarray(cert.margins) < 0)
    return {"satisfies": ~fell & ~viol, "violates": viol, "fell": fell}


def _save(fig: Figure, path: str | Path) -> Path:
    """Save through the output writer (:mod:`robustgait.io.output`): the target is checked first (a .png,
    .pdf or .svg path in a writable directory, not a link or device), the figure is written beside it and
    renamed into place, and nothing half-written or temporary is left behind."""
    try:
        with atomic_output(path, "plot") as tmp:
            fig.savefig(tmp, dpi=120, bbox_inches="tight", format=tmp.suffix.lstrip(".").lower())
    finally:
        plt.close(fig)
    return Path(path)


def _axis_labels(coordinates: Coordinates | None, dim: int, shaped: bool) -> list[str]:
    """Names of the plotted axes: the state's coordinates, or the ellipsoid's axes (longest first)."""
    unit = coordinates.unit if coordinates is not None else "rad/s"
    space = coordinates.space if coordinates is not None else "omega"
    if shaped:
        return [f"ellipsoid axis {i + 1} [{unit}]" for i in range(dim)]
    if space == "omega":
        return [f"{n} [{unit}]" for n in OMEGA_LABELS]
    if space == "push":
        return ["J_x (heading frame) [N s]", "J_y [N s]"]
    if space == "centroidal":
        names = ["p_x/√m", "p_y/√m", "p_z/√m", "(I_c^-½ L)_1", "(I_c^-½ L)_2", "(I_c^-½ L)_3"]
        return [f"{n} [{unit}]" for n in names]
    return [f"y_{i + 1} [{unit}]" for i in range(dim)]


def _ellipse(s_inv: FloatArray, r: float, n: int = 200) -> FloatArray:
    """(n, 2) boundary of the 2-D shadow {p : pᵀ (S⁻¹)_sub⁻¹ p ≤ r²} of an ellipsoid {yᵀ S y ≤ r²}."""
    t = np.linspace(0, 2 * np.pi, n)
    chol = np.linalg.cholesky(s_inv)
    return np.asarray((r * chol @ np.stack([np.cos(t), np.sin(t)])).T)


def plot_certificate(cert: Certificate, path: str | Path, *, title: str = "", coordinates: Coordinates | None = None,
                     ball: Certificate | None = None) -> Path:
    """The certified invariant set (paper Fig. 4) and how the estimator got there. Writes ``path``
    (PNG/PDF/SVG by extension).

    Samples are drawn in the state's metric coordinates y (the ball is a disk there; ``coordinates`` gives them —
    without it the certificate's own coordinates, the paper's ω), coloured by outcome at r*. For an ellipsoid the
    axes are the ellipsoid's principal axes (longest first) and both certified sets are drawn: the ellipsoid's
    shadow and, when ``ball`` (the ball of the same state) is given, its disk. Top row: the image distance
    ‖P(x) − x*‖ against the sample's (the DTBF boundary p² = α r*² + (1 − α) d² dashed), then the 2-D projections
    on axes (1, 2) and (1, 3) (for a 3-D ball, the first panel is the 3-D view). Bottom: projection (2, 3), each
    sample's distance by round, r̂ against samples used.
    """
    check_output(path, "plot")
    if coordinates is not None and coordinates.space == "push":
        return _plot_push_certificate(cert, path, title)
    z = np.asarray(cert.samples)
    k = z.shape[1]
    zs = np.asarray(cert.x_star)
    s_mat = coordinates.shape.s if coordinates is not None else np.eye(k)
    shaped = not np.allclose(s_mat, np.eye(k))
    c_t = np.linalg.cholesky(s_mat).T  # z − z* = Cᵀ y
    y = np.linalg.solve(c_t, (z - zs).T).T
    if shaped:
        w, v = np.linalg.eigh(s_mat)  # smallest eigenvalue first: the longest axis first
        view = v
    else:
        w, view = np.ones(k), np.eye(k)
    yv = y @ view
    s_inv_view = view.T @ np.linalg.inv(s_mat) @ view
    labels = _axis_labels(coordinates, k, shaped)
    masks = outcome_masks(cert)
    r = cert.radius
    rb = ball.radius if ball is not None else (r if not shaped else None)
    longest = float(1.0 / np.sqrt(w.min())) if shaped else 1.0
    half = float(cert.r_max if r <= 0 else min(cert.r_max * longest, 3.0 * r * longest))
    near = np.all(np.abs(yv) <= half, axis=1)
    fig = plt.figure(figsize=(17, 10))
    if k == 3 and not shaped:
        ax3 = fig.add_subplot(2, 3, 1, projection="3d")
        for name, m in masks.items():
            ax3.scatter(*yv[m & near].T, s=8, c=COLORS[name], label=f"{name} ({int(m.sum())})", depthshade=False)
        u, vv = np.mgrid[0:2 * np.pi:40j, 0:np.pi:20j]
        ax3.plot_wireframe(r * np.cos(u) * np.sin(vv), r * np.sin(u) * np.sin(vv), r * np.cos(vv),
                           color="tab:blue", linewidth=0.4, alpha=0.6)
        for set_lim in (ax3.set_xlim, ax3.set_ylim, ax3.set_zlim):
            set_lim(-half, half)
        ax3.set_xlabel("δ" + labels[0])
        ax3.set_ylabel("δ" + labels[1])
        ax3.set_zlabel("δ" + labels[2])
        ax3.legend(loc="upper left", fontsize=8)
    else:
        _plot_distances(cert, fig.add_subplot(2, 3, 1))
    planes = [(0, 1), (0, 2), (1, 2)] if k >= 3 else [(0, 1)]
    slots = [2, 3, 4]
    t = np.linspace(0, 2 * np.pi, 200)
    for (i, j), slot in zip(planes, slots, strict=False):
        ax = fig.add_subplot(2, 3, slot)
        for name, m in masks.items():
            ax.scatter(yv[m & near, i], yv[m & near, j], s=8, c=COLORS[name], marker="x" if name == "fell" else "o",
                       label=f"{name} ({int(m.sum())})")
        if shaped:
            e = _ellipse(s_inv_view[np.ix_([i, j], [i, j])], r)
            ax.plot(e[:, 0], e[:, 1], color="tab:blue", label=f"ellipsoid r* = {r:.3g}")
        if rb is not None:
            ax.plot(rb * np.cos(t), rb * np.sin(t), color="tab:blue" if not shaped else "tab:gray",
                    ls="-" if not shaped else "--", label=f"ball r* = {rb:.3g}")
        ax.plot(0, 0, "k+", ms=12)
        ax.set_xlim(-half, half)
        ax.set_ylim(-half, half)
        ax.set_xlabel("δ" + labels[i])
        ax.set_ylabel("δ" + labels[j])
        ax.set_aspect("equal")
        if slot == 2:
            ax.legend(fontsize=8)
    _plot_rounds(cert, fig.add_subplot(2, 3, 5), fig.add_subplot(2, 3, 6))
    n = f"N = {cert.n_samples}" + (f" in {len(cert.rounds)} rounds" if len(cert.rounds) > 1 else "")
    fig.suptitle(title or f"DTBF certificate ({cert.method}): r* = {r:.4f}, {n}, α = {cert.alpha:g} "
                 f"({cert.n_inside} samples inside, {int(np.sum(cert.fell))} fell)")
    return _save(fig, path)


def _plot_push_certificate(cert: Certificate, path: str | Path, title: str) -> Path:
    """J* (``certify --disturbance push``): the sampled impulses in the heading frame (walked or fell) with the
    certified disk; the fraction that fell per band of |J| (95 % Wilson intervals); the rounds and Ĵ."""
    from robustgait.validate.stats import wilson_interval

    j = np.asarray(cert.samples)
    size = np.linalg.norm(j, axis=1)
    fell = np.asarray(cert.fell, dtype=bool)
    r = cert.radius
    fig = plt.figure(figsize=(14, 10))
    ax = fig.add_subplot(2, 2, 1)
    ax.scatter(j[~fell, 0], j[~fell, 1], s=9, c=COLORS["satisfies"], label=f"walked on ({int((~fell).sum())})")
    ax.scatter(j[fell, 0], j[fell, 1], s=14, c=COLORS["fell"], marker="x", label=f"fell ({int(fell.sum())})")
    t = np.linspace(0, 2 * np.pi, 200)
    ax.plot(r * np.cos(t), r * np.sin(t), color="tab:blue", label=f"J* = {r:.3g} N s")
    ax.plot(0, 0, "k+", ms=12)
    lim = cert.r_max * 1.02
    ax.set_xlim(-lim, lim)
    ax.set_ylim(-lim, lim)
    ax.set_aspect("equal")
    ax.set_xlabel("J_x: forward (heading frame) [N s]")
    ax.set_ylabel("J_y: to the left [N s]")
    ax.legend(fontsize=8, loc="upper right")
    ax.set_title("pushes sampled (the robot walks along +J_x)", fontsize=9)
    ax = fig.add_subplot(2, 2, 2)
    edges = np.linspace(0.0, cert.r_max, 11)
    for lo, hi in itertools.pairwise(edges):
        m = (size >= lo) & (size < hi)
        if m.any():
            k, n = int(fell[m].sum()), int(m.sum())
            low, high = wilson_interval(k, n)
            ax.bar((lo + hi) / 2, k / n, width=0.9 * (hi - lo), color="tab:red", alpha=0.35)
            ax.errorbar((lo + hi) / 2, k / n, yerr=[[max(0.0, k / n - low)], [max(0.0, high - k / n)]], color="k",
                        lw=0.8, capsize=2)
            ax.text((lo + hi) / 2, high + 0.02, str(n), ha="center", fontsize=7)
    ax.axvline(r, color="tab:blue", label=f"J* = {r:.3g} N s")
    ax.axhline(cert.violation_bound, color="tab:blue", ls=":", lw=0.8,
               label=f"certified bound {100 * cert.violation_bound:.3g} % below J*")
    ax.set_ylim(0, 1.1)
    ax.set_xlabel("|J| [N s]")
    ax.set_ylabel("fraction that fell (number of pushes above)")
    ax.legend(fontsize=8, loc="upper left")
    _plot_rounds(cert, fig.add_subplot(2, 2, 3), fig.add_subplot(2, 2, 4), name="J")
    fig.suptitle(title or f"Push certificate ({cert.method}): J* = {r:.4g} N s, N = {cert.n_samples}")
    return _save(fig, path)


def _plot_distances(cert: Certificate, ax: Axes) -> None:
    """Image distance p = ‖P(x) − x*‖ against the sample's d (falls on top), with the DTBF boundary at r*."""
    d = np.linalg.norm(np.asarray(cert.samples) - np.asarray(cert.x_star), axis=1)
    with np.errstate(invalid="ignore"):
        p = np.linalg.norm(np.asarray(cert.images) - np.asarray(cert.x_star), axis=1)
    masks = outcome_masks(cert)
    top = float(np.nanmax(np.concatenate([d, p[np.isfinite(p)]]))) * 1.05 if d.size else 1.0
    for name, m in masks.items():
        ax.scatter(d[m], np.full(int(m.sum()), top) if name == "fell" else p[m], s=6, c=COLORS[name],
                   marker="x" if name == "fell" else "o", label=f"{name} ({int(m.sum())})")
    dd = np.linspace(0, max(cert.radius, 1e-12), 100)
    ax.plot(dd, np.sqrt(cert.alpha * cert.radius ** 2 + (1 - cert.alpha) * dd ** 2), "b--", lw=0.8,
            label="DTBF boundary at r*")
    ax.plot([0, top], [0, top], color="0.6", lw=0.6)
    ax.axvline(cert.radius, color="tab:blue", ls=":", lw=0.8)
    ax.set_xlabel("‖x − x*‖ (sample)")
    ax.set_ylabel("‖P(x) − x*‖ (image; falls at the top)")
    ax.legend(fontsize=8)


ROUND_COLORS = {"uniform": "tab:gray", "explore": "tab:purple", "verify": "tab:cyan"}


def _plot_rounds(cert: Certificate, ax_d: Axes, ax_r: Axes, name: str = "r") -> None:
    """Distances by round (ax_d) and r̂ (``name`` r, or J for pushes) against samples used (ax_r)."""
    hat, star = f"{name}\u0302", f"{name}*"
    d = np.linalg.norm(np.asarray(cert.samples) - np.asarray(cert.x_star), axis=1)
    idx = np.arange(d.size)
    which = cert.round_of_sample
    kinds = [rd.kind for rd in cert.rounds] or ["uniform"]
    pos = d > 0
    for kind, color in ROUND_COLORS.items():
        m = np.isin(which, [k for k, kd in enumerate(kinds) if kd == kind]) & pos
        if m.any():
            ax_d.scatter(idx[m], d[m], s=5, c=color, label=kind)
    used = np.array([0] + [rd.samples_used for rd in cert.rounds])
    r_hat = np.array([cert.r_max] + [rd.r_hat for rd in cert.rounds])
    for ax in (ax_d, ax_r):
        ax.step(used, r_hat, where="post", color="tab:blue", label=f"{hat} after each round")
        ax.axhline(cert.radius, color="tab:blue", ls=":", lw=0.8)
        ax.set_yscale("log")
        ax.set_xlabel("samples used")
    for rd in cert.rounds:
        if rd.kind == "verify":
            ax_r.plot(rd.samples_used, rd.r_hat, "o" if rd.passed else "x", color="tab:green" if rd.passed
                      else "tab:red", ms=8, label=f"verification {'passed' if rd.passed else 'failed'}")
    ax_d.set_ylabel("|J_i| [N s] (colour: round kind)" if name == "J" else "‖x_i − x*‖ (colour: round kind)")
    ax_d.legend(fontsize=8, loc="upper right")
    ax_r.set_ylabel(hat)
    handles, labels = ax_r.get_legend_handles_labels()
    uniq = dict(zip(labels, handles, strict=True))
    ax_r.legend(uniq.values(), uniq.keys(), fontsize=8)
    ax_r.set_title(f"{cert.method}: {star} = {cert.radius:.4g}, bound {100 * cert.violation_bound:.3g}% at "
                   f"{100 * cert.confidence:g}%", fontsize=9)


def plot_barrier_trace(trace: BarrierTrace, path: str | Path, *, title: str = "") -> Path:
    """H(x_k) along a sequence and the DTBF margin H(x_{k+1}) − (1 − α) H(x_k) of each step."""
    check_output(path, "plot")
    fig, (a1, a2) = plt.subplots(2, 1, figsize=(8, 6), sharex=True)
    k = np.arange(trace.h.size)
    a1.plot(k, trace.h, "o-", ms=3)
    a1.axhline(0, color="k", lw=0.8)
    a1.set_ylabel("H(x_k) = r² − ‖x_k − x*‖²")
    colors = np.where(trace.margins >= 0, "tab:green", "tab:red")
    a2.bar(k[:-1], trace.margins, color=colors)
    a2.axhline(0, color="k", lw=0.8)
    a2.set_ylabel("H(x_k+1) − (1 − α) H(x_k)")
    a2.set_xlabel("step k")
    verdict = "satisfied at every step" if trace.ok else f"first violated at step {trace.first_violation}"
    fig.suptitle(title or f"Barrier along the sequence (r = {trace.r:g}, α = {trace.alpha:g}): {verdict}")
    return _save(fig, path)
