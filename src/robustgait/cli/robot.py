"""``robustgait robot init`` (a commented spec written from a robot's MJCF or URDF) and ``robustgait robot check``
(a spec checked against its model); ``docs/robots.md``, "Your robot"."""

from __future__ import annotations

import argparse
import json
import sys

from robustgait.cli.common import command
from robustgait.cli.options import output_path

INIT = {"--name": "robot.name", "--plan": "robot.plan", "--keyframe": "robot.keyframe",
        "--bandwidth": "robot.bandwidth", "--damping-ratio": "robot.damping_ratio",
        "--tracking-error": "robot.tracking_error", "--timestep-rule": "robot.timestep_rule"}
CHECK = {"--stand-time": "robot.check.stand_time", "--seed": "robot.seed", "--timestep": "robot.check.timestep"}


def progress(line: str) -> None:
    """A progress line on stderr (stdout keeps the command's answer)."""
    print(line, file=sys.stderr, flush=True)


def _init(args: argparse.Namespace) -> int:
    from robustgait.cli.options import config_from
    from robustgait.io.robotfile import write_spec
    from robustgait.robotinit.init import init_spec
    from robustgait.robotinit.writer import render, summary

    config = config_from(args)
    draft = init_spec(args.model, args.output, config, say=progress)
    write_spec(args.output, render(draft, args.output))
    print("\n".join(summary(draft, args.output)))
    return 0


def _check(args: argparse.Namespace) -> int:
    from robustgait.cli.options import config_from
    from robustgait.inspection.check import run_checks
    from robustgait.io.robotfile import load_robot
    from robustgait.robotinit.timestep import check_timestep

    config = config_from(args)
    robot = load_robot(args.spec)
    results = run_checks(robot, config.robot)
    if config.robot.check.timestep:
        results.append(check_timestep(robot, config, say=None if args.json else progress))
    failed = [r.name for r in results if not r.passed]
    if args.json:
        print(json.dumps({"robot": robot.name, "passed": not failed,
                          "checks": [{"name": r.name, "passed": r.passed, "line": r.line, **r.values}
                                     for r in results]}))
    else:
        for r in results:
            print(r.line)
        print(f"{robot.name}: " + (f"{len(failed)} of {len(results)} checks failed ({', '.join(failed)})" if failed
                                   else f"all {len(results)} checks passed"))
    return 1 if failed else 0


def add_parsers(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    r = sub.add_parser("robot", help="your robot: write a spec from its MJCF/URDF (init), check a spec (check)")
    rsub = r.add_subparsers(dest="robot_command", required=True, parser_class=type(r))
    i = command(rsub, "init", "write a commented robot spec from an MJCF or URDF: legs, soles, floor, mirror "
                "(verified), PD gains from the reflected inertias, posture, gait values scaled to the robot, the "
                "timestep by accuracy (the default gait walked at each candidate step and at half of it: tens of "
                "seconds; progress on stderr)", _init, INIT)
    i.add_argument("model", help="the robot's model: an MJCF (.xml) with a free joint, or a URDF (.urdf)")
    i.add_argument("-o", "--output", required=True, metavar="SPEC.toml", type=output_path("toml"),
                   help="the spec to write (.toml; written only if it loads)")
    c = command(rsub, "check", "check a robot spec against its model: mirror, soles, torque limits, standing, "
                "tracking, the timestep (the default gait walked at it and at half of it); exit 1 if a check fails",
                _check, CHECK)
    c.add_argument("spec", help="a robot spec .toml (or a shipped robot's name)")
    c.add_argument("--json", action="store_true", help="print one JSON object")
