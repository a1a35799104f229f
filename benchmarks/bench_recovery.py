"""Does the push certificate hold at the user's horizon? (issue 28, item 5.) Per robot, on ≥ 10 gaits: J* with the
recovery criterion (a pushed walk fails if it falls within the pushed step and ``push.steps`` more, or is not back in
its orbit's neighbourhood at their end; ``--radii``: the ``push.recovery_radius`` values ν compared, ``none`` = falls
only), then the validation's pushes (``validate.trials``, 20 steps after): the falls among pushes with |J| < J* within
20 steps (the user's horizon; goal ≤ ε with the upper 95 % bound ≤ 5 %, pooled per robot), the same check at the
certificate's own horizon, and on exo J*'s Spearman ρ with the push that fells half (push s₅₀; today 0.646 on 77
study gaits).

Gaits: ``--from-jsonl`` (exo: the 77 unique gaits of the two paper-size studies, regenerated from their parameters
in ``benchmarks/data/bench_predict_exo.jsonl``: generation is a function of robot, parameters and configuration) or
``--grid N`` (N points of the robot's action-space grid, evenly spaced in grid order). Each gait, in one worker
process: generated cold, walked to the step cap; if it walks, its fixed point; J* for each ν (one seed, the default
sequential estimator; the pushed walks of one J are simulated once and reused by every ν: the map is deterministic);
the validation pushes. One JSON line per gait in ``--out`` (a gait already there is skipped: a killed run continues).

    python benchmarks/bench_recovery.py run --robot exo --from-jsonl benchmarks/data/bench_predict_exo.jsonl \\
        --out benchmarks/data/recovery_exo.jsonl [--limit N] [--workers 2] [--radii none,0.3]
    python benchmarks/bench_recovery.py run --robot examples/atalante.toml --grid 12 --out …
    python benchmarks/bench_recovery.py report FILE.jsonl [FILE.jsonl …]
"""

from __future__ import annotations

import argparse
import json
import math
import os
import subprocess
import time
from concurrent.futures import ProcessPoolExecutor, as_completed
from datetime import date
from pathlib import Path
from typing import Any

import numpy as np

REPO = Path(__file__).resolve().parents[1]


def _radii(text: str) -> list[float | None]:
    return [None if t == "none" else float(t) for t in text.split(",")]


def _key(r: float | None) -> str:
    return "none" if r is None else f"{r:g}"


def grid_params(robot_name: str, n: int, domains: str) -> list[dict[str, float]]:
    """n points of the robot's action-space grid, evenly spaced in grid order (the studies' grid)."""
    from robustgait.io.robotfile import load_robot
    from robustgait.learn.space import ActionSpace

    space = ActionSpace.from_robot(load_robot(robot_name), domains)
    idx = np.unique(np.linspace(0, space.size - 1, n).round().astype(int))
    return [space.value(int(i)) for i in idx]


class MemoPushes:
    """The push map's raw outcome per impulse — the step it fell in (0: none) and its scaled distance from the orbit
    at the end — computed once per J (the map is deterministic) and shared by the maps of every radius ν."""

    def __init__(self, pm: Any):
        self.pm, self.cache = pm, {}  # type: ignore[var-annotated]

    def outcomes(self, j: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        from robustgait.certificate.push import push_phase

        keys = [row.tobytes() for row in np.ascontiguousarray(j, dtype="<f8")]
        todo = [i for i, k in enumerate(keys) if k not in self.cache]
        if todo:
            jj = j[todo]
            _, _, fall, dist = self.pm.walk(jj, push_phase(jj, *self.pm.validate.push_phase))
            for i, f, d in zip(todo, fall, dist, strict=True):
                self.cache[keys[i]] = (int(f), float(d))
        out = [self.cache[k] for k in keys]
        return np.array([o[0] for o in out]), np.array([o[1] for o in out])

    def map(self, radius: float | None, scatter: float, multiple: float) -> Any:
        limit = math.inf if radius is None else max(radius, multiple * scatter)

        def P(j: np.ndarray, progress: Any = None) -> np.ndarray:
            fall, dist = self.outcomes(np.atleast_2d(j))
            out = np.zeros((j.shape[0], 2))
            with np.errstate(invalid="ignore"):
                out[(fall > 0) | ~(dist <= limit)] = np.nan
            return out
        return P


def run_gait(job: dict[str, Any]) -> dict[str, Any]:
    """One gait (module docstring)."""
    from dataclasses import replace

    from robustgait.certificate.estimators import certify_map_sequential
    from robustgait.certificate.poincare import FixedPointFailure, settle
    from robustgait.certificate.push import PushMap
    from robustgait.config import CertifyConfig, Config, GaitParams, SimConfig, ValidateConfig
    from robustgait.gaitgen import GaitGenerator
    from robustgait.io.gaitfile import save_gait
    from robustgait.io.robotfile import load_robot
    from robustgait.sim import walk
    from robustgait.sim.trials import simulate_trials
    from robustgait.study.validate import _orbitless_start
    from robustgait.validate import disturbances as dist
    from robustgait.validate.run import Validator
    from robustgait.validate.stats import logistic_fit

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
    w = walk(robot, gait, replace(sim, step_cap=cfg.sim.step_cap))
    out["steps_taken"] = w.steps_taken
    if w.steps_taken < cfg.sim.step_cap:
        return out | {"status": "fell", "reason": w.fall_reason}
    base = CertifyConfig()
    if job.get("push_steps"):  # a longer certificate horizon: the pushed step and N more
        base = replace(base, push=replace(base.push, steps=int(job["push_steps"])))
    raw_push = replace(base.push, recovery_radius=0.0, recovery_scatter=0.0)  # distances only: radii applied below
    pmap, found = settle(robot, gait, base, sim)  # the stride map when the step map has no orbit (T1)
    with pmap:
        if isinstance(found, FixedPointFailure):
            return out | {"status": found.status, "reason": str(found)}
        fp = found
        out["map"] = pmap.kind
        vcfg = ValidateConfig()
        pm = PushMap(pmap.engine, fp, vcfg, raw_push)
        assert pm.band is not None
        memo = MemoPushes(pm)
        out["scatter"] = pm.band.scatter
        out["fixed_point_steps"] = fp.steps
        certs = {}
        for r in job["radii"]:
            t1 = time.perf_counter()
            before = pm.physics_steps
            c = certify_map_sequential(memo.map(r, pm.band.scatter, base.push.recovery_scatter), np.zeros(2), base)
            certs[_key(r)] = {"j_star": c.r_star, "attained": c.attained, "samples": c.n_samples,
                              "verified": c.violation_bound < 1.0, "seconds": time.perf_counter() - t1,
                              "new_physics": pm.physics_steps - before}
        out["certificates"] = certs
        # the validation's pushes, 20 steps after, with the section states to apply the criterion at the horizon
        _, ref = _orbitless_start(robot, gait, base)
        with Validator(robot, gait, vcfg, certificate=ref, sim=sim, start=fp) as v:
            d = dist.draw("push", vcfg.trials, vcfg, robot)
            n_steps = v.period + vcfg.steps_after
            nq = robot.model.nq
            sections = np.full((d.size.size, n_steps, nq + robot.model.nv), np.nan)
            ok, _, fall_step, _, _ = simulate_trials(
                v.engine, np.tile(fp.qpos, (d.size.size, 1)), np.tile(fp.qvel, (d.size.size, 1)), n_steps,
                v.period, v.inputs_for("push", d), first_at=v.nominal_at, sections=sections)
            h = 1 + base.push.steps
            end = sections[:, h - 1]
            standing = np.isfinite(end).all(axis=1)
            distance_h = np.full(d.size.size, np.nan)
            distance_h[standing] = pm.band.distance(end[standing, :nq], end[standing, nq:])
    fit = logistic_fit(d.size, ok)
    out.update(status="ok", pushes={"size": d.size.tolist(), "fall_step": fall_step.tolist(),
                                    "distance_h": [None if not math.isfinite(x) else x for x in distance_h]},
               s50=fit.s50 if fit.in_range else None, horizon=h, seconds=time.perf_counter() - t0)
    return out


def cmd_run(args: argparse.Namespace) -> None:
    out = Path(args.out)
    done = set()
    if out.exists():
        done = {json.loads(line)["label"] for line in out.read_text().splitlines() if line.strip()}
    if args.from_jsonl:
        rows = [json.loads(line) for line in Path(args.from_jsonl).read_text().splitlines() if line.strip()]
        params = [{k: r["params"][k] for k in ("step_length", "step_duration", "step_width", "step_height")}
                  for r in rows]
    else:
        params = grid_params(args.robot, args.grid, "flat")
    if args.only_ok:
        certified = [json.loads(line) for line in Path(args.only_ok).read_text().splitlines() if line.strip()]
        params = [r["params"] for r in certified if r.get("status") == "ok"]
    if args.limit:
        params = [params[i] for i in np.unique(np.linspace(0, len(params) - 1, args.limit).round().astype(int))]
    jobs = []
    for p in params:
        label = "L{step_length:g}_T{step_duration:g}_W{step_width:g}_H{step_height:g}".format(**p)
        if label not in done:
            jobs.append({"robot": args.robot, "label": label, "params": p, "radii": _radii(args.radii),
                         "push_steps": args.push_steps, "gait_dir": args.gait_dir})
    if args.gait_dir:
        Path(args.gait_dir).mkdir(parents=True, exist_ok=True)
    commit = subprocess.run(["git", "-C", str(REPO), "rev-parse", "--short", "HEAD"], capture_output=True,
                            text=True).stdout.strip()
    print(f"# bench_recovery run {date.today()} commit {commit} robot {args.robot}: {len(jobs)} gaits to do "
          f"({len(done)} done), {args.workers} workers", flush=True)
    t0 = time.perf_counter()
    with ProcessPoolExecutor(args.workers) as pool, out.open("a") as fh:
        futures = {pool.submit(run_gait, j): j["label"] for j in jobs}
        for k, f in enumerate(as_completed(futures), 1):
            try:
                row = f.result()
            except Exception as exc:  # a gait that breaks the bench is a row, not a crash of the run
                row = {"label": futures[f], "status": "error", "reason": f"{type(exc).__name__}: {exc}"}
            row["commit"] = commit
            fh.write(json.dumps(row) + "\n")
            fh.flush()
            js = {k2: round(v["j_star"], 2) for k2, v in row.get("certificates", {}).items()}
            print(f"[{k}/{len(jobs)} {time.perf_counter() - t0:.0f} s] {row['label']}: {row['status']} {js}",
                  flush=True)


def cmd_report(args: argparse.Namespace) -> None:
    from robustgait.config import PushConfig
    from robustgait.validate.stats import Rate, spearman

    eps = 0.02
    push = PushConfig()
    for path in args.files:
        rows = [json.loads(line) for line in Path(path).read_text().splitlines() if line.strip()]
        ok = [r for r in rows if r.get("status") == "ok"]
        statuses: dict[str, int] = {}
        for r in rows:
            statuses[r["status"]] = statuses.get(r["status"], 0) + 1
        robot = rows[0].get("robot", "?") if rows else "?"
        print(f"## {path}: robot {robot}, {len(rows)} gaits ({', '.join(f'{v} {k}' for k, v in statuses.items())})")
        print("| radius ν | median J* [N s] | falls within 20 steps among |J| < J* (95 % CI) | failures at the "
              "certificate's horizon (fall or off the orbit) among |J| < J* | ρ(J*, push s₅₀) (p, n) |")
        print("|---|---|---|---|---|")
        keys = list(ok[0]["certificates"]) if ok else []
        for key in keys:
            radius = None if key == "none" else float(key)
            k20 = n20 = kh = 0
            js, s50 = [], []
            for r in ok:
                c = r["certificates"][key]
                size = np.asarray(r["pushes"]["size"])
                fall = np.asarray(r["pushes"]["fall_step"])
                dh = np.array([np.nan if x is None else x for x in r["pushes"]["distance_h"]])
                below = size < c["j_star"]
                n20 += int(below.sum())
                k20 += int(((fall > 0) & below).sum())
                limit = math.inf if radius is None else max(radius, push.recovery_scatter * r["scatter"])
                with np.errstate(invalid="ignore"):
                    fail_h = ((fall > 0) & (fall <= r["horizon"])) | ((fall == 0) | (fall > r["horizon"])) & (
                        dh > limit)
                kh += int((fail_h & below).sum())
                js.append(c["j_star"])
                s50.append(r["s50"] if r["s50"] is not None else np.nan)
            rate, rate_h = Rate.of(k20, n20), Rate.of(kh, n20)
            x, y = np.asarray(js), np.asarray(s50)
            good = np.isfinite(y)
            rho = spearman(x[good], y[good], "J*", "push s50") if good.sum() > 2 else None
            rho_text = "—" if rho is None or rho.rho is None else f"{rho.rho:.3f} (p {rho.p:.1g}, n {rho.n})"
            verdict = "met" if rate.high <= 0.05 and rate.rate <= eps else "not met"
            print(f"| {key} | {np.median(x):.2f} | {k20}/{n20} = {100 * rate.rate:.1f} % [{100 * rate.low:.1f}, "
                  f"{100 * rate.high:.1f}] ({verdict}) | {kh}/{n20} = {100 * rate_h.rate:.1f} % | {rho_text} |")
        if args.stored:  # the study gaits' stored s50 and J* (bench_predict.py): today's ranking on the same gaits
            stored = {}
            for line in Path(args.stored).read_text().splitlines():
                if line.strip():
                    row = json.loads(line)
                    stored[row["label"]] = row
            both = [r for r in ok if r["label"] in stored and stored[r["label"]]["kinds"]["push"]["s50"] is not None]
            s50 = [stored[r["label"]]["kinds"]["push"]["s50"] for r in both]
            if len(both) < 3:
                print(f"\nagainst the stored push s50 of {args.stored}: {len(both)} gaits in common")
                continue
            old = spearman([stored[r["label"]]["push_cert"]["j_star"] for r in both], s50, "J*", "push s50")
            print(f"\nagainst the stored push s50 of {args.stored} ({len(both)} gaits): the stored J* ρ {old.rho:.3f} "
                  f"(p {old.p:.1g})" + "".join(
                      f"; J* ν = {key} ρ {sp.rho:.3f} (p {sp.p:.1g})" for key in keys
                      for sp in [spearman([r["certificates"][key]["j_star"] for r in both], s50, "J*", "push s50")]))
        secs = [r["seconds"] for r in ok]
        if secs:
            print(f"\nper gait: {np.median(secs):.0f} s median (generation, walk, fixed point, J* per ν, "
                  f"{len(ok[0]['pushes']['size'])} validation pushes)\n")


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = p.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("run")
    r.add_argument("--robot", default="exo")
    r.add_argument("--from-jsonl")
    r.add_argument("--grid", type=int, default=12)
    r.add_argument("--limit", type=int, default=0)
    r.add_argument("--radii", default="none,0.3")
    r.add_argument("--push-steps", type=int, default=0, help="certify.push.steps (0: the default, 3)")
    r.add_argument("--only-ok", help="a result file of this bench: run only the gaits certified there")
    r.add_argument("--workers", type=int, default=min(2, os.cpu_count() or 1))
    r.add_argument("--out", required=True)
    r.add_argument("--gait-dir")
    r.set_defaults(func=cmd_run)
    rep = sub.add_parser("report")
    rep.add_argument("files", nargs="+")
    rep.add_argument("--stored", help="bench_predict.py rows (benchmarks/data/bench_predict_exo.jsonl): ρ against "
                     "their push s50, and their stored J*'s")
    rep.set_defaults(func=cmd_report)
    args = p.parse_args()
    args.func(args)


if __name__ == "__main__":
    main()
