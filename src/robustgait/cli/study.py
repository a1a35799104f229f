"""``robustgait study run | resume | status | report | compare | validate`` and ``robustgait demo``: they parse
arguments and call :mod:`robustgait.study`."""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path
from typing import Any

from robustgait.cli.common import ROBOT_HELP, command
from robustgait.cli.options import FlagTable, config_from
from robustgait.config import DEMO_DIRECTORY, DEMO_ROBOT, Config, RunConfig, radius_name
from robustgait.errors import RobustGaitError
from robustgait.study.outcome import EvaluationStatus

RUN: FlagTable = {"--executor": "run.executor", "--workers": "run.workers", "--address": "run.address"}
STUDY: FlagTable = {"--metric": "study.metric", "--learner": "study.learner", "--iterations": "study.iterations",
         "--batch": "study.batch", "--method": "certify.method", "--samples": "certify.n_samples",
         "--budget": "certify.sequential.budget", "--epsilon": "certify.sequential.epsilon", "--steps": "sim.step_cap",
         "--domains": "generate.domains", "--storage": "study.storage", "--seed": ("study.seed", "certify.seed"),
         "--state": "certify.state", "--set": "certify.set", "--horizon": "certify.horizon",
         "--controller": "sim.controller", "--require": "study.require", "--floor": "person.floor",
         "--blind": "person.blind", "--person-seed": "person.simulated.seed"}


def _check_executor(run: RunConfig) -> None:
    if run.executor == "ray":
        try:
            import ray  # noqa: F401
        except ImportError:
            raise RobustGaitError('--executor ray needs Ray: pip install "robustgait[ray]"') from None


def _name(status: dict[str, object]) -> str:
    """r* or J* (a push study's certificate)."""
    return radius_name(str(status.get("certificate")))


def _value(entry: dict[str, Any], st: dict[str, Any]) -> str:
    """A gait's certificate figure as a user reads it: verified, or the estimate said to be one."""
    from robustgait.study.status import figure_text

    return f"{_name(st)} {figure_text(entry, st['unit'])}"


def print_summary(directory: str | Path, seconds: float | None = None) -> None:
    from robustgait.study.status import study_status

    st = study_status(directory)
    best = st["best"]
    took = f" in {seconds:.0f} s" if seconds is not None else ""
    done, planned = st["trials_done"], st["trials_planned"]
    count = f"{done}/{planned}" if done <= planned else str(done)
    extra = f"; {planned} planned + {done - planned} over-drawn candidates" if done > planned else ""  # docs/person.md
    print(f"study {directory}: {count} gaits evaluated{took} "
          f"({st['unique_gaits']} unique{extra}), {st['iterations_done']}/{st['iterations_planned']} iterations, "
          f"{st['state']}")
    if st["outcomes"]:
        print("outcomes: " + ", ".join(f"{k.replace('_', ' ')} {v}" for k, v in st["outcomes"].items()))
    use = st.get("utilisation")
    if use:
        print(f"machine use: {use['share']:.0%} of {use['cores']:.0f} cores while evaluating ({use['cpu_seconds']:.0f} "
              f"CPU s over {use['busy_seconds']:.0f} s)")
    if best is not None:
        params = ", ".join(f"{k} = {v:g}" for k, v in best["params"].items())
        print(f"best gait (trial {best['trial']}): {params}; {_value(best, st)}, "
              f"{best['steps_taken']} steps; {best['gait_file'] or 'no gait file'}")
        c = best.get("comfort")
        if c:
            cot = "—" if c["cost_of_transport"] is None else f"{c['cost_of_transport']:.3g}"
            print(f"  comfort: speed {c['speed']:.3f} m/s, pelvis acceleration RMS vertical "
                  f"{c['pelvis_acc_vertical_rms']:.3g} / lateral {c['pelvis_acc_lateral_rms']:.3g} m/s², cost of "
                  f"transport {cot} (docs/comfort.md)")
    obs = st["best_observed"]
    if obs is not None and not st.get("person") and (best is None or obs["score"] != best["score"]):
        params = ", ".join(f"{k} = {v:g}" for k, v in obs["params"].items())
        print(f"best evaluated gait (trial {obs['trial']}; the best gait above is the learner's highest posterior "
              f"mean): {params}; {_value(obs, st)}, {obs['steps_taken']} steps")
    person = st.get("person")
    if person:  # docs/person.md
        floor = person["floor"]
        shown = "" if floor is None else f"robustness floor {_name(st)} ≥ {floor['value']:.4g} {st['unit']}; "
        waiting = "" if person["pending"] is None else f"; batch {person['pending'] + 1} waits for an answer " \
            f"(robustgait study serve {directory})"
        ahead = person.get("ahead") or {}
        if ahead.get("evaluated"):
            waiting += (f"; {ahead['evaluated']} gaits evaluated ahead of an answer, {ahead['used']} of them then "
                        "proposed")
        print(f"  person: {shown}{len(person['answers'])} batches answered{waiting}")
    if st["environment_changes"]:
        print("created with other library versions (" + ", ".join(st["environment_changes"]) + "): the learner "
              "may propose other gaits than it did, and `study resume` refuses a proposal that differs")


def _run_interruptible(directory: str, run: RunConfig, args: argparse.Namespace) -> bool:
    """Run a study; on Ctrl-C say how to continue (the running trials are re-run by resume)."""
    from robustgait.study.run import run_study

    _check_executor(run)
    try:
        run_study(directory, run, progress=not getattr(args, "quiet", False), verbose=getattr(args, "verbose", False))
    except KeyboardInterrupt:
        print(f"\nrobustgait: interrupted; continue with: robustgait study resume {directory}", file=sys.stderr)
        return False
    return True


def _study_run(args: argparse.Namespace) -> int:
    from robustgait.cli.person import serve
    from robustgait.study.run import create_study

    config = config_from(args)
    _check_executor(config.run)
    sock = None
    if config.study.metric == "person":  # a port in use: one line, before the study exists
        from robustgait.web.server import bind

        sock = bind(config.web)
    create_study(args.dir, args.robot, config)
    t0 = time.perf_counter()
    if config.study.metric == "person":
        if not serve(args.dir, config.run, config, args, sock):
            return 130
    elif not _run_interruptible(args.dir, config.run, args):
        return 130
    print_summary(args.dir, time.perf_counter() - t0)
    return 0


def _study_resume(args: argparse.Namespace) -> int:
    from robustgait.cli.person import is_person_study, serve

    t0 = time.perf_counter()
    config = config_from(args)
    if is_person_study(args.dir):  # its batches wait for answers on the page
        if not serve(args.dir, config.run, config, args):
            return 130
    elif not _run_interruptible(args.dir, config.run, args):
        return 130
    print_summary(args.dir, time.perf_counter() - t0)
    return 0


def _study_serve(args: argparse.Namespace) -> int:
    from robustgait.cli.person import serve

    config = config_from(args)
    if not serve(args.dir, config.run, config, args):
        return 130
    print_summary(args.dir)
    return 0


def _study_status(args: argparse.Namespace) -> int:
    from robustgait.study.status import study_status

    st = study_status(args.dir)
    if args.json:
        print(json.dumps(st, allow_nan=False))
        return 0
    print_summary(args.dir)
    print(f"{'iteration':>9}  {'best ' + _name(st):>8}  {'':9}  {'steps':>5}  best gait")
    for it in st["iterations"]:
        b = it["best"]
        if b is None:
            print(f"{it['iteration'] + 1:>9}  {'—':>8}  {'':9}  {'—':>5}  "
                  f"{'running' if it['trials'] else 'not started'}")
        else:
            verified = bool(b["verified"])
            value = b["value"] if verified else b["estimate"]
            shown = "—" if value is None else f"{value:.4f}"
            how = "verified" if verified else EvaluationStatus.ESTIMATED.value
            print(f"{it['iteration'] + 1:>9}  {shown:>8}  {how:9}  "
                  f"{b['steps_taken']:>5}  " + ", ".join(f"{v:g}" for v in b["params"].values()))
    return 0


def _study_report(args: argparse.Namespace) -> int:
    from robustgait.report.study import write_study_report

    print(write_study_report(args.dir, config_from(args).report))
    return 0


def _study_compare(args: argparse.Namespace) -> int:
    from robustgait.study.compare import compare_studies

    res = compare_studies(args.dir_a, args.dir_b, config_from(args).compare)
    if args.json:
        print(json.dumps(res, allow_nan=False))
        return 0
    how = (f"uniform, N = {res['n_samples']}" if res["method"] == "uniform"
           else f"sequential, ε = {res['epsilon']:g}")
    print(f"best gaits re-certified with seeds {res['seeds'][0]}–{res['seeds'][-1]} ({how}), "
          f"walked {res['step_cap']} steps")
    if res["note"]:
        print(f"note: {res['note']}")
    for name, s in zip("AB", res["studies"], strict=True):
        params = ", ".join(f"{v:g}" for v in s["params"].values())
        print(f"{name} {s['directory']} ({s['learner']}, {s['metric']}): gait ({params}), {s['steps_taken']} steps, "
              f"{_name(res)} = {s['value_mean']:.4g} ± {s['value_sd']:.4g} {res['unit']}  "
              f"[{', '.join(f'{r:.3f}' for r in s['values'])}] "
              f"(study: {'—' if s['study_value'] is None else format(s['study_value'], '.4f')})")
    w = res["winner"]
    print(f"equal mean {_name(res)}" if w is None else f"higher mean {_name(res)}: {'AB'[w]} (per seed: A wins "
          f"{res['wins_per_seed'][0]}, B wins {res['wins_per_seed'][1]})")
    if res["note"]:
        print(f"note: {res['note']}")
    return 0


def _study_validate(args: argparse.Namespace) -> int:
    from robustgait.cli.validate import CERTIFICATE_KIND, given
    from robustgait.io.studyfile import load_config
    from robustgait.study.validate import summary_path, validate_study
    from robustgait.validate.stats import correlation_text

    setup = load_config(args.dir)
    config = config_from(args, setup.config)
    cfg = config.validate
    # --state/--set/--horizon/--method: certify every gait again with them (default: the study's certificates)
    again = given(args, (*CERTIFICATE_KIND, "certify.method"))
    try:
        out = validate_study(args.dir, cfg, certify=config.study_certify if again else None, progress=not args.quiet)
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
        star = radius_name("push" if s["certify"].get("disturbance") == "push" else "state")
        print(f"  {'gait':<26} {'study':<13} {star:>7} {'steps':>7}  {'success [95% CI]':<27} half fail at ({name})")
        for r in s["gaits"]:
            c = r["critical"]
            crit = (f"{c['s50']:.4g} ± {c['s50_se'] or 0:.2g} {unit}" if c["s50"] is not None else f"— ({c['note']})")
            sr = r["success"]
            print(f"  {r['label']:<26} {r['status']:<13} {r['value']:>7.4f} "
                  f"{r['steps_taken']:>3}/{r['step_cap']:<3}  "
                  f"{sr['k']}/{sr['n']} = {sr['rate']:.2f} [{sr['low']:.2f}, {sr['high']:.2f}]{'':<4} {crit}")
        for sk in s["skipped"]:
            print(f"  {sk['label']:<26} skipped: {sk['why']}")
        for c in s["correlations"].values():
            print(f"  {correlation_text(c)}")
        print(f"  results: {summary_path(args.dir, kind)}")
    return 0


def _demo(args: argparse.Namespace) -> int:
    from robustgait.config import preset
    from robustgait.report.study import write_study_report
    from robustgait.study.run import create_study

    config: Config = config_from(args, preset("demo"))
    d = Path(args.dir)
    t0 = time.perf_counter()
    if not (d / "study.json").exists():
        create_study(d, DEMO_ROBOT, config)
        s = config.study
        what = {"push": "push robustness (J*)", "robustness": "robustness (r*)", "stability": "stability"}[s.metric]
        print(f"demo: a study of {what} on the shipped exoskeleton ({s.iterations} iterations × {s.batch} gaits) "
              f"in {d}", flush=True)
    else:
        print(f"demo: resuming the study in {d}", flush=True)
    if not _run_interruptible(str(d), config.run, args):
        return 130
    print_summary(str(d), time.perf_counter() - t0)
    print(write_study_report(d, config.report))
    return 0


def _run_flags(p: argparse.ArgumentParser) -> None:
    p.add_argument("--verbose", action="store_true", help="print IPOPT's iteration log of every gait")
    p.add_argument("--quiet", action="store_true", help="no progress bar")


def add_parsers(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    s = sub.add_parser("study", help="learn the most robust gait: the simulation-in-the-loop preference study")
    ssub = s.add_subparsers(dest="study_command", required=True, parser_class=type(s))
    s.set_defaults(certificate="study")  # certificate options are checked against the study's certificate
    from robustgait.cli import person

    r = command(ssub, "run", "start a study in a new directory and run it to its budget (--metric person: serve its "
                "page, docs/person.md)", _study_run, {**STUDY, **RUN, **person.WEB})
    r.add_argument("dir", help="study directory (new or empty)")
    r.add_argument("--robot", required=True, help=f"{ROBOT_HELP} with [action_space]")
    _run_flags(r)
    rs = command(ssub, "resume", "continue a stopped or killed study to its total budget (a person study: with its "
                 "page)", _study_resume, {**RUN, **person.WEB})
    rs.add_argument("dir")
    _run_flags(rs)
    st = ssub.add_parser("status", help="progress, best gait and every trial of a study")
    st.add_argument("dir")
    st.add_argument("--json", action="store_true", help="print one JSON object")
    st.set_defaults(func=_study_status)
    rp = command(ssub, "report", "write DIR/report/index.html (self-contained) and its figures", _study_report,
                 {"--axes": "report.axes", "--video": "report.video"})
    rp.add_argument("dir")
    cp = command(ssub, "compare", "re-certify the best gaits of two studies with fresh seeds, side by side",
                 _study_compare, {"--seeds": "compare.seeds", "--seed-base": "compare.seed_base",
                                  "--samples": "compare.samples"})
    cp.add_argument("dir_a")
    cp.add_argument("dir_b")
    cp.add_argument("--json", action="store_true")
    va = command(ssub, "validate", "every unique gait of a study under the same disturbances: success rates and the "
                 "Spearman correlation of r* and of steps taken with success", _study_validate,
                 {"--trials": "validate.trials", "--seed": "validate.seed", "--disturbance": "validate.disturbance",
                  "--steps-after": "validate.steps_after", "--workers": "validate.workers",
                  "--state": "certify.state", "--set": "certify.set", "--horizon": "certify.horizon",
                  "--method": "certify.method"})
    va.add_argument("dir", help="study directory")
    va.add_argument("--json", action="store_true", help="print one JSON object: the summary of each kind")
    va.add_argument("--quiet", action="store_true", help="no progress bar")
    person.add_parsers(ssub, RUN, _study_serve)

    dm = command(sub, "demo", "the main job on shipped defaults: a small study of push robustness (J*) on exo + report",
                 _demo, {"--workers": "run.workers"})
    dm.set_defaults(certificate="study")
    dm.add_argument("--dir", default=DEMO_DIRECTORY, help=f"study directory (default ./{DEMO_DIRECTORY})")
