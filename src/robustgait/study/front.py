"""The trade-off front of a study's gaits (docs/studies.md): the gaits that no other gait beats on every one of three
objectives — the certificate (higher is better), the walking speed (higher) and a comfort cost (lower) —, over trials as
``study status`` lists them. Pure: read by ``study pareto`` and by the run that verifies the front."""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from robustgait.errors import RobustGaitError
from robustgait.sim.comfort import FIGURES
from robustgait.study.outcome import known_figure

HIGHER_IS_BETTER = ("speed", "step_length", "cadence")  # not a cost: refused as the comfort objective


def non_dominated(objectives: NDArray[np.float64]) -> NDArray[np.bool_]:
    """Rows (n, m) of objectives, all to be maximized: True where no other row is ≥ in every objective and > in one."""
    x = np.asarray(objectives, dtype=float)
    keep = np.ones(len(x), dtype=bool)
    for i in range(len(x)):
        dominated = np.all(x >= x[i], axis=1) & np.any(x > x[i], axis=1)
        keep[i] = not dominated.any()
    return keep


def front_rows(trials: list[dict[str, Any]], figure: str) -> list[dict[str, Any]]:
    """The rows of :func:`pareto` from trials as ``study status`` lists them
    (:func:`~robustgait.study.trials.trial_summary`) that have a certificate figure
    (:func:`~robustgait.study.outcome.known_figure`), each marked ``front`` or not."""
    if figure not in FIGURES or figure in HIGHER_IS_BETTER:
        costs = ", ".join(n for n in FIGURES if n not in HIGHER_IS_BETTER)
        raise RobustGaitError(f"report.pareto_figure: {figure!r} is not a comfort cost (one of {costs})")
    seen: set[int] = set()
    rows = []
    for t in trials:
        if t["state"] != "COMPLETE" or known_figure(t) is None or t["grid_index"] in seen:
            continue
        c = t.get("comfort") or {}
        if c.get(figure) is None or c.get("speed") is None:
            continue
        seen.add(t["grid_index"])
        rows.append({"trial": t["number"], "grid_index": t["grid_index"], "params": t["params"], "status": t["status"],
                     "value": t["value"], "estimate": t["estimate"], "verified": bool(t.get("verified")),
                     "speed": c["speed"], figure: c[figure], "gait_file": t["gait_file"]})
    obj = np.array([[known_figure(r), r["speed"], -r[figure]] for r in rows], dtype=float).reshape(-1, 3)
    front = non_dominated(obj) if rows else np.zeros(0, dtype=bool)
    for r, f in zip(rows, front, strict=True):
        r["front"] = bool(f)
    rows.sort(key=lambda r: -float(known_figure(r) or 0.0))
    return rows
