"""PD vs passivity-based tracking (issue 20, item 4): on the default exo gait, the Atalante FROST gait (if
``../shared/atalante`` is there) and any ``--gait FILE`` (e.g. the robustness study's best), for each controller:
tracking along the nominal orbit (a ``--steps`` walk: RMS and max of q − y_d, torque saturation), r* (sequential,
the default certificate, ``--seeds`` seeds) and every validation kind (``--trials`` trials each, the same draws for
both controllers: success with its 95 % Wilson interval and the logistic s₅₀ ± s.e.).

One task per (gait, controller) in ``--workers`` processes (one rollout thread each); a JSON line per task in
``--out`` (a task already there is not run again: a killed run continues); ``--report`` prints the tables.

    python benchmarks/experiments/controllers/run.py [--gait FILE ...] [--seeds 5] [--trials 60] [--kinds all] \\
        [--steps 20]
        [--workers 2] [--out FILE.jsonl] [--report]
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from concurrent.futures import ProcessPoolExecutor, as_completed
from datetime import date
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))  # benchmarks/common.py
from common import ATALANTE_SPEC, SHARED, git_commit

ATALANTE = SHARED / "atalante"
CONTROLLERS = ("pd", "passivity")


def gait_cases(extra: list[str]) -> list[dict[str, str]]:
    out = [{"name": "exo default", "robot": "exo", "gait": ""}]
    if (ATALANTE / "loadedExo.xml").is_file():
        out.append({"name": "Atalante FROST", "robot": str(ATALANTE_SPEC),
                    "gait": str(ATALANTE / "jt_bez_2023-09-10.yaml")})
    else:
        print("../shared/atalante is missing: the Atalante gait is skipped")
    out += [{"name": Path(g).parent.name or Path(g).stem, "robot": "exo", "gait": str(Path(g).resolve())}
            for g in extra]
    return out


def one(task: dict[str, Any]) -> dict[str, Any]:
    """Tracking, r* over seeds and every validation kind of one gait under one controller (or the one-line error
    that stopped it, e.g. a spec without passivity gains)."""
    from robustgait.errors import RobustGaitError

    try:
        return measure(task)
    except RobustGaitError as e:
        return {"name": task["name"], "controller": task["controller"], "error": str(e)}


def measure(task: dict[str, Any]) -> dict[str, Any]:
    from robustgait import load_gait, load_robot, walk
    from robustgait.certificate.certify import certify_gait
    from robustgait.config import KINDS, CertifyConfig, GaitParams, SimConfig, ValidateConfig
    from robustgait.gaitgen import generate_gait
    from robustgait.validate import validate_gait

    robot = load_robot(task["robot"])
    if task["gait"]:
        gait = load_gait(task["gait"], robot)
    else:
        res = generate_gait(robot, GaitParams().resolved("flat"))
        assert res.gait is not None, res.reason
        gait = res.gait
    sim = SimConfig(controller=task["controller"], n_threads=1)
    out: dict[str, Any] = {k: task[k] for k in ("name", "controller")}
    t0 = time.perf_counter()
    w = walk(robot, gait, sim, steps=task["steps"])
    out["walk"] = {"steps": w.steps_taken, "fall": w.fall_reason, "speed": w.mean_speed, "tracking": w.tracking,
                   "seconds": time.perf_counter() - t0, "note": w.controller_note}
    gcs = [certify_gait(robot, gait, CertifyConfig(disturbance="state", seed=seed), sim)
           for seed in range(max(task["seeds"], 1))]
    out["certify"] = [{"r_star": gc.value, "status": gc.status, "seconds": gc.seconds["total"]} for gc in gcs]
    cert = gcs[0]  # seed 0: the certificate the validation checks
    kinds = list(KINDS) if task["kinds"] == "all" else task["kinds"].split(",")
    t1 = time.perf_counter()
    v = validate_gait(robot, gait, ValidateConfig(trials=task["trials"], seed=0), sim=sim, kinds=kinds,
                      certificate=cert)
    out["validate"] = {}
    for k, kr in v.kinds.items():
        rate, fit = kr.success_rate(), kr.critical()
        out["validate"][k] = {"n": rate.n, "k": rate.k, "rate": rate.rate, "low": rate.low, "high": rate.high,
                              "s50": fit.s50, "s50_se": fit.s50_se, "unit": kr.size_label[1]}
    out["seconds_validate"] = time.perf_counter() - t1
    out["seconds"] = time.perf_counter() - t0
    return out


def run(args: argparse.Namespace) -> None:
    from robustgait.study.executors import blas_threads

    done = set()
    if args.out.exists():
        done = {(r["name"], r["controller"]) for r in map(json.loads, args.out.read_text().splitlines())}
    tasks = [{**g, "controller": c, "seeds": args.seeds, "trials": args.trials, "kinds": args.kinds,
              "steps": args.steps} for g in gait_cases(args.gait) for c in CONTROLLERS
             if (g["name"], c) not in done]
    print(f"{len(tasks)} tasks ({len(done)} already in {args.out}); {args.workers} workers; load "
          f"{os.getloadavg()[0]:.1f}", flush=True)
    t0 = time.perf_counter()
    with blas_threads(1), ProcessPoolExecutor(args.workers) as pool, args.out.open("a") as f:
        futures = [pool.submit(one, t) for t in tasks]
        for fut in as_completed(futures):
            r = fut.result()
            f.write(json.dumps(r, allow_nan=False) + "\n")
            f.flush()
            print(f"[{time.perf_counter() - t0:.0f} s] {r['name']} / {r['controller']}: "
                  + (f"ERROR {r['error']}" if "error" in r else f"{r['seconds']:.0f} s"), flush=True)


def fmt_s50(v: dict[str, Any], kind: str) -> str:
    if v["s50"] is None:
        return "—"
    scale, unit = {"latency": (1e3, "ms"), "noise": (1e3, "mrad"), "terrain": (1e3, "mm")}.get(
        kind, (1.0, "" if v["unit"] == "1" else v["unit"]))
    se = f" ± {v['s50_se'] * scale:.3g}" if v["s50_se"] is not None else ""
    return f"{v['s50'] * scale:.3g}{se} {unit}".strip()


def report(path: Path) -> None:
    import numpy as np

    rows = [json.loads(line) for line in path.read_text().splitlines() if line.strip()]
    for r in rows:
        if "error" in r:
            print(f"{r['name']} / {r['controller']}: not measured — {r['error']}")
    rows = [r for r in rows if "error" not in r]
    commit = git_commit()
    print(f"{len(rows)} (gait, controller) results from {path} (report {date.today()}, commit {commit})\n")
    print("| gait | controller | walk | tracking RMS / max [mrad] | saturation (fraction) | r* mean ± sd (seeds) "
          "| certificate wall [s] |")
    print("|---|---|---|---|---|---|---|")
    for r in rows:
        w, c = {**r["walk"], **r["walk"]["tracking"], "steps": r["walk"]["steps"]}, r["certify"]
        rs = np.array([x["r_star"] for x in c])
        print(f"| {r['name']} | {r['controller']} | {w['steps']} steps{'' if w['fall'] is None else ' ' + w['fall']} "
              f"| {w.get('rms', 0) * 1e3:.3g} / {w.get('max', 0) * 1e3:.3g} | {w.get('saturation', 0)} "
              f"({w.get('saturation_fraction', 0):.2%}) | {rs.mean():.4f} ± {rs.std(ddof=1) if rs.size > 1 else 0:.4f}"
              f" ({rs.size}) | {np.mean([x['seconds'] for x in c]):.0f} |")
    kinds = sorted({k for r in rows for k in r["validate"]})
    print("\n| gait | controller | " + " | ".join(f"{k}: success [95 %], s₅₀" for k in kinds) + " |")
    print("|---|---|" + "---|" * len(kinds))
    for r in rows:
        cells = []
        for k in kinds:
            v = r["validate"].get(k)
            if v is None:
                cells.append("")
                continue
            cells.append(f"{v['k']}/{v['n']} [{v['low']:.2f}, {v['high']:.2f}], {fmt_s50(v, k)}")
        print(f"| {r['name']} | {r['controller']} | " + " | ".join(cells) + " |")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--gait", action="append", default=[], help="another exo gait file (repeatable)")
    ap.add_argument("--seeds", type=int, default=5)
    ap.add_argument("--trials", type=int, default=60)
    ap.add_argument("--kinds", default="all")
    ap.add_argument("--steps", type=int, default=20)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--out", type=Path, default=Path("controllers.jsonl"))
    ap.add_argument("--report", action="store_true")
    args = ap.parse_args()
    if args.report:
        report(args.out)
    else:
        run(args)


if __name__ == "__main__":
    main()
