"""Trade-offs without a person (``robustgait study pareto DIR``, docs/studies.md): the study's gaits that no other gait
beats on every one of three objectives — the certificate (J* or r*, higher is better), the walking speed (higher) and a
comfort figure (``report.pareto_figure``, lower is better: an acceleration, a jerk, a torque, the cost of transport,
an impact). Over the certified gaits (each unique gait once); a gait without the comfort figure is left out."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from robustgait.errors import RobustGaitError
from robustgait.sim.comfort import FIGURES

HIGHER_IS_BETTER = ("speed", "step_length", "cadence")  # not a cost: refused as the comfort objective


def non_dominated(objectives: NDArray[np.float64]) -> NDArray[np.bool_]:
    """Rows (n, m) of objectives, all to be maximized: True where no other row is ≥ in every objective and > in one."""
    x = np.asarray(objectives, dtype=float)
    keep = np.ones(len(x), dtype=bool)
    for i in range(len(x)):
        dominated = np.all(x >= x[i], axis=1) & np.any(x > x[i], axis=1)
        keep[i] = not dominated.any()
    return keep


def pareto(status: dict[str, Any], figure: str) -> dict[str, Any]:
    """From :func:`robustgait.study.status.study_status`: every certified or estimated unique gait with its
    certificate, speed and ``figure``, whether it is on the front, sorted by the certificate (descending): per gait
    ``trial``, ``grid_index``, ``params``, ``certificate_value`` (in ``certificate_unit``: the verified value, else the
    estimate), ``verified``, ``speed``, ``figure``, ``gait_file``, ``front``."""
    if figure not in FIGURES or figure in HIGHER_IS_BETTER:
        costs = ", ".join(n for n in FIGURES if n not in HIGHER_IS_BETTER)
        raise RobustGaitError(f"report.pareto_figure: {figure!r} is not a comfort cost (one of {costs})")
    seen: set[int] = set()
    rows = []
    for t in status["trials"]:
        if t["state"] != "COMPLETE" or t["status"] not in ("certified", "estimated") or t["grid_index"] in seen:
            continue
        c = t.get("comfort") or {}
        if c.get(figure) is None or c.get("speed") is None:
            continue
        seen.add(t["grid_index"])
        verified = bool(t.get("verified"))
        value = t["verified_value"] if verified else t.get("estimate", t["certificate_value"])
        rows.append({"trial": t["number"], "grid_index": t["grid_index"], "params": t["params"],
                     "certificate_value": value, "verified": verified, "speed": c["speed"],
                     figure: c[figure], "gait_file": t["gait_file"]})
    obj = np.array([[r["certificate_value"], r["speed"], -r[figure]] for r in rows]).reshape(-1, 3)
    front = non_dominated(obj) if rows else np.zeros(0, dtype=bool)
    for r, f in zip(rows, front, strict=True):
        r["front"] = bool(f)
    rows.sort(key=lambda r: -r["certificate_value"])
    return {"figure": figure, "unit": FIGURES[figure][0], "certificate_unit": status["unit"],
            "certificate": status["certificate"], "gaits": rows, "front": [r for r in rows if r["front"]]}


def study_pareto(directory: str | Path, figure: str, *, verify: bool = True, progress: bool = True
                 ) -> dict[str, Any]:
    """:func:`pareto` of the study in ``directory``. ``verify``: the front is of verified values — each gait on it
    whose certificate is an estimate is verified first (:func:`~robustgait.study.verify.verify_now`, stored in the
    study), and the front made again, until every gait on it is verified (a verified value is at most the estimate,
    so each round can only bring other gaits onto the front)."""
    from robustgait.study.status import study_status
    from robustgait.study.verify import verify_now

    while True:
        res = pareto(study_status(directory), figure)
        todo = [r["grid_index"] for r in res["front"] if not r["verified"]]
        if not verify or not todo or not verify_now(Path(directory), todo, progress=progress):
            return res
