"""200 push trials of one gait (issue 12 acceptance: ≤ 60 s on 2 cores), against raw ``mujoco.rollout``.

Certifies the gait (default config, not timed in the trial figure), then times ``Validator.run("push")``
(200 trials, each the pushed step plus 20 steps, batched on ``mujoco.rollout``) and raw ``mujoco.rollout``
on the same model, the same thread count, a batch of the same size from the same start state and the same
number of physics steps per trial (the validation's total / trials), with zero control. Prints the wall
times, simulated steps per second and their ratio (measured in the same run), and ``uptime``'s load.

    python benchmarks/perf/validate.py [--robot robots/atalante/spec.toml] [--gait ../shared/atalante/...yaml]
                                        [--trials 200] [--repeat 3] [--kind push]
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
import time
from pathlib import Path

import mujoco
import numpy as np
from mujoco import rollout

from robustgait import load_gait, load_robot
from robustgait.config import ValidateConfig
from robustgait.validate import Validator

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # benchmarks/common.py
from common import ATALANTE_SPEC, SHARED

ATALANTE = SHARED / "atalante"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--robot", default=str(ATALANTE_SPEC))
    ap.add_argument("--gait", default=str(ATALANTE / "jt_bez_2023-09-10.yaml"))
    ap.add_argument("--trials", type=int, default=200)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--kind", default="push")
    args = ap.parse_args()
    robot = load_robot(args.robot)
    gait = load_gait(args.gait, robot)
    cfg = ValidateConfig(trials=args.trials)
    t0 = time.perf_counter()
    v = Validator(robot, gait, cfg)
    setup = time.perf_counter() - t0
    threads = v.sim.threads
    print(f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores; mujoco "
          f"{mujoco.__version__}; threads {threads}; {robot.name}, dt {robot.dt} s; r* = {v.certificate.radius:.4f}; "
          f"certificate + fixed point {setup:.2f} s")
    fp = v.fixed_point
    ours, raws, walls = [], [], []
    with rollout.Rollout(nthread=threads) as pool:
        datas = [robot.new_data() for _ in range(threads)]
        for _ in range(args.repeat):
            t0 = time.perf_counter()
            res = v.run(args.kind)
            wall = time.perf_counter() - t0
            nstep = int(np.ceil(res.physics_steps / args.trials))
            init = v.engine.full_states(np.tile(fp.qpos, (args.trials, 1)), np.tile(fp.qvel, (args.trials, 1)))
            t0 = time.perf_counter()
            pool.rollout(robot.model, datas, init, np.zeros((args.trials, nstep, robot.model.nu)))
            raw = time.perf_counter() - t0
            walls.append(wall)
            ours.append(res.physics_steps / wall)
            raws.append(args.trials * nstep / raw)
            sr = res.success_rate()
            print(f"{args.kind}: {args.trials} trials in {wall:.2f} s ({res.physics_steps} physics steps, "
                  f"{ours[-1]:.0f} steps/s); raw mujoco.rollout {raws[-1]:.0f} steps/s; "
                  f"ratio {ours[-1] / raws[-1]:.2f}; "
                  f"success {sr.k}/{sr.n}")
    v.close()
    ratios = np.array(ours) / np.array(raws)
    print(f"median: wall {np.median(walls):.2f} s for {args.trials} trials (goal ≤ 60 s), ratio to raw rollout "
          f"{np.median(ratios):.2f} (runs {ratios.min():.2f}–{ratios.max():.2f}); load {os.getloadavg()}")


if __name__ == "__main__":
    main()
