"""``robustgait validate``: disturbed walks of a gait and the certificate's promise tested."""

from __future__ import annotations

import argparse
import sys

from robustgait.cli.common import GAIT_HELP, ROBOT_HELP, command, inputs, naming_file
from robustgait.cli.options import output_path

VALIDATE = {"--trials": "validate.trials", "--seed": "validate.seed", "--disturbance": "validate.disturbance",
            "--steps-after": "validate.steps_after", "--state": "certify.state", "--set": "certify.set",
            "--horizon": "certify.horizon", "--method": "certify.method", "--controller": "sim.controller"}
CERTIFICATE_KIND = ("certify.state", "certify.set", "certify.horizon")


def given(args: argparse.Namespace, paths: tuple[str, ...]) -> bool:
    """Whether any of these config paths was set by a flag on the command line."""
    return any(f"cfg:{'|'.join(f.paths)}" in vars(args) and set(f.paths) & set(paths)
               for f in getattr(args, "robustgait_flags", []))


def _validate(args: argparse.Namespace) -> int:
    from robustgait.validate import validate_gait

    config, robot, gait = inputs(args)
    cfg = config.validate
    # with --certificate the file says what was certified; --state/--set/--horizon given too must agree with it
    certify = config.certify if args.certificate is None or given(args, CERTIFICATE_KIND) else None
    with naming_file(args.gait):
        res = validate_gait(robot, gait, cfg, certify=certify, sim=config.sim, certificate=args.certificate,
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
    from robustgait.config.certify import R_MAX_UNIT, radius_name

    name = radius_name(c.space)
    energy = "" if c.energy is None else f", E* = {c.energy:.4g} J"
    kind = "disk of push impulses" if c.space == "push" else (f"{c.space} {c.set}, horizon {c.horizon}, {c.map} "
                                                               "map")
    print(f"{robot.name}: {name} = {c.value:.4g} {R_MAX_UNIT[c.space]}{energy} ({'closed' if c.attained else 'open'} "
          f"{kind}, certificate {c.source}); {cfg.trials} trials per "
          f"kind, seed {cfg.seed}, success = no fall in {cfg.steps_after} steps after the first switching event")
    inside = f"|J| ≤ J*: fell in {cfg.steps_after} steps" if c.space == "push" else "falls inside the set"
    print(f"{'kind':<9} {'success [95% CI]':<24} {'half fail at (± s.e.)':<30} {inside:<26} "
          f"{'falls outside':<24} {'fell before event':>17}")
    for kind, kr in res.kinds.items():
        sr, fit, chk = kr.success_rate(), kr.critical(), kr.certificate_check()
        _, unit = kr.size_label
        if fit.s50 is not None:
            crit = f"{fit.s50:.4g} ± {fit.s50_se or 0:.2g} {unit}" + ("" if fit.in_range else " (extrapolated)") + (
                "" if fit.converged else " (gap)")
        else:
            crit = f"— ({fit.note})"
        print(f"{kind:<9} {rate_text(sr):<24} {crit:<30} {rate_text(chk['inside']):<26} "
              f"{rate_text(chk['outside']):<24} {chk['fell_before_event']:>17}")
        if "inside_at_horizon" in chk and kr.horizon is not None:
            print(f"          the certificate's own promise at its horizon (the pushed step and {kr.horizon - 1} "
                  f"more: no fall before it was back in its orbit's band), pushes |J| ≤ J* that failed it: "
                  f"{rate_text(chk['inside_at_horizon'])}; at the user's horizon, {cfg.steps_after} steps: fell "
                  f"{rate_text(chk['inside'])}")
        q = kr.summary()["energy"]
        if q is not None:
            line = (f"          kinetic energy added at the first section: median {q['median']:.3g} J "
                    f"[{q['q25']:.3g}, {q['q75']:.3g}]")
            if "energy_below_star" in chk:
                line += f"; falls among trials adding ≤ E*: {rate_text(chk['energy_below_star'])}"
            print(line)
    print(f"time: setup {res.seconds['setup']:.1f} s, " + ", ".join(
        f"{k} {v.seconds:.1f} s" for k, v in res.kinds.items()))
    for what, out in (("plot", args.plot), ("results", args.output)):
        if out is not None:
            print(f"{what}: {out}")
    return 0


def rate_text(r: object) -> str:
    from robustgait.validate import Rate

    assert isinstance(r, Rate)
    if r.n == 0:
        return "0/0"
    return f"{r.k}/{r.n} = {r.rate:.2f} [{r.low:.2f}, {r.high:.2f}]"


def add_parsers(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    v = command(sub, "validate", "disturbed walks (pushes, model mismatch, rough ground) and the certificate's "
                "promise tested", _validate, VALIDATE)
    v.add_argument("gait", help=GAIT_HELP)
    v.add_argument("--robot", required=True, help=ROBOT_HELP)
    v.add_argument("--certificate", metavar="CERT.json",
                   help="check against this certificate (robustgait certify -o); default: certify first")
    v.add_argument("--plot", metavar="OUT.png", type=output_path("plot"),
                   help="success against disturbance size, and the certificate check")
    v.add_argument("-o", "--output", metavar="OUT.json", type=output_path("json"),
                   help="write the results with every trial")
    v.add_argument("--json", action="store_true", help="print one JSON object (without the trials)")
