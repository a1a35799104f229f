"""``robustgait gait convert | generate | tiles``: gait files, HZD gait generation, frames of a step."""

from __future__ import annotations

import argparse
import json

from robustgait.cli.common import GAIT_HELP, ROBOT_HELP, command, inputs, naming_file
from robustgait.cli.options import config_from, output_path
from robustgait.config import GAIT_FORMATS, Config
from robustgait.errors import RobustGaitError

GENERATE = {"--domains": "generate.domains", "--step-length": "gait.step_length",
            "--step-duration": "gait.step_duration", "--step-width": "gait.step_width",
            "--step-height": "gait.step_height", "--rolling-fraction": "gait.rolling_fraction",
            "--nodes": "generate.nodes", "--stance": "generate.stance"}


def _convert(args: argparse.Namespace) -> int:
    from robustgait.io.gaitfile import gait_format, load_gait, save_gait
    from robustgait.io.robotfile import load_robot

    fmt = gait_format(args.output, args.to)
    robot = load_robot(args.robot)
    gait = load_gait(args.gait, robot)
    if args.mirror:
        gait = gait.mirrored(robot)
    save_gait(gait, args.output, fmt, src=args.gait)
    what = "FROST/ambersim YAML" if fmt == "frost" else "robustgait JSON"
    print(f"wrote {args.output} ({what}: {gait.stance} stance, {gait.n_outputs} outputs, T = {gait.step_duration} s)")
    return 0


def _generate(args: argparse.Namespace) -> int:
    from robustgait.gaitgen import GaitGenerator
    from robustgait.gaitgen.solve import params_problem
    from robustgait.gaitgen.walkcheck import generate_walking
    from robustgait.io.gaitfile import load_gait, save_gait
    from robustgait.io.robotfile import load_robot

    robot = load_robot(args.robot)
    config = config_from(args, Config(gait=robot.default_params))  # the spec's [gait] under file and flags
    params = config.params.resolved(config.generate.domains)
    problem = params_problem(robot, params, config.generate.for_robot(robot.scale, robot.spec.generation))
    if problem is not None:  # before the problem is built: no solve can walk it
        raise RobustGaitError(f"{robot.name}: {problem}")
    warm = load_gait(args.warm_start, robot) if args.warm_start else None
    live = not args.json
    if live:
        what = "flat-foot" if config.generate.domains == "flat" else "multi-contact (heel/toe rolling)"
        print(f"building the {what} HZD problem for {robot.name} ({config.generate.nodes} nodes) ...", flush=True)
    gen = GaitGenerator(robot, config.generate, verbose=live and args.verbose)
    if live:
        print(f"built in {gen.build_seconds:.1f} s: {gen.n_variables} variables, {gen.n_constraints} constraints; "
              + ("IPOPT iterations:" if args.verbose else f"solving T = {params.duration:g} s ..."), flush=True)
    done = generate_walking(robot, params, config, gen, warm=warm,
                            say=(lambda line: print(line, flush=True)) if live else None)
    res, walked = done.result, done.walked
    summary = {**res.summary(), "build_seconds": gen.build_seconds, "output": args.output if done.passed else None}
    if done.first is not None:
        summary["retried"] = {"joint_margin": done.margin, "first_walk_check": done.first.to_dict()}
    if walked is not None:
        summary["walk_check"] = walked.to_dict()
    if not done.passed:
        if args.json:
            print(json.dumps(summary, allow_nan=False))
        if res.gait is None:
            again = (f" when solved again with joint margin {done.margin:g} rad after its walk check fell "
                     f"({done.first.cause})" if done.first is not None and done.margin is not None else "")
            raise RobustGaitError(f"gait generation failed ({res.status}){again}: {res.reason}")
        assert walked is not None
        raise RobustGaitError(f"gait generation failed (Walk_Check_Failed): {walked.text()}")
    assert res.gait is not None and walked is not None
    save_gait(res.gait, args.output)
    if args.json:
        print(json.dumps(summary, allow_nan=False))
    else:
        c = res.check
        assert c is not None
        print(f"{res.status}: {res.iterations} iterations in {res.solve_seconds:.2f} s "
              f"({res.solve_seconds / max(res.iterations, 1) * 1e3:.0f} ms/iteration), ∫‖u‖²dt = {res.objective:.4g}")
        print(f"physics check passed: dynamics residual {c.dynamics_residual:.1e} (MuJoCo), periodicity "
              f"{c.periodicity:.1e}, min normal force {c.min_normal_force:.0f} N, friction |f_t|/f_z ≤ "
              f"{c.friction_ratio:.2f}, {c.cop_text()}")
        if walked.steps:
            print(f"walk check passed: the gait {walked.text()}")
        print(f"wrote {args.output}")
    return 0


def _tiles(args: argparse.Namespace) -> int:
    from robustgait.report.tiles import render_tiles

    config, robot, gait = inputs(args)
    with naming_file(args.gait):
        shape = render_tiles(robot, gait, args.output, config.report, config.sim)
    print(f"wrote {args.output} ({shape[1]} x {shape[0]} px: {config.report.tile_frames} frames of one step, side "
          "and front)")
    return 0


def add_parsers(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    g = sub.add_parser("gait", help="gait files: convert, generate (HZD), tiles")
    gsub = g.add_subparsers(dest="gait_command", required=True, parser_class=type(g))
    gc = command(gsub, "convert", "read a gait (either format) and write it as robustgait JSON or FROST/ambersim "
                 "YAML", _convert)
    gc.add_argument("gait", help=GAIT_HELP)
    gc.add_argument("--robot", required=True, help=ROBOT_HELP)
    gc.add_argument("-o", "--output", required=True, type=output_path("gait"),
                    help="output gait: .json (robustgait) or .yaml/.yml (FROST/ambersim)")
    gc.add_argument("--to", choices=GAIT_FORMATS,
                    help="output format (default: the output's suffix picks it; a contradicting suffix is refused)")
    gc.add_argument("--mirror", action="store_true", help="relabel for the other stance leg")

    gg = command(gsub, "generate", "HZD trajectory optimization of a gait (CasADi + IPOPT): flat-foot or "
                 "multi-contact heel/toe rolling", _generate, GENERATE)
    gg.add_argument("--robot", required=True, help=ROBOT_HELP)
    gg.add_argument("--warm-start", metavar="GAIT", help="start from a neighbouring gait (.json or .yaml)")
    gg.add_argument("-o", "--output", required=True, type=output_path("json"),
                    help="output gait .json (checked before the solve)")
    gg.add_argument("--json", action="store_true", help="print one JSON summary instead of the live log")
    gg.add_argument("--verbose", action="store_true", help="print IPOPT's iteration log")

    gt = command(gsub, "tiles", "frames of one step side by side, seen from the side and the front (PNG)", _tiles,
                 {"--frames": "report.tile_frames", "--warmup-steps": "report.tile_warmup_steps"})
    gt.add_argument("gait", help=GAIT_HELP)
    gt.add_argument("--robot", required=True, help=ROBOT_HELP)
    gt.add_argument("-o", "--output", required=True, metavar="TILES.png", type=output_path("plot"))
