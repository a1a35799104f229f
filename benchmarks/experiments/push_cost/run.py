"""What J*, the push certificate, costs and where a gait's pushes fail.

    python benchmarks/experiments/push_cost/run.py [all|push|push-gaits|push-sweep] [options]

* ``push``: on the default exo gait (or ``--exo-gait``), ``--seeds`` omega/ball certificates, then the push
  certificate J* for each ``--push-variants`` tuple (first round / exploration / exploration after a failed
  verification / ``push.horizon``, the steps after the pushed one; the first tuple is the shipped default
  certificate), same run: J*, samples, physics steps of the sampling and of the orbit search, wall, the orbit
  search's seconds, and the wall's ratio to omega/ball's.
* ``push-gaits`` (not part of ``all``): per gait of ``--gaits`` (a glob, e.g. the gait files of studies; ``--limit``
  of them evenly spaced), omega/ball, then J* for each ``--gait-variants``
  (``name:verify_chunk/horizon[/explore_after_failure]``; default: whole verification batches,
  ``sequential.verify_chunk = 0``, and as shipped, chunked; both at the shipped horizon of 20), one after the other in
  one worker: their wall-time and physics-step ratios and verification attempts; then each variant's check against
  the gaits' validation pushes in ``experiments/predictors/data/exo.jsonl`` (pushes ≤ J* that fell).
* ``push-sweep`` (not part of ``all``): where one exo gait's pushes fail (the default gait or ``--exo-gait``): its
  orbit (:func:`robustgait.certificate.search.find_orbit`), its J* (the default push certificate's estimator on the
  push map from the orbit's x* and band), the failures the estimator met below ``--near`` × J* (direction, phase,
  the step it fell in or that it was not back in the band, reason), and grids of outcomes over 24 directions × 13
  phases at ``--sweep`` × J* (``PushMap.walk`` at explicit phases: recovered, fell in step n, or not back in the band
  within ``push.horizon``).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import platform
import sys
import time
from dataclasses import replace
from pathlib import Path

import mujoco
import numpy as np

from robustgait import load_gait, load_robot
from robustgait.certificate import Walking, find_orbit
from robustgait.certificate.certify import certify_gait
from robustgait.certificate.estimators import certify_map_sequential
from robustgait.config import CertifyConfig, SequentialConfig, SimConfig
from robustgait.sim.factory import make_engine
from robustgait.validate.stats import wilson_interval

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))  # benchmarks/common.py
from common import REPO, add_gait_arguments, default_gaits, load_average


def cmd_push(args: argparse.Namespace) -> None:
    """J*'s cost against the omega/ball certificate on the same gait (the default exo gait or ``--exo-gait``), same
    run, per push round sizes and steps; J*'s spread over ``--seeds``."""
    from robustgait.config.certify import PushConfig

    sim = SimConfig(n_threads=args.threads)
    exo, gait = default_gaits(args)["exo"]
    variants = [tuple(int(v) for v in t.split("/")) for t in args.push_variants.split(",")]
    print(f"## push: {args.exo_gait or 'default exo gait'}, {args.seeds} seeds each, sequential; J* per (first round / "
          f"exploration / exploration after a failure / horizon: steps after the pushed one) against omega/ball; "
          f"{load_average()}")
    print("| certificate | J* or r* mean (range) | samples | physics steps: sampling (orbit search) | wall: mean "
          "(range) | orbit search: mean | ratio to omega/ball |")
    print("|---|---|---|---|---|---|---|")
    cfgs = [("omega/ball", CertifyConfig(disturbance="state"))] + [
        (f"push {f}/{e}/{a}/{k}", CertifyConfig(disturbance="push", push=PushConfig(horizon=k),
                                                sequential=SequentialConfig(first_round=f, explore=e,
                                                                            explore_after_failure=a)))
        for f, e, a, k in variants]
    base = None
    for name, cfg in cfgs:
        gcs = [certify_gait(exo, gait, replace(cfg, seed=s), sim) for s in range(args.seeds)]
        failed = [g for g in gcs if not g.ok]
        if failed:
            print(f"| {name} | {failed[0].status}: {failed[0].reason} | | | | | |", flush=True)
            continue
        r = np.array([g.value for g in gcs])
        wall = np.array([g.seconds["total"] for g in gcs])
        base = wall.mean() if base is None else base
        print(f"| {name} | {r.mean():.4g} ({r.min():.4g}–{r.max():.4g}) | "
              f"{np.mean([g.certificate.n_samples for g in gcs if g.certificate]):.0f} | "
              f"{np.mean([g.physics_steps for g in gcs]) / 1e6:.2f} M "
              f"({np.mean([g.orbit_physics_steps for g in gcs]) / 1e6:.2f} M) | {wall.mean():.1f} s ({wall.min():.1f}–"
              f"{wall.max():.1f}) | {np.mean([g.seconds['orbit'] for g in gcs]):.1f} s | {wall.mean() / base:.2f} |",
              flush=True)


def _variants(spec: str) -> list[tuple[str, int, int, int | None]]:
    """``name:chunk/horizon[/after],…`` → [(name, sequential.verify_chunk, push.horizon,
    sequential.explore_after_failure or None for the default)]."""
    out = []
    for item in spec.split(","):
        name, _, rest = item.partition(":")
        chunk, horizon, *after = rest.split("/")
        out.append((name, int(chunk), int(horizon), int(after[0]) if after else None))
    return out


def _push_gait(job: tuple[str, str]) -> dict:
    """omega/ball, then J* for each variant (``--gait-variants``): one gait, one thread, one after the other (a
    worker of ``push-gaits``)."""
    from robustgait.config.certify import PushConfig

    path, spec = job
    exo = load_robot("exo")
    gait = load_gait(path, exo)
    sim = SimConfig(n_threads=1)
    out: dict = {"gait": Path(path).parent.name}
    runs = [("omega", CertifyConfig(disturbance="state"))] + [
        (name, CertifyConfig(disturbance="push", push=PushConfig(horizon=horizon), sequential=SequentialConfig(
            verify_chunk=chunk, explore_after_failure=after)))
        for name, chunk, horizon, after in _variants(spec)]
    for name, cfg in runs:
        t0 = time.perf_counter()
        gc = certify_gait(exo, gait, cfg, sim)
        if not gc.ok:
            return {**out, "error": f"{name}: {gc.status}"}
        out[name] = {"r_star": gc.value, "seconds": time.perf_counter() - t0, "physics": gc.physics_steps,
                     "samples": gc.certificate.n_samples if gc.certificate else 0,
                     "attempts": sum(r.kind == "verify" for r in gc.certificate.rounds) if gc.certificate else 0,
                     "bound": gc.certificate.violation_bound if gc.certificate else 1.0}
    return out


def _validation_check(rows: list[dict], names: list[str]) -> None:
    """For each variant, the validation pushes (``benchmarks/experiments/predictors/data/exo.jsonl``: 200 per
    gait, 20 steps
    after) with |J| ≤ that gait's J* that fell, with a Wilson interval — J*'s own check against ε."""
    table = REPO / "benchmarks" / "experiments" / "predictors" / "data" / "exo.jsonl"
    pushes = {}
    for line in table.read_text().splitlines():
        rec = json.loads(line)
        push = rec.get("kinds", {}).get("push")
        if push:
            pushes[rec["label"]] = (np.asarray(push["size"]), np.asarray(push["ok"], dtype=bool))
    for k in names:
        n = fell = 0
        for r in rows:
            if r["gait"] in pushes:
                size, walked = pushes[r["gait"]]
                inside = size <= r[k]["r_star"]
                n += int(inside.sum())
                fell += int((inside & ~walked).sum())
        if n:
            lo, hi = wilson_interval(fell, n)
            print(f"check {k}: {fell} of {n} validation pushes with |J| ≤ J* fell, {100 * fell / n:.1f} % "
                  f"[{100 * lo:.1f}, {100 * hi:.1f}] (95 % Wilson; ε = 2 %)")


def cmd_push_gaits(args: argparse.Namespace) -> None:
    """J*'s cost over many gaits: per gait (``--gaits`` glob, one per directory name, ``--limit`` evenly spaced),
    J* for each ``--gait-variants`` (verification chunk / horizon) against omega/ball on the same gait,
    same worker; then each variant's check on the gaits' validation pushes."""
    import glob
    from concurrent.futures import ProcessPoolExecutor

    from robustgait.study.executors import blas_threads

    paths = {Path(p).parent.name: p for p in sorted(glob.glob(args.gaits))}
    names = sorted(paths)
    if args.limit and args.limit < len(names):
        names = [names[i] for i in np.unique(np.round(np.linspace(0, len(names) - 1, args.limit)).astype(int))]
    variants = [v[0] for v in _variants(args.gait_variants)]
    print(f"## push-gaits: {len(names)} gaits of {args.gaits}, {args.workers} workers, one rollout thread each; "
          f"variants {args.gait_variants} (name:verify_chunk/horizon[/explore after a failure]); {load_average()}")
    print("| gait | omega r* (s) | " + " | ".join(f"J* {k} (samples, attempts, s, ratio; physics ratio)"
                                                for k in variants) + " |")
    print("|---|---|" + "---|" * len(variants))
    rows = []
    with blas_threads(1), ProcessPoolExecutor(args.workers) as pool:
        for r in pool.map(_push_gait, [(paths[n], args.gait_variants) for n in names]):
            if "error" in r:
                print(f"| {r['gait']} | {r['error']} |" + " |" * len(variants), flush=True)
                continue
            rows.append(r)
            o = r["omega"]
            print(f"| {r['gait']} | {o['r_star']:.3f} ({o['seconds']:.1f}) | " + " | ".join(
                f"{r[k]['r_star']:.2f} ({r[k]['samples']}, {r[k]['attempts']}, {r[k]['seconds']:.1f}, "
                f"{r[k]['seconds'] / o['seconds']:.2f}×; {r[k]['physics'] / o['physics']:.2f}×)"
                for k in variants) + " |", flush=True)
    if not rows:
        return
    for k in variants:
        ratio = np.array([r[k]["seconds"] / r["omega"]["seconds"] for r in rows])
        phys = np.array([r[k]["physics"] / r["omega"]["physics"] for r in rows])
        attempts = np.array([r[k]["attempts"] for r in rows])
        print(f"J* {k}: time over omega/ball median {np.median(ratio):.2f}× ({ratio.min():.2f}–{ratio.max():.2f}), "
              f"≤ 2× on {int((ratio <= 2).sum())} of {ratio.size}; physics steps median {np.median(phys):.2f}× "
              f"(≤ 2× on {int((phys <= 2).sum())}); samples median {np.median([r[k]['samples'] for r in rows]):.0f}; "
              f"verification attempts 1/2/3+: {int((attempts == 1).sum())}/{int((attempts == 2).sum())}/"
              f"{int((attempts >= 3).sum())}")
    for k in variants[1:]:
        dj = np.array([r[k]["r_star"] - r[variants[0]]["r_star"] for r in rows])
        print(f"J* {k} − {variants[0]}: median {np.median(dj):+.2f} N s ({dj.min():+.2f} to {dj.max():+.2f})")
    _validation_check(rows, variants)
    print(load_average())


def cmd_push_sweep(args: argparse.Namespace) -> None:
    """Where a gait's pushes fail: its J* (default certificate), the failures the estimator met below ``--near`` × J*
    (impulse, direction, phase, the step it fell in or that it did not come back to the band, and the reason), then
    pushes at fixed impulses (``--sweep`` × J*) over 24 directions × 13 phases of the validation's range: a grid of
    outcomes (:meth:`robustgait.certificate.push.PushMap.walk` at explicit phases)."""
    from robustgait.certificate.push import PushMap, push_phase
    from robustgait.config import ValidateConfig

    robot, gait = default_gaits(args)["exo"]
    cfg = CertifyConfig()
    vcfg = ValidateConfig()
    engine = make_engine(robot, gait, SimConfig(n_threads=args.threads))
    try:
        t0 = time.perf_counter()
        orbit = find_orbit(Walking(robot, gait, validate=vcfg, engine=engine), cfg)
        if not orbit.ok or orbit.qpos is None or orbit.qvel is None:
            raise SystemExit(f"push-sweep: no orbit ({orbit.status}: {orbit.reason})")
        print(f"## push-sweep: orbit in {time.perf_counter() - t0:.1f} s: {orbit.describe()}")
        pm = PushMap(engine, orbit.qpos, orbit.qvel, orbit.band, vcfg, cfg.push)
        t0 = time.perf_counter()
        cert = certify_map_sequential(pm, np.zeros(2), cfg)
        j_star = cert.radius
        d = np.linalg.norm(cert.samples, axis=1)
        near = np.flatnonzero(cert.fell & (d < args.near * j_star))
        attempts = sum(r.kind == "verify" for r in cert.rounds)
        print(f"{args.exo_gait or 'the default exo gait'}: J* {j_star:.2f} N s ({cert.n_samples} pushes, {attempts} "
              f"verification attempts, {time.perf_counter() - t0:.1f} s; horizon {cfg.push.horizon} steps after the "
              f"pushed one, back in the band for {cfg.push.recovery_steps} steps); failures below {args.near} J*: "
              f"{near.size}")
        if near.size:
            j = cert.samples[near]
            phase = push_phase(j, *vcfg.push_phase)
            _, reasons, steps, _ = pm.walk(j, phase)
            for k in np.argsort(d[near]):
                what = f"fell in step {steps[k]}" if steps[k] > 0 else "not back in the band"
                print(f"  |J| {d[near][k]:6.2f} N s, direction {math.degrees(math.atan2(j[k, 1], j[k, 0])):5.0f}°, "
                      f"phase {phase[k]:.2f}: {what} ({reasons[k]})")
        directions = np.arange(-180, 180, 15)
        phases = np.linspace(vcfg.push_phase[0], vcfg.push_phase[1], 13)
        dd, pp = np.meshgrid(np.radians(directions), phases, indexing="ij")
        for f in (float(x) for x in args.sweep.split(",")):
            mag = f * j_star
            j = mag * np.stack([np.cos(dd.ravel()), np.sin(dd.ravel())], axis=1)
            alive, _, steps, recovered = pm.walk(j, pp.ravel())
            fell = steps > 0
            cells = np.where(alive, ".", np.where(fell, np.minimum(steps, 9).astype(str), "o")).reshape(dd.shape)
            print(f"|J| = {f:g} J* = {mag:.2f} N s: {int((~alive).sum())} of {alive.size} pushes fail "
                  f"({100 * (~alive).mean():.1f} %: {int(fell.sum())} fall, {int((~alive & ~fell).sum())} not back "
                  f"in the band); recovered by step {np.median(recovered[alive]) if alive.any() else float('nan'):.0f} "
                  f"(median); rows: direction in the heading frame (0° forward, 90° left), columns: phase "
                  f"{phases[0]:.2f} … {phases[-1]:.2f}; '.' recovered, digit: the step it fell in, 'o': walked but "
                  f"not back in the band within the horizon")
            for a, deg in enumerate(directions):
                print(f"  {deg:5d}°  " + "".join(cells[a]))
    finally:
        engine.close()
    print(load_average())



def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("part", nargs="?", default="all",
                    choices=("all", "push", "push-gaits", "push-sweep"))
    ap.add_argument("--seeds", type=int, default=10, help="seeds: seeds per gait and method (default 10)")
    add_gait_arguments(ap)
    ap.add_argument("--threads", type=int, default=0, help="0 = one per core")
    ap.add_argument("--push-variants", default="50/100/50/20,100/200/100/20,50/100/50/10",
                    help="push: first-round/explore/explore-after-failure/horizon tuples (the shipped one first; "
                         "horizon: push.horizon, steps after the pushed one)")
    ap.add_argument("--gaits", default="", help="push-gaits: a glob of gait files (one per directory name)")
    ap.add_argument("--limit", type=int, default=0, help="push-gaits: at most N gaits, evenly spaced by name")
    ap.add_argument("--workers", type=int, default=2, help="push-gaits: worker processes")
    ap.add_argument("--gait-variants", default="whole:0/20,chunked:25/20",
                    help="push-gaits: J* variants name:verify_chunk/horizon[/explore_after_failure] (default "
                         "whole:0/20,chunked:25/20)")
    ap.add_argument("--near", type=float, default=1.2, help="push-sweep: list the falls below this × J* (1.2)")
    ap.add_argument("--sweep", default="0.8,1.0,1.1", help="push-sweep: impulses of the grids, × J* (0.8,1.0,1.1)")
    args = ap.parse_args()
    print(f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores; mujoco "
          f"{mujoco.__version__}; numpy {np.__version__}; {load_average()}")
    for part, fn in (("push", cmd_push), ("push-gaits", cmd_push_gaits), ("push-sweep", cmd_push_sweep)):
        if args.part == part or (args.part == "all" and part not in ("push-gaits", "push-sweep")):
            fn(args)


if __name__ == "__main__":
    main()
