"""Does the verdict agree with the simulation, and does the push certificate hold at the user's horizon?

Per robot, gait by gait (``--from-jsonl``: the study gaits of
``benchmarks/experiments/predictors/data/exo.jsonl``, regenerated
from their parameters — generation is a function of robot, parameters and configuration; ``--grid N``: N points of the
robot's flat-foot action-space grid, evenly spaced in grid order), in worker processes:

1. the gait generated cold, then walked 300 steps undisturbed (``--steps``): does it walk?
2. certified with the shipped defaults (:func:`robustgait.certify_gait`): the verdict (certified, or refused with its
   status and reason), the orbit (period, σ), J*, the certificate's physics steps and seconds;
3. the validation's pushes (``--trials``, default 100; 20 steps after; at ``--validate-timestep``, the reference
   physics step, when given) from x* — the certificate's, or for a refused
   gait the orbit search's x* when it settled, else its initial switching state — : push s₅₀ (the impulse that fells
   half, logistic fit), and for a certified gait the falls within 20 steps among the pushes with |J| < J*.

``report``: the refusal table (every gait: walks 300?, verdict, J*, push s₅₀) and its goal — no gait that walks 300
steps and survives the median push at least as well as the median certified gait is refused —, the share certified,
the promise at 20 steps pooled over the certified gaits (falls among |J| < J*: rate and Wilson 95 % interval, goal
upper bound ≤ 5 %), J*'s Spearman ρ with push s₅₀ (fresh, and with ``--stored`` the study gaits' stored 200-push
s₅₀), and the median certificate cost.

    python benchmarks/experiments/recovery_horizon/run.py run --robot exo --from-jsonl \\
        benchmarks/experiments/predictors/data/exo.jsonl \\
        --out benchmarks/experiments/recovery_horizon/data/exo.jsonl [--limit N] [--workers 2]
    python benchmarks/experiments/recovery_horizon/run.py run --robot robots/atalante/spec.toml --grid 20 --out …
    python benchmarks/experiments/recovery_horizon/run.py report FILE.jsonl [--stored \\
        benchmarks/experiments/predictors/data/exo.jsonl]

A killed run continues: a gait already in ``--out`` is skipped. ``recheck FILE --robot R [--status unstable]``
certifies the rows of those statuses again with the current code (a change of the verdict's rule that leaves the
other rows as they are), keeping their walks and validation pushes; each records what it was (``recheck``).

``scan``: how the recovery rule was chosen. For a gait, ``--pushes`` pushes uniform in the disk of radius ``--r-max``
(seeded directions, the certificate's hashed phases) from the orbit search's x*, each walked ``--horizon`` steps
after the pushed one whatever happens, recording after every step the band distance d = the largest |z_i − c_i| over
the coordinates outside κ σ_i of the orbit's band (0 when none: a state is in the band of floor ν iff d ≤ ν).
``scan-report``: per rule (ν, m) the pushes called recovered (in the band m consecutive steps) that fell later, the
survivors never called recovered, and the steps a push costs against the pushed step and 3 more; per m the smallest
ν at which a push that fell later would have been called recovered.

    python benchmarks/experiments/recovery_horizon/run.py scan --robot exo --gait tests/data/exo_gait.json \\
        --r-max 45 --out scan.json
    python benchmarks/experiments/recovery_horizon/run.py scan-report scan_exo.json scan_atalante.json scan_t1.json
"""

from __future__ import annotations

import os
import sys

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse
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


def certify_fields(robot: Any, gait: Any, sim: Any) -> tuple[Any, dict[str, Any]]:
    """The gait certified with the shipped defaults, and the row's certificate fields (module docstring, 2)."""
    from robustgait.certificate.certify import certify_gait
    from robustgait.config import CertifyConfig

    t1 = time.perf_counter()
    gc = certify_gait(robot, gait, CertifyConfig(), sim)
    o = gc.orbit
    c = gc.certificate
    verify = [r for r in c.rounds if r.kind == "verify"] if c is not None else []
    return gc, dict(status=str(gc.status), reason=gc.reason, j_star=gc.value if gc.ok else None,
                    estimate=c.estimate if c is not None else None, attempts=len(verify),
                    first_passed=bool(verify and verify[0].passed),
                    certify_seconds=time.perf_counter() - t1, physics_steps=gc.physics_steps,
                    orbit_physics_steps=gc.orbit_physics_steps,
                    samples=gc.certificate.n_samples if gc.certificate is not None else 0,
                    orbit={"status": str(o.status), "period": o.period, "sigma": o.sigma, "settled": o.settled,
                           "steps": o.steps, "probe": o.probe.impulse if o.probe is not None else None}
                    if o is not None else None)


def recheck_gait(job: dict[str, Any]) -> dict[str, Any]:
    """A row's gait regenerated and certified again with the current code; the row's walk and validation kept."""
    from robustgait.config import Config, GaitParams, SimConfig
    from robustgait.gaitgen import GaitGenerator
    from robustgait.io.robotfile import load_robot

    os.nice(5)
    robot = load_robot(job["robot"])
    res = GaitGenerator(robot, Config().generate).solve(GaitParams(**job["row"]["params"]))
    if res.gait is None:
        return {"status": "generation_failed", "reason": res.reason}
    return certify_fields(robot, res.gait, SimConfig(n_threads=1))[1]


def cmd_recheck(args: argparse.Namespace) -> None:
    """Certify again, with the current code, the rows of ``FILE`` whose status is in ``--status``; each keeps its walk
    and validation pushes (they do not depend on the verdict) and records what it was (``recheck``). The file is
    rewritten once every row is done."""
    path = Path(args.file)
    rows = load_rows(str(path))
    wanted = set(args.status.split(","))
    todo = [i for i, r in enumerate(rows) if r.get("status") in wanted and "params" in r]
    commit = git_commit()
    print(f"# recovery_horizon recheck {date.today()} commit {commit}: {len(todo)} rows of {path} ({args.status})",
          flush=True)
    with ProcessPoolExecutor(args.workers) as pool:
        futures = {pool.submit(recheck_gait, {"robot": args.robot, "row": rows[i]}): i for i in todo}
        for f in as_completed(futures):
            i = futures[f]
            before = {k: rows[i].get(k) for k in ("status", "reason", "j_star", "commit", "date")}
            rows[i].update(f.result())
            rows[i]["recheck"] = {"commit": commit, "date": str(date.today()), "before": before}
            print(f"{rows[i]['label']}: {before['status']} -> {rows[i]['status']}"
                  + ("" if rows[i].get("j_star") is None else f" J* {rows[i]['j_star']:.3f}"), flush=True)
    tmp = path.with_suffix(".tmp")
    tmp.write_text("".join(json.dumps(r) + "\n" for r in rows))
    tmp.replace(path)


def run_gait(job: dict[str, Any]) -> dict[str, Any]:
    """One gait (module docstring)."""
    from dataclasses import replace

    from robustgait.config import CertifyConfig, Config, GaitParams, SimConfig, ValidateConfig
    from robustgait.gaitgen import GaitGenerator
    from robustgait.io.gaitfile import save_gait
    from robustgait.io.robotfile import load_robot
    from robustgait.sim import walk
    from robustgait.study.validate import orbitless_start
    from robustgait.validate.run import Validator
    from robustgait.validate.stats import logistic_fit

    os.nice(5)
    t0 = time.perf_counter()
    robot = load_robot(job["robot"])
    cfg = Config()
    sim = SimConfig(n_threads=1)
    out: dict[str, Any] = {"label": job["label"], "robot": robot.name, "params": job["params"]}
    res = GaitGenerator(robot, cfg.generate).solve(GaitParams(**job["params"]))
    if res.gait is None:
        return out | {"status": "generation_failed", "reason": res.reason}
    gait = res.gait
    if job.get("gait_dir"):
        save_gait(gait, Path(job["gait_dir"]) / f"{job['label']}.json")
    w = walk(robot, gait, replace(sim, step_cap=job["steps"]))
    out.update(steps_taken=w.steps_taken, fall=w.fall_reason)
    gc, fields = certify_fields(robot, gait, sim)
    out.update(fields)
    o = gc.orbit
    # the validation's pushes: from the certificate's x*, or the orbit's, or the gait's first switching state
    vcfg = ValidateConfig(trials=job["trials"])
    start, ref = orbitless_start(robot, gait, CertifyConfig())
    certificate: Any = gc if gc.ok else ref
    if not gc.ok and o is not None and o.qpos is not None:
        start = o.fixed_point("heading")
    # validated at the reference timestep (--validate-timestep), from the same states: the promise at 20 steps is
    # the physics', not the certifying timestep's
    fine = robot if not job.get("validate_timestep") else robot.at_timestep(job["validate_timestep"],
                                                                            robot.spec.stable_pd)
    out["validate_timestep"] = fine.dt
    try:
        with Validator(fine, gait, vcfg, sim=sim, certificate=certificate,
                       start=None if gc.ok else start) as v:
            kind = v.run("push")
    except Exception as exc:  # a gait the validation refuses (falls in its first step) is a row
        return out | {"validate_error": f"{type(exc).__name__}: {exc}", "seconds": time.perf_counter() - t0}
    fit = logistic_fit(kind.size, kind.success)
    out.update(pushes={"size": kind.size.tolist(), "fall_step": kind.fall_step.tolist()},
               s50=fit.s50 if fit.in_range else None, survived=float(kind.success.mean()),
               seconds=time.perf_counter() - t0)
    return out


def cmd_scan(args: argparse.Namespace) -> None:
    import math

    from robustgait.certificate import Walking, find_orbit
    from robustgait.certificate.band import band_coordinates
    from robustgait.certificate.push import push_phase, push_series
    from robustgait.config import CertifyConfig, SimConfig, ValidateConfig
    from robustgait.io.gaitfile import load_gait
    from robustgait.io.robotfile import load_robot
    from robustgait.rotations import quat_to_mat
    from robustgait.sim.factory import make_engine
    from robustgait.sim.trials import pushed_first_step, simulate_trials

    robot = load_robot(args.robot)
    gait = load_gait(args.gait, robot)
    cfg, vcfg = CertifyConfig(), ValidateConfig()
    engine = make_engine(robot, gait, SimConfig())
    t0 = time.perf_counter()
    orbit = find_orbit(Walking(robot, gait, engine=engine), cfg)
    if orbit.qpos is None or orbit.qvel is None or orbit.band is None:
        raise SystemExit(f"no orbit to push from: {orbit.describe()}")
    rng = np.random.default_rng(args.seed)
    r = args.r_max * np.sqrt(rng.uniform(size=args.pushes))
    th = rng.uniform(0.0, 2.0 * math.pi, args.pushes)
    j = np.column_stack([r * np.cos(th), r * np.sin(th)])
    rot = quat_to_mat(orbit.qpos[3:7])
    wrench = push_series(j, push_phase(j, *vcfg.push_phase), math.atan2(rot[1, 0], rot[0, 0]), vcfg.push_duration,
                         gait.step_duration, robot.dt, sum(engine.horizons))
    n_steps, nq = 1 + args.horizon, robot.model.nq
    sections = np.full((args.pushes, n_steps, nq + robot.model.nv), np.nan)
    _, _, fall_step, _, _ = simulate_trials(engine, np.tile(orbit.qpos, (args.pushes, 1)),
                                            np.tile(orbit.qvel, (args.pushes, 1)), n_steps, n_steps,
                                            pushed_first_step(engine, wrench), first_at=0, sections=sections)
    engine.close()
    band = orbit.band
    d = np.full((args.pushes, n_steps), np.nan)
    for s in range(n_steps):
        ok = np.isfinite(sections[:, s]).all(axis=1)
        if ok.any():
            z = band_coordinates(robot, sections[ok, s, :nq], sections[ok, s, nq:])
            d[ok, s] = band.floor_needed(z, s + 1)
    commit = git_commit()
    Path(args.out).write_text(json.dumps({
        "robot": robot.name, "gait": str(args.gait), "orbit": orbit.describe(), "r_max": args.r_max,
        "horizon": args.horizon, "impulse": j.tolist(), "fall_step": fall_step.tolist(),
        "distance": [[None if not math.isfinite(x) else round(float(x), 6) for x in row] for row in d],
        "seconds": time.perf_counter() - t0, "commit": commit, "date": str(date.today())}))
    print(f"{args.out}: {args.pushes} pushes, {int((fall_step > 0).sum())} fell, {time.perf_counter() - t0:.0f} s")


def cmd_scan_report(args: argparse.Namespace) -> None:
    radii, steps = (0.02, 0.03, 0.04, 0.05, 0.1), (1, 2, 3)
    print("| scan | ν / m | recovered, then fell | survivors never recovered | steps a push costs (against 1 + 3) |")
    print("|---|---|---|---|---|")
    for path in args.files:
        s = json.loads(Path(path).read_text())
        d = np.array([[np.nan if x is None else x for x in row] for row in s["distance"]])
        fall = np.asarray(s["fall_step"])
        n, h = d.shape
        before = np.where(fall > 0, np.minimum(fall, 4), 4).mean()
        for m in steps:
            for nu in radii:
                with np.errstate(invalid="ignore"):
                    inside = d <= nu
                rec = np.zeros(n, dtype=int)
                for i in range(n):
                    run = 0
                    for k in range(h):
                        run = run + 1 if inside[i, k] else 0
                        if run >= m:
                            rec[i] = k + 1
                            break
                false = int(((rec > 0) & (fall > rec)).sum())
                never = int(((rec == 0) & (fall == 0)).sum())
                cost = np.where(rec > 0, rec, np.where(fall > 0, fall, h)).mean()
                print(f"| {Path(path).stem} ({s['robot']}) | {nu:g} / {m} | {false} | {never} | "
                      f"{cost / before:.2f}× |")
        for m in steps:  # the smallest ν at which a push that fell later is called recovered
            crit = []
            for i in np.flatnonzero(fall > 1):
                runs = [np.max(d[i, k:k + m]) for k in range(0, fall[i] - m) if np.isfinite(d[i, k:k + m]).all()]
                if runs:
                    crit.append(min(runs))
            low = ", ".join(f"{c:.3f}" for c in sorted(crit)[:3])
            print(f"| {Path(path).stem} | m = {m}: the smallest ν calling a later fall recovered | {low} | | |")


def cmd_run(args: argparse.Namespace) -> None:
    out = Path(args.out)
    done = set()
    if out.exists():
        done = {json.loads(line)["label"] for line in out.read_text().splitlines() if line.strip()}
    if args.from_jsonl:
        rows = [json.loads(line) for line in Path(args.from_jsonl).read_text().splitlines() if line.strip()]
        params = [{k: r["params"][k] for k in PARAMS} for r in rows]
    else:
        params = grid_params(args.robot, args.grid, "flat")
    if args.limit:
        params = [params[i] for i in np.unique(np.linspace(0, len(params) - 1, args.limit).round().astype(int))]
    jobs = []
    for p in params:
        label = "L{step_length:g}_T{step_duration:g}_W{step_width:g}_H{step_height:g}".format(**p)
        if label not in done:
            jobs.append({"robot": args.robot, "label": label, "params": p, "steps": args.steps,
                         "trials": args.trials, "gait_dir": args.gait_dir,
                         "validate_timestep": args.validate_timestep})
    if args.gait_dir:
        Path(args.gait_dir).mkdir(parents=True, exist_ok=True)
    commit = git_commit()
    print(f"# recovery_horizon run {date.today()} commit {commit} robot {args.robot}: {len(jobs)} gaits to do "
          f"({len(done)} done), {args.workers} workers", flush=True)
    t0 = time.perf_counter()
    with ProcessPoolExecutor(args.workers) as pool, out.open("a") as fh:
        futures = {pool.submit(run_gait, j): j["label"] for j in jobs}
        for k, f in enumerate(as_completed(futures), 1):
            try:
                row = f.result()
            except Exception as exc:  # a gait that breaks the bench is a row, not a crash of the run
                row = {"label": futures[f], "status": "error", "reason": f"{type(exc).__name__}: {exc}"}
            row["commit"], row["date"] = commit, str(date.today())
            fh.write(json.dumps(row) + "\n")
            fh.flush()
            js = "" if row.get("j_star") is None else f" J* {row['j_star']:.2f}"
            s50 = "" if row.get("s50") is None else f" s50 {row['s50']:.2f}"
            print(f"[{k}/{len(jobs)} {time.perf_counter() - t0:.0f} s] {row['label']}: {row['status']}{js}{s50} "
                  f"(walked {row.get('steps_taken')})", flush=True)


def load_rows(path: str) -> list[dict[str, Any]]:
    return [json.loads(line) for line in Path(path).read_text().splitlines() if line.strip()]


def cmd_report(args: argparse.Namespace) -> None:
    from robustgait.validate.stats import Rate, spearman

    for path in args.files:
        rows = sorted(load_rows(path), key=lambda r: r["label"])
        robot = rows[0].get("robot", "?") if rows else "?"
        commits = sorted({r.get("commit", "?") for r in rows})
        print(f"## {path}: robot {robot}, {len(rows)} gaits (commit {', '.join(commits)})\n")
        print("| gait | walks 300 | verdict | period, σ | J* [N s] | push s₅₀ [N s] | survived |")
        print("|---|---|---|---|---|---|---|")
        for r in rows:
            o = r.get("orbit") or {}
            orbit = "" if o.get("sigma") is None else f"{o['period']}, {o['sigma']:.2g}"
            verdict = "certified" if r.get("status") == "ok" else f"refused: {r.get('status')}"
            walks = "" if r.get("steps_taken") is None else ("yes" if r["steps_taken"] >= 300 else
                                                                f"fell in {r['steps_taken'] + 1}")
            js = "" if r.get("j_star") is None else f"{r['j_star']:.2f}"
            s50 = "" if r.get("s50") is None else f"{r['s50']:.1f}"
            surv = "" if r.get("survived") is None else f"{100 * r['survived']:.0f} %"
            print(f"| {r['label']} | {walks} | {verdict} | {orbit} | {js} | {s50} | {surv} |")
        rechecked = [r for r in rows if "recheck" in r]
        if rechecked:
            commits_r = sorted({r["recheck"]["commit"] for r in rechecked})
            print(f"\ncertified again at commit {', '.join(commits_r)} (`recheck`; walks and pushes of the run): "
                  + "; ".join(f"{r['label']} {r['recheck']['before']['status']} → {r['status']}" for r in rechecked))
        ok = [r for r in rows if r.get("status") == "ok"]
        walked = [r for r in rows if (r.get("steps_taken") or 0) >= 300]
        refused_walking = [r for r in walked if r.get("status") != "ok"]
        s50_ok = [r["s50"] for r in ok if r.get("s50") is not None]
        median_ok = float(np.median(s50_ok)) if s50_ok else float("nan")
        wrong = [r for r in refused_walking if r.get("s50") is not None and r["s50"] >= median_ok]
        print(f"\ncertified {len(ok)} of {len(rows)} ({100 * len(ok) / max(len(rows), 1):.0f} %); walk 300 steps "
              f"{len(walked)}; refused while walking 300 steps: {len(refused_walking)} "
              f"({', '.join(sorted({str(r.get('status')) for r in refused_walking})) or 'none'}); "
              f"median push s₅₀ of the certified {median_ok:.2f} N s; refused gaits that walk 300 steps with s₅₀ ≥ "
              f"it: {len(wrong)} ({', '.join(r['label'] for r in wrong) or 'none'}) — "
              f"{'met' if not wrong else 'NOT met'}")
        k20 = n20 = 0
        for r in ok:
            if "pushes" not in r:
                continue
            size, fall = np.asarray(r["pushes"]["size"]), np.asarray(r["pushes"]["fall_step"])
            below = size < r["j_star"]
            n20 += int(below.sum())
            k20 += int(((fall > 0) & below).sum())
        rate = Rate.of(k20, n20)
        verdict = "met" if rate.high <= 0.05 else "NOT met"
        print(f"the promise at 20 steps: falls among pushes with |J| < J* on the {len(ok)} certified gaits: "
              f"{k20}/{n20} = {100 * rate.rate:.1f} % [{100 * rate.low:.1f}, {100 * rate.high:.1f}] ({verdict}: upper "
              "95 % bound ≤ 5 %)")
        both = [r for r in ok if r.get("s50") is not None]
        if len(both) > 2:
            sp = spearman([r["j_star"] for r in both], [r["s50"] for r in both], "J*", "push s50")
            print(f"J*'s Spearman ρ with push s₅₀ ({args_trials(rows)} pushes): {sp.rho:.3f} (p {sp.p:.2g}, n {sp.n})")
        if args.stored:
            stored = {r["label"]: r for r in load_rows(args.stored)}
            common = [r for r in ok if r["label"] in stored and stored[r["label"]]["kinds"]["push"]["s50"] is not None]
            if len(common) > 2:
                s50 = [stored[r["label"]]["kinds"]["push"]["s50"] for r in common]
                sp = spearman([r["j_star"] for r in common], s50, "J*", "push s50")
                old = spearman([stored[r["label"]]["push_cert"]["j_star"] for r in common], s50, "J*", "push s50")
                print(f"against the stored 200-push s₅₀ of {args.stored} ({len(common)} gaits): J* ρ {sp.rho:.3f} "
                      f"(p {sp.p:.2g}); the stored J* (its own study's certificate) ρ {old.rho:.3f} (p {old.p:.2g})")
        attempts = [r for r in ok if "first_passed" in r]
        if attempts:
            first = sum(r["first_passed"] for r in attempts)
            print(f"verification batches: the first passed on {first} of {len(attempts)} certified gaits "
                  f"({100 * first / len(attempts):.0f} %; goal ≥ 90 %)")
        with_estimate = [r for r in ok if r.get("estimate") is not None]
        if len(with_estimate) > 2:
            sp = spearman([r["estimate"] for r in with_estimate], [r["j_star"] for r in with_estimate], "Ĵ", "J*")
            print(f"the exploration's estimate Ĵ against the verified J*: Spearman ρ {sp.rho:.3f} (p {sp.p:.2g}, "
                  f"n {sp.n}; goal ≥ 0.9), J*/Ĵ median "
                  f"{np.median([r['j_star'] / r['estimate'] for r in with_estimate]):.3f}")
        phys = [r["physics_steps"] + r.get("orbit_physics_steps", 0) for r in ok]
        secs = [r["certify_seconds"] for r in ok]
        if phys:
            print(f"certificate cost on the certified gaits: median {np.median(phys) / 1e6:.2f} M physics steps, "
                  f"{np.median(secs):.1f} s (1 rollout thread, 2 workers)\n")


def args_trials(rows: list[dict[str, Any]]) -> int:
    sizes = [len(r["pushes"]["size"]) for r in rows if "pushes" in r]
    return max(sizes) if sizes else 0


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = p.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("run")
    r.add_argument("--robot", default="exo")
    r.add_argument("--from-jsonl")
    r.add_argument("--grid", type=int, default=12)
    r.add_argument("--limit", type=int, default=0)
    r.add_argument("--steps", type=int, default=300, help="the undisturbed walk")
    r.add_argument("--trials", type=int, default=100, help="validation pushes per gait")
    r.add_argument("--validate-timestep", type=float, default=0.0,
                   help="the validation's pushes at this physics step [s] (the reference; 0: the spec's own)")
    r.add_argument("--workers", type=int, default=min(2, os.cpu_count() or 1))
    r.add_argument("--out", required=True)
    r.add_argument("--gait-dir")
    r.set_defaults(func=cmd_run)
    rep = sub.add_parser("report")
    rep.add_argument("files", nargs="+")
    rep.add_argument("--stored", help="rows of experiments/predictors/run.py (its data/exo.jsonl): ρ against their "
                     "push s50, and their stored J*'s")
    rep.set_defaults(func=cmd_report)
    rc = sub.add_parser("recheck", help="certify some rows again with the current code (their walks and pushes kept)")
    rc.add_argument("file")
    rc.add_argument("--robot", required=True, help="the robot the rows were run on (as given to run)")
    rc.add_argument("--status", default="unstable", help="comma-separated statuses to recheck")
    rc.add_argument("--workers", type=int, default=min(2, os.cpu_count() or 1))
    rc.set_defaults(func=cmd_recheck)
    sc = sub.add_parser("scan")
    sc.add_argument("--robot", required=True)
    sc.add_argument("--gait", required=True)
    sc.add_argument("--r-max", type=float, required=True, help="radius of the disk of impulses [N s]")
    sc.add_argument("--pushes", type=int, default=300)
    sc.add_argument("--horizon", type=int, default=40, help="steps walked after the pushed one")
    sc.add_argument("--seed", type=int, default=0)
    sc.add_argument("--out", required=True)
    sc.set_defaults(func=cmd_scan)
    sr = sub.add_parser("scan-report")
    sr.add_argument("files", nargs="+")
    sr.set_defaults(func=cmd_scan_report)
    args = p.parse_args()
    args.func(args)


if __name__ == "__main__":
    main()
