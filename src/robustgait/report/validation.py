"""Figures of a validation: success against disturbance size and the certificate check per kind (one gait);
success against r* and steps taken (the gaits of a study)."""

from __future__ import annotations

import textwrap
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from matplotlib.cm import ScalarMappable
from matplotlib.colors import Normalize
from scipy.special import expit

from robustgait.config import R_MAX_UNIT, CertifyConfig, radius_name
from robustgait.report.figures import _save, plt
from robustgait.study.outcome import EvaluationStatus
from robustgait.validate.stats import binned_rates, correlation_text

if TYPE_CHECKING:
    from robustgait.validate import ValidationResult


def plot_validation(result: ValidationResult, path: str | Path, *, title: str = "") -> Path:
    """One row per disturbance kind. Left: success rate in size bins (Wilson 95 % intervals), the logistic
    fit and the size at which half fail. Right: distance of the first post-disturbance reduced state to x̄*
    against the size, by outcome, with r*. Writes ``path`` (PNG/PDF/SVG by extension)."""
    kinds = list(result.kinds.values())
    fig, axes = plt.subplots(len(kinds), 2, figsize=(11, 3.4 * len(kinds)), squeeze=False)
    ref = result.certificate
    radius, cunit = ref.value, R_MAX_UNIT[ref.space]
    star = radius_name(ref.space)
    for row, kr in zip(axes, kinds, strict=True):
        name, unit = kr.size_label
        a1, a2 = row
        bins = binned_rates(kr.size, kr.success)
        mid = np.array([(b["size_low"] + b["size_high"]) / 2 for b in bins])
        rate = np.array([np.nan if b["rate"] is None else b["rate"] for b in bins])
        lo = np.array([b["low"] for b in bins])
        hi = np.array([b["high"] for b in bins])
        yerr = np.maximum(0.0, np.nan_to_num([rate - lo, hi - rate]))  # rounding: lo may exceed a rate of 0
        a1.errorbar(mid, rate, yerr=yerr, fmt="o", capsize=3,
                    label="binned (95 % Wilson)")
        fit = kr.critical()
        if np.isfinite(fit.a) and np.isfinite(fit.b):
            s = np.linspace(kr.size.min(), kr.size.max(), 200)
            a1.plot(s, expit(fit.a + fit.b * s), color="tab:blue", lw=1, label="logistic fit")
        if fit.s50 is not None and fit.in_range:
            a1.axvline(fit.s50, color="tab:red", ls="--", lw=1, label=f"half fail: {fit.s50:.3g} {unit}")
        sr = kr.success_rate()
        a1.set_ylim(-0.05, 1.05)
        a1.set_xlabel(f"{name} [{unit}]")
        a1.set_ylabel("success")
        a1.set_title(f"{kr.kind}: success {sr.k}/{sr.n} = {sr.rate:.2f} [{sr.low:.2f}, {sr.high:.2f}]", fontsize=10)
        a1.legend(fontsize=7)
        reached = np.isfinite(kr.distance)
        for ok, color, label in ((True, "tab:green", "walked"), (False, "tab:red", "fell")):
            m = reached & (kr.success == ok)
            a2.scatter(kr.size[m], kr.distance[m], s=8, c=color, label=f"{label} ({int(m.sum())})")
        a2.axhline(radius, color="tab:blue", lw=1, label=f"{star} = {radius:.3g} {cunit}")
        chk = kr.certificate_check()
        inside = chk["inside"]
        n_in = getattr(inside, "n", 0)
        k_in = getattr(inside, "k", 0)
        a2.set_yscale("log")
        a2.set_xlabel(f"{name} [{unit}]")
        a2.set_ylabel("impulse |J| [N s]" if ref.space == "push" else f"‖z₁ − z*‖ ({ref.space} {ref.set}) [{cunit}]")
        inside_what = "|J| ≤ J*" if ref.space == "push" else "inside the set"
        a2.set_title(f"{inside_what}: {k_in}/{n_in} fell; {chk['fell_before_event']} fell before the event",
                     fontsize=10)
        a2.legend(fontsize=7)
    fig.suptitle(title or f"{result.robot}: validation ({result.config.trials} trials per kind, seed "
                 f"{result.config.seed}, {result.config.steps_after} steps after)")
    fig.tight_layout(rect=(0.0, 0.0, 1.0, 1.0 - 0.35 / fig.get_figheight()))  # room for the title
    return _save(fig, path)


_STUDY_MARKERS = {EvaluationStatus.CERTIFIED.value: "o", EvaluationStatus.NOT_CERTIFIED.value: "s",
                  EvaluationStatus.FELL.value: "X"}


def plot_study_validation(summary: dict[str, Any], path: str | Path) -> Path:
    """A study's gaits under one disturbance kind (a summary of :func:`robustgait.study.validate.validate_study`):
    the success rate (y, 95 % Wilson error bars) against r* (left) and against the steps taken in the study
    (right), each titled with its Spearman ρ, p and n; colour = steps taken (the cap's colour: walked it),
    marker = the study's outcome (○ certified: trials from its fixed point; ■ not certified, ✕ fell: trials
    from the gait's initial state)."""
    rows = summary["gaits"]
    kind, cap = summary["kind"], summary["study"]["step_cap"]
    fig, axes = plt.subplots(1, 2, figsize=(11.5, 4.4))
    rate = np.array([r["success"]["rate"] for r in rows], dtype=float)
    err = np.maximum(0.0, np.array([[r["success"]["rate"] - r["success"]["low"] for r in rows],
                                    [r["success"]["high"] - r["success"]["rate"] for r in rows]], dtype=float))
    steps = np.array([r["steps_taken"] for r in rows], dtype=float)
    norm = Normalize(vmin=0.0, vmax=float(cap))
    cmap = plt.get_cmap("viridis")
    cert = CertifyConfig(**{k: v for k, v in summary["certify"].items() if k in ("state", "disturbance")})
    star = radius_name(cert.space)
    panels = ((axes[0], "value", f"{star} ({cert.space}) [{cert.unit}]"),
              (axes[1], "steps_taken", f"steps taken in the study (cap {cap})"))
    for ax, key, label in panels:
        x = np.array([r[key] for r in rows], dtype=float)
        if rows:
            ax.errorbar(x, rate, yerr=err.reshape(2, -1), fmt="none", ecolor="0.55", elinewidth=1, capsize=3, zorder=1)
        for status, marker in _STUDY_MARKERS.items():
            m = np.array([r["status"] == status for r in rows], dtype=bool)
            if m.any():
                ax.scatter(x[m], rate[m], c=steps[m], cmap=cmap, norm=norm, marker=marker, s=55, edgecolors="k",
                           linewidths=0.6, zorder=2, label=status.replace("_", " "))
        ax.set_ylim(-0.05, 1.05)
        if key == "steps_taken":
            ax.set_xlim(-0.04 * cap, 1.04 * cap)
        ax.set_xlabel(label)
        ax.set_ylabel(f"{kind} success (95 % Wilson)")
        ax.set_title(textwrap.fill(correlation_text(summary["correlations"][key], names=False), 58), fontsize=9)
        if rows:
            ax.legend(fontsize=7, loc="best", title="study outcome", title_fontsize=7)
        else:
            ax.text(0.5, 0.5, "no validated gait", ha="center", va="center", transform=ax.transAxes)
    fig.colorbar(ScalarMappable(norm=norm, cmap=cmap), ax=list(axes), label="steps taken in the study", shrink=0.9)
    cfg = summary["config"]
    skipped = sum(summary["skipped_counts"].values())
    fig.suptitle(f"{kind}: {summary['n_validated']} gaits of the study under the same {cfg['trials']} disturbances "
                 f"(seed {cfg['seed']}, {cfg['steps_after']} steps after)"
                 + (f"; {skipped} skipped" if skipped else ""), fontsize=10, y=1.04)  # above two-line titles
    return _save(fig, path)
