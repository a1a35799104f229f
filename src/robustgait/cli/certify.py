"""``robustgait certify`` (a gait's robustness certificate) and ``robustgait barrier-eval`` (the DTBF condition along
a logged sequence of reduced states)."""

from __future__ import annotations

import argparse
import json
import sys
from typing import TYPE_CHECKING

from robustgait.cli.common import GAIT_HELP, ROBOT_HELP, command, inputs, naming_file
from robustgait.cli.options import config_from, number_within, numbers_within, output_path
from robustgait.config import CertifyConfig, radius_name
from robustgait.errors import RobustGaitError
from robustgait.io.limits import BARRIER_R, X_STAR

if TYPE_CHECKING:
    from robustgait.certificate.barrier import Round

CERTIFY = {"--state": "certify.state", "--set": "certify.set", "--horizon": "certify.horizon",
           "--disturbance": "certify.disturbance", "--push-horizon": "certify.push.horizon",
           "--push-duration": "validate.push_duration", "--compare-ball": "certify.ellipsoid.compare_ball",
           "--method": "certify.method", "--samples": "certify.n_samples", "--epsilon": "certify.sequential.epsilon",
           "--budget": "certify.sequential.budget", "--beta": "certify.beta", "--barrier": "certify.barrier",
           "--r-max": "certify.r_max", "--alpha": "certify.alpha", "--seed": "certify.seed", "--map": "certify.map",
           "--reconstruction": "certify.reconstruction", "--frame": "certify.frame",
           "--switching": "sim.switching", "--controller": "sim.controller",
           "--orbit-steps": "certify.orbit.max_steps", "--rho": "certify.orbit.linearization"}


def _certificate_kind(cfg: CertifyConfig) -> str:
    """The certificate's kind in a few words: state, set, horizon, map, reconstruction (or the push's steps)."""
    if cfg.disturbance == "push":
        return f"pushes, back in the band within {cfg.push.horizon} steps"
    bits = [f"{cfg.state} {cfg.set}"] + ([] if cfg.horizon == 1 else [f"horizon {cfg.horizon}"])
    if cfg.state == "omega":
        bits += [f"{cfg.frame} frame", f"{cfg.reconstruction} reconstruction"]
    return ", ".join(bits)


def _certify(args: argparse.Namespace) -> int:
    from robustgait.certificate.certify import certify_gait

    config, robot, gait = inputs(args)
    cfg = config.certify
    with naming_file(args.gait):
        gc = certify_gait(robot, gait, cfg, config.sim, validate=config.validate,
                          progress=not args.json and sys.stderr.isatty())
    c, fp, co = gc.certificate, gc.fixed_point, gc.coordinates
    name = radius_name(cfg.space)
    if args.plot is not None and c is not None:
        from robustgait.report import plot_certificate

        label = f"N = {c.n_samples}" + (f" in {len(c.rounds)} rounds" if cfg.method == "sequential" else "")
        kind = _certificate_kind(cfg)
        plot_certificate(c, args.plot, title=f"{robot.name}: {name} = {gc.value:.4g} {cfg.unit} ({kind}, "
                         f"{cfg.method}, {label}, α = {cfg.alpha:g})", coordinates=co, ball=gc.ball)
    if args.output is not None:
        from robustgait.io.output import write_json

        write_json(args.output, gc.to_dict())
    if args.json:
        print(json.dumps(gc.to_dict(samples=False), allow_nan=False))
    elif c is None:
        print(f"{gc.status}: {name} = 0 ({gc.reason}; {gc.steps_walked} steps walked)")
        if gc.orbit is not None and gc.orbit.band is not None:
            print(f"orbit: {gc.orbit.describe()}")
        if gc.speed_note:
            print(f"note: {gc.speed_note}")
    else:
        assert fp is not None and co is not None and gc.orbit is not None
        energy = "" if gc.energy is None else f", E* = {gc.energy:.4g} J"
        kind = _certificate_kind(cfg)
        print(f"{name} = {c.radius:.4g} {cfg.unit}{energy}  ({kind}, {cfg.barrier} barrier, α = {cfg.alpha:g}, "
              f"{cfg.method}: N = {c.n_samples}, seed {cfg.seed})")
        print(f"orbit: {gc.orbit.describe()}")
        print(f"x*: the switching state after step {fp.step}, ω* = [{', '.join(f'{v:.4f}' for v in fp.omega)}] rad/s"
              + ("" if gc.map_residual is None else f"; map at x*: {gc.map_residual:.2e} {cfg.unit}")
              + ("" if gc.sigma is None else f"; the orbit's scatter σ = {gc.sigma:.3g} {cfg.unit}"))
        if cfg.set == "ellipsoid" and cfg.disturbance == "state":
            sh = co.shape
            if sh.fallback:
                print(f"ellipsoid: fell back to the ball ({sh.fallback})")
            else:
                assert sh.fit is not None
                print(f"ellipsoid: semi-axes at r = 1 {' '.join(f'{v:.3g}' for v in sh.axes)} (det S = 1); fitted "
                      f"linearization spectral radius {sh.fit.spectral_radius:.3g}, relative residual "
                      f"{sh.fit.relative_residual:.2g} on {sh.fit.used} samples")
            if gc.ball is not None:
                print(f"ball of the same state: r* = {gc.ball.radius:.4g} {cfg.unit}; volume ratio ellipsoid / ball "
                      f"= {gc.volume_ratio:.3g}")
        if gc.excursion is not None:
            print("largest ‖P^j(z) − z*‖ over the samples inside, j = 1 … k: "
                  + " ".join(f"{v:.4g}" for v in gc.excursion))
        if cfg.method == "sequential":
            # a push certificate's rounds end at its nearest fall; its estimate Ĵ is the fall curve's, not that
            what = "nearest fall" if cfg.disturbance == "push" else f"{name[0]}̂"
            print(f"{what} after each round: " + " ".join(_round_text(r) for r in c.rounds)
                  + "  (u = uniform, e = explore, v = verify at the radius @, ✓ passed, ✗ failed; samples used: "
                  f"{what})")
            if cfg.disturbance == "push" and c.estimate is not None:
                print(f"Ĵ = {c.estimate:.4g} N s: the push size whose disk the fall curve fitted to the exploration "
                      f"predicts to fail in {100 * cfg.estimator.epsilon:g} % of its pushes (what a study ranks by)")
        print(f"{int(c.fell.sum())} of {c.n_samples} samples fell; {c.n_inside} inside; controller {gc.controller}"
              + (f" ({gc.controller_note})" if gc.controller_note else ""))
        print(gc.statement())
        if gc.speed_note:
            print(f"note: {gc.speed_note}")
        print(f"time: orbit {gc.seconds['orbit']:.2f} s, sampling {gc.seconds['sampling']:.2f} s "
              f"({gc.seconds['sim_steps_per_s']:.0f} simulated steps/s)")
    return 0 if gc.ok else 1


def _round_text(r: Round) -> str:
    """One round of the sequential estimator in a few characters: its kind, the samples used after it, the estimate
    after it and, for a verification batch, the radius it was drawn in and whether it passed."""
    text = f"{r.kind[0]}{r.samples_used}:{r.r_hat:.4g}"
    if r.kind == "verify":
        text += f"@{r.radius:.4g}{'✓' if r.passed else '✗'}"
    return text


def _barrier_eval(args: argparse.Namespace) -> int:
    from robustgait.certificate.barrier import barrier_along
    from robustgait.io.logs import load_reduced_log

    alpha = config_from(args).certify.alpha
    x_star = numbers_within(X_STAR, args.x_star, "argument --x-star")
    xs = load_reduced_log(args.log, args.columns.split(",") if args.columns else None)
    if xs.shape[1] != len(x_star):
        raise RobustGaitError(f"{args.log}: the log has {xs.shape[1]} columns but --x-star has "
                              f"{len(x_star)} values")
    if xs.shape[0] < 2:
        raise RobustGaitError(f"{args.log}: the DTBF condition needs at least 2 consecutive states (rows), got "
                              f"{xs.shape[0]}")
    trace = barrier_along(xs, x_star, args.r, alpha)
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


def add_parsers(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    c = command(sub, "certify", "robustness certificate of a gait: J* by default (the push impulse it survives, with "
                "a stated confidence; --disturbance state: r*, DTBF on the Poincaré map in a reduced state); exit 1 "
                "if the gait falls, its switching states settle in no band, or small pushes do not come back to it "
                "(its figure is then 0)", _certify, CERTIFY)
    c.add_argument("gait", help=GAIT_HELP)
    c.add_argument("--robot", required=True, help=ROBOT_HELP)
    c.add_argument("--plot", metavar="CERT.png", type=output_path("plot"),
                   help="draw the certificate: the pushes and the J* disk (a state certificate: its samples, the r* "
                   "sphere, projections): .png, .pdf or .svg")
    c.add_argument("-o", "--output", metavar="CERT.json", type=output_path("json"),
                   help="write the full certificate with samples")
    c.add_argument("--json", action="store_true", help="print one JSON object (without the samples)")

    b = command(sub, "barrier-eval", "evaluate the DTBF condition along a logged sequence of reduced states",
                _barrier_eval, {"--alpha": "certify.alpha"})
    b.add_argument("log", help="CSV with a header row, NPY (one 2-D array) or NPZ (array 'x')")
    b.add_argument("--x-star", nargs="+", required=True,
                   help="fixed point: 0.42,0.21,0.30 or 0.42 0.21 0.30 (negative values: -0.4 0.2 0.3)")
    b.add_argument("--r", type=number_within(BARRIER_R), required=True, help=f"ball radius r ({BARRIER_R.text()})")
    b.add_argument("--columns", help="comma-separated CSV columns to use (default: all numeric columns)")
    b.add_argument("--plot", metavar="OUT.png", type=output_path("plot"),
                   help="plot H and the DTBF margin along the sequence (.png, .pdf or .svg)")
    b.add_argument("--json", action="store_true")
    b.add_argument("--check", action="store_true", help="exit 1 if the condition is violated anywhere")
