"""Which certificate predicts robustness? (issue 18, item 6.) On the unique gaits of studies (default: the two
paper-size studies of ``benchmarks/experiments/study_size/run.py``), for each certificate choice — state × set
× horizon, and the push
certificate J* — the certificate, and every gait under the same disturbances (``validate``'s draws, seed 0).

Per gait (one worker process each, one rollout thread): the fixed point; ``--trials`` pushes (20 steps after),
their success, fall step and the full state at the first section after the push; the other ``--kinds``
(``--other-trials`` each); then every ``--configs`` certificate (r*, E*, cost) and its check — the pushes whose
first post-push state lies in the certified set, in that certificate's own coordinates, and how many fell; with
``--push-cert``, J* and its check (pushes with |J| ≤ J* that fell). One JSON line per gait in ``--out``; a gait
already there is not computed again (a killed run continues). ``--kinds-only`` measures only the ``--kinds`` (a second
run for more disturbance kinds, on all gaits or a ``--spread``), merged into the report with ``--merge``.

``--report`` reads the lines and prints, per choice: the median r*, Spearman ρ (p, n) of r* with push success and
with push s₅₀, the certificate check pooled over gaits (falls inside / inside, 95 % Wilson interval), and for J*
its ρ with the s₅₀ of each other kind; plus the gaits' own step length as a baseline predictor.

    python benchmarks/experiments/predictors/run.py [--studies DIR,DIR] [--configs \\
        omega/ball/1,velocity/ellipsoid/2,...]
        [--gaits 'GLOB'] [--push-cert] [--kinds latency,noise,mass,terrain] [--trials 200] [--other-trials 100]
        [--workers 2] [--limit N] [--spread N] [--out FILE.jsonl] [--kinds-only] [--report] [--merge FILE.jsonl]
        [--plot FILE.png]
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import os
import platform
import sys
import time
from concurrent.futures import ProcessPoolExecutor, as_completed
from datetime import date
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))  # benchmarks/common.py
from common import REPO, git_commit

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
                            "study_r_star": g.certificate_value})
    return out


def one_gait(task: dict[str, Any]) -> dict[str, Any]:
    """Everything of one gait (module docstring). Runs in a worker: one rollout thread, BLAS on one thread."""
    from robustgait.certificate.certify import certify_gait
    from robustgait.certificate.reduced import ReducedState
    from robustgait.config import CertifyConfig, SimConfig, ValidateConfig
    from robustgait.io.gaitfile import load_gait
    from robustgait.io.robotfile import load_robot
    from robustgait.validate import disturbances as dist
    from robustgait.validate.run import CertificateRef, Validator, simulate_trials
    from robustgait.validate.stats import logistic_fit

    t0 = time.perf_counter()
    robot = load_robot("exo")
    gait = load_gait(task["gait"], robot)
    sim = SimConfig(n_threads=1)
    base = CertifyConfig(**{"disturbance": "state", **task.get("certify", {})})
    gc0 = certify_gait(robot, gait, dataclasses.replace(base, method="uniform", n_samples=1), sim)
    if not gc0.ok or gc0.fixed_point is None:
        return {**task, "error": f"{gc0.status}: {gc0.reason}"}
    fp = gc0.fixed_point
    out: dict[str, Any] = {**task, "kinds": {}, "configs": {}}
    ref = CertificateRef.of(gc0)
    nq = robot.model.nq
    first_push = None
    pushes = [] if task.get("kinds_only") else [("push", task["trials"])]
    for kind, trials in pushes + [(k, task["other_trials"]) for k in task["kinds"]]:
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
    if task.get("kinds_only"):
        out["seconds"] = out["seconds_validate"]
        return out
    assert first_push is not None
    push_ok = np.array(out["kinds"]["push"]["ok"])
    reached = np.isfinite(first_push).all(axis=1)
    for text in task["configs"]:
        cfg = dataclasses.replace(base, **parse_config(text))
        t1 = time.perf_counter()
        gc = certify_gait(robot, gait, cfg, sim)
        row = {"status": gc.status, "r_star": gc.value, "energy": gc.energy, "seconds": time.perf_counter() - t1,
               "physics": gc.physics_steps, "samples": gc.certificate.n_samples if gc.certificate else 0,
               "bound": gc.certificate.violation_bound if gc.certificate else 1.0}
        if gc.ok and gc.coordinates is not None and gc.certificate is not None:
            co, c = gc.coordinates, gc.certificate
            red = ReducedState.at(cfg.state, robot, fp.qpos, fp.qvel, gait.stance, cfg)
            z = np.full((first_push.shape[0], co.dim), np.nan)
            z[reached] = co.to_z(red.phi(first_push[reached, :nq], first_push[reached, nq:]))
            d = np.linalg.norm(z - co.x_star, axis=1)
            with np.errstate(invalid="ignore"):
                inside = (d <= c.radius) if c.attained else (d < c.radius)
            row.update({"inside": int(inside.sum()), "fell_inside": int((inside & ~push_ok).sum()),
                        "volume_ratio": gc.volume_ratio, "excursion": gc.excursion,
                        "fallback": co.shape.fallback if cfg.set == "ellipsoid" else None})
        out["configs"][text] = row
    if task["want_push_cert"]:
        t1 = time.perf_counter()
        cfg = dataclasses.replace(base, disturbance="push")
        gc = certify_gait(robot, gait, cfg, sim)
        size = np.array(out["kinds"]["push"]["size"])
        inside = size <= gc.value if (gc.certificate is None or gc.certificate.attained) else size < gc.value
        out["push_cert"] = {"status": gc.status, "j_star": gc.value, "seconds": time.perf_counter() - t1,
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
    what = (f"kinds {args.kinds} only" if args.kinds_only else f"configs {args.configs}; push certificate "
            f"{args.push_cert}; kinds push + {args.kinds or 'none'}")
    print(f"{len(gaits)} gaits ({len(gaits) - len(todo)} already in {args.out}); {what}; {args.workers} workers; "
          f"load {os.getloadavg()[0]:.1f}", flush=True)
    tasks = [{**g, "configs": args.configs.split(","), "kinds": [k for k in args.kinds.split(",") if k],
              "trials": args.trials, "other_trials": args.other_trials, "want_push_cert": args.push_cert,
              "kinds_only": args.kinds_only}
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


def read_rows(path: Path, merge: list[Path]) -> list[dict[str, Any]]:
    """The gaits of ``path`` (errors left out), each with the kinds of the same gait in the ``merge`` files (runs
    with ``--kinds-only``) added to its own."""
    def lines(p: Path) -> list[dict[str, Any]]:
        rows = [json.loads(line) for line in p.read_text().splitlines() if line.strip()]
        return [r for r in rows if "error" not in r]

    rows = lines(path)
    extra: dict[str, dict[str, Any]] = {}
    for p in merge:
        for r in lines(p):
            extra.setdefault(r["label"] + "|" + r["study"], {}).update(r["kinds"])
    for r in rows:
        r["kinds"] = {**extra.get(r["label"] + "|" + r["study"], {}), **r["kinds"]}
    return rows


def report(path: Path, plot: Path | None = None, merge: list[Path] | None = None) -> None:
    from robustgait.validate.stats import Rate, spearman

    rows = read_rows(path, merge or [])
    commit = git_commit()
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
        have_all = have
        for k in kinds:  # a kind measured on part of the gaits (a --kinds-only run on a subset) is ranked there
            have = [r for r in have_all if k in r["kinds"]]
            idx = [rows.index(r) for r in have]
            j = np.array([r["push_cert"]["j_star"] for r in have])
            ks = np.array([np.nan if r["kinds"][k]["s50"] is None else r["kinds"][k]["s50"] for r in have])
            ksucc = np.array([r["kinds"][k]["success"] for r in have])
            print(f"J* vs {k}: success {corr(j, ksucc, 'success')}, s₅₀ {corr(j, ks, 's50')}")
            for name in names:
                x = np.array([r["configs"][name]["r_star"] for r in have if name in r["configs"]])
                if x.size == len(have):
                    print(f"   r* {name} vs {k}: success {corr(x, ksucc, 'success')}, s₅₀ {corr(x, ks, 's50')}")
    cost_ratios(rows, names)
    length = np.array([r["params"]["step_length"] for r in rows])
    print(f"\nbaseline: step length vs push success {corr(length, success, 'success')}, vs s₅₀ "
          f"{corr(length, s50, 's50')}")
    print("beyond the step length (partial Spearman ρ with push s₅₀, step length held fixed):")
    for name, _, x, _, _ in _choices(rows):
        print(f"  {name}: {partial_spearman(x, s50, length)}")
    target_reliability(rows)
    if plot is not None:
        print(f"figure: {plot_report(rows, s50, plot)}")


def partial_spearman(x: np.ndarray, y: np.ndarray, z: np.ndarray) -> str:
    """ρ(x, y | z): the Pearson correlation of the ranks of x and y after a least-squares line in the ranks of z is
    taken out of each, with its two-sided p-value (t with n − 3 degrees of freedom)."""
    from scipy.stats import rankdata
    from scipy.stats import t as student

    m = np.isfinite(x) & np.isfinite(y) & np.isfinite(z)
    n = int(m.sum())
    if n < 4:
        return f"undefined (n = {n})"
    rx, ry, rz = (rankdata(v[m]) for v in (x, y, z))
    design = np.column_stack([np.ones(n), rz])
    ex = rx - design @ np.linalg.lstsq(design, rx, rcond=None)[0]
    ey = ry - design @ np.linalg.lstsq(design, ry, rcond=None)[0]
    rho = float(ex @ ey / math.sqrt((ex @ ex) * (ey @ ey)))
    tt = rho * math.sqrt((n - 3) / max(1e-300, 1 - rho * rho))
    p = float(2 * student.sf(abs(tt), n - 3))
    return f"{rho:+.3f} (p {p:.2g}, n {n})"


def cost_ratios(rows: list[dict[str, Any]], names: list[str]) -> None:
    """Each choice's wall time over the first choice's on the same gait in the same worker (item 7's ratios)."""
    if not names:
        return
    ref = names[0]
    print(f"\ncost on the same gait, same run, over {ref}:")
    for name in names[1:] + (["push J*"] if any("push_cert" in r for r in rows) else []):
        have = [r for r in rows if ref in r["configs"] and (name in r["configs"] or name == "push J*")
                and (name != "push J*" or "push_cert" in r)]
        t = np.array([(r["push_cert"] if name == "push J*" else r["configs"][name])["seconds"] for r in have])
        ratio = t / np.array([r["configs"][ref]["seconds"] for r in have])
        print(f"  {name}: median {np.median(ratio):.2f}× ({ratio.min():.2f}–{ratio.max():.2f}), ≤ 2× on "
              f"{int((ratio <= 2).sum())} of {ratio.size} gaits")


def _choices(rows: list[dict[str, Any]]) -> list[tuple[str, str, np.ndarray, int, int]]:
    """(name, unit, value per gait, falls inside, inside) of every certificate choice in the rows (all gaits)."""
    out = []
    for name in dict.fromkeys(c for r in rows for c in r["configs"]):
        if all(name in r["configs"] for r in rows):
            unit = "rad/s" if name.startswith("omega") else "√J"
            out.append((name, unit, np.array([r["configs"][name]["r_star"] for r in rows]),
                        sum(r["configs"][name].get("fell_inside", 0) for r in rows),
                        sum(r["configs"][name].get("inside", 0) for r in rows)))
    if all("push_cert" in r for r in rows):
        out.append(("push J*", "N s", np.array([r["push_cert"]["j_star"] for r in rows]),
                    sum(r["push_cert"]["fell_inside"] for r in rows), sum(r["push_cert"]["inside"] for r in rows)))
    return out


def plot_report(rows: list[dict[str, Any]], s50: np.ndarray, path: Path) -> Path:
    """One panel per choice — its value against the gait's push s₅₀, with Spearman ρ — and one of the certificate
    check: the share of pushes landing inside the certified set that fell, 95 % Wilson interval, against 5 %."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from robustgait.validate.stats import Rate, spearman

    choices = _choices(rows)
    fig, axes = plt.subplots(1, len(choices) + 1, figsize=(3.6 * (len(choices) + 1), 3.6))
    for ax, (name, unit, x, _, _) in zip(axes, choices, strict=False):
        m = np.isfinite(x) & np.isfinite(s50)
        c = spearman(x[m], s50[m], name, "s50")
        ax.scatter(x[m], s50[m], s=12, alpha=0.7)
        ax.set_xlabel(f"{name} [{unit}]")
        ax.set_ylabel("push s₅₀ [N s]")
        ax.set_title(f"ρ {c.rho:+.2f} (p {c.p:.1g}, n {c.n})" if c.defined else "ρ undefined", fontsize=9)
    ax = axes[-1]
    for i, (_, _, _, fell, inside) in enumerate(choices):
        rate = Rate.of(fell, inside)
        ax.errorbar([i], [100 * rate.rate], yerr=[[100 * (rate.rate - rate.low)], [100 * (rate.high - rate.rate)]],
                    fmt="o", capsize=4)
    ax.axhline(5.0, color="red", lw=1, ls="--", label="goal: upper bound ≤ 5 %")
    ax.set_xticks(range(len(choices)), [n for n, *_ in choices], rotation=30, ha="right", fontsize=8)
    ax.set_ylabel("falls among pushes inside [%]")
    ax.set_title("certificate check (95 % Wilson)", fontsize=9)
    ax.legend(fontsize=7)
    fig.suptitle(f"{len(rows)} gaits: which certificate predicts push robustness", fontsize=10)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def target_reliability(rows: list[dict[str, Any]]) -> None:
    """How well can *anything* rank these gaits' push robustness, given the pushes measured? Split each gait's
    pushes into two halves (even and odd trials: independent draws of one distribution, the same draws for
    every gait), measure success and s₅₀ on each half, and correlate the halves across gaits. The Spearman–Brown
    step-up 2ρ_h / (1 + ρ_h) estimates the reliability R of the full-size measure; a predictor's correlation
    with the measured target cannot exceed about √R however well it predicts the true one (the attenuation
    bound), so ρ ≥ 0.6 is out of reach when R < 0.36."""
    from robustgait.validate.stats import logistic_fit, spearman

    halves: list[dict[str, np.ndarray]] = []
    for h in (0, 1):
        succ, s50 = [], []
        for r in rows:
            size = np.asarray(r["kinds"]["push"]["size"], dtype=float)[h::2]
            ok = np.asarray(r["kinds"]["push"]["ok"], dtype=bool)[h::2]
            fit = logistic_fit(size, ok)
            succ.append(ok.mean())
            s50.append(fit.s50 if (fit.s50 is not None and fit.in_range) else np.nan)
        halves.append({"success": np.array(succ), "s50": np.array(s50)})
    print("\ntarget reliability (pushes split in even/odd halves, correlated across gaits):")
    for what in ("success", "s50"):
        a, b = halves[0][what], halves[1][what]
        m = np.isfinite(a) & np.isfinite(b)
        c = spearman(a[m], b[m], "half 1", "half 2")
        if not c.defined or c.rho is None:
            print(f"  push {what}: undefined ({c.reason})")
            continue
        rel = 2 * c.rho / (1 + c.rho) if c.rho > -1 else float("nan")
        bound = math.sqrt(rel) if rel > 0 else 0.0
        print(f"  push {what}: half vs half ρ {c.rho:+.3f} (p {c.p:.2g}, n {c.n}); Spearman–Brown reliability "
              f"{rel:+.3f}; attenuation bound on any predictor's ρ ≈ {bound:.2f}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--studies", default=",".join(str(REPO / "benchmarks" / "experiments" / "study_size" / "data" / m)
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
    ap.add_argument("--out", type=Path, default=Path(__file__).parent / "data" / "exo.jsonl")
    ap.add_argument("--report", action="store_true")
    ap.add_argument("--kinds-only", action="store_true",
                    help="only the --kinds (no pushes, no certificates): a run whose --out is --merge'd into a report")
    ap.add_argument("--merge", default="", help="with the report: JSONL files of --kinds-only runs (comma-separated)")
    ap.add_argument("--plot", type=Path, help="with the report: a PNG of each choice against push s₅₀ and the check")
    args = ap.parse_args()
    if not args.report:
        run(args)
    if not args.kinds_only:
        report(args.out, args.plot, [Path(p) for p in args.merge.split(",") if p])


if __name__ == "__main__":
    sys.exit(main())
