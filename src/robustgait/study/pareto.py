"""Trade-offs without a person (``robustgait study pareto DIR``, docs/studies.md): the study's gaits that no other gait
beats on every one of three objectives — the certificate (J* or r*, higher is better), the walking speed (higher) and a
comfort figure (``report.pareto_figure``, lower is better: an acceleration, a jerk, a torque, the cost of transport,
an impact). Over the certified gaits (each unique gait once); a gait without the comfort figure is left out."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from robustgait.sim.comfort import FIGURES
from robustgait.study.front import front_rows


def pareto(status: dict[str, Any], figure: str) -> dict[str, Any]:
    """From :func:`robustgait.study.status.study_status`: every certified or estimated unique gait with its
    certificate, speed and ``figure``, whether it is on the front, sorted by the certificate (descending): per gait
    ``trial``, ``grid_index``, ``params``, ``status``, ``value`` (in ``certificate_unit``; None unless ``verified``),
    ``estimate``, ``verified``, ``speed``, ``figure``, ``gait_file``, ``front``."""
    rows = front_rows(status["trials"], figure)
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
