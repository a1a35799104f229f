"""Where should a push certificate's verification batch be drawn so that it passes at its first attempt?

The sequential estimator explores cheaply (exploration pushes stop sooner: ``certify.push.explore_*``), which places
an estimate Ĵ; its verification batch is then drawn uniformly in the disk of radius c Ĵ (``certify.push.verify_margin``
c) and simulated at the statement's settings. The batch passes when none of its n₁ pushes falls, with probability
(1 − V(c Ĵ))^n₁, V(r) the falling share of the disk of radius r. This script measures V on real gaits.

``run``: per gait (``--from-jsonl``: the exo study gaits of ``benchmarks/experiments/predictors/data/exo.jsonl``,
regenerated from their parameters; ``--grid N``: N points of the robot's action-space grid; ``--gait FILE``: stored
gaits), in worker processes: the gait generated cold, the exploration alone (:func:`robustgait.certify_gait` with
``verify=False``: the orbit, Ĵ, its pushes and physics steps) under each exploration rule of ``--rules``, then
``--pushes`` M fresh pushes uniform in the disk of radius ``--outer`` × the largest Ĵ (their own seed stream, the
certificate's hashed phases) under the statement's rule (fall
within the pushed step and ``push.horizon`` more; recovered walks stop): each push's |J| / Ĵ, whether it fell and its
walking steps. ``--full`` also runs the default certificate (first attempt passed or not, J*, pushes, physics steps,
seconds). One JSON line per gait; a killed run continues (a gait already in ``--out`` is skipped).

``report``: per exploration rule and margin c, the expected share of first attempts that pass, mean over the gaits
of (1 − V̂(c))^n₁ with V̂(c) the falling share of the M pushes inside c Ĵ; the gaits with a fall inside c Ĵ; the
mean steps of a push inside c Ĵ; and, with ``--full`` rows, the measured first-attempt passes and J* against Ĵ.

``margins``: per gait of a robot's action-space grid (``--grid N`` points, generated cold), the default certificate
(the shipped options) at each ``push.verify_margin`` c of ``--margins``: whether its first batch passed, its attempts,
J*, Ĵ, pushes, physics steps and seconds (the exploration is the same at every margin: common random numbers).
``margins-report``: per margin, the share of first batches that passed, and J* against J* at the first margin.

    python benchmarks/experiments/verify_margin/run.py run --robot exo --from-jsonl \\
        benchmarks/experiments/predictors/data/exo.jsonl --out benchmarks/experiments/verify_margin/data/exo.jsonl
    python benchmarks/experiments/verify_margin/run.py run --robot robots/t1/spec.toml --grid 30 --out …/t1.jsonl
    python benchmarks/experiments/verify_margin/run.py report benchmarks/experiments/verify_margin/data/*.jsonl
    python benchmarks/experiments/verify_margin/run.py margins --robot robots/t1/spec.toml --grid 12 \\
        --margins 0.8,0.7,0.65 --out benchmarks/experiments/verify_margin/data/t1_margins.jsonl
"""

from __future__ import annotations

import os
import sys

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse
import dataclasses
import json
import time
from concurrent.futures import ProcessPoolExecutor, as_completed
from datetime import date
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))  # benchmarks/common.py
from common import git_commit, grid_params

PARAMS = ("step_length", "step_duration", "step_width", "step_height")
MARGINS = (0.6, 0.65, 0.7, 0.75, 0.8, 0.85, 0.9, 0.95, 1.0)


def label_of(p: dict[str, float]) -> str:
    return "L{step_length:g}_T{step_duration:g}_W{step_width:g}_H{step_height:g}".format(**p)


def measure(job: dict[str, Any]) -> dict[str, Any]:
    """One gait's row (module docstring, ``run``)."""
    from robustgait import SimConfig, load_gait, load_robot
    from robustgait.certificate.certify import certify_gait
    from robustgait.certificate.push import PushMap, push_phase
    from robustgait.config import CertifyConfig, GaitParams, ValidateConfig
    from robustgait.gaitgen import generate_gait
    from robustgait.sim.factory import make_engine

    robot = load_robot(job["robot"])
    sim = SimConfig(n_threads=1)
    row: dict[str, Any] = {"label": job["label"], "robot": job["robot"], "params": job["params"]}
    t0 = time.perf_counter()
    if job.get("gait"):
        gait = load_gait(job["gait"], robot)
    else:
        res = generate_gait(robot, GaitParams(**job["params"]))
        if res.gait is None:
            return {**row, "status": "generation_failed", "reason": f"{res.status}: {res.reason}"}
        gait = res.gait
    row["generate_s"] = time.perf_counter() - t0
    cfg = CertifyConfig()
    estimates: dict[str, dict[str, Any]] = {}
    est = None
    for rule in job["rules"]:
        nu, steps, horizon, *sizes_ = rule.split("/")
        first, explore = (int(sizes_[0]), int(sizes_[1])) if sizes_ else (cfg.push.first_round, cfg.push.explore)
        rcfg = dataclasses.replace(cfg, push=dataclasses.replace(
            cfg.push, explore_recovery_radius=float(nu), explore_recovery_steps=int(steps),
            explore_horizon=int(horizon), first_round=first, explore=explore))
        t0 = time.perf_counter()
        est = certify_gait(robot, gait, rcfg, sim, verify=False)
        row.update(status=str(est.status), reason=est.reason, orbit_physics=est.orbit_physics_steps)
        if not est.ok or est.certificate is None or est.orbit is None:
            return row
        c = est.certificate
        estimates[rule] = {"j_hat": float(c.r_star), "explore_s": time.perf_counter() - t0,
                           "explore_physics": est.physics_steps, "explore_pushes": c.n_samples,
                           "sizes": [float(x) for x in np.linalg.norm(c.samples, axis=1)],
                           "fell": [bool(x) for x in c.fell]}
    assert est is not None and est.orbit is not None
    row["estimates"] = estimates
    j_hat = max(e["j_hat"] for e in estimates.values())
    row.update(j_hat=j_hat)
    rng = np.random.default_rng([job["seed"], 7])
    m = job["pushes"]
    angle = rng.uniform(0.0, 2 * np.pi, m)
    radius = job["outer"] * j_hat * np.sqrt(rng.uniform(size=m))
    impulse = np.stack([radius * np.cos(angle), radius * np.sin(angle)], axis=1)
    v = ValidateConfig()
    engine = make_engine(robot, gait, sim)
    try:
        pushes = PushMap(engine, est.orbit.qpos, est.orbit.qvel, est.orbit.band, v, cfg.push)
        t0 = time.perf_counter()
        ok, _, fall_step, recovered = pushes.walk(impulse, push_phase(impulse, *v.push_phase))
        # the walking steps each push took: to its fall, to its recovery, or the whole horizon
        walked = np.where(fall_step > 0, fall_step, np.where(recovered > 0, recovered, 1 + cfg.push.horizon))
        fell, steps = [bool(x) for x in ~ok], [int(x) for x in walked]
        row["dense_physics"] = pushes.physics_steps
        row.update(dense_s=time.perf_counter() - t0, outer=job["outer"],
                   size=[float(x) for x in radius], fell=fell, steps=steps)
    finally:
        engine.close()
    if job["full"]:
        t0 = time.perf_counter()
        gc = certify_gait(robot, gait, cfg, sim)
        c = gc.certificate
        verify = [r for r in c.rounds if r.kind == "verify"] if c is not None else []
        row["full"] = {"status": str(gc.status), "j_star": gc.value if gc.ok else None,
                       "estimate": None if c is None else c.estimate,
                       "first_passed": bool(verify and verify[0].passed), "attempts": len(verify),
                       "pushes": 0 if c is None else c.n_samples, "physics": gc.physics_steps,
                       "orbit_physics": gc.orbit_physics_steps, "seconds": time.perf_counter() - t0}
    return row


def cmd_run(args: argparse.Namespace) -> None:
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    lines = [line for f in (out, *map(Path, args.done)) if f.exists() for line in f.read_text().splitlines()]
    done = {json.loads(line)["label"] for line in lines if line.strip()}
    if args.gait:
        points = [({}, g) for g in args.gait]
    elif args.from_jsonl:
        rows = [json.loads(line) for line in Path(args.from_jsonl).read_text().splitlines() if line.strip()]
        points = [({k: r["params"][k] for k in PARAMS}, "") for r in rows]
    else:
        points = [(p, "") for p in grid_params(args.robot, args.grid, "flat")]
    if args.limit:
        points = [points[i] for i in np.unique(np.linspace(0, len(points) - 1, args.limit).round().astype(int))]
    jobs = [{"robot": args.robot, "label": Path(g).stem if g else label_of(p), "params": p, "gait": g,
             "pushes": args.pushes, "outer": args.outer, "seed": args.seed, "full": args.full,
             "rules": args.rules.split(",")}
            for p, g in points]
    shard, shards = (int(x) for x in args.shard.split("/"))
    jobs = [j for i, j in enumerate(jobs) if i % shards == shard and j["label"] not in done]
    commit, day = git_commit(), date.today().isoformat()
    print(f"# verify_margin run {day} at {commit}: {args.robot}, {len(jobs)} gaits to go, {args.workers} workers")
    with ProcessPoolExecutor(args.workers) as pool:
        futures = [pool.submit(measure, j) for j in jobs]
        for f in as_completed(futures):
            row = {**f.result(), "commit": commit, "date": day}
            with out.open("a") as fh:
                fh.write(json.dumps(row) + "\n")
            full = row.get("full") or {}
            print(f"{row['label']}: {row['status']} Ĵ {row.get('j_hat', 0):.3f} falls inside "
                  f"{sum(row.get('fell', []))}/{len(row.get('fell', []))}"
                  + (f"; full J* {full.get('j_star')}, first passed {full.get('first_passed')}" if full else ""),
                  flush=True)


def estimate(row: dict[str, Any], rule: str) -> dict[str, Any]:
    """A row's exploration estimate under ``rule`` (a row of one rule, written before rules were compared: its
    own)."""
    if "estimates" in row:
        return dict(row["estimates"][rule])
    return {"j_hat": row["j_hat"], "explore_physics": row["explore_physics"]}


def sizes(row: dict[str, Any]) -> np.ndarray:
    """|J| [N s] of a row's fresh pushes."""
    return np.asarray(row["size"]) if "size" in row else np.asarray(row["rho"]) * row["j_hat"]


def cmd_report(args: argparse.Namespace) -> None:
    from robustgait.config import CertifyConfig

    cfg = CertifyConfig()
    n1 = cfg.estimator.batch_size(cfg.beta, 1)
    for path in args.files:
        rows = [json.loads(line) for line in Path(path).read_text().splitlines() if line.strip()]
        ok = [r for r in rows if "fell" in r]
        commits = sorted({r.get("commit", "?") for r in rows})
        print(f"## {path}: {len(rows)} gaits, {len(ok)} with an estimate (commit {', '.join(commits)}); "
              f"n₁ = {n1}\n")
        # in the order they were run: the first is the one the others are compared with
        rules = list(dict.fromkeys(rule for r in ok for rule in r.get("estimates", {"legacy": 0})))
        for rule in rules:
            base = [estimate(r, rules[0]) for r in ok]
            here = [estimate(r, rule) for r in ok]
            ratio = np.array([h["j_hat"] / b["j_hat"] for h, b in zip(here, base, strict=True) if b["j_hat"] > 0])
            print(f"rule {rule} (ν/m/h[/first/explore]): exploration physics steps, median "
                  f"{np.median([h['explore_physics'] for h in here]) / 1e3:.0f} k; Ĵ / Ĵ of rule {rules[0]}: median "
                  f"{np.median(ratio):.3f}, range {ratio.min():.3f}–{ratio.max():.3f}, equal on "
                  f"{int(np.sum(np.isclose(ratio, 1.0)))} of {ratio.size}\n")
            print("| margin c | expected first-attempt passes | gaits with a fall inside c Ĵ | walking steps per push "
                  "inside |")
            print("|---|---|---|---|")
            for c in MARGINS:
                passes, with_fall, steps = [], 0, []
                for r in ok:
                    size, fell, st = sizes(r), np.asarray(r["fell"]), np.asarray(r["steps"])
                    inside = size <= c * estimate(r, rule)["j_hat"]
                    if not inside.any():
                        continue
                    v = fell[inside].mean()
                    passes.append((1.0 - v) ** n1)
                    with_fall += int(fell[inside].any())
                    steps.extend(st[inside].tolist())
                print(f"| {c:g} | {100 * np.mean(passes):.1f} % | {with_fall} of {len(passes)} | "
                      f"{np.mean(steps):.2f} |")
            print()
        full = [r["full"] for r in rows if r.get("full")]
        if full:
            certified = [f for f in full if f["j_star"] is not None]
            first = sum(f["first_passed"] for f in certified)
            ratio = [f["j_star"] / f["estimate"] for f in certified if f["estimate"]]
            print(f"\nfull certificates: {len(certified)} certified of {len(full)}; first attempt passed "
                  f"{first} of {len(certified)} ({100 * first / max(len(certified), 1):.0f} %); J*/Ĵ median "
                  f"{np.median(ratio):.3f}; median {np.median([f['seconds'] for f in certified]):.1f} s, "
                  f"{np.median([f['physics'] for f in certified]) / 1e6:.2f} M physics steps")
        print()


def measure_margins(job: dict[str, Any]) -> dict[str, Any]:
    """One gait's row of ``margins`` (module docstring)."""
    from robustgait import SimConfig, load_robot
    from robustgait.certificate.certify import certify_gait
    from robustgait.config import CertifyConfig, GaitParams
    from robustgait.gaitgen import generate_gait

    robot = load_robot(job["robot"])
    row: dict[str, Any] = {"label": job["label"], "params": job["params"]}
    res = generate_gait(robot, GaitParams(**job["params"]))
    if res.gait is None:
        return {**row, "status": "generation_failed"}
    base = CertifyConfig()
    row["margins"] = {}
    for c in job["margins"]:
        cfg = dataclasses.replace(base, push=dataclasses.replace(base.push, verify_margin=c))
        t0 = time.perf_counter()
        gc = certify_gait(robot, res.gait, cfg, SimConfig(n_threads=1))
        cert = gc.certificate
        verify = [r for r in cert.rounds if r.kind == "verify"] if cert is not None else []
        row["status"] = str(gc.status)
        row["margins"][f"{c:g}"] = {"j_star": gc.value if gc.ok else None,
                                    "estimate": None if cert is None else cert.estimate,
                                    "first_passed": bool(verify and verify[0].passed), "attempts": len(verify),
                                    "pushes": 0 if cert is None else cert.n_samples, "physics": gc.physics_steps,
                                    "seconds": time.perf_counter() - t0}
    return row


def cmd_margins(args: argparse.Namespace) -> None:
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    done = {json.loads(line)["label"] for line in (out.read_text().splitlines() if out.exists() else []) if line}
    margins = [float(x) for x in args.margins.split(",")]
    jobs = [{"robot": args.robot, "label": label_of(p), "params": p, "margins": margins}
            for p in grid_params(args.robot, args.grid, "flat")]
    jobs = [j for j in jobs if j["label"] not in done]
    commit, day = git_commit(), date.today().isoformat()
    print(f"# verify_margin margins {day} at {commit}: {args.robot}, {len(jobs)} gaits, margins {margins}")
    with ProcessPoolExecutor(args.workers) as pool:
        for f in as_completed([pool.submit(measure_margins, j) for j in jobs]):
            row = {**f.result(), "commit": commit, "date": day}
            with out.open("a") as fh:
                fh.write(json.dumps(row) + "\n")
            passes = {c: m["first_passed"] for c, m in row.get("margins", {}).items()}
            print(f"{row['label']}: {row['status']} first passed {passes}", flush=True)


def cmd_margins_report(args: argparse.Namespace) -> None:
    for path in args.files:
        rows = [json.loads(line) for line in Path(path).read_text().splitlines() if line.strip()]
        ok = [r for r in rows if r.get("margins")]
        margins = list(ok[0]["margins"]) if ok else []
        print(f"## {path}: {len(rows)} gaits (commit {', '.join(sorted({r['commit'] for r in rows}))})\n")
        print(f"| margin c | first batches passed | J* / J* at c = {margins[0]} (median) | the same, gaits whose first "
              "batch passed at both | median seconds |")
        print("|---|---|---|---|---|")
        for c in margins:
            cert = [r for r in ok if r["margins"][c]["j_star"] is not None]
            first = sum(r["margins"][c]["first_passed"] for r in cert)
            ratio = [r["margins"][c]["j_star"] / r["margins"][margins[0]]["j_star"] for r in cert
                     if r["margins"][margins[0]]["j_star"]]
            both = [r["margins"][c]["j_star"] / r["margins"][margins[0]]["j_star"] for r in cert
                    if r["margins"][c]["first_passed"] and r["margins"][margins[0]]["first_passed"]]
            secs = [r["margins"][c]["seconds"] for r in cert]
            print(f"| {c} | {first} of {len(cert)} ({100 * first / max(len(cert), 1):.0f} %) | "
                  f"{np.median(ratio):.3f} | {np.median(both) if both else float('nan'):.3f} | "
                  f"{np.median(secs):.1f} |")
        print()


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("run")
    r.add_argument("--robot", required=True)
    r.add_argument("--from-jsonl", default="")
    r.add_argument("--grid", type=int, default=12)
    r.add_argument("--gait", nargs="*", default=[])
    r.add_argument("--limit", type=int, default=0)
    r.add_argument("--pushes", type=int, default=300, help="M: fresh pushes per gait")
    r.add_argument("--outer", type=float, default=1.2, help="their disk's radius over the largest Ĵ")
    r.add_argument("--rules", default="0.03/1/8",
                   help="exploration rules ν/m/h[/first/explore] (explore_recovery_radius / explore_recovery_steps / "
                        "explore_horizon, and optionally push.first_round / push.explore), "
                        "comma-separated: each one's estimate Ĵ")
    r.add_argument("--seed", type=int, default=0)
    r.add_argument("--full", action="store_true", help="also the default certificate")
    r.add_argument("--workers", type=int, default=2)
    r.add_argument("--out", required=True)
    r.add_argument("--shard", default="0/1", help="i/n: the gaits whose index is i modulo n (runs side by side, each "
                                                  "with its own --out)")
    r.add_argument("--done", nargs="*", default=[], help="other --out files: their gaits are skipped")
    p = sub.add_parser("report")
    p.add_argument("files", nargs="+")
    m = sub.add_parser("margins")
    m.add_argument("--robot", required=True)
    m.add_argument("--grid", type=int, default=12)
    m.add_argument("--margins", default="0.8,0.7,0.65")
    m.add_argument("--workers", type=int, default=1)
    m.add_argument("--out", required=True)
    mr = sub.add_parser("margins-report")
    mr.add_argument("files", nargs="+")
    args = ap.parse_args()
    {"run": cmd_run, "report": cmd_report, "margins": cmd_margins, "margins-report": cmd_margins_report}[args.cmd](args)


if __name__ == "__main__":
    main()
