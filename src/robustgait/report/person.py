"""The parts of a study report about what a person wants (docs/person.md): the answers of a person study (every batch's
ranking and labels, the floor that kept gaits from being shown, the recommendation with its certificate and comfort
figures) and, for any study, the trade-off front over the certificate, the speed and a comfort figure
(:mod:`robustgait.study.pareto`)."""

from __future__ import annotations

import html
import time
from pathlib import Path
from typing import Any

from robustgait.config import radius_name
from robustgait.report.figures import _save, plt
from robustgait.report.marks import labelled, plotted_figure
from robustgait.sim.comfort import FIGURES
from robustgait.study.pareto import pareto
from robustgait.study.status import figure_text
from robustgait.study.verify import params_label


def _params(p: dict[str, float]) -> str:
    return ", ".join(f"{v:g}" for v in p.values())


def plot_pareto(front: dict[str, Any], path: Path) -> Path:
    """Certificate against speed, coloured by the comfort figure (dots verified, triangles estimates); the
    non-dominated gaits circled."""
    rows = front["gaits"]
    fig, ax = plt.subplots(figsize=(6.5, 4.5))
    color = [r[front["figure"]] for r in rows]
    lo, hi = min(color, default=0.0), max(color, default=1.0)
    sc = None
    for marker, label, verified in (("o", "verified", True), ("^", "estimate, not verified", False)):
        pts = [r for r in rows if bool(r["verified"]) == verified]
        if pts:
            sc = ax.scatter([r["speed"] for r in pts], [plotted_figure(r) for r in pts], marker=marker, label=label,
                            c=[r[front["figure"]] for r in pts], cmap="viridis_r", vmin=lo, vmax=hi, s=30)
    if sc is not None:
        fig.colorbar(sc, ax=ax, label=labelled(front["figure"].replace("_", " "), front["unit"]))
    on = [r for r in rows if r["front"]]
    ax.scatter([r["speed"] for r in on], [plotted_figure(r) for r in on], s=140, facecolors="none",
               edgecolors="tab:red", label=f"non-dominated ({len(on)})")
    name = radius_name(front["certificate"])
    ax.set_xlabel("speed [m/s]")
    ax.set_ylabel(labelled(name, front["certificate_unit"]))
    ax.set_title(f"Trade-offs: {name} ↑, speed ↑, {front['figure'].replace('_', ' ')} ↓", fontsize=10)
    ax.legend(fontsize=8)
    return _save(fig, path)


def pareto_table(front: dict[str, Any]) -> tuple[list[str], list[list[str]]]:
    name = radius_name(front["certificate"])
    header = ["trial", "gait (L, T, W, h)", labelled(name, front["certificate_unit"]), "speed [m/s]",
              labelled(front["figure"], front["unit"])]
    return header, [[str(r["trial"]), _params(r["params"]), figure_text(r, "", 4), f"{r['speed']:.3f}",
                     f"{r[front['figure']]:.3g}"] for r in front["front"]]


def pareto_parts(status: dict[str, Any], out: Path, figure: str, table: Any, img: Any) -> list[str]:
    front = pareto(status, figure)
    if not front["gaits"]:
        return []
    header, rows = pareto_table(front)
    return [f"<h2>Trade-offs: the non-dominated gaits</h2>{img(plot_pareto(front, out / 'pareto.png'))}"
            f"<p>{len(front['front'])} of {len(front['gaits'])} certified gaits are not beaten on all three of "
            f"{radius_name(front['certificate'])}, speed and {html.escape(figure)} (robustgait study pareto).</p>"
            + table(rows, header)]


def answer_rows(status: dict[str, Any]) -> list[list[str]]:
    """One row per answered batch: the ranking (gaits by their page names A, B, …, with parameters), labels, what
    was not shown and why, who answered and when."""
    by_number = {t["number"]: t for t in status["trials"]}
    rows = []
    for a in status["person"]["answers"]:
        it = status["iterations"][a["iteration"]]
        batch = [by_number[n] for n in it["trials"]]
        tiers: dict[int, list[str]] = {}
        for slot, rank in enumerate(a["ranks"]):
            if rank is not None:
                tiers.setdefault(rank, []).append(f"{chr(65 + slot)} ({_params(batch[slot]['params'])})")
        ranking = " ≻ ".join(" = ".join(t) for _, t in sorted(tiers.items())) or "—"
        labels = ", ".join(f"{chr(65 + s)}: {lab}" for s, lab in enumerate(a.get("labels") or []) if lab)
        hidden = sum(r is None for r in a["ranks"])
        when = time.strftime("%Y-%m-%d %H:%M:%S", time.localtime(a["answered_at"])) if a.get("answered_at") else ""
        rows.append([str(a["iteration"] + 1), html.escape(ranking), html.escape(labels or "—"), str(hidden),
                     html.escape(str(a.get("by"))), when])
    return rows


def person_parts(status: dict[str, Any], table: Any) -> list[str]:
    """The person section: floor, every answer, the recommendation with its certificate and comfort figures."""
    p = status.get("person")
    if not p:
        return []
    name, unit = radius_name(status["certificate"]), status["unit"]
    floor = p.get("floor") or {}
    ref = floor.get("reference")
    of_ref = "" if not ref else (f": {floor.get('fraction')} × the reference gait's "
                                 f"{figure_text(ref, unit) if ref.get('verified') else 'value 0 (not certified)'}"
                                 + (f" ({params_label(ref['params'])})" if ref.get("params") else ""))
    text = (f"<h2>The person's answers</h2><p>Shown: gaits certified at or above the floor {name} ≥ "
            f"{floor.get('value', 0):.4g} {unit} ({html.escape(str(floor.get('source')))}{of_ref})"
            + (f" meeting {html.escape(', '.join(status['require']))}" if status["require"] else "")
            + "; the others ranked below every shown gait without asking."
            + (f" Batch {p['pending'] + 1} waits for an answer." if p["pending"] is not None else "") + "</p>")
    parts = [text + table(answer_rows(status), ["batch", "ranking (best first; = cannot tell)", "labels",
                                                "not shown", "by", "answered"])]
    best = status.get("best")
    if best is not None:
        c = best.get("comfort") or {}
        rows = [[labelled(name, unit), figure_text(best, "")]] + [
            [labelled(n, FIGURES[n][0]), "—" if c.get(n) is None else f"{c[n]:.4g}"] for n in FIGURES if n in c]
        parts.append(f"<h3>The recommendation: {_params(best['params'])} (trial {best['trial']})</h3>"
                     + table(rows, ["figure", "value"]))
    return parts
