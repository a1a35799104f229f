"""Flat-foot HZD gait generation: build time, cold and warm-started solves, a 3 × 3 grid, walking.

Prints the problem build time (once per robot), then for the default gait and for a 3 × 3 grid of
step length × step duration (default width and height): IPOPT status, iterations, time per iteration,
solve time cold (standing initial guess) and warm (from the nearest solved gait), the physics check, and
how many steps the gait walks in MuJoCo (impact switching, PD + feedforward, cap 50) at what speed.
Run on one core (the script pins BLAS/OpenMP threads to 1):

    python benchmarks/bench_gaitgen.py [--robot exo] [--no-walk]
"""

from __future__ import annotations

import os

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse
import platform
import time

import numpy as np

from robustgait import GaitParams, SimConfig, load_robot, walk
from robustgait.gaitgen import GaitGenerator, GaitGenResult

LENGTHS = (0.10, 0.15, 0.20)
DURATIONS = (0.6, 0.8, 1.0)


def row(label: str, res: GaitGenResult, walked: str = "") -> str:
    per = res.solve_seconds / max(res.iterations, 1) * 1e3
    chk = res.check
    physics = (f"dyn {chk.dynamics_residual:.0e} per {chk.periodicity:.0e} {'ok' if chk.passed else 'FAIL'}"
               if chk else "-")
    return (f"{label:<28} {res.status:<22} {res.iterations:>4} it {per:6.0f} ms/it {res.solve_seconds:6.2f} s  "
            f"{physics}  {walked}")


def walk_figures(robot, res: GaitGenResult) -> str:  # type: ignore[no-untyped-def]
    if res.gait is None:
        return ""
    w = walk(robot, res.gait, steps=50, config=SimConfig())
    p = res.params
    assert p is not None
    nominal = p.step_length / p.step_duration
    return (f"walks {w.steps_taken:>2}/50{' (' + str(w.fall_reason) + ')' if w.fell else ''}, "
            f"{w.mean_speed:.3f} m/s ({(w.mean_speed / nominal - 1) * 100:+.0f} % of L/T)")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--robot", default="exo")
    ap.add_argument("--no-walk", action="store_true")
    args = ap.parse_args()
    robot = load_robot(args.robot)
    print(f"machine: {platform.machine()}, 1 thread; robot {robot.name}")
    t0 = time.perf_counter()
    gen = GaitGenerator(robot)
    print(f"build: {time.perf_counter() - t0:.1f} s ({gen.n_variables} variables, {gen.n_constraints} constraints, "
          f"{gen.config.nodes} nodes)")
    base = gen.solve(GaitParams())
    print(row("default cold", base, "" if args.no_walk else walk_figures(robot, base)))
    if base.gait is not None:
        warm = gen.solve(GaitParams(step_length=0.17), warm_start=base.gait)
        print(row("L=0.17 warm from default", warm))
    cold_t, warm_t, passed = [], [], 0
    solved: dict[tuple[int, int], GaitGenResult] = {}
    for i, length in enumerate(LENGTHS):
        for j, duration in enumerate(DURATIONS):
            params = GaitParams(step_length=length, step_duration=duration)
            cold = gen.solve(params)
            cold_t.append(cold.solve_seconds)
            near = [solved[k] for k in ((i - 1, j), (i, j - 1)) if k in solved and solved[k].gait is not None]
            warm_line = ""
            if near:
                w = gen.solve(params, warm_start=near[0].gait)
                warm_t.append(w.solve_seconds)
                warm_line = f" | warm {w.iterations} it {w.solve_seconds:.2f} s"
            solved[(i, j)] = cold
            passed += bool(cold.success)
            label = f"L={length:.2f} T={duration:.1f}"
            print(row(label, cold, ("" if args.no_walk else walk_figures(robot, cold)) + warm_line))
    print(f"grid: {passed}/9 solved and passed the physics check; cold solve median {np.median(cold_t):.2f} s "
          f"(max {max(cold_t):.2f}); warm solve median {np.median(warm_t):.2f} s (max {max(warm_t):.2f})")


if __name__ == "__main__":
    main()
