"""``robustgait walk``: a gait walked in MuJoCo."""

from __future__ import annotations

import argparse
import json

from robustgait.cli.common import GAIT_HELP, ROBOT_HELP, command, inputs, naming_file
from robustgait.cli.options import output_path

SIM = {"--controller": "sim.controller", "--switching": "sim.switching", "--feedforward": "sim.feedforward"}


def _walk(args: argparse.Namespace) -> int:
    from robustgait.certificate.orbit import canonical_event_states
    from robustgait.certificate.reduced import reduce_state
    from robustgait.certificate.search import Walked, find_orbit
    from robustgait.io.output import write_csv
    from robustgait.sim import walk

    config, robot, gait = inputs(args)
    with naming_file(args.gait):
        result = walk(robot, gait, config.sim, video=args.video, comfort=config.comfort)
    orbit = find_orbit(Walked(robot, gait, result), config.certify)
    if args.log is not None:
        xs = reduce_state(*canonical_event_states(robot, gait, result.events), config.certify.frame)
        write_csv(args.log, ["wx", "wy", "wz"], xs.tolist())
    if args.json:
        print(json.dumps({**result.to_dict(), "orbit": orbit.to_dict()}, allow_nan=False))
    else:
        end = f"fell ({result.fall_reason}) at t = {result.time:.2f} s" if result.fell else "no fall"
        plan = "" if result.planned_speed is None else f" (planned {result.planned_speed:.3f})"
        print(f"{gait.robot} gait on {robot.name}: {result.steps_taken}/{result.max_steps} steps, {end}; "
              f"mean forward speed {result.mean_speed:.3f} m/s{plan}; lowest base height "
              f"{result.min_base_height:.3f} m; {result.switching} switching")
        tr = result.tracking
        print(f"controller {result.controller}: joint tracking error RMS {1e3 * tr['rms']:.3g} mrad, max "
              f"{1e3 * tr['max']:.3g} mrad; torque saturation {tr['saturation']} joint-steps "
              f"({100 * tr['saturation_fraction']:.3g} %)"
              + (f"  ({result.controller_note})" if result.controller_note else ""))
        reg = result.regulator
        if reg is not None:
            why = ""  # κ came from how the walk's lateral error grows: under the sole's share, then the whole gain
            for key, under in (("growth", "under the sole's share"), ("growth_whole", "under the whole gain")):
                g = reg.get(key)
                if g is not None:
                    grows = "it fell within the probe's steps" if g == "fell" else f"its error grows ×{g:.3g}/step"
                    why += f"; {under} {grows}"
            print(f"step regulator (H-LIP, z0 {reg['z0']:.3g} m, T_S {reg['t_ssp']:.3g} s, κ {reg['share']:.3g}{why},"
                  f" gain {reg['gain']}): "
                  f"{reg['updates']} corrections, largest landing change {100 * reg['largest_step_change']:.3g} cm, "
                  f"{reg['clipped']} clipped (tracking errors include its corrections)")
        print(f"orbit of the switching events: {orbit.describe()} (stability: robustgait certify)")
        note = result.speed_note(config.sim.speed_agreement)
        if note:
            print(f"note: {note}")
        if result.comfort is not None:
            print("\n".join(result.comfort.text()))
        else:
            print(f"comfort: not measured (the walk completed no step from step {config.comfort.skip_steps + 1} on: "
                  "comfort.skip_steps)")
        for what, out in (("video", args.video), ("reduced-state log", args.log)):
            if out is not None:
                print(f"{what}: {out}")
    return 0


def add_parsers(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    w = command(sub, "walk", "walk a gait in MuJoCo and report steps taken, falls and speed", _walk,
                {"--steps": "sim.step_cap", **SIM, "--frame": "certify.frame"})
    w.add_argument("gait", help=GAIT_HELP)
    w.add_argument("--robot", required=True, help=ROBOT_HELP)
    w.add_argument("--json", action="store_true", help="print one JSON object")
    w.add_argument("--video", metavar="OUT.mp4", type=output_path("video"),
                   help="render the walk with MuJoCo's offscreen renderer (.mp4 or .gif)")
    w.add_argument("--log", metavar="OUT.csv", type=output_path("csv"),
                   help="write the reduced state (base angular velocity in --frame, canonical stance) at every "
                   "switching event, one row per step, for barrier-eval")
