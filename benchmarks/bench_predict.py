"""Which certificate predicts robustness? (issue 18, item 6.) On the unique gaits of studies (default: the two
paper-size studies of ``bench_study.py``), for each certificate choice — state × set × horizon, and the push
certificate J* — the certificate, and every gait under the same disturbances (``validate``'s draws, seed 0).

Per gait (one worker process each, one rollout thread): the fixed point; ``--trials`` pushes (20 steps after),
their success, fall step and the full state at the first section after the push; the other ``--kinds``
(``--other-trials`` each); then every ``--configs`` certificate (r*, E*, cost) and its check — the pushes whose
first post-push state lies in the certified set, in that certificate's own coordinates, and how many fell; with
``--push-cert``, J* and its check (pushes with |J| ≤ J* that fell). One JSON line per gait in ``--out``; a gait
already there is not computed again (a killed run continues).

``--report`` reads the lines and prints, per choice: the median r*, Spearman ρ (p, n) of r* with push success and
with push s₅₀, the certificate check pooled over gaits (falls inside / inside, 95 % Wilson interval), and for J*
its ρ with the s₅₀ of each other kind; plus the gaits' own step length as a baseline predictor.

    python benchmarks/bench_predict.py [--studies DIR,DIR] [--configs omega/ball/1,velocity/ellipsoid/2,...]
        [--gaits 'GLOB'] [--push-cert] [--kinds latency,noise,mass,terrain] [--trials 200] [--other-trials 100]
        [--workers 2] [--limit N] [--spread N] [--out FILE.jsonl] [--report]
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import os
import platform
import subprocess
import sys
import time
from concurrent.futures import ProcessPoolExecutor, as_completed
from datetime import date
from pathlib import Path
from typing import Any

import numpy as np

REPO = Path(__file__).resolve().parents[1]
DEFAULT_CONFIGS = ",".join(f"{s}/{k}/1" for s in ("omega", "centroidal", "velocity") for k in ("ball", "ellipsoid"))


def parse_config(text: str) -> dict[str, Any]:
    state, shape, horizon = text.split("/")
    return {"state": state, "set": shape, "horizon": int(horizon)}


def gait_files(pattern: str) -> list[dict[str, Any]]:
    """Gait files named by a glob (``--gaits``), each its own 'study' (their parameters from the files)."""
    import glob

    from robustgait.io.gaitfile import load_gait
    from robustgait.io.robotfile import load_robot

    robot = load_robot("exo")
    out = []
    for p in sorted(glob.glob(pattern)):
        g = load_gait(p, robot)
        params = g.params.to_dict() if g.params is not None else {}
        out.append({"label": Path(p).stem, "params": params, "gait": str(Path(p).resolve()), "study": "files",
                    "study_r_star": None})
    return out


def gaits_of(studies: list[Path]) -> list[dict[str, Any]]:
    """The unique certified gaits of the studies (the first study that has a grid point keeps it)."""
    from robustgait.study.validate import study_gaits

    out, seen = [], set()
    for d in studies:
        _, gaits = study_gaits(d)
        for g in gaits:
            key = json.dumps(g.params, sort_keys=True)
            if g.status == "certified" and g.gait_file is not None and key not in seen:
                seen.add(key)
                out.append({"label": g.label, "params": g.params, "gait": str(d / g.gait_file), "study": d.name,
                            "study_r_star": g.r_star})
    return out


def one_gait(task: dict[str, Any]) -> dict[str, Any]:
    """Everything of one gait (module docstring). Runs in a worker: one rollout thread, BLAS on one thread."""
    from robustgait.certify import certify_gait
    from robustgait.config import CertifyConfig, SimConfig, ValidateConfig
    from robustgait.io.gaitfile import load_gait
    from robustgait.io.robotfile import load_robot
    from robustgait.reduced import ReducedState
    from robustgait.validate import disturbances as dist
    from robustgait.validate.run import CertificateRef, Validator, simulate_trials
    from robustgait.validate.stats import logistic_fit

    t0 = time.perf_counter()
    robot = load_robot("exo")
    gait = load_gait(task["gait"], robot)
    sim = SimConfig(n_threads=1)
    base = CertifyConfig(**task.get("certify", {}))
    gc0 = certify_gait(robot, gait, dataclasses.replace(base, method="uniform", n_samples=1), sim)
    if not gc0.ok or gc0.fixed_point is None:
        return {**task, "error": f"{gc0.status}: {gc0.reason}"}
    fp = gc0.fixed_point
    out: dict[str, Any] = {**task, "kinds": {}, "configs": {}}
    ref = CertificateRef.of(gc0)
    nq = robot.model.nq
    first_push = None
    for kind, trials in [("push", task["trials"])] + [(k, task["other_trials"]) for k in task["kinds"]]:
        vcfg = ValidateConfig(trials=trials, seed=0)
        with Validator(robot, gait, vcfg, sim=sim, certificate=ref) as v:
            draws = dist.draw(kind, trials, vcfg, robot)
            ok, _, fall_step, first, physics = simulate_trials(
                v.engine, np.tile(fp.qpos, (trials, 1)), np.tile(fp.qvel, (trials, 1)), 1 + vcfg.steps_after, 1,
                v.inputs_for(kind, draws), first_at=v.nominal_at)
            if kind == "push":
                first_push, red0 = first, v.reduced
        fit = logistic_fit(draws.size, ok)
        row = {"success": float(ok.mean()), "s50": fit.s50 if fit.in_range else None, "s50_raw": fit.s50,
               "size": draws.size.tolist(), "ok": ok.tolist(), "fall_step": fall_step.tolist(), "physics": physics}
        if kind == "push":
            reached = np.isfinite(first).all(axis=1)
            energy = np.full(trials, np.nan)
            energy[reached] = red0.kinetic_energy(first[reached, :nq], first[reached, nq:])
            row["energy"] = [None if not math.isfinite(e) else float(e) for e in energy]
        out["kinds"][kind] = row
    out["seconds_validate"] = time.perf_counter() - t0
    assert first_push is not None
    push_ok = np.array(out["kinds"]["push"]["ok"])
    reached = np.isfinite(first_push).all(axis=1)
    for text in task["configs"]:
        cfg = dataclasses.replace(base, **parse_config(text))
        t1 = time.perf_counter()
        gc = certify_gait(robot, gait, cfg, sim)
        row = {"status": gc.status, "r_star": gc.r_star, "energy": gc.energy, "seconds": time.perf_counter() - t1,
               "physics": gc.physics_steps, "samples": gc.certificate.n_samples if gc.certificate else 0,
               "bound": gc.certificate.violation_bound if gc.certificate else 1.0}
        if gc.ok and gc.coordinates is not None and gc.certificate is not None:
            co, c = gc.coordinates, gc.certificate
            red = ReducedState.at(cfg.state, robot, fp.qpos, fp.qvel, gait.stance, cfg)
            z = np.full((first_push.shape[0], co.dim), np.nan)
            z[reached] = co.to_z(red.phi(first_push[reached, :nq], first_push[reached, nq:]))
            d = np.linalg.norm(z - co.x_star, axis=1)
            with np.errstate(invalid="ignore"):
                inside = (d <= c.r_star) if c.attained else (d < c.r_star)
            row.update({"inside": int(inside.sum()), "fell_inside": int((inside & ~push_ok).sum()),
                        "volume_ratio": gc.volume_ratio, "excursion": gc.excursion,
                        "fallback": co.shape.fallback if cfg.set == "ellipsoid" else None})
        out["configs"][text] = row
    if task["push_cert"]:
        t1 = time.perf_counter()
        cfg = dataclasses.replace(base, disturbance="push")
        gc = certify_gait(robot, gait, cfg, sim)
        size = np.array(out["kinds"]["push"]["size"])
        inside = size <= gc.r_star if (gc.certificate is None or gc.certificate.attained) else size < gc.r_star
        out["push_cert"] = {"status": gc.status, "j_star": gc.r_star, "seconds": time.perf_counter() - t1,
                            "physics": gc.physics_steps, "inside": int(inside.sum()),
                            "fell_inside": int((inside & ~push_ok).sum()),
                            "bound": gc.certificate.violation_bound if gc.certificate else 1.0}
    out["seconds"] = time.perf_counter() - t0
    return out


def run(args: argparse.Namespace) -> None:
    from robustgait.study.executors import blas_threads

    gaits = (gait_files(args.gaits) if args.gaits else gaits_of([Path(s) for s in args.studies.split(",")]))[
        : args.limit]
    if args.spread is not None and args.spread < len(gaits):
        # evenly spaced in the studies' own r* (so a short run still spans weak to strong gaits)
        ranked = sorted(gaits, key=lambda g: (g["study_r_star"] is None, g["study_r_star"] or 0.0))
        picks = np.unique(np.round(np.linspace(0, len(ranked) - 1, args.spread)).astype(int))
        gaits = [ranked[i] for i in picks]
    done = set()
    if args.out.exists():
        old = [json.loads(line) for line in args.out.read_text().splitlines() if line.strip()]
        done = {r["label"] + "|" + r["study"] for r in old}
    todo = [g for g in gaits if g["label"] + "|" + g["study"] not in done]
    print(f"{len(gaits)} gaits ({len(gaits) - len(todo)} already in {args.out}); configs {args.configs}; "
          f"push certificate {args.push_cert}; kinds push + {args.kinds or 'none'}; {args.workers} workers; "
          f"load {os.getloadavg()[0]:.1f}", flush=True)
    tasks = [{**g, "configs": args.configs.split(","), "kinds": [k for k in args.kinds.split(",") if k],
              "trials": args.trials, "other_trials": args.other_trials, "push_cert": args.push_cert}
             for g in todo]
    t0 = time.perf_counter()
    with blas_threads(1), ProcessPoolExecutor(args.workers) as pool, args.out.open("a") as f:
        futures = [pool.submit(one_gait, t) for t in tasks]
        for k, fut in enumerate(as_completed(futures), 1):
            res = fut.result()
            f.write(json.dumps(res, allow_nan=False) + "\n")
            f.flush()
            cfgs = " ".join(f"{c.split('/')[0][:3]}/{c.split('/')[1][:3]}/{c.split('/')[2]} {v['r_star']:.3g}"
                            for c, v in res.get("configs", {}).items())
            j = res.get("push_cert", {}).get("j_star")
            print(f"[{k}/{len(tasks)} {time.perf_counter() - t0:.0f} s] {res['label']}: push "
                  f"{res.get('kinds', {}).get('push', {}).get('success', float('nan')):.2f}  {cfgs}"
                  + (f"  J* {j:.3g}" if j is not None else "") + f"  ({res.get('seconds', 0):.0f} s)"
                  + (f"  ERROR {res['error']}" if "error" in res else ""), flush=True)


def report(path: Path) -> None:
    from robustgait.validate.stats import Rate, spearman

    rows = [json.loads(line) for line in path.read_text().splitlines() if line.strip()]
    rows = [r for r in rows if "error" not in r]
    commit = subprocess.run(["git", "-C", str(REPO), "rev-parse", "--short", "HEAD"], capture_output=True,
                            text=True).stdout.strip()
    print(f"{len(rows)} gaits from {path} (report {date.today()}, commit {commit}, {platform.machine()})")
    success = np.array([r["kinds"]["push"]["success"] for r in rows])
    s50 = np.array([np.nan if r["kinds"]["push"]["s50"] is None else r["kinds"]["push"]["s50"] for r in rows])
    print(f"push success {success.min():.2f}–{success.max():.2f} (median {np.median(success):.2f}); s₅₀ defined "
          f"for {int(np.isfinite(s50).sum())}")

    def corr(x: np.ndarray, y: np.ndarray, what: str) -> str:
        m = np.isfinite(x) & np.isfinite(y)
        c = spearman(x[m], y[m], "x", what)
        return f"{c.rho:+.3f} (p {c.p:.2g}, n {c.n})" if c.defined else f"undefined ({c.reason})"

    print("\n| choice | median r* | median cost [s] | ρ(r*, push success) | ρ(r*, push s₅₀) | falls inside / inside "
          "[95 % CI] |")
    print("|---|---|---|---|---|---|")
    names = list(dict.fromkeys(c for r in rows for c in r["configs"]))  # in the order the run listed them
    for name in names:
        have = [r for r in rows if name in r["configs"]]
        x = np.array([r["configs"][name]["r_star"] for r in have])
        idx = [rows.index(r) for r in have]
        fell = sum(r["configs"][name].get("fell_inside", 0) for r in have)
        inside = sum(r["configs"][name].get("inside", 0) for r in have)
        rate = Rate.of(fell, inside)
        cost = np.median([r["configs"][name]["seconds"] for r in have])
        print(f"| {name} | {np.median(x):.3g} | {cost:.1f} | {corr(x, success[idx], 'success')} | "
              f"{corr(x, s50[idx], 's50')} | {fell}/{inside} = {rate.rate:.3f} [{rate.low:.3f}, {rate.high:.3f}] |")
    if any("push_cert" in r for r in rows):
        have = [r for r in rows if "push_cert" in r]
        idx = [rows.index(r) for r in have]
        j = np.array([r["push_cert"]["j_star"] for r in have])
        fell = sum(r["push_cert"]["fell_inside"] for r in have)
        inside = sum(r["push_cert"]["inside"] for r in have)
        rate = Rate.of(fell, inside)
        cost = np.median([r["push_cert"]["seconds"] for r in have])
        print(f"| push J* [N s] | {np.median(j):.3g} | {cost:.1f} | {corr(j, success[idx], 'success')} | "
              f"{corr(j, s50[idx], 's50')} | {fell}/{inside} = {rate.rate:.3f} [{rate.low:.3f}, {rate.high:.3f}] |")
        kinds = sorted({k for r in have for k in r["kinds"] if k != "push"})
        for k in kinds:
            ks = np.array([np.nan if r["kinds"][k]["s50"] is None else r["kinds"][k]["s50"] for r in have])
            ksucc = np.array([r["kinds"][k]["success"] for r in have])
            print(f"J* vs {k}: success {corr(j, ksucc, 'success')}, s₅₀ {corr(j, ks, 's50')}")
            for name in names:
                x = np.array([r["configs"][name]["r_star"] for r in have if name in r["configs"]])
                if x.size == len(have):
                    print(f"   r* {name} vs {k}: success {corr(x, ksucc, 'success')}, s₅₀ {corr(x, ks, 's50')}")
    length = np.array([r["params"]["step_length"] for r in rows])
    print(f"\nbaseline: step length vs push success {corr(length, success, 'success')}, vs s₅₀ "
          f"{corr(length, s50, 's50')}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--studies", default=",".join(str(REPO / "benchmarks" / "data" / "bench_study" / m)
                                                  for m in ("robustness", "stability")))
    ap.add_argument("--gaits", help="a glob of gait files instead of studies")
    ap.add_argument("--configs", default=DEFAULT_CONFIGS)
    ap.add_argument("--push-cert", action="store_true")
    ap.add_argument("--kinds", default="")
    ap.add_argument("--trials", type=int, default=200)
    ap.add_argument("--other-trials", type=int, default=100)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--limit", type=int, default=None)
    ap.add_argument("--spread", type=int, default=None, help="N gaits evenly spaced in the studies' r*")
    ap.add_argument("--out", type=Path, default=REPO / "benchmarks" / "data" / "bench_predict.jsonl")
    ap.add_argument("--report", action="store_true")
    args = ap.parse_args()
    if args.report:
        report(args.out)
    else:
        run(args)
        report(args.out)


if __name__ == "__main__":
    sys.exit(main())
