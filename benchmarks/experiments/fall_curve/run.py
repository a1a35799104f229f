"""J* from the fall curve: does the first verification batch pass, do estimates tie, do they rank gaits, what does a
certificate cost against the statement's own batch, and how does J* move from the nearest fall's estimator?

``run``: per gait (``--from-jsonl``: the study gaits of a predictors-style file, regenerated from their parameters;
``--grid N``: N points of the robot's action-space grid; ``--gait FILE ...``: stored gaits), in worker processes: the
gait generated cold (``--domains``), then the default certificate (:func:`robustgait.certificate.certify.certify_gait`;
``--seed``, or ``--seeds`` N seeds from it; ``--push``: JSON overrides of ``certify.push``): J*, Ĵ, whether the first
batch passed, attempts, pushes, physics steps (all, the verification's, the orbit search's), the ratio to the
statement's minimum (the first batch's size × the mean physics steps of a verification push), CPU seconds and the
fitted curve. The yardstick (:func:`common.yardstick`) is measured once per worker, beside the gaits. One JSON line
per gait and seed (``--samples``: with every push of the certificate, its impulse, whether it fell and its round); a
killed run continues (a row already in ``--out`` is skipped). ``--explore-only``: the
exploration alone, with the verification radius its curve gives at each pass probability of :data:`LEVELS`.

``report FILES [--before OLD.jsonl ...] [--s50 PREDICTORS.jsonl]``: per robot, the share of first batches that passed,
ties (pairs of different gaits whose Ĵ agree to 1e-9), the cost ratio and CPU yardsticks (median, max), J*'s
coefficient of variation over seeds; with ``--s50`` the Spearman ρ of Ĵ and of J* with each gait's push s₅₀
(``validate``) and of Ĵ with J*; with ``--before`` (rows with a ``full`` certificate of the same gaits, e.g.
``data/before_exo77.jsonl``: the deleted ``verify_margin`` experiment's rows at 55d9b54, the nearest fall's
estimator) the same for it and J* / J*_before per gait (median and quartiles). ``calibrate``: the verification radii
of ``--explore-only`` rows against dense fresh pushes of the same gaits (``data/before_*.jsonl`` rows).

    python benchmarks/experiments/fall_curve/run.py run --robot exo \\
        --from-jsonl benchmarks/experiments/predictors/data/exo.jsonl --out data/exo77.jsonl
    python benchmarks/experiments/fall_curve/run.py run --robot robots/t1/spec.toml --grid 12 --out data/t1grid.jsonl
    python benchmarks/experiments/fall_curve/run.py run --robot exo --gait tests/data/exo_gait.json --seeds 5 \\
        --out data/seeds.jsonl
    python benchmarks/experiments/fall_curve/run.py report data/exo77.jsonl \\
        --before data/before_exo77.jsonl --s50 ../predictors/data/exo.jsonl
"""

from __future__ import annotations

import os
import sys

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse
import itertools
import json
import time
from concurrent.futures import ProcessPoolExecutor, as_completed
from datetime import date
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))  # benchmarks/common.py
from common import git_commit, grid_params, yardstick

PARAMS = ("step_length", "step_duration", "step_width", "step_height")
_YARDSTICK: list[float] = []


def label_of(p: dict[str, float]) -> str:
    return "L{step_length:g}_T{step_duration:g}_W{step_width:g}_H{step_height:g}".format(**p)


def measure(job: dict[str, Any]) -> dict[str, Any]:
    """One gait's row (module docstring, ``run``)."""
    from robustgait import SimConfig, load_gait, load_robot
    from robustgait.certificate.certify import certify_gait
    from robustgait.certificate.verification import attempt_size
    from robustgait.config import CertifyConfig, GaitParams, GenerationConfig
    from robustgait.gaitgen import generate_gait

    if not _YARDSTICK:
        _YARDSTICK.append(yardstick())
    robot = load_robot(job["robot"])
    sim = SimConfig(n_threads=1)
    row: dict[str, Any] = {"label": job["label"], "robot": job["robot"], "params": job["params"],
                           "yardstick_s": _YARDSTICK[0]}
    if job.get("gait"):
        gait = load_gait(job["gait"], robot)
    else:
        res = generate_gait(robot, GaitParams(**job["params"]), GenerationConfig(domains=job["domains"]))
        if res.gait is None:
            return {**row, "status": "generation_failed", "reason": f"{res.status}: {res.reason}"}
        gait = res.gait
    cfg = CertifyConfig(seed=job["seed"], push=job["push"])
    if job["explore_only"]:
        return {**row, **explore_row(robot, gait, cfg, sim)}
    t0 = time.process_time()
    gc = certify_gait(robot, gait, cfg, sim)
    cpu = time.process_time() - t0
    row.update(status=str(gc.status), reason=gc.reason, cpu_s=cpu, yardsticks=cpu / _YARDSTICK[0])
    c = gc.certificate
    if not gc.ok or c is None:
        return row
    verify = [r for r in c.rounds if r.kind == "verify"]
    verify_physics = getattr(gc, "verify_physics_steps", 0)  # 0: a checkout from before it was counted
    per_push = verify_physics / max(1, sum(r.n_samples for r in verify))
    total = gc.physics_steps + gc.orbit_physics_steps
    first_n = attempt_size(cfg, 1)
    row.update(j_star=gc.value, estimate=c.estimate, verified=c.violation_bound < 1.0,
               first_passed=bool(verify and verify[0].passed), attempts=len(verify), pushes=c.n_samples,
               physics=total, verify_physics=verify_physics, orbit_physics=gc.orbit_physics_steps,
               ratio=total / (first_n * per_push) if per_push else None, curve=getattr(c, "curve", None))
    if job.get("samples"):  # every push: impulse (heading frame; its phase is push.push_phase of it), fell, round
        row.update(impulses=[[float(v) for v in x] for x in c.samples], fell=[bool(f) for f in c.fell],
                   sample_round=[int(k) for k in c.round_of_sample], rounds=[r.kind for r in c.rounds])
    return row


LEVELS = (0.5, 0.6, 0.7, 0.8, 0.9, 0.95)


def explore_row(robot: Any, gait: Any, cfg: Any, sim: Any) -> dict[str, Any]:
    """The exploration alone (``verify=False``) and, from its fitted curve, the verification radius at each pass
    probability of :data:`LEVELS` for the first batch; the exploration's pushes (sizes, falls) and physics steps."""
    from robustgait.certificate.certify import certify_gait
    from robustgait.certificate.fallcurve import fit_fall_curve
    from robustgait.certificate.verification import attempt_size

    t0 = time.process_time()
    est = certify_gait(robot, gait, cfg, sim, verify=False)
    cpu = time.process_time() - t0
    out: dict[str, Any] = {"status": str(est.status), "reason": est.reason, "cpu_s": cpu,
                           "physics": est.physics_steps + est.orbit_physics_steps,
                           "orbit_physics": est.orbit_physics_steps}
    c = est.certificate
    if not est.ok or c is None:
        return out
    sizes = np.linalg.norm(c.samples, axis=1)
    curve = fit_fall_curve(sizes, c.fell, c.r_max)  # the exploration's pushes, as the certificate fits them
    n1 = attempt_size(cfg, 1)
    out.update(estimate=c.estimate, curve=c.curve, sizes=[float(x) for x in sizes], fell=[bool(x) for x in c.fell],
               radius={f"{lv:g}": curve.verification_radius(n1, lv) for lv in LEVELS})
    return out


def cmd_run(args: argparse.Namespace) -> None:
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    done = {json.loads(line)["label"] for line in (out.read_text().splitlines() if out.exists() else []) if line}
    if args.gait:
        points = [({}, g) for g in args.gait]
    elif args.from_jsonl:
        rows = [json.loads(line) for line in Path(args.from_jsonl).read_text().splitlines() if line.strip()]
        points = [({k: r["params"][k] for k in PARAMS}, "") for r in rows]
    else:
        points = [(p, "") for p in grid_params(args.robot, args.grid, args.domains)]
    push = json.loads(args.push)
    seeds = range(args.seed, args.seed + args.seeds)
    jobs = [{"robot": args.robot, "label": (Path(g).stem if g else label_of(p)) + (f"_seed{seed}" if args.seeds > 1
                                                                                   else ""),
             "params": p, "gait": g, "domains": args.domains, "seed": seed, "push": push,
             "explore_only": args.explore_only, "samples": args.samples} for p, g in points for seed in seeds]
    jobs = [j for j in jobs if j["label"] not in done]
    import robustgait  # the checkout measured: this one, or another's src first on PYTHONPATH

    commit, day = git_commit(Path(robustgait.__file__).resolve().parents[2]), date.today().isoformat()
    print(f"# fall_curve run {day} at {commit}: {args.robot}, {len(jobs)} gaits to go, {args.workers} workers")
    with ProcessPoolExecutor(args.workers) as pool:
        futures = [pool.submit(measure, j) for j in jobs]
        for f in as_completed(futures):
            row = {**f.result(), "commit": commit, "date": day}
            with out.open("a") as fh:
                fh.write(json.dumps(row) + "\n")
            print(f"{row['label']}: {row['status']} J* {row.get('j_star')} Ĵ {row.get('estimate')} "
                  f"first {row.get('first_passed')} ratio {row.get('ratio')}", flush=True)


def _rho(a: list[float], b: list[float]) -> str:
    from scipy.stats import spearmanr

    if len(a) < 3:
        return "n/a"
    r = spearmanr(a, b)
    return f"{r.statistic:.3f} (p {r.pvalue:.2g}, n {len(a)})"


def _ties(values: dict[str, float]) -> int:
    return sum(abs(values[a] - values[b]) <= 1e-9 for a, b in itertools.combinations(values, 2))


def cmd_report(args: argparse.Namespace) -> None:
    rows = [json.loads(line) for f in args.files for line in Path(f).read_text().splitlines() if line.strip()]
    before = {r["label"]: r["full"] for f in args.before for line in Path(f).read_text().splitlines()
              if line.strip() and (r := json.loads(line)).get("full")}
    s50 = {r["label"]: r["kinds"]["push"]["s50"] for line in (Path(args.s50).read_text().splitlines()
                                                              if args.s50 else []) if line.strip()
           and (r := json.loads(line)).get("kinds", {}).get("push", {}).get("s50") is not None}
    for robot in sorted({r["robot"] for r in rows}):
        mine = [r for r in rows if r["robot"] == robot]
        ok = [r for r in mine if r.get("status") == "ok" and r.get("j_star") is not None]
        first = sum(r["first_passed"] for r in ok)
        commits = sorted({r["commit"] for r in mine})
        print(f"## {robot}: {len(mine)} gaits, {len(ok)} certified ({', '.join(commits)}, {mine[0]['date']})")
        print(f"first batches passed: {first} of {len(ok)} ({100.0 * first / max(1, len(ok)):.1f} %); "
              f"attempts max {max((r['attempts'] for r in ok), default=0)}")
        print(f"ties in Ĵ (pairs to 1e-9): {_ties({r['label']: r['estimate'] for r in ok})}")
        ratio = [r["ratio"] for r in ok if r.get("ratio")]
        yard = [r["yardsticks"] for r in ok]
        if ratio:
            print(f"physics / statement's minimum: median {np.median(ratio):.2f}, max {max(ratio):.2f}; "
                  f"CPU yardsticks median {np.median(yard):.1f}, max {max(yard):.1f}")
        by_gait: dict[str, list[float]] = {}
        for r in ok:
            by_gait.setdefault(r["label"].split("_seed")[0], []).append(r["j_star"])
        for g, js in by_gait.items():
            if len(js) > 1:
                print(f"{g}: J* over {len(js)} seeds mean {np.mean(js):.4g}, coefficient of variation "
                      f"{100.0 * np.std(js, ddof=1) / np.mean(js):.1f} %")
        have = [r for r in ok if r["label"] in s50]
        if have:
            s = [s50[r["label"]] for r in have]
            print(f"Spearman with push s50: Ĵ {_rho([r['estimate'] for r in have], s)}, "
                  f"J* {_rho([r['j_star'] for r in have], s)}; Ĵ with J* "
                  f"{_rho([r['estimate'] for r in have], [r['j_star'] for r in have])}")
        old = [r for r in ok if r["label"] in before and before[r["label"]].get("j_star")]
        if old:
            q = np.array([r["j_star"] / before[r["label"]]["j_star"] for r in old])
            ob = [before[r["label"]] for r in old]
            print(f"before ({len(old)} gaits): first batches {sum(b['first_passed'] for b in ob)} of {len(ob)}; "
                  f"ties in Ĵ {_ties({r['label']: before[r['label']]['estimate'] for r in old})}; "
                  f"J* / J*_before median {np.median(q):.3f} (quartiles {np.quantile(q, 0.25):.3f}–"
                  f"{np.quantile(q, 0.75):.3f}, range {q.min():.3f}–{q.max():.3f})")
            hb = [before[r["label"]] for r in old if r["label"] in s50]
            if hb:
                s = [s50[r["label"]] for r in old if r["label"] in s50]
                est, js = [b["estimate"] for b in hb], [b["j_star"] for b in hb]
                print(f"before, Spearman with push s50: Ĵ {_rho(est, s)}, J* {_rho(js, s)}; Ĵ with J* {_rho(est, js)}")
        print()


def cmd_calibrate(args: argparse.Namespace) -> None:
    """Per pass probability of :data:`LEVELS`: the verification radius of each gait's fitted curve (``--explore-only``
    rows) against fresh pushes at the statement's settings uniform in a disk around it (``--dense``: rows with
    ``size``/``fell``, e.g. ``data/before_exo77.jsonl``): the gaits with a dense push that fell inside their
    radius (such a gait's batch of 154 would fail with probability at least 1 − (1 − 1/k)^154), the pooled falling share
    inside the radii and the first-batch pass rate it implies, (1 − V̄)^154 averaged over gaits by their own V̂ and
    pooled; and J*(level) / J*_before (``full`` of the dense rows)."""
    explore = {r["label"]: r for f in args.files for line in Path(f).read_text().splitlines()
               if line.strip() and (r := json.loads(line)).get("radius")}
    dense = {r["label"]: r for f in args.dense for line in Path(f).read_text().splitlines()
             if line.strip() and (r := json.loads(line)).get("size")}
    both = [k for k in explore if k in dense]
    print(f"{len(both)} gaits with both an exploration and dense pushes")
    for lv in LEVELS:
        key = f"{lv:g}"
        k_all = f_all = with_fall = covered = 0
        own, ratio = [], []
        for k in both:
            r = explore[k]["radius"][key]
            size, fell = np.asarray(dense[k]["size"]), np.asarray(dense[k]["fell"], dtype=bool)
            if r > size.max():
                continue
            covered += 1
            inside = size <= r
            n, f = int(inside.sum()), int((inside & fell).sum())
            k_all, f_all = k_all + n, f_all + f
            with_fall += f > 0
            own.append((1.0 - f / max(n, 1)) ** 154)
            full = dense[k].get("full") or {}
            if full.get("j_star"):
                ratio.append(r / full["j_star"])
        v = f_all / max(k_all, 1)
        print(f"level {key}: {covered} gaits covered; gaits with a fall inside r_v {with_fall}; pooled falls "
              f"{f_all}/{k_all} (V {v:.5f}, pass ≈ {(1 - v) ** 154:.3f}); mean own (1 − V̂)^154 "
              f"{np.mean(own) if own else float('nan'):.3f}; r_v / J*_before median "
              f"{np.median(ratio) if ratio else float('nan'):.3f} (quartiles "
              f"{np.quantile(ratio, 0.25) if ratio else float('nan'):.3f}–"
              f"{np.quantile(ratio, 0.75) if ratio else float('nan'):.3f})")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("run")
    r.add_argument("--robot", required=True)
    r.add_argument("--from-jsonl", default="")
    r.add_argument("--grid", type=int, default=12)
    r.add_argument("--gait", nargs="*", default=[])
    r.add_argument("--domains", default="flat", choices=("flat", "multicontact"))
    r.add_argument("--seed", type=int, default=0)
    r.add_argument("--seeds", type=int, default=1, help="certify each gait with seeds seed … seed + seeds − 1")
    r.add_argument("--push", default="{}", help="JSON overrides of certify.push")
    r.add_argument("--samples", action="store_true", help="also every push of the certificate: impulse, fell, round "
                   "(for fitting other fall models offline)")
    r.add_argument("--explore-only", action="store_true", help="the exploration alone, and the verification "
                   "radius at each pass probability of LEVELS")
    r.add_argument("--workers", type=int, default=2)
    r.add_argument("--out", required=True)
    p = sub.add_parser("report")
    p.add_argument("files", nargs="+")
    p.add_argument("--before", nargs="*", default=[])
    p.add_argument("--s50", default="")
    c = sub.add_parser("calibrate")
    c.add_argument("files", nargs="+")
    c.add_argument("--dense", nargs="+", required=True)
    args = ap.parse_args()
    {"run": cmd_run, "report": cmd_report, "calibrate": cmd_calibrate}[args.cmd](args)


if __name__ == "__main__":
    main()
