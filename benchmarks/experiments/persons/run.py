"""Simulated persons in the loop (issue 29, item 3), as CoSpar and ROIAL evaluate their learners: for ``--persons``
simulated persons (``person.simulated.seed`` 0, 1, …) and each of ``--learners``, a study of exo ranked by the person
(``--metric simulated-person``, 10 × 5, learner seed 0, the default certificate, the default floor), then per study:

* the utility regret of the recommended gait: the person's utility of the best gait certified at or above the floor
  among the gaits whose evaluation is known (the whole grid when ``benchmarks/experiments/persons/cache.py
  grid`` and the certificates have
  covered it; the coverage is printed) minus that of the recommendation, and the rank the recommendation reaches
  among them (1: the best);
* how many gaits shown to the person were below the floor (goal 0);
* what a study ranked by J* alone recommended (``--jstar-study``, the default push study with the same evaluation
  configuration, e.g. ``benchmarks/experiments/requirements/run.py``'s unconstrained one), scored by the same person.

Evaluations come from a cache shared by every study (``benchmarks/experiments/persons/cache.py``: an evaluation
is a function of (robot,
parameters, configuration)), so a gait is evaluated once however many persons' studies visit it; the cost of what was
computed is printed. Results per study are appended to ``--out``/results.jsonl as they come (a killed run resumes).

    python benchmarks/experiments/persons/run.py --cache DIR [--persons 20] [--learners polar,eubo,random]
        [--jstar-study DIR] [--out DIR]
"""

from __future__ import annotations

import argparse
import json
import math
import os
import time
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
from cache import CachedExecutor, EvaluationCache

from robustgait.config import Config, SimulatedPersonConfig, StudyConfig, to_dict
from robustgait.learn.person import SimulatedPerson
from robustgait.study.outcome import known_figure
from robustgait.study.run import create_study, run_study
from robustgait.study.status import study_status


def known(cache: EvaluationCache) -> list[dict[str, Any]]:
    """Every whole evaluation in the cache (grid gaits only)."""
    out = []
    for i in range(cache.space.size):
        ev = cache.full(cache.params(i))
        if ev is not None:
            out.append({"index": i, "params": cache.params(i), "status": ev["status"],
                        "r_star": known_figure(ev) or 0.0,
                        "comfort": ev.get("comfort")})
    return out


def score_for(person: SimulatedPerson, gaits: list[dict[str, Any]], floor: float, params: dict[str, float]
              ) -> dict[str, Any]:
    """The person's utility of the gait of ``params``, its regret against the best certified gait at or above the floor
    among ``gaits``, and its rank among them."""
    eligible = [g for g in gaits if g["status"] == "certified" and g["r_star"] >= floor]
    utils = sorted((person.utility(g["comfort"]) for g in eligible), reverse=True)
    mine = next((g for g in gaits if g["params"] == params), None)
    u = person.utility(mine["comfort"]) if mine else -math.inf
    return {"utility": u, "best_utility": utils[0] if utils else None, "regret": (utils[0] - u) if utils else None,
            "rank": 1 + sum(x > u for x in utils), "of": len(utils),
            "above_floor": bool(mine and mine["status"] == "certified" and mine["r_star"] >= floor)}


def run_person(cache: EvaluationCache, out: Path, seed: int, learner: str, args: argparse.Namespace) -> dict[str, Any]:
    d = out / f"{learner}_person{seed}"
    study = StudyConfig(metric="simulated-person", learner=learner, iterations=args.iterations, batch=args.batch,
                        seed=0)
    cfg = replace(cache.config, study=study,
                  person=replace(cache.config.person, simulated=SimulatedPersonConfig(seed=seed)))
    if not (d / "study.json").exists():
        create_study(d, "exo", cfg)
    before = dict(cache.computed)
    t0 = time.perf_counter()
    run_study(d, executor=CachedExecutor(cache), progress=False)
    wall = time.perf_counter() - t0
    st = study_status(d)
    floor = st["person"]["floor"]["value"]
    by_number = {t["number"]: t for t in st["trials"]}
    shown_below = sum(1 for a in st["person"]["answers"] for n, rank in zip(st["iterations"][a["iteration"]]["trials"],
                                                                             a["ranks"], strict=True)
                      if rank is not None and (known_figure(by_number[n]) or 0.0) < floor)
    return {"person": seed, "learner": learner, "floor": floor, "recommendation": st["best"]["params"],
            "rec_r_star": known_figure(st["best"]), "shown_below_floor": shown_below,
            "shown": sum(r is not None for a in st["person"]["answers"] for r in a["ranks"]),
            "wall": wall, "computed": {k: cache.computed[k] - before[k] for k in before}}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--cache", required=True)
    ap.add_argument("--persons", type=int, default=20)
    ap.add_argument("--first-person", type=int, default=0)
    ap.add_argument("--learners", default="polar,eubo,random")
    ap.add_argument("--iterations", type=int, default=10)
    ap.add_argument("--batch", type=int, default=5)
    ap.add_argument("--jstar-study", default=None)
    ap.add_argument("--out", default=str(Path(__file__).parent / "data" / "studies"))
    args = ap.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    cache = EvaluationCache(args.cache, "exo", Config())
    if args.jstar_study:
        print(f"imported {cache.import_study(args.jstar_study)} evaluations of {args.jstar_study}", flush=True)
    results = out / "results.jsonl"
    done = {(r["person"], r["learner"]) for r in map(json.loads, results.read_text().splitlines())} \
        if results.is_file() else set()
    t0 = time.perf_counter()
    for seed in range(args.first_person, args.first_person + args.persons):
        for learner in args.learners.split(","):
            if (seed, learner) in done:
                continue
            r = run_person(cache, out, seed, learner, args)
            with results.open("a") as f:
                f.write(json.dumps(r) + "\n")
            print(json.dumps(r), flush=True)
    # score every study against what is known now (the cache only grows)
    gaits = known(cache)
    jstar = study_status(args.jstar_study)["best"]["params"] if args.jstar_study else None
    # one row per (person, learner): several processes may share the results file (learners run side by side)
    rows = list({(r["person"], r["learner"]): r for r in map(json.loads, results.read_text().splitlines())}.values())
    table: dict[str, list[dict[str, Any]]] = {}
    for r in rows:
        person = SimulatedPerson.from_config(SimulatedPersonConfig(seed=r["person"]))
        table.setdefault(r["learner"], []).append({**r, **score_for(person, gaits, r["floor"], r["recommendation"])})
        if jstar is not None:
            table.setdefault("J* alone", []).append({**r, **score_for(person, gaits, r["floor"], jstar)})
    summary = {}
    for name, rs in table.items():
        if name == "J* alone":  # one entry per person
            rs = list({r["person"]: r for r in rs}.values())
        reg = np.array([r["regret"] for r in rs], dtype=float)
        rank = np.array([r["rank"] for r in rs], dtype=float)
        summary[name] = {"n": len(rs), "regret_mean": float(reg.mean()), "regret_se": float(reg.std(ddof=1) /
                                                                                          math.sqrt(len(rs)))
                         if len(rs) > 1 else None, "rank_median": float(np.median(rank)),
                         "rank_mean": float(rank.mean()), "eligible": rs[0]["of"],
                         "shown_below_floor": sum(r.get("shown_below_floor", 0) for r in rs),
                         "shown": sum(r.get("shown", 0) for r in rs)}
    print(json.dumps({"grid": cache.space.size, "known_evaluations": len(gaits),
                      "certified_known": sum(g["status"] == "certified" for g in gaits),
                      "wall_this_run": time.perf_counter() - t0, "computed_this_run": cache.computed,
                      "load": os.getloadavg(), "config": to_dict(cache.config)["certify"]["sequential"],
                      "summary": summary}, indent=1))


if __name__ == "__main__":
    main()
