"""The ``robustgait`` command: parses arguments and calls the API, nothing else.

Every user-input problem ends in one line on stderr, ``robustgait: error: ...``, and exit status 2.
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from typing import TYPE_CHECKING, NoReturn

from robustgait.errors import RobustGaitError
from robustgait.io import limits as L
from robustgait.io.args import finite_float, float_in, floats_in, int_in, output_path
from robustgait.io.output import check_output, kind_of

if TYPE_CHECKING:
    pass


def _check_outputs(*paths: str | None) -> None:
    """Fail before any work when an output file could not be written (:func:`robustgait.io.output.check_output`,
    the kind of output from the extension). Output arguments declared with ``type=output_path(kind)`` are
    checked while parsing already; this is for paths that are not."""
    for out in paths:
        if out is not None:
            check_output(out, kind_of(out))


@contextmanager
def _about(path: str) -> Iterator[None]:
    """Report a problem found while running an input (a gait that cannot start, has no fixed point, ...)
    against its file: every bad-input message names the file."""
    try:
        yield
    except RobustGaitError as exc:
        msg = str(exc)
        raise RobustGaitError(msg if msg.startswith(f"{path}: ") else f"{path}: {msg}") from None


def _cmd_robots(args: argparse.Namespace) -> int:
    from robustgait.robots import load_robot, shipped_robots

    rows = []
    for name in shipped_robots():
        r = load_robot(name)
        rows.append({"name": name, "joints": r.n_joints, "mass_kg": round(r.mass, 3),
                     "description": r.spec.description})
    if args.json:
        print(json.dumps(rows))
    else:
        print(f"{'robot':<10} {'joints':>6} {'mass [kg]':>10}  description")
        for row in rows:
            print(f"{row['name']:<10} {row['joints']:>6} {row['mass_kg']:>10.1f}  {row['description']}")
    return 0


def _cmd_walk(args: argparse.Namespace) -> int:
    from robustgait.gait import load_gait
    from robustgait.io.output import write_csv
    from robustgait.robots import load_robot
    from robustgait.sim import SimConfig, render_video, walk

    robot = load_robot(args.robot)
    gait = load_gait(args.gait, robot)
    config = SimConfig(switching=args.switching, feedforward=not args.no_feedforward)
    _check_outputs(args.video, args.log)
    L.check_work(args.steps, gait.step_duration * config.max_step_tau, robot.dt,
                 f"{args.gait}: --steps {args.steps}",
                 L.MAX_VIDEO_PHYSICS_STEPS if args.video is not None else L.MAX_PHYSICS_STEPS)
    if args.video is not None and args.video.lower().endswith(".gif"):
        L.check_gif(args.steps * gait.step_duration * config.max_step_tau, args.video)
    with _about(args.gait):
        result = walk(robot, gait, steps=args.steps, config=config, keep_trajectory=args.video is not None)
    if args.video is not None and result.trajectory is not None:
        render_video(robot, result.trajectory, args.video)
    if args.log is not None:
        from robustgait.poincare import canonical_reduced_events

        xs = canonical_reduced_events(robot, gait, result.events, args.frame)
        write_csv(args.log, ["wx", "wy", "wz"], xs.tolist())
    if args.json:
        print(result.to_json())
    else:
        end = f"fell ({result.fall_reason}) at t = {result.time:.2f} s" if result.fell else "no fall"
        print(f"{gait.robot} gait on {robot.name}: {result.steps_taken}/{result.max_steps} steps, {end}; "
              f"mean forward speed {result.mean_speed:.3f} m/s; lowest base height "
              f"{result.min_base_height:.3f} m; {result.switching} switching")
        for what, out in (("video", args.video), ("reduced-state log", args.log)):
            if out is not None:
                print(f"{what}: {out}")
    return 0


class _Parser(argparse.ArgumentParser):
    """argparse with the project's error format: one line on stderr, exit status 2."""

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"robustgait: error: {message} (see {self.prog} --help)\n")


def _cmd_certify(args: argparse.Namespace) -> int:
    from robustgait.certify import CertifyConfig, certify_gait
    from robustgait.estimators import SequentialConfig
    from robustgait.gait import load_gait
    from robustgait.robots import load_robot
    from robustgait.sim import SimConfig

    seq = SequentialConfig(epsilon=args.epsilon, budget=args.budget)
    cfg = CertifyConfig(n_samples=args.samples, r_max=args.r_max, alpha=args.alpha, seed=args.seed, beta=args.beta,
                        method=args.method, barrier=args.barrier, sequential=seq,
                        map=args.map, reconstruction=args.reconstruction, frame=args.frame,
                        fp_tol=args.fp_tol, fp_max_steps=args.fp_max_steps,
                        fp_min_steps=min(10, max(args.fp_max_steps, 1)), sim=SimConfig(switching=args.switching))
    _check_outputs(args.plot, args.output)
    robot = load_robot(args.robot)
    gait = load_gait(args.gait, robot)
    per_map = 2 if cfg.map == "stride" else 1
    n, what = (cfg.n_samples, "--samples") if cfg.method == "uniform" else (seq.budget, "--budget")
    L.check_work(per_map * (cfg.fp_max_steps + n + 1), gait.step_duration * cfg.sim.max_step_tau,
                 robot.dt, f"{args.gait}: --fp-max-steps {cfg.fp_max_steps} + {what} {n}")
    with _about(args.gait):
        gc = certify_gait(robot, gait, cfg, progress=not args.json and sys.stderr.isatty())
    c, fp = gc.certificate, gc.fixed_point
    if args.plot is not None and c is not None:
        from robustgait.report import plot_certificate

        label = f"N = {c.n_samples}" + (f" in {len(c.rounds)} rounds" if cfg.method == "sequential" else "")
        plot_certificate(c, args.plot, title=f"{robot.name}: r* = {gc.r_star:.4f} rad/s ({cfg.map} map, "
                         f"{cfg.reconstruction}, {cfg.method}, {label}, α = {cfg.alpha:g})")
    if args.output is not None:
        from robustgait.io.output import write_json

        write_json(args.output, gc.to_dict())
    if args.json:
        print(json.dumps(gc.to_dict(samples=False), allow_nan=False))
    elif c is None:
        print(f"{gc.status}: r* = 0 ({gc.reason}; {gc.steps_walked} steps walked)")
    else:
        assert fp is not None and gc.map_residual is not None
        print(f"r* = {c.r_star:.4f} rad/s  ({cfg.map} map, {cfg.reconstruction} reconstruction, {cfg.frame} frame, "
              f"{cfg.barrier} barrier, α = {cfg.alpha:g}, {cfg.method}: N = {c.n_samples}, seed {cfg.seed})")
        print(f"x* = [{', '.join(f'{v:.4f}' for v in fp.x_star)}] rad/s after {fp.steps} steps; residual "
              f"{fp.residual:.2e} (map at x*: {gc.map_residual:.2e})")
        if cfg.method == "sequential":
            print("r̂ after each round: " + " ".join(f"{r.kind[0]}{r.samples_used}:{r.r_hat:.4g}" for r in c.rounds)
                  + "  (u = uniform, e = explore, v = verify; samples used: r̂)")
        print(f"{int(c.fell.sum())} of {c.n_samples} samples fell; {c.n_inside} inside B(r*)")
        print(c.statement())
        print(f"time: fixed point {gc.seconds['fixed_point']:.2f} s, sampling {gc.seconds['sampling']:.2f} s "
              f"({gc.seconds['sim_steps_per_s']:.0f} simulated steps/s)")
    return 0 if gc.ok else 1


def _cmd_barrier_eval(args: argparse.Namespace) -> int:
    from robustgait.barrier import barrier_along, load_reduced_log

    x_star = floats_in(L.X_STAR, args.x_star, "argument --x-star")
    xs = load_reduced_log(args.log, args.columns.split(",") if args.columns else None)
    if xs.shape[1] != len(x_star):
        raise RobustGaitError(f"{args.log}: the log has {xs.shape[1]} columns but --x-star has "
                              f"{len(x_star)} values")
    if xs.shape[0] < 2:
        raise RobustGaitError(f"{args.log}: the DTBF condition needs at least 2 consecutive states (rows), got "
                              f"{xs.shape[0]}")
    trace = barrier_along(xs, x_star, args.r, args.alpha)
    if args.plot is not None:
        from robustgait.report import plot_barrier_trace

        plot_barrier_trace(trace, args.plot)
    if args.json:
        print(json.dumps({"ok": trace.ok, "first_violation": trace.first_violation, "r": trace.r,
                          "alpha": trace.alpha, "h": trace.h.tolist(), "margins": trace.margins.tolist()}))
    else:
        verdict = "holds at every step" if trace.ok else f"is violated first at step {trace.first_violation}"
        print(f"DTBF condition (r = {trace.r:g}, α = {trace.alpha:g}) {verdict} over {trace.h.size} states; "
              f"min H = {trace.h.min():.4g}, min margin = {trace.margins.min():.4g}")
    return 0 if trace.ok or not args.check else 1


def _cmd_gait_convert(args: argparse.Namespace) -> int:
    from robustgait.gait import load_gait
    from robustgait.robots import load_robot

    robot = load_robot(args.robot)
    gait = load_gait(args.gait, robot)
    if args.mirror:
        gait = gait.mirrored(robot)
    gait.save(args.output)
    print(f"wrote {args.output} ({gait.stance} stance, {gait.n_outputs} outputs, T = {gait.step_duration} s)")
    return 0


def _cmd_gait_generate(args: argparse.Namespace) -> int:
    from robustgait.gait import GaitParams, load_gait
    from robustgait.gaitgen import DEFAULT_STEP_DURATION, GaitGenConfig, GaitGenerator, generate_gait
    from robustgait.robots import load_robot

    if args.step_duration is None:
        args.step_duration = DEFAULT_STEP_DURATION[args.domains]
    try:  # out-of-bounds parameters fail before the (seconds-long) problem build
        GaitParams(args.step_length, args.step_duration, args.step_width, args.step_height, args.rolling_fraction)
    except RobustGaitError as exc:
        raise RobustGaitError(f"gait generation failed (Infeasible_Parameters): {exc}") from None
    if args.nodes % 2 == 0:
        raise RobustGaitError(f"--nodes must be odd and ≥ 5, got {args.nodes}")
    robot = load_robot(args.robot)
    _check_outputs(args.output)
    warm = load_gait(args.warm_start, robot) if args.warm_start else None
    config = GaitGenConfig(domains=args.domains, nodes=args.nodes, stance=args.stance)
    live = not args.json
    if live:
        what = "flat-foot" if args.domains == "flat" else "multi-contact (heel/toe rolling)"
        print(f"building the {what} HZD problem for {robot.name} ({args.nodes} nodes) ...", flush=True)
    gen = GaitGenerator(robot, config, verbose=live and args.verbose)
    if live:
        print(f"built in {gen.build_seconds:.1f} s: {gen.n_variables} variables, {gen.n_constraints} constraints; "
              + ("IPOPT iterations:" if args.verbose else "solving ..."), flush=True)
    res = generate_gait(robot, args.step_length, args.step_duration, args.step_width, args.step_height,
                        args.rolling_fraction, warm_start=warm, generator=gen)
    summary = {**res.summary(), "build_seconds": gen.build_seconds, "output": args.output if res.gait else None}
    if res.gait is None:
        if args.json:
            print(json.dumps(summary, allow_nan=False))
        raise RobustGaitError(f"gait generation failed ({res.status}): {res.reason}")
    res.gait.save(args.output)
    if args.json:
        print(json.dumps(summary, allow_nan=False))
    else:
        c = res.check
        assert c is not None
        print(f"{res.status}: {res.iterations} iterations in {res.solve_seconds:.2f} s "
              f"({res.solve_seconds / max(res.iterations, 1) * 1e3:.0f} ms/iteration), ∫‖u‖²dt = {res.objective:.4g}")
        print(f"physics check passed: dynamics residual {c.dynamics_residual:.1e} (MuJoCo), periodicity "
              f"{c.periodicity:.1e}, min normal force {c.min_normal_force:.0f} N, friction |f_t|/f_z ≤ "
              f"{c.friction_ratio:.2f}, CoP margin {c.cop_margin * 1e3:.1f} mm")
        print(f"wrote {args.output}")
    return 0


def _cmd_validate(args: argparse.Namespace) -> int:
    from robustgait.gait import load_gait
    from robustgait.robots import load_robot
    from robustgait.validate import KINDS, ValidateConfig, validate_gait

    cfg = ValidateConfig(trials=args.trials, seed=args.seed, steps_after=args.steps_after)
    robot = load_robot(args.robot)
    gait = load_gait(args.gait, robot)
    # one kind is one batch of trials, each 1 (or 2, stride map) + --steps-after steps
    L.check_work(args.trials * (2 + args.steps_after), gait.step_duration * cfg.sim.max_step_tau, robot.dt,
                 f"{args.gait}: --trials {args.trials} × (--steps-after {args.steps_after} + 1) per kind")
    kinds = list(KINDS) if args.disturbance == "all" else [args.disturbance]
    with _about(args.gait):
        res = validate_gait(robot, gait, cfg, kinds=kinds, certificate=args.certificate,
                            progress=not args.json and sys.stderr.isatty())
    if args.output is not None:  # the results first: they took minutes, the figure is redrawn from them
        from robustgait.io.output import write_text

        write_text(args.output, res.to_json(), "json")
    if args.plot is not None:
        from robustgait.report import plot_validation

        plot_validation(res, args.plot)
    if args.json:
        print(res.to_json(trials=False))
        return 0
    c = res.certificate
    print(f"{robot.name}: r* = {c.r_star:.4f} rad/s ({'closed' if c.attained else 'open'} ball, {c.map} map, "
          f"certificate {c.source}); {cfg.trials} trials per kind, seed {cfg.seed}, success = no fall in "
          f"{cfg.steps_after} steps after the first switching event")
    print(f"{'kind':<9} {'success [95% CI]':<24} {'half fail at (± s.e.)':<30} {'falls inside B(r*)':<26} "
          f"{'falls outside':<24} {'fell before event':>17}")
    for kind, kr in res.kinds.items():
        sr, fit, chk = kr.success_rate(), kr.critical(), kr.certificate_check()
        _, unit = kr.size_label
        if fit.s50 is not None:
            crit = f"{fit.s50:.4g} ± {fit.s50_se or 0:.2g} {unit}" + ("" if fit.in_range else " (extrapolated)") + (
                "" if fit.converged else " (gap)")
        else:
            crit = f"— ({fit.note})"
        print(f"{kind:<9} {_rate(sr):<24} {crit:<30} {_rate(chk['inside']):<26} {_rate(chk['outside']):<24} "
              f"{chk['fell_before_event']:>17}")
    print(f"time: setup {res.seconds['setup']:.1f} s, " + ", ".join(
        f"{k} {v.seconds:.1f} s" for k, v in res.kinds.items()))
    for what, out in (("plot", args.plot), ("results", args.output)):
        if out is not None:
            print(f"{what}: {out}")
    return 0


def _rate(r: object) -> str:
    from robustgait.validate import Rate

    assert isinstance(r, Rate)
    if r.n == 0:
        return "0/0"
    return f"{r.k}/{r.n} = {r.rate:.2f} [{r.low:.2f}, {r.high:.2f}]"


def _cmd_gait_tiles(args: argparse.Namespace) -> int:
    from robustgait.gait import load_gait
    from robustgait.report.tiles import render_tiles
    from robustgait.robots import load_robot

    robot = load_robot(args.robot)
    gait = load_gait(args.gait, robot)
    with _about(args.gait):
        shape = render_tiles(robot, gait, args.output, frames=args.frames, warmup_steps=args.warmup_steps)
    print(f"wrote {args.output} ({shape[1]} x {shape[0]} px: {args.frames} frames of one step, side and front)")
    return 0


def build_parser() -> argparse.ArgumentParser:
    p = _Parser(prog="robustgait", description="Synthesize and certify robust walking gaits.")
    sub = p.add_subparsers(dest="command", required=True)

    r = sub.add_parser("robots", help="list the shipped robots")
    r.add_argument("--json", action="store_true", help="print JSON")
    r.set_defaults(func=_cmd_robots)

    w = sub.add_parser("walk", help="walk a gait in MuJoCo and report steps taken, falls and speed")
    w.add_argument("gait", help="gait file: .json (robustgait) or .yaml (FROST/ambersim)")
    w.add_argument("--robot", required=True, help="shipped robot name or path to a spec .toml")
    w.add_argument("--steps", type=int_in(L.STEPS), default=50, help=f"step cap (default 50; {L.STEPS.text()})")
    w.add_argument("--switching", choices=("impact", "time"), default="impact",
                   help="switch stance at swing-foot touchdown once τ ≥ 0.8 (impact) or at τ = 1 (time)")
    w.add_argument("--no-feedforward", action="store_true", help="joint PD only, ignore feedforward torques")
    w.add_argument("--json", action="store_true", help="print one JSON object")
    w.add_argument("--video", metavar="OUT.mp4", type=output_path("video"),
                   help="render the walk with MuJoCo's offscreen renderer (.mp4 or .gif)")
    w.add_argument("--log", metavar="OUT.csv", type=output_path("csv"),
                   help="write the reduced state (base angular velocity, canonical stance) at every switching "
                   "event, one row per step, for barrier-eval")
    w.add_argument("--frame", choices=("heading", "world", "body"), default="heading",
                   help="frame of the logged angular velocity (default heading)")
    w.set_defaults(func=_cmd_walk)

    c = sub.add_parser("certify", help="robustness certificate r* of a gait (DTBF on the Poincaré map); exit 1 "
                       "if the gait falls or has no fixed point (r* = 0)")
    c.add_argument("gait", help="gait file: .json (robustgait) or .yaml (FROST/ambersim)")
    c.add_argument("--robot", required=True, help="shipped robot name or path to a spec .toml")
    c.add_argument("--method", choices=("uniform", "sequential"), default="uniform",
                   help="uniform: the paper's N samples in B(r_max) (default); sequential: rounds inside B(r̂) "
                   "until a fresh batch certifies the violating fraction ≤ epsilon (studies use it)")
    c.add_argument("--samples", type=int_in(L.SAMPLES), default=200,
                   help=f"uniform: number of sampled perturbations N (default 200; {L.SAMPLES.text()})")
    c.add_argument("--epsilon", type=float_in(L.EPSILON), default=0.02,
                   help="sequential: bound on the violating volume fraction to certify (default 0.02)")
    c.add_argument("--budget", type=int_in(L.BUDGET), default=3000,
                   help=f"sequential: most samples in all rounds (default 3000; {L.BUDGET.text()})")
    c.add_argument("--beta", type=float_in(L.BETA), default=0.05, help="1 − confidence of the statement (default 0.05)")
    c.add_argument("--barrier", choices=("ball", "paper"), default="ball",
                   help="ball: H = r² − ‖x − x*‖² (default); paper: the paper's literal H = r − ‖x − x*‖²")
    c.add_argument("--r-max", type=float_in(L.R_MAX), default=2.0,
                   help=f"radius of the sampled ball [rad/s] (default 2; {L.R_MAX.text()})")
    c.add_argument("--alpha", type=float_in(L.ALPHA), default=0.05, help="DTBF decay rate α in (0, 1) (default 0.05)")
    c.add_argument("--seed", type=int_in(L.SEED), default=0, help="sampling seed (default 0; ≥ 0)")
    c.add_argument("--map", choices=("step", "stride"), default="step", help="step (mirrored) or stride map")
    c.add_argument("--reconstruction", choices=("holonomic", "angular-only"), default="holonomic",
                   help="how a full state is rebuilt from a reduced one (default holonomic)")
    c.add_argument("--frame", choices=("heading", "world", "body"), default="heading",
                   help="frame of the base angular velocity (default heading: world frame without yaw)")
    c.add_argument("--switching", choices=("impact", "time"), default="impact")
    c.add_argument("--fp-tol", type=float_in(L.FP_TOL), default=5e-3,
                   help="fixed point: stop when successive reduced states differ by less (default 5e-3 rad/s)")
    c.add_argument("--fp-max-steps", type=int_in(L.FP_MAX_STEPS), default=100,
                   help=f"fixed point: give up after this many steps (default 100; {L.FP_MAX_STEPS.text()})")
    c.add_argument("--plot", metavar="CERT.png", type=output_path("plot"),
                   help="draw the invariant set (samples, r* sphere, projections): .png, .pdf or .svg")
    c.add_argument("-o", "--output", metavar="CERT.json", type=output_path("json"),
                   help="write the full certificate with samples")
    c.add_argument("--json", action="store_true", help="print one JSON object (without the samples)")
    c.set_defaults(func=_cmd_certify)

    b = sub.add_parser("barrier-eval", help="evaluate the DTBF condition along a logged sequence of reduced states")
    b.add_argument("log", help="CSV with a header row, NPY (one 2-D array) or NPZ (array 'x')")
    b.add_argument("--x-star", nargs="+", required=True,
                   help="fixed point: 0.42,0.21,0.30 or 0.42 0.21 0.30 (negative values: -0.4 0.2 0.3)")
    b.add_argument("--r", type=float_in(L.BARRIER_R), required=True, help="ball radius r")
    b.add_argument("--alpha", type=float_in(L.ALPHA), default=0.05)
    b.add_argument("--columns", help="comma-separated CSV columns to use (default: all numeric columns)")
    b.add_argument("--plot", metavar="OUT.png", type=output_path("plot"),
                   help="plot H and the DTBF margin along the sequence (.png, .pdf or .svg)")
    b.add_argument("--json", action="store_true")
    b.add_argument("--check", action="store_true", help="exit 1 if the condition is violated anywhere")
    b.set_defaults(func=_cmd_barrier_eval)

    g = sub.add_parser("gait", help="gait files")
    gsub = g.add_subparsers(dest="gait_command", required=True)
    gc = gsub.add_parser("convert", help="read a gait (either format) and write robustgait JSON")
    gc.add_argument("gait")
    gc.add_argument("--robot", required=True)
    gc.add_argument("-o", "--output", required=True, type=output_path("json"), help="output gait .json")
    gc.add_argument("--mirror", action="store_true", help="relabel for the other stance leg")
    gc.set_defaults(func=_cmd_gait_convert)
    gg = gsub.add_parser("generate", help="HZD trajectory optimization of a gait (CasADi + IPOPT): flat-foot or "
                         "multi-contact heel/toe rolling")
    gg.add_argument("--robot", required=True, help="shipped robot name or path to a spec .toml")
    gg.add_argument("--domains", choices=("flat", "multicontact"), default="flat",
                    help="domain graph: flat (one domain, flat foot) or multicontact (single support, heel strike, "
                    "rolling double support, toe-off); default flat")
    gg.add_argument("--step-length", type=finite_float, default=0.15, help="[m] (default 0.15)")
    gg.add_argument("--step-duration", type=finite_float, default=None,
                    help="[s] (default 0.7 flat, 0.9 multicontact)")
    gg.add_argument("--rolling-fraction", type=finite_float, default=0.2,
                    help="multicontact: the fraction of the step in rolling double support (default 0.2)")
    gg.add_argument("--step-width", type=finite_float, default=0.25, help="[m] (default 0.25)")
    gg.add_argument("--step-height", type=finite_float, default=0.07,
                    help="swing-foot height at mid-step [m] (default 0.07)")
    gg.add_argument("--warm-start", metavar="GAIT", help="start from a neighbouring gait (.json or .yaml)")
    gg.add_argument("--nodes", type=int_in(L.NODES), default=17,
                    help=f"collocation nodes, odd (default 17; {L.NODES.text()})")
    gg.add_argument("--stance", choices=("left", "right"), default="right", help="stance leg of the written gait")
    gg.add_argument("-o", "--output", required=True, type=output_path("json"),
                    help="output gait .json (checked before the solve)")
    gg.add_argument("--json", action="store_true", help="print one JSON summary instead of the live log")
    gg.add_argument("--verbose", action="store_true", help="print IPOPT's iteration log")
    gg.set_defaults(func=_cmd_gait_generate)
    gt = gsub.add_parser("tiles", help="frames of one step side by side, seen from the side and the front (PNG)")
    gt.add_argument("gait", help="gait file: .json (robustgait) or .yaml (FROST/ambersim)")
    gt.add_argument("--robot", required=True, help="shipped robot name or path to a spec .toml")
    gt.add_argument("-o", "--output", required=True, metavar="TILES.png", type=output_path("plot"))
    gt.add_argument("--frames", type=int_in(L.FRAMES), default=6, help="frames of the step (default 6)")
    gt.add_argument("--warmup-steps", type=int_in(L.WARMUP_STEPS), default=4,
                    help="steps walked before the step shown, to be on the periodic orbit (default 4)")
    gt.set_defaults(func=_cmd_gait_tiles)

    v = sub.add_parser("validate", help="disturbed walks (pushes, model mismatch, rough ground) and the "
                       "certificate's promise tested")
    v.add_argument("gait", help="gait file: .json (robustgait) or .yaml (FROST/ambersim)")
    v.add_argument("--robot", required=True, help="shipped robot name or path to a spec .toml")
    v.add_argument("--trials", type=int_in(L.TRIALS), default=200, help="trials per disturbance kind (default 200)")
    v.add_argument("--seed", type=int_in(L.SEED), default=0, help="seed of the disturbances (default 0)")
    v.add_argument("--disturbance", choices=("push", "mass", "friction", "latency", "noise", "terrain", "all"),
                   default="push", help="disturbance kind (default push; all = every kind in turn)")
    v.add_argument("--steps-after", type=int_in(L.STEPS_AFTER), default=20,
                   help="steps to walk after the first switching event after the disturbance (default 20)")
    v.add_argument("--certificate", metavar="CERT.json",
                   help="check against this certificate (robustgait certify -o); default: certify first")
    v.add_argument("--plot", metavar="OUT.png", type=output_path("plot"),
                   help="success against disturbance size, and the certificate check")
    v.add_argument("-o", "--output", metavar="OUT.json", type=output_path("json"),
                   help="write the results with every trial")
    v.add_argument("--json", action="store_true", help="print one JSON object (without the trials)")
    v.set_defaults(func=_cmd_validate)
    from robustgait.cli_study import add_study_parsers

    add_study_parsers(sub)
    return p


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; returns the exit status (0 ok, 1 ``--check`` violated or stdout closed, 2 bad
    input with one line on stderr, 130 interrupted)."""
    parser = build_parser()
    try:  # a bad argument: argparse printed one line; return its status so that in-process callers get it
        args = parser.parse_args(argv)
    except SystemExit as exc:
        return exc.code if isinstance(exc.code, int) else 2
    func: Callable[[argparse.Namespace], int] = args.func
    try:
        return func(args)
    except RobustGaitError as exc:
        print(f"robustgait: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:  # outputs are written atomically: nothing half-written is left
        print("robustgait: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:  # stdout closed early (``robustgait ... | head``): not an error of ours
        _silence_stdout()
        return 1


def _silence_stdout() -> None:
    """Point stdout at /dev/null so that the interpreter's final flush does not fail again."""
    import os

    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
    except (OSError, ValueError):  # stdout has no file descriptor (captured in-process)
        pass


if __name__ == "__main__":
    sys.exit(main())
