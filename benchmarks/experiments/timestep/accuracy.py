"""The table of robot init's timestep rule (docs/robots.md, "The timestep"): for a robot spec and a gait, each
candidate timestep h walked at h and at h/2 until the switching states settle, and the error — the largest difference
of the two settled bands' centres, band coordinates — against ``robot.timestep_tolerance``.

Every candidate is walked (robot init stops at the first that passes); the walks and the error are the package's
(:func:`robustgait.robotinit.timestep.select_timestep`). The servos are the spec's at every step, stable PD unless
``--no-stable-pd`` (robot init drafts the gains at each step: with its rules they are the same at every candidate
below the servos' stability bound). The gait: ``--gait`` (a file), else the robot's default gait, generated as robot
init generates it (:func:`robustgait.robotinit.timestep.default_gait`). Progress on stderr; the table and the
choice on stdout.

    python benchmarks/experiments/timestep/accuracy.py --robot exo
    python benchmarks/experiments/timestep/accuracy.py --robot robots/t1/spec.toml \
        [--gait G.json] [--timesteps 0.002 0.001 0.0005 0.00025] [--tolerance 0.02] [--no-stable-pd]

``--timesteps``: default the spec's own step and ``robot.timestep_candidates``, largest first.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from robustgait import load_gait, load_robot
from robustgait.config import Config, RobotConfig
from robustgait.robotinit.timestep import TimestepWalk, default_gait, ms, select_timestep
from robustgait.robots import Robot

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))  # benchmarks/common.py
from common import git_commit


def walk_text(w: TimestepWalk) -> str:
    return w.describe() + f", {w.steps} steps"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--robot", required=True, help="a shipped robot's name or a spec .toml")
    ap.add_argument("--gait", default=None, help="a gait file (default: the robot's default gait, generated)")
    ap.add_argument("--timesteps", type=float, nargs="+", default=None, help="candidate timesteps [s]")
    ap.add_argument("--tolerance", type=float, default=RobotConfig().timestep_tolerance,
                    help="robot.timestep_tolerance (band coordinates)")
    ap.add_argument("--stable-pd", action=argparse.BooleanOptionalAction, default=True,
                    help="walk with stable PD servos (default: yes, as robot init)")
    args = ap.parse_args()
    robot = load_robot(args.robot)
    config = Config(robot=RobotConfig(timestep_tolerance=args.tolerance))
    candidates = tuple(sorted(set(args.timesteps or (*config.robot.timestep_candidates, robot.dt)), reverse=True))
    print(f"# timestep accuracy {time.strftime('%Y-%m-%d %H:%M')} at {git_commit()}: {args.robot}, "
          f"{'stable PD' if args.stable_pd else 'the spec servos'}, tolerance {args.tolerance:g}", flush=True)
    t0 = time.perf_counter()
    if args.gait:
        gait = load_gait(args.gait, robot)
        what = Path(args.gait).name
    else:
        found, why = default_gait(robot, config)
        if found is None:
            sys.exit(f"the default gait of {robot.name} could not be generated: {why}")
        gait, what = found, "default gait"
    print(f"# gait: {what} ({time.perf_counter() - t0:.1f} s)", flush=True)

    def robot_at(h: float) -> Robot:
        return robot.at_timestep(h, args.stable_pd)

    choice = select_timestep(robot_at, gait, candidates, config, every=True,
                             say=lambda line: print(line, file=sys.stderr, flush=True))
    print("\n| h | at h | at h/2 | error (band units) | passes | walks [s] | physics steps |")
    print("|---|---|---|---|---|---|---|")
    for t in choice.trials:
        err = "—" if t.error is None else f"{t.error:.3g}"
        print(f"| {ms(t.timestep)} | {walk_text(t.coarse)} | {walk_text(t.fine)} | {err} | "
              f"{'yes' if t.passes(args.tolerance) else 'no'} | {t.coarse.seconds + t.fine.seconds:.1f} | "
              f"{t.coarse.physics_steps + t.fine.physics_steps} |")
    chosen = f"chosen: {ms(choice.timestep)}" + ("" if choice.passed else f" ({choice.note})")
    print(f"\n{chosen}; total {time.perf_counter() - t0:.1f} s (a walk shared by two candidates is made once and "
          "counted in both rows)")


if __name__ == "__main__":
    main()
