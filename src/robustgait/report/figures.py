"""Figures: the certified invariant set (paper Fig. 4) and the barrier along a walk or a log (Fig. 5)."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")  # files only; no display on the machines this runs on

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from robustgait.barrier import BarrierTrace, Certificate
from robustgait.io.output import atomic_output, check_output

LABELS = ("ω_x [rad/s]", "ω_y [rad/s]", "ω_z [rad/s]")
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


def _zoom(cert: Certificate) -> float:
    """Half-width of the spatial panels: the whole sampled ball, or 3 r* when r* is much smaller."""
    return float(cert.r_max if cert.r_star <= 0 else min(cert.r_max, 3.0 * cert.r_star))


def plot_certificate(cert: Certificate, path: str | Path, *, title: str = "") -> Path:
    """The certified invariant set (paper Fig. 4) and how the estimator got there. Writes ``path``
    (PNG/PDF/SVG by extension).

    Top left: samples in the 3-D reduced space coloured by outcome at r*, with the r* sphere; then the three
    2-D projections (circles of radius r* around x*). The spatial panels show the cube of half-width
    min(r_max, 3 r*) around x*. Bottom middle: each sample's distance ‖x_i − x*‖ against its index,
    coloured by the round it came from (uniform / exploration / verification), with r̂ after each round.
    Bottom right: r̂ against samples used.
    """
    check_output(path, "plot")
    x = np.asarray(cert.samples)
    xs = np.asarray(cert.x_star)
    if x.shape[1] != 3:
        raise ValueError("plot_certificate draws 3-D reduced states")
    masks = outcome_masks(cert)
    half = _zoom(cert)
    near = np.all(np.abs(x - xs) <= half, axis=1)
    fig = plt.figure(figsize=(17, 10))
    ax3 = fig.add_subplot(2, 3, 1, projection="3d")
    for name, m in masks.items():
        ax3.scatter(*x[m & near].T, s=8, c=COLORS[name], label=f"{name} ({int(m.sum())})", depthshade=False)
    u, v = np.mgrid[0:2 * np.pi:40j, 0:np.pi:20j]
    r = cert.r_star
    ax3.plot_wireframe(xs[0] + r * np.cos(u) * np.sin(v), xs[1] + r * np.sin(u) * np.sin(v),
                       xs[2] + r * np.cos(v), color="tab:blue", linewidth=0.4, alpha=0.6)
    for k, set_lim in enumerate((ax3.set_xlim, ax3.set_ylim, ax3.set_zlim)):
        set_lim(xs[k] - half, xs[k] + half)
    ax3.set_xlabel(LABELS[0])
    ax3.set_ylabel(LABELS[1])
    ax3.set_zlabel(LABELS[2])
    ax3.legend(loc="upper left", fontsize=8)
    t = np.linspace(0, 2 * np.pi, 200)
    for k, (i, j) in enumerate(((0, 1), (0, 2), (1, 2))):
        ax = fig.add_subplot(2, 3, k + 2 if k < 2 else 4)
        for name, m in masks.items():
            ax.scatter(x[m & near, i], x[m & near, j], s=8, c=COLORS[name], marker="x" if name == "fell" else "o")
        ax.plot(xs[i] + r * np.cos(t), xs[j] + r * np.sin(t), color="tab:blue", label=f"r* = {r:.3f}")
        ax.plot(xs[i] + cert.r_max * np.cos(t), xs[j] + cert.r_max * np.sin(t), color="0.6", ls="--",
                label=f"r_max = {cert.r_max:g}")
        ax.plot(xs[i], xs[j], "k+", ms=12)
        ax.set_xlim(xs[i] - half, xs[i] + half)
        ax.set_ylim(xs[j] - half, xs[j] + half)
        ax.set_xlabel(LABELS[i])
        ax.set_ylabel(LABELS[j])
        ax.set_aspect("equal")
        if k == 0:
            ax.legend(fontsize=8)
    _plot_rounds(cert, fig.add_subplot(2, 3, 5), fig.add_subplot(2, 3, 6))
    n = f"N = {cert.n_samples}" + (f" in {len(cert.rounds)} rounds" if len(cert.rounds) > 1 else "")
    fig.suptitle(title or f"DTBF certificate ({cert.method}): r* = {r:.4f}, {n}, α = {cert.alpha:g} "
                 f"({cert.n_inside} samples inside, {int(np.sum(cert.fell))} fell)")
    return _save(fig, path)


ROUND_COLORS = {"uniform": "tab:gray", "explore": "tab:purple", "verify": "tab:cyan"}


def _plot_rounds(cert: Certificate, ax_d: Axes, ax_r: Axes) -> None:
    """Distances by round (ax_d) and r̂ against samples used (ax_r)."""
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
        ax.step(used, r_hat, where="post", color="tab:blue", label="r̂ after each round")
        ax.axhline(cert.r_star, color="tab:blue", ls=":", lw=0.8)
        ax.set_yscale("log")
        ax.set_xlabel("samples used")
    for rd in cert.rounds:
        if rd.kind == "verify":
            ax_r.plot(rd.samples_used, rd.r_hat, "o" if rd.passed else "x", color="tab:green" if rd.passed
                      else "tab:red", ms=8, label=f"verification {'passed' if rd.passed else 'failed'}")
    ax_d.set_ylabel("‖x_i − x*‖ [rad/s] (colour: round kind)")
    ax_d.legend(fontsize=8, loc="upper right")
    ax_r.set_ylabel("r̂ [rad/s]")
    handles, labels = ax_r.get_legend_handles_labels()
    uniq = dict(zip(labels, handles, strict=True))
    ax_r.legend(uniq.values(), uniq.keys(), fontsize=8)
    ax_r.set_title(f"{cert.method}: r* = {cert.r_star:.4g}, bound {100 * cert.violation_bound:.3g}% at "
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
