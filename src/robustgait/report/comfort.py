"""What a passenger feels on the gaits of a study (``docs/comfort.md``): the certificate against speed and against the
pelvis acceleration, and one row of comfort figures per evaluated gait, for the study report."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

from robustgait.config import radius_name
from robustgait.report.figures import _save, plt
from robustgait.report.marks import labelled, plotted_figure
from robustgait.study.outcome import known_figure
from robustgait.study.status import figure_text

# the table's columns: (header, figure, scale, digits); the figures' units are robustgait.sim.comfort.FIGURES'
COLUMNS: tuple[tuple[str, str, float, int], ...] = (
    ("speed [m/s]", "speed", 1.0, 3),
    ("cadence [steps/min]", "cadence", 1.0, 1),
    ("pelvis acc. RMS vert. / lat. / fwd. [m/s²]", "pelvis_acc_*_rms", 1.0, 2),
    ("pelvis acc. peak vert. / lat. / fwd. [m/s²]", "pelvis_acc_*_peak", 1.0, 2),
    ("pelvis jerk RMS vert. / lat. / fwd. [m/s³]", "pelvis_jerk_*_rms", 1.0, 0),
    ("torque RMS / peak [N m]", "torque_rms/torque_peak", 1.0, 0),
    ("cost of transport", "cost_of_transport", 1.0, 3),
    ("impact [body weights]", "impact_force_ratio", 1.0, 2),
    ("touchdown speed [m/s]", "touchdown_speed", 1.0, 3),
    ("pelvis roll / pitch excursion [deg]", "pelvis_roll_excursion/pelvis_pitch_excursion", 180.0 / math.pi, 2),
)


def measured_trials(status: dict[str, Any]) -> list[dict[str, Any]]:
    """The evaluated gaits of a study (:func:`robustgait.study.status.study_status`) with comfort figures, each gait
    once (trials that reused an earlier evaluation left out)."""
    return [t for t in status["trials"] if t["state"] == "COMPLETE" and t["reused_from"] is None and t.get("comfort")]


def _cell(comfort: dict[str, Any], key: str, scale: float, digits: int) -> str:
    if "*" in key:
        keys = [key.replace("*", ax) for ax in ("vertical", "lateral", "forward")]
    else:
        keys = key.split("/")
    values = [comfort.get(k) for k in keys]
    return " / ".join("—" if v is None else f"{v * scale:.{digits}f}" for v in values)


def comfort_rows(status: dict[str, Any]) -> tuple[list[str], list[list[str]]]:
    """The header and one row per measured gait: trial, parameters, outcome, the certificate, then :data:`COLUMNS`."""
    name = radius_name(status["certificate"])
    unit = status.get("unit", "rad/s")
    header = ["trial", "params", "outcome", labelled(name, unit), *(c[0] for c in COLUMNS)]
    rows = []
    for t in measured_trials(status):
        c = t["comfort"]
        rows.append([str(t["number"]), ", ".join(f"{v:g}" for v in t["params"].values()), str(t["status"]),
                     figure_text(t, ""),
                     *(_cell(c, key, scale, digits) for _, key, scale, digits in COLUMNS)])
    return header, rows


def plot_comfort(status: dict[str, Any], path: str | Path) -> Path:
    """Two panels over the measured gaits: the certificate (J* or r*) against the forward speed, coloured by the
    vertical pelvis acceleration RMS; and against the vertical pelvis acceleration RMS, coloured by the cost of
    transport. Verified gaits are dots, gaits whose figure is only an estimate triangles at the estimate, the others
    (refused, fell) crosses at 0."""
    trials = measured_trials(status)
    name = radius_name(status["certificate"])
    unit = status.get("unit", "rad/s")
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(11, 4.2))
    for ax, x_key, c_key, x_label, c_label in (
            (a1, "speed", "pelvis_acc_vertical_rms", "forward speed [m/s]", "vertical pelvis acc. RMS [m/s²]"),
            (a2, "pelvis_acc_vertical_rms", "cost_of_transport", "vertical pelvis acceleration RMS [m/s²]",
             "cost of transport")):
        groups = (("o", "verified", lambda t: bool(t.get("verified"))),
                  ("^", "estimate, not verified", lambda t: not t.get("verified") and known_figure(t) is not None),
                  ("x", "no certificate (0)", lambda t: known_figure(t) is None))
        for marker, label, member in groups:
            pts = [t for t in trials if member(t)]
            if not pts:
                continue
            colors = [t["comfort"].get(c_key) for t in pts]
            sc = ax.scatter([t["comfort"][x_key] for t in pts], [plotted_figure(t) for t in pts],
                            c=[math.nan if v is None else v for v in colors], cmap="viridis", marker=marker, s=36,
                            label=label)
        if trials:
            fig.colorbar(sc, ax=ax, label=c_label)
            ax.legend(fontsize=8)
        ax.set_xlabel(x_label)
        ax.set_ylabel(labelled(name, unit))
    fig.suptitle(f"{name} and what the passenger feels ({len(trials)} gaits; steps measured after "
                 f"{status['config']['comfort']['skip_steps']} skipped)")
    return _save(fig, path)
