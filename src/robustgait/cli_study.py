"""The ``robustgait study ...`` and ``robustgait demo`` commands (split from :mod:`robustgait.cli`, which
builds the whole parser): they only parse arguments and call :mod:`robustgait.study`."""

from __future__ import annotations

import argparse
import json
import sys
from typing import TYPE_CHECKING, Any

from robustgait.errors import RobustGaitError
from robustgait.io import limits as L
from robustgait.io.args import float_in, int_in

if TYPE_CHECKING:
    from robustgait.study.run import RunOptions


def _study_options(args: argparse.Namespace) -> RunOptions:
    import os

    from robustgait.study.run import RunOptions

    workers = args.workers if args.workers is not None else max(1, min(os.cpu_count() or 1, 2))
    if workers < 1:
        raise RobustGaitError(f"--workers must be ≥ 1, got {workers}")
    if args.executor == "ray":
        try:
            import ray  # noqa: F401
        except ImportError:
            raise RobustGaitError('--executor ray needs Ray: pip install "robustgait[ray]"') from None
    return RunOptions(executor=args.executor, workers=workers, address=args.address, verbose=args.verbose,
                      progress=not args.quiet)


def _print_study_summary(directory: str, seconds: float | None = None) -> None:
    from robustgait.study.status import study_status

    st = study_status(directory)
    best = st["best"]
    took = f" in {seconds:.0f} s" if seconds is not None else ""
    print(f"study {directory}: {st['trials_done']}/{st['trials_planned']} gaits evaluated{took} "
          f"({st['unique_gaits']} unique), {st['iterations_done']}/{st['iterations_planned']} iterations, "
          f"{st['state']}")
    if best is not None:
        params = ", ".join(f"{k} = {v:g}" for k, v in best["params"].items())
        print(f"best gait (trial {best['trial']}): {params}; r* = {best['r_star']:.4f} rad/s, "
              f"{best['steps_taken']} steps; {best['gait_file'] or 'no gait file'}")
    obs = st["best_observed"]
    if obs is not None and (best is None or obs["score"] != best["score"]):
        params = ", ".join(f"{k} = {v:g}" for k, v in obs["params"].items())
        print(f"best evaluated gait (trial {obs['trial']}; the best gait above is the learner's highest posterior "
              f"mean): {params}; r* = {obs['r_star']:.4f} rad/s, {obs['steps_taken']} steps")


def _cmd_study_run(args: argparse.Namespace) -> int:
    import dataclasses
    import time

    from robustgait.gaitgen.config import GaitGenConfig
    from robustgait.study.config import StudyConfig
    from robustgait.study.evaluate import EvaluationConfig
    from robustgait.study.run import create_study

    options = _study_options(args)
    base = EvaluationConfig().certify  # the study default: the sequential estimator
    seq = dataclasses.replace(base.sequential, **{k: v for k, v in (("epsilon", args.epsilon), ("budget", args.budget))
                                                  if v is not None})
    certify = dataclasses.replace(base, seed=args.seed, method=args.method, sequential=seq,
                                  **({"n_samples": args.samples} if args.samples is not None else {}))
    config = StudyConfig(robot=args.robot, metric=args.metric, learner=args.learner, iterations=args.iterations,
                         batch=args.batch, seed=args.seed, storage=args.storage,
                         evaluation=EvaluationConfig(step_cap=args.steps, certify=certify,
                                                     gaitgen=GaitGenConfig(domains=args.domains)))
    create_study(args.dir, config)
    t0 = time.perf_counter()
    if not _run_interruptible(args.dir, options):
        return 130
    _print_study_summary(args.dir, time.perf_counter() - t0)
    return 0


def _run_interruptible(directory: str, options: RunOptions) -> bool:
    """Run a study; on Ctrl-C say how to continue (the running trials are re-run by resume)."""
    from robustgait.study.run import run_study

    try:
        run_study(directory, options)
    except KeyboardInterrupt:
        print(f"\nrobustgait: interrupted; continue with: robustgait study resume {directory}", file=sys.stderr)
        return False
    return True


def _cmd_study_resume(args: argparse.Namespace) -> int:
    import time

    t0 = time.perf_counter()
    if not _run_interruptible(args.dir, _study_options(args)):
        return 130
    _print_study_summary(args.dir, time.perf_counter() - t0)
    return 0


def _cmd_study_status(args: argparse.Namespace) -> int:
    from robustgait.study.status import study_status

    st = study_status(args.dir)
    if args.json:
        print(json.dumps(st, allow_nan=False))
        return 0
    _print_study_summary(args.dir)
    print(f"{'iteration':>9}  {'best r*':>8}  {'steps':>5}  best gait")
    for it in st["iterations"]:
        b = it["best"]
        if b is None:
            print(f"{it['iteration'] + 1:>9}  {'—':>8}  {'—':>5}  {'running' if it['trials'] else 'not started'}")
        else:
            print(f"{it['iteration'] + 1:>9}  {b['r_star']:>8.4f}  {b['steps_taken']:>5}  "
                  + ", ".join(f"{v:g}" for v in b["params"].values()))
    return 0


def _cmd_study_report(args: argparse.Namespace) -> int:
    from robustgait.report.study import write_study_report

    axes = tuple(args.axes.split(","))
    if len(axes) != 2:
        raise RobustGaitError(f"--axes takes two parameter names separated by a comma, got {args.axes!r}")
    print(write_study_report(args.dir, axes=(axes[0], axes[1]), video=not args.no_video))
    return 0


def _cmd_study_compare(args: argparse.Namespace) -> int:
    from robustgait.study.compare import compare_studies

    res = compare_studies(args.dir_a, args.dir_b, seeds=args.seeds, seed_base=args.seed_base, samples=args.samples)
    if args.json:
        print(json.dumps(res, allow_nan=False))
        return 0
    print(f"best gaits re-certified with seeds {res['seeds'][0]}–{res['seeds'][-1]} (N = {res['n_samples']}), "
          f"walked {res['step_cap']} steps")
    for name, s in zip("AB", res["studies"], strict=True):
        params = ", ".join(f"{v:g}" for v in s["params"].values())
        print(f"{name} {s['directory']} ({s['learner']}, {s['metric']}): gait ({params}), {s['steps_taken']} steps, "
              f"r* = {s['r_star_mean']:.4f} ± {s['r_star_sd']:.4f} rad/s  "
              f"[{', '.join(f'{r:.3f}' for r in s['r_star'])}] (study: {s['study_r_star']:.4f})")
    w = res["winner"]
    print("equal mean r*" if w is None else f"higher mean r*: {'AB'[w]} (per seed: A wins {res['wins_per_seed'][0]}, "
          f"B wins {res['wins_per_seed'][1]})")
    if res["note"]:
        print(f"note: {res['note']}")
    return 0


def _cmd_study_validate(args: argparse.Namespace) -> int:
    from robustgait.study.validate import summary_path, validate_study
    from robustgait.validate import ValidateConfig
    from robustgait.validate.stats import correlation_text

    cfg = ValidateConfig(trials=args.trials, seed=args.seed, steps_after=args.steps_after)
    try:
        out = validate_study(args.dir, cfg, kinds=[args.disturbance], workers=args.workers, progress=not args.quiet)
    except KeyboardInterrupt:
        print("\nrobustgait: interrupted; the gaits validated so far are stored: run the same command again to "
              "continue", file=sys.stderr)
        return 130
    if args.json:
        print(json.dumps(out, allow_nan=False))
        return 0
    for kind, s in out.items():
        st, name, unit = s["study"], s["size"], s["unit"]
        skipped = ", ".join(f"{n} {what.replace('_', ' ')}" for what, n in s["skipped_counts"].items())
        print(f"{kind}: {s['n_validated']} of {st['unique_gaits']} unique gaits validated"
              + (f" ({s['n_from_earlier_runs']} from an earlier run)" if s["n_from_earlier_runs"] else "")
              + (f"; skipped: {skipped}" if skipped else "") + f"; {cfg.trials} trials each, seed {cfg.seed}, "
              f"success = no fall in {cfg.steps_after} steps after the first switching event")
        print(f"  {'gait':<26} {'study':<13} {'r*':>7} {'steps':>7}  {'success [95% CI]':<27} half fail at ({name})")
        for r in s["gaits"]:
            c = r["critical"]
            crit = (f"{c['s50']:.4g} ± {c['s50_se'] or 0:.2g} {unit}" if c["s50"] is not None else f"— ({c['note']})")
            sr = r["success"]
            print(f"  {r['label']:<26} {r['status']:<13} {r['r_star']:>7.4f} {r['steps_taken']:>3}/{r['step_cap']:<3}  "
                  f"{sr['k']}/{sr['n']} = {sr['rate']:.2f} [{sr['low']:.2f}, {sr['high']:.2f}]{'':<4} {crit}")
        for sk in s["skipped"]:
            print(f"  {sk['label']:<26} skipped: {sk['why']}")
        for c in s["correlations"].values():
            print(f"  {correlation_text(c)}")
        print(f"  results: {summary_path(args.dir, kind)}")
    return 0


def _cmd_demo(args: argparse.Namespace) -> int:
    import time
    from pathlib import Path

    from robustgait.report.study import write_study_report
    from robustgait.study.config import demo_config
    from robustgait.study.run import RunOptions, create_study

    d = Path(args.dir)
    t0 = time.perf_counter()
    if not (d / "study.json").exists():
        create_study(d, demo_config())
        print(f"demo: a robustness study on the shipped exoskeleton (3 iterations × 4 gaits) in {d}", flush=True)
    else:
        print(f"demo: resuming the study in {d}", flush=True)
    if not _run_interruptible(str(d), RunOptions(workers=args.workers or 2, progress=True)):
        return 130
    _print_study_summary(str(d), time.perf_counter() - t0)
    print(write_study_report(d))
    return 0


def add_study_parsers(sub: Any) -> None:
    def run_options(q: argparse.ArgumentParser) -> None:
        q.add_argument("--executor", choices=("local", "ray"), default="local",
                       help="local worker processes (default) or Ray actors (pip install \"robustgait[ray]\")")
        q.add_argument("--workers", type=int_in(L.WORKERS), help="parallel evaluations (default: min(cores, 2))")
        q.add_argument("--address", help="Ray cluster address, e.g. auto (default: start a local Ray)")
        q.add_argument("--verbose", action="store_true", help="print IPOPT's iteration log of every gait")
        q.add_argument("--quiet", action="store_true", help="no progress bar")

    s = sub.add_parser("study", help="learn the most robust gait: the simulation-in-the-loop preference study")
    ssub = s.add_subparsers(dest="study_command", required=True)
    r = ssub.add_parser("run", help="start a study in a new directory and run it to its budget")
    r.add_argument("dir", help="study directory (new or empty)")
    r.add_argument("--robot", required=True, help="shipped robot name or path to a spec .toml with [action_space]")
    r.add_argument("--metric", choices=("robustness", "stability"), default="robustness",
                   help="preference oracle: r* among gaits that walk the cap (default), or steps only")
    r.add_argument("--learner", choices=("polar", "eubo", "random"), default="polar")
    r.add_argument("--iterations", type=int_in(L.ITERATIONS), default=10, help="batches (default 10)")
    r.add_argument("--batch", type=int_in(L.BATCH), default=5, help="gaits per batch (default 5; ≥ 2)")
    r.add_argument("--method", choices=("sequential", "uniform"), default="sequential",
                   help="r* estimator: sequential (default: CV ≈ 1 %% between seeds) or uniform (the paper's N "
                   "samples)")
    r.add_argument("--samples", type=int_in(L.SAMPLES), help="uniform: certificate samples N (default 200)")
    r.add_argument("--budget", type=int_in(L.BUDGET), help="sequential: most samples (default 3000)")
    r.add_argument("--epsilon", type=float_in(L.EPSILON),
                   help="sequential: certified bound on the violating volume fraction (default 0.02)")
    r.add_argument("--steps", type=int_in(L.STEPS), default=50,
                   help="step cap of the walk before certifying (default 50)")
    r.add_argument("--domains", choices=("flat", "multicontact"), default="flat",
                   help="domain graph of the gaits: flat-foot (default) or multi-contact heel/toe rolling, "
                   "searched over the spec's [action_space.multicontact]")
    r.add_argument("--storage", help="SQLAlchemy URL of the Optuna database (default: sqlite file in DIR)")
    r.add_argument("--seed", type=int_in(L.SEED), default=0,
                   help="seed of the learner and of the certificates (default 0)")
    run_options(r)
    r.set_defaults(func=_cmd_study_run)
    rs = ssub.add_parser("resume", help="continue a stopped or killed study to its total budget")
    rs.add_argument("dir")
    run_options(rs)
    rs.set_defaults(func=_cmd_study_resume)
    st = ssub.add_parser("status", help="progress, best gait and every trial of a study")
    st.add_argument("dir")
    st.add_argument("--json", action="store_true", help="print one JSON object")
    st.set_defaults(func=_cmd_study_status)
    rp = ssub.add_parser("report", help="write DIR/report/index.html (self-contained) and its figures")
    rp.add_argument("dir")
    rp.add_argument("--axes", default="step_length,step_duration",
                    help="the two parameters of the posterior-mean map (default step_length,step_duration)")
    rp.add_argument("--no-video", action="store_true", help="skip the video of the best gait")
    rp.set_defaults(func=_cmd_study_report)
    cp = ssub.add_parser("compare", help="re-certify the best gaits of two studies with fresh seeds, side by side")
    cp.add_argument("dir_a")
    cp.add_argument("dir_b")
    cp.add_argument("--seeds", type=int_in(L.COMPARE_SEEDS), default=5, help="fresh certificate seeds (default 5)")
    cp.add_argument("--seed-base", type=int_in(L.SEED), default=1000, help="first fresh seed (default 1000)")
    cp.add_argument("--samples", type=int_in(L.SAMPLES), help="certificate samples N (default: study A's)")
    cp.add_argument("--json", action="store_true")
    cp.set_defaults(func=_cmd_study_compare)

    va = ssub.add_parser("validate", help="every unique gait of a study under the same disturbances: success "
                         "rates and the Spearman correlation of r* and of steps taken with success")
    va.add_argument("dir", help="study directory")
    va.add_argument("--trials", type=int_in(L.TRIALS), default=200,
                    help=f"trials per gait and disturbance kind (default 200; {L.TRIALS.text()})")
    va.add_argument("--seed", type=int_in(L.SEED), default=0,
                    help="seed of the disturbances, the same for every gait (default 0)")
    va.add_argument("--disturbance", choices=("push", "mass", "friction", "latency", "noise", "terrain", "all"),
                    default="push", help="disturbance kind (default push; all = every kind in turn)")
    va.add_argument("--steps-after", "--steps", dest="steps_after", type=int_in(L.STEPS_AFTER), default=20,
                    help="steps to walk after the first switching event after the disturbance (default 20)")
    va.add_argument("--workers", type=int_in(L.WORKERS), default=1,
                    help="gaits validated in parallel processes, each with cores / workers rollout threads "
                    "(default 1: one process, the rollout on every core)")
    va.add_argument("--json", action="store_true", help="print one JSON object: the summary of each kind")
    va.add_argument("--quiet", action="store_true", help="no progress bar")
    va.set_defaults(func=_cmd_study_validate)

    dm = sub.add_parser("demo", help="the main job on shipped defaults: a small robustness study on exo + report")
    dm.add_argument("--dir", default="robustgait-demo", help="study directory (default ./robustgait-demo)")
    dm.add_argument("--workers", type=int_in(L.WORKERS), help="parallel evaluations (default 2)")
    dm.set_defaults(func=_cmd_demo)
