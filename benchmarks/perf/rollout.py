"""Batched one-step rollouts of a gait (the Atalante FROST gait by default): our engine vs raw ``mujoco.rollout``.

For K start states on the switching surface (the orbit's state after 10 steps, base angular velocity
perturbed uniformly in a ball of 0.3 rad/s) it times ``StepEngine.step`` (each sample to its touchdown or
fall) and raw ``mujoco.rollout`` on the same model, the same start states, the same thread count and the
same number of physics steps per sample, under the step's own control series. Prints simulated physics steps per
second for both and their ratio (goal ≥ 0.8).

    python benchmarks/perf/rollout.py [--k 64 200] [--repeat 5] [--threads 0] [--robot SPEC --gait FILE]
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

from robustgait import SimConfig, StepEngine, load_gait, load_robot, walk

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # benchmarks/common.py
from common import ATALANTE_SPEC, SHARED, start_states

ATALANTE = SHARED / "atalante"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--k", type=int, nargs="+", default=[64, 200])
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--threads", type=int, default=0, help="0 = one per core")
    ap.add_argument("--robot", default=str(ATALANTE_SPEC), help="a robot name or spec")
    ap.add_argument("--gait", default=str(ATALANTE / "jt_bez_2023-09-10.yaml"))
    args = ap.parse_args()
    robot = load_robot(args.robot)
    gait = load_gait(args.gait, robot)
    config = SimConfig(n_threads=args.threads)
    threads = config.threads
    warm = walk(robot, gait, config, steps=10)
    ev = warm.events[-1]
    stance = "left" if ev.stance == "right" else "right"
    print(f"{robot.name}, {Path(args.gait).name}; machine: {platform.processor() or platform.machine()}, "
          f"{os.cpu_count()} cores; mujoco "
          f"{mujoco.__version__}; threads {threads}; model timestep {robot.dt} s; chunk {config.chunk_steps}")
    with StepEngine(robot, gait, config) as eng, rollout.Rollout(nthread=threads) as pool:
        datas = [robot.new_data() for _ in range(threads)]
        for k in args.k:
            qpos, qvel = start_states(np.array(ev.qpos), np.array(ev.qvel), k)
            ours, raw = [], []
            for _ in range(args.repeat):
                t0 = time.perf_counter()
                batch = eng.step(qpos, qvel, stance)
                t_ours = time.perf_counter() - t0
                ours.append(batch.physics_steps / t_ours)
                nstep = int(np.ceil(batch.physics_steps / k))
                init = eng.full_states(qpos, qvel)
                series = eng.controls[(stance, 0)]
                ctrl = np.repeat(series[None, np.minimum(np.arange(nstep), len(series) - 1)], k, axis=0)
                t0 = time.perf_counter()
                pool.rollout(robot.model, datas, init, ctrl)
                t_raw = time.perf_counter() - t0
                raw.append(k * nstep / t_raw)
            o, r = float(np.median(ours)), float(np.median(raw))
            print(f"K={k:4d}: ours {o:10.0f} steps/s  raw mujoco.rollout {r:10.0f} steps/s  ratio {o / r:.2f}  "
                  f"({batch.physics_steps / k:.0f} steps/sample, {int(batch.fell.sum())} fell, wall "
                  f"{batch.physics_steps / o:.3f} s)")


if __name__ == "__main__":
    main()
