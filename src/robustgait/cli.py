"""The ``robustgait`` command: parses arguments and calls the API, nothing else.

Every user-input problem ends in one line on stderr, ``robustgait: error: ...``, and exit status 2.
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Callable, Sequence
from pathlib import Path

from robustgait.errors import RobustGaitError


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
    from robustgait.robots import load_robot
    from robustgait.sim import SimConfig, render_video, walk

    robot = load_robot(args.robot)
    gait = load_gait(args.gait, robot)
    config = SimConfig(switching=args.switching, feedforward=not args.no_feedforward)
    if args.video is not None and not Path(args.video).parent.resolve().is_dir():
        raise RobustGaitError(f"{args.video}: output directory does not exist")
    result = walk(robot, gait, steps=args.steps, config=config, keep_trajectory=args.video is not None)
    if args.video is not None and result.trajectory is not None:
        render_video(robot, result.trajectory, args.video)
    if args.json:
        print(result.to_json())
    else:
        end = f"fell ({result.fall_reason}) at t = {result.time:.2f} s" if result.fell else "no fall"
        print(f"{gait.robot} gait on {robot.name}: {result.steps_taken}/{result.max_steps} steps, {end}; "
              f"mean forward speed {result.mean_speed:.3f} m/s; lowest base height "
              f"{result.min_base_height:.3f} m; {result.switching} switching")
        if args.video is not None:
            print(f"video: {args.video}")
    return 0


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


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="robustgait", description="Synthesize and certify robust walking gaits.")
    sub = p.add_subparsers(dest="command", required=True)

    r = sub.add_parser("robots", help="list the shipped robots")
    r.add_argument("--json", action="store_true", help="print JSON")
    r.set_defaults(func=_cmd_robots)

    w = sub.add_parser("walk", help="walk a gait in MuJoCo and report steps taken, falls and speed")
    w.add_argument("gait", help="gait file: .json (robustgait) or .yaml (FROST/ambersim)")
    w.add_argument("--robot", required=True, help="shipped robot name or path to a spec .toml")
    w.add_argument("--steps", type=int, default=50, help="step cap (default 50)")
    w.add_argument("--switching", choices=("impact", "time"), default="impact",
                   help="switch stance at swing-foot touchdown once τ ≥ 0.8 (impact) or at τ = 1 (time)")
    w.add_argument("--no-feedforward", action="store_true", help="joint PD only, ignore feedforward torques")
    w.add_argument("--json", action="store_true", help="print one JSON object")
    w.add_argument("--video", metavar="OUT.mp4", help="render the walk with MuJoCo's offscreen renderer")
    w.set_defaults(func=_cmd_walk)

    g = sub.add_parser("gait", help="gait files")
    gsub = g.add_subparsers(dest="gait_command", required=True)
    c = gsub.add_parser("convert", help="read a gait (either format) and write robustgait JSON")
    c.add_argument("gait")
    c.add_argument("--robot", required=True)
    c.add_argument("-o", "--output", required=True)
    c.add_argument("--mirror", action="store_true", help="relabel for the other stance leg")
    c.set_defaults(func=_cmd_gait_convert)
    return p


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    func: Callable[[argparse.Namespace], int] = args.func
    try:
        return func(args)
    except RobustGaitError as exc:
        print(f"robustgait: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
