"""``robustgait robots`` (the shipped robots) and ``robustgait config show`` (the effective configuration)."""

from __future__ import annotations

import argparse
import json

from robustgait.cli.common import ROBOT_HELP, command
from robustgait.cli.options import config_from
from robustgait.config import PRESETS


def _robots(args: argparse.Namespace) -> int:
    from robustgait.io.robotfile import load_robot, shipped_robots

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


def _config_show(args: argparse.Namespace) -> int:
    from robustgait.config import preset

    if args.markdown:
        from robustgait.config import Config

        print(Config.markdown(), end="")
        return 0
    config = config_from(args, preset(args.preset) if args.preset else None)
    header = ["robustgait configuration: read it back with --config FILE.toml (flags override it)."]
    if args.preset:
        header.append(f"preset: {args.preset}")
    if args.robot is not None:
        header += _robot_notes(args.robot, config)
    print(config.show("\n".join(header)), end="")
    return 0


def _robot_notes(robot_ref: str, config: object) -> list[str]:
    """What the robot spec decides beside the configuration (comments of config show --robot)."""
    from robustgait.config import Config
    from robustgait.io.robotfile import load_robot
    from robustgait.learn.space import ActionSpace

    assert isinstance(config, Config)
    robot = load_robot(robot_ref)
    spec, q = robot.spec, robot.spec.gait_quality
    out = [f"robot {robot.name} ({spec.source}): {robot.n_joints} joints, {robot.mass:.1f} kg; sim.timestep "
           f"{robot.dt:g} s and integrator from its spec",
           f"its [gait_quality]: pelvis roll ≤ {q.pelvis_roll:g} rad, yaw ≤ {q.pelvis_yaw:g} rad, pitch in "
           f"[{q.pelvis_pitch[0]:g}, {q.pelvis_pitch[1]:g}] rad, swing tilt ≤ {q.swing_tilt:g} rad"]
    domains = config.generate.domains
    try:
        space = ActionSpace.from_robot(robot, domains)
        out.append(f"its {domains} action space (studies): {space.describe()}, {space.size} gaits")
    except Exception as exc:
        out.append(f"no {domains} study on this robot: {exc}")
    return out


def add_parsers(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    r = sub.add_parser("robots", help="list the shipped robots")
    r.add_argument("--json", action="store_true", help="print JSON")
    r.set_defaults(func=_robots)

    c = sub.add_parser("config", help="the configuration: every option's default, unit, limits and help")
    csub = c.add_subparsers(dest="config_command", required=True, parser_class=type(c))
    s = command(csub, "show", "print the effective configuration as TOML (round-trips through --config)",
                _config_show, {"--domains": "generate.domains"})
    s.add_argument("--robot", help=f"{ROBOT_HELP}: add what its spec decides (comments)")
    s.add_argument("--preset", choices=sorted(PRESETS), help="start from a shipped preset (demo: robustgait demo's)")
    s.add_argument("--markdown", action="store_true", help="every field as markdown tables (docs/configuration.md)")
