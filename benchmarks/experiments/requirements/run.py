"""Constraints and trade-offs without a person (issue 29, item 4): the default exo study ranked by J* (10 × 5, polar,
seed 0), unconstrained and with ``--require speed>=0.2``; per study its wall time, the recommendation's parameters, J*,
speed and comfort figures, how many evaluated gaits met the requirement, and its Pareto front (J*, speed, vertical
pelvis acceleration RMS). Studies in ``--out`` (resumed when they exist).

    python benchmarks/experiments/requirements/run.py [--out DIR] [--require speed>=0.2] [--workers 2] [--only \\
        unconstrained|required]
"""

from __future__ import annotations

import argparse
import json
import os
import time
from pathlib import Path

from robustgait.config import Config, RunConfig, StudyConfig
from robustgait.study.outcome import known_figure
from robustgait.study.pareto import pareto
from robustgait.study.run import create_study, run_study
from robustgait.study.status import study_status

FIGURES = ("speed", "pelvis_acc_vertical_rms", "pelvis_acc_lateral_rms", "impact_force_ratio", "cost_of_transport")


def one(d: Path, require: tuple[str, ...], workers: int) -> dict:  # type: ignore[type-arg]
    if not (d / "study.json").exists():
        create_study(d, "exo", Config(study=StudyConfig(require=require)))
    load0, t0 = os.getloadavg()[0], time.perf_counter()
    run_study(d, RunConfig(workers=workers), progress=False)
    wall = time.perf_counter() - t0
    st = study_status(d)
    best = st["best"]
    import optuna

    trials = optuna.load_study(study_name="robustgait", storage=f"sqlite:///{d / 'study.db'}").get_trials()
    span = (max(t.datetime_complete for t in trials if t.datetime_complete) -
            min(t.datetime_start for t in trials if t.datetime_start)).total_seconds()
    done = [t for t in st["trials"] if t["state"] == "COMPLETE" and t["reused_from"] is None]
    meets = [t for t in done if t["score"] is not None and t["score"] > -1e6]
    front = pareto(st, "pelvis_acc_vertical_rms")
    return {"directory": str(d), "require": list(require), "wall": wall, "first_start_to_last_complete": span,
            "load": [load0, os.getloadavg()[0]],
            "unique": len(done), "meet_requirements": len(meets),
            "certified": sum(t["status"] == "certified" for t in done),
            "best": {"params": best["params"], "r_star": known_figure(best),
                     "comfort": {k: (best["comfort"] or {}).get(k) for k in FIGURES}},
            "front": [{"params": r["params"], "r_star": known_figure(r), "speed": r["speed"],
                       "pelvis_acc_vertical_rms": r["pelvis_acc_vertical_rms"]} for r in front["front"]]}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", default=str(Path(__file__).parent / "data" / "studies"))
    ap.add_argument("--require", default="speed>=0.2")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--only", choices=("unconstrained", "required"), default=None, help="run one of the two studies")
    args = ap.parse_args()
    out = Path(args.out)
    studies = {"unconstrained": (), "required": (args.require,)}
    res = [one(out / name, req, args.workers) for name, req in studies.items() if args.only in (None, name)]
    print(json.dumps(res, indent=1))


if __name__ == "__main__":
    main()
