"""Flat-foot HZD gait generation: build, cold and warm solves, and how the gaits walk (issue: exoskeleton-grade).

Prints the problem build time (once per robot); the default gait's cold solve, a warm-started neighbour
(L = 0.17 m from the default), and its walk; then the acceptance grid — a 4 × 4 grid of step length × step
duration over the robot's action space (default width and height) plus the 4 corners of width × height —
with, per point: IPOPT status, iterations, cold solve time, warm solve time (from the previous solved point
of the grid), and in MuJoCo (impact switching, PD + feedforward, 50 steps): steps walked, speed error
against L/T, pelvis roll range over the walk, ‖x̄*‖ of the step map's fixed point and r* (uniform, N
samples). Markdown rows are printed for benchmarks/README.md. Gait generation runs on one core (BLAS/OpenMP
pinned to 1); the simulator uses its default threads.

    python benchmarks/bench_gaitgen.py [--robot exo] [--samples 200] [--no-walk]
"""

from __future__ import annotations

import os

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse
import platform
import time

import numpy as np

from robustgait import GaitParams, load_robot, walk
from robustgait.certify import CertifyConfig, certify_gait
from robustgait.errors import RobustGaitError
from robustgait.gait import Gait
from robustgait.gaitgen import GaitGenerator, GaitGenResult
from robustgait.robots import Robot
from robustgait.rotations import quat_to_mat


def walk_figures(robot: Robot, gait: Gait, samples: int) -> dict[str, object]:
    """Steps walked (of 50), speed error vs L/T, pelvis roll range [deg] over the walk, ‖x̄*‖ and r*."""
    w = walk(robot, gait, steps=50, keep_trajectory=True)
    p = gait.params
    assert p is not None and w.trajectory is not None
    r = quat_to_mat(w.trajectory[:, 4:8])
    roll = np.degrees(np.arctan2(r[:, 2, 1], r[:, 2, 2]))
    out: dict[str, object] = {"steps": w.steps_taken, "fall": w.fall_reason,
                              "speed_error": w.mean_speed / (p.step_length / p.step_duration) - 1,
                              "roll": (float(roll.min()), float(roll.max())), "x_star": None, "r_star": None}
    if w.steps_taken == 50:
        try:
            c = certify_gait(robot, gait, CertifyConfig(n_samples=samples))
            out["x_star"], out["r_star"] = float(np.linalg.norm(c.fixed_point.x_star)), c.r_star
        except RobustGaitError as exc:
            out["fall"] = f"certificate: {exc}"
    return out


def fmt_walk(f: dict[str, object]) -> str:
    if f["steps"] != 50:
        return f"walks {f['steps']}/50 ({f['fall']})"
    lo, hi = f["roll"]  # type: ignore[misc]
    xs = "—" if f["x_star"] is None else f"{f['x_star']:.2f}"
    rs = "—" if f["r_star"] is None else f"{f['r_star']:.3f}"
    return (f"walks 50/50, speed {f['speed_error'] * 100:+.1f} %, roll {lo:+.1f}…{hi:+.1f}°, ‖x̄*‖ {xs}, "
            f"r* {rs}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--robot", default="exo")
    ap.add_argument("--samples", type=int, default=200, help="certificate samples (uniform) per gait")
    ap.add_argument("--no-walk", action="store_true")
    args = ap.parse_args()
    robot = load_robot(args.robot)
    print(f"machine: {platform.machine()}, {os.cpu_count()} cores, load {os.getloadavg()[0]:.2f}; gait generation "
          f"on 1 thread; robot {robot.name}")
    t0 = time.perf_counter()
    gen = GaitGenerator(robot)
    print(f"build: {time.perf_counter() - t0:.1f} s ({gen.n_variables} variables, {gen.n_constraints} constraints, "
          f"{gen.config.nodes} nodes)")
    base = gen.solve(GaitParams())
    print(f"default cold: {base.status}, {base.iterations} iterations, {base.solve_seconds:.2f} s "
          f"({base.solve_seconds / max(base.iterations, 1) * 1e3:.0f} ms/iteration)")
    if base.gait is not None:
        warm = gen.solve(GaitParams(step_length=0.17), warm_start=base.gait)
        print(f"L = 0.17 warm from the default: {warm.status}, {warm.iterations} iterations, "
              f"{warm.solve_seconds:.2f} s")
        if not args.no_walk:
            print("default walk:", fmt_walk(walk_figures(robot, base.gait, args.samples)))
    a = robot.spec.action_space
    if a is None:
        raise SystemExit(f"{robot.name}: the spec has no [action_space] to take the grid from")
    grid = [(float(length), float(duration), 0.25, 0.07)
            for length in np.linspace(a["step_length"].low, a["step_length"].high, 4)
            for duration in np.linspace(a["step_duration"].low, a["step_duration"].high, 4)]
    grid += [(0.15, 0.7, w, h) for w in (a["step_width"].low, a["step_width"].high)
             for h in (a["step_height"].low, a["step_height"].high)]
    print("\n| L [m] | T [s] | W [m] | h [m] | status | it | cold | warm | walks | speed vs L/T | roll range | "
          "‖x̄*‖ | r* |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    cold_t: list[float] = []
    warm_t: list[float] = []
    walks = 0
    prev: GaitGenResult | None = None
    for values in grid:
        params = GaitParams(*values)
        cold = gen.solve(params)
        warm_s = "—"
        if prev is not None and prev.gait is not None:
            w = gen.solve(params, warm_start=prev.gait)
            warm_t.append(w.solve_seconds)
            warm_s = f"{w.solve_seconds:.2f} s"
        cells = [f"{v:.3g}" for v in values] + [cold.status if cold.success else f"{cold.status}: {cold.reason}",
                                                str(cold.iterations), f"{cold.solve_seconds:.2f} s", warm_s]
        if cold.gait is not None:
            cold_t.append(cold.solve_seconds)
            prev = cold
            if not args.no_walk:
                f = walk_figures(robot, cold.gait, args.samples)
                lo, hi = f["roll"]  # type: ignore[misc]
                ok = f["steps"] == 50 and max(abs(lo), abs(hi)) < 6.0
                walks += ok
                cells += [f"{f['steps']}/50" + ("" if f["steps"] == 50 else f" ({f['fall']})"),
                          f"{f['speed_error'] * 100:+.1f} %", f"{lo:+.1f}…{hi:+.1f}°",
                          "—" if f["x_star"] is None else f"{f['x_star']:.2f}",
                          "—" if f["r_star"] is None else f"{f['r_star']:.3f}"]
        print("| " + " | ".join(cells) + " |", flush=True)
    print(f"\n{walks}/{len(grid)} walk 50 steps with the pelvis roll within ±6°; cold solve median "
          f"{np.median(cold_t):.2f} s (max {max(cold_t):.2f}); warm median {np.median(warm_t):.2f} s "
          f"(max {max(warm_t):.2f})")


if __name__ == "__main__":
    main()
