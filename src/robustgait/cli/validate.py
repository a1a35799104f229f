"""``robustgait validate``: disturbed walks of a gait and the certificate's promise tested."""

from __future__ import annotations

import argparse
import sys

from robustgait.cli.common import GAIT_HELP, ROBOT_HELP, about, command, inputs
from robustgait.cli.options import output_path

VALIDATE = {"--trials": "validate.trials", "--seed": "validate.seed", "--disturbance": "validate.disturbance",
            "--steps-after": "validate.steps_after"}


def _validate(args: argparse.Namespace) -> int:
    from robustgait.validate import validate_gait

    config, robot, gait = inputs(args)
    cfg = config.validate
    with about(args.gait):
        res = validate_gait(robot, gait, cfg, certify=config.certify, sim=config.sim, certificate=args.certificate,
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
        print(f"{kind:<9} {rate_text(sr):<24} {crit:<30} {rate_text(chk['inside']):<26} "
              f"{rate_text(chk['outside']):<24} {chk['fell_before_event']:>17}")
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
