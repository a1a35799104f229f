"""Figures: the certified invariant set (paper Fig. 4) and the barrier along a walk or a log (Fig. 5)."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")  # files only; no display on the machines this runs on

import matplotlib.pyplot as plt
import numpy as np
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


def plot_certificate(cert: Certificate, path: str | Path, *, title: str = "") -> Path:
    """Samples in the 3-D reduced space coloured by outcome at r*, the r* sphere, and the three 2-D
    projections (circles of radius r* around x*). Writes ``path`` (PNG/PDF/SVG by extension)."""
    check_output(path, "plot")
    x = np.asarray(cert.samples)
    xs = np.asarray(cert.x_star)
    if x.shape[1] != 3:
        raise ValueError("plot_certificate draws 3-D reduced states")
    masks = outcome_masks(cert)
    fig = plt.figure(figsize=(12, 9))
    ax3 = fig.add_subplot(2, 2, 1, projection="3d")
    for name, m in masks.items():
        ax3.scatter(*x[m].T, s=8, c=COLORS[name], label=f"{name} ({int(m.sum())})", depthshade=False)
    u, v = np.mgrid[0:2 * np.pi:40j, 0:np.pi:20j]
    r = cert.r_star
    ax3.plot_wireframe(xs[0] + r * np.cos(u) * np.sin(v), xs[1] + r * np.sin(u) * np.sin(v),
                       xs[2] + r * np.cos(v), color="tab:blue", linewidth=0.4, alpha=0.6)
    ax3.set_xlabel(LABELS[0])
    ax3.set_ylabel(LABELS[1])
    ax3.set_zlabel(LABELS[2])
    ax3.legend(loc="upper left", fontsize=8)
    t = np.linspace(0, 2 * np.pi, 200)
    for k, (i, j) in enumerate(((0, 1), (0, 2), (1, 2))):
        ax = fig.add_subplot(2, 2, k + 2)
        for name, m in masks.items():
            ax.scatter(x[m, i], x[m, j], s=8, c=COLORS[name], marker="x" if name == "fell" else "o")
        ax.plot(xs[i] + r * np.cos(t), xs[j] + r * np.sin(t), color="tab:blue", label=f"r* = {r:.3f}")
        ax.plot(xs[i] + cert.r_max * np.cos(t), xs[j] + cert.r_max * np.sin(t), color="0.6", ls="--",
                label=f"r_max = {cert.r_max:g}")
        ax.plot(xs[i], xs[j], "k+", ms=12)
        ax.set_xlabel(LABELS[i])
        ax.set_ylabel(LABELS[j])
        ax.set_aspect("equal")
        if k == 0:
            ax.legend(fontsize=8)
    fig.suptitle(title or f"DTBF certificate: r* = {r:.4f}, N = {cert.n_samples}, α = {cert.alpha:g} "
                 f"({cert.n_inside} samples inside, {int(np.sum(cert.fell))} fell)")
    return _save(fig, path)


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
