"""Flat-foot HZD gait generation: build, cold and warm solves, and how the gaits walk (issue: exoskeleton-grade).

Prints the problem build time (once per robot); the default gait's cold solve, a warm-started neighbour
(L = 0.17 m from the default), and its walk; then the acceptance grid — a 4 × 4 grid of step length × step
duration over the robot's action space (default width and height) plus the 4 corners of width × height —
with, per point: IPOPT status, iterations, cold solve time, warm solve time (from the previous solved point
of the grid), and in MuJoCo (impact switching, PD + feedforward, 50 steps): steps walked, speed error
against L/T, pelvis roll range over the walk, ‖x̄*‖ of the step map's fixed point and r* (uniform, N
samples). Markdown rows are printed for benchmarks/README.md. Gait generation runs on one core (BLAS/OpenMP
pinned to 1); the simulator uses its default threads.

    python benchmarks/experiments/gait_generation/run.py [--robot exo] [--domains flat|multicontact] [--step-duration T]
        [--samples 200] [--no-walk] [--no-grid]

With ``--domains multicontact`` the default gait (step duration 0.9 s) is also certified with the sequential
estimator, and its walk reports how far each sole pitches during double support (the rolling).
``--step-duration`` replaces the graph's default step duration of the default gait (Atalante's multi-contact
gait walks at 1.0 s, not 0.9 s); ``--no-grid`` stops after the default gait.
"""

from __future__ import annotations

import os

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse
import platform
import time
from dataclasses import replace

import numpy as np

from robustgait import GaitParams, load_robot, walk
from robustgait.certificate.certify import certify_gait
from robustgait.config import CertifyConfig, GenerationConfig
from robustgait.gait import Gait
from robustgait.gaitgen import GaitGenerator, GaitGenResult
from robustgait.robots import Robot
from robustgait.rotations import roll_pitch_yaw


def rolling(robot: Robot, gait: Gait, trajectory: np.ndarray, events: list) -> tuple[float, float]:  # type: ignore[type-arg]
    """Smallest sweep [deg] of the back and of the front sole's pitch over the double supports of steps 10–20."""
    import mujoco

    m, d = robot.model, mujoco.MjData(robot.model)
    t_ds = gait.domains[1].duration

    def pitch(k: int, side: str) -> float:
        mujoco.mj_setState(m, d, trajectory[k], mujoco.mjtState.mjSTATE_FULLPHYSICS)
        mujoco.mj_kinematics(m, d)
        return float(np.degrees(-np.arcsin(d.geom_xmat[robot.sole_geom_id[side]].reshape(3, 3)[2, 0])))

    back, front = [], []
    for e in events[10:20]:
        k0 = int(np.argmin(np.abs(trajectory[:, 0] - e.time)))
        ks = range(k0, min(len(trajectory), k0 + round(t_ds / robot.dt)), 5)
        other = "left" if e.stance == "right" else "right"
        b, f = [pitch(k, e.stance) for k in ks], [pitch(k, other) for k in ks]
        back.append(max(b) - min(b))
        front.append(max(f) - min(f))
    return (min(back), min(front)) if back else (float("nan"), float("nan"))


def walk_figures(robot: Robot, gait: Gait, samples: int) -> dict[str, object]:
    """Steps walked (of 50), speed error vs L/T, pelvis roll range [deg] over the walk, ‖x̄*‖ and r*."""
    w = walk(robot, gait, steps=50, keep_trajectory=True)
    p = gait.params
    assert p is not None and w.trajectory is not None
    roll = np.degrees(roll_pitch_yaw(w.trajectory[:, 4:8])[:, 0])
    out: dict[str, object] = {"steps": w.steps_taken, "fall": w.fall_reason,
                              "speed_error": w.mean_speed / (p.step_length / p.duration) - 1,
                              "roll": (float(roll.min()), float(roll.max())), "x_star": None, "r_star": None}
    if len(gait.domains) > 1 and w.steps_taken >= 20:
        out["rolling"] = rolling(robot, gait, w.trajectory, w.events)
    if w.steps_taken == 50:
        c = certify_gait(robot, gait, CertifyConfig(n_samples=samples, method="uniform", disturbance="state"))
        if c.fixed_point is not None:
            out["x_star"] = float(np.linalg.norm(c.fixed_point.omega))
        if c.ok:
            out["r_star"] = c.value
        else:
            out["fall"] = f"certificate: {c.status}"
    return out


def fmt_walk(f: dict[str, object]) -> str:
    if f["steps"] != 50:
        return f"walks {f['steps']}/50 ({f['fall']})"
    lo, hi = f["roll"]  # type: ignore[misc]
    xs = "—" if f["x_star"] is None else f"{f['x_star']:.2f}"
    rs = "—" if f["r_star"] is None else f"{f['r_star']:.3f}"
    roll_s = "" if "rolling" not in f else (f", double support: back sole sweeps ≥ {f['rolling'][0]:.1f}°, "  # type: ignore[index]
                                           f"front ≥ {f['rolling'][1]:.1f}°")  # type: ignore[index]
    return (f"walks 50/50, speed {f['speed_error'] * 100:+.1f} %, roll {lo:+.1f}…{hi:+.1f}°, ‖x̄*‖ {xs}, "
            f"r* {rs}{roll_s}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--robot", default="exo")
    ap.add_argument("--domains", choices=("flat", "multicontact"), default="flat")
    ap.add_argument("--samples", type=int, default=200, help="certificate samples (uniform) per gait")
    ap.add_argument("--no-walk", action="store_true")
    ap.add_argument("--step-duration", type=float, help="the default gait's step duration [s]")
    ap.add_argument("--no-grid", action="store_true", help="stop after the default gait")
    args = ap.parse_args()
    robot = load_robot(args.robot)
    print(f"machine: {platform.machine()}, {os.cpu_count()} cores, load {os.getloadavg()[0]:.2f}; gait generation "
          f"on 1 thread; robot {robot.name}")
    t0 = time.perf_counter()
    gen = GaitGenerator(robot, GenerationConfig(domains=args.domains))
    print(f"domain graph {args.domains}; build: {time.perf_counter() - t0:.1f} s ({gen.n_variables} variables, "
          f"{gen.n_constraints} constraints, {gen.config.nodes} nodes)")
    dflt = GaitParams().resolved(args.domains)
    if args.step_duration is not None:
        dflt = replace(dflt, step_duration=args.step_duration)
    base = gen.solve(dflt)
    print(f"default {dflt} cold: {base.status}, {base.iterations} iterations, {base.solve_seconds:.2f} s "
          f"({base.solve_seconds / max(base.iterations, 1) * 1e3:.0f} ms/iteration)")
    if base.gait is not None:
        warm = gen.solve(GaitParams(step_length=0.17, step_duration=dflt.step_duration), warm_start=base.gait)
        print(f"L = 0.17 warm from the default: {warm.status}, {warm.iterations} iterations, "
              f"{warm.solve_seconds:.2f} s")
        if not args.no_walk:
            print("default walk:", fmt_walk(walk_figures(robot, base.gait, args.samples)))
            if args.domains == "multicontact":
                seq = certify_gait(robot, base.gait, CertifyConfig(method="sequential", disturbance="state"))
                print(f"default gait, sequential certificate: {seq.status}, r* = {seq.value:.4f} rad/s, "
                      f"{seq.to_dict().get('n_samples')} samples")
    if args.no_grid:
        return
    mc = args.domains == "multicontact"
    a = robot.spec.multicontact_action_space if mc else robot.spec.action_space
    if a is None:
        raise SystemExit(f"{robot.name}: the spec has no [action_space{'.multicontact' if mc else ''}] to take the "
                         "grid from")
    # 4 × 4 of step length × duration at the middle width and height, then the four width × height corners at
    # the default length and duration
    mid = {k: round(float((a[k].low + a[k].high) / 2), 3) for k in ("step_width", "step_height")}
    grid = [(float(length), float(duration), mid["step_width"], mid["step_height"])
            for length in np.linspace(a["step_length"].low, a["step_length"].high, 4)
            for duration in np.linspace(a["step_duration"].low, a["step_duration"].high, 4)]
    grid += [(dflt.step_length, dflt.step_duration, w, h) for w in (a["step_width"].low, a["step_width"].high)
             for h in (a["step_height"].low, a["step_height"].high)]
    print("\n| L [m] | T [s] | W [m] | h [m] | status | it | cold | warm | walks | speed vs L/T | roll range | "
          "‖x̄*‖ | r* |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    cold_t: list[float] = []
    warm_t: list[float] = []
    walks = solved = fixed = 0
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
            solved += 1
            cold_t.append(cold.solve_seconds)
            prev = cold
            if not args.no_walk:
                f = walk_figures(robot, cold.gait, args.samples)
                lo, hi = f["roll"]  # type: ignore[misc]
                ok = f["steps"] == 50 and max(abs(lo), abs(hi)) < 6.0
                walks += ok
                fixed += ok and f["x_star"] is not None
                cells += [f"{f['steps']}/50" + ("" if f["steps"] == 50 else f" ({f['fall']})"),
                          f"{f['speed_error'] * 100:+.1f} %", f"{lo:+.1f}…{hi:+.1f}°",
                          "—" if f["x_star"] is None else f"{f['x_star']:.2f}",
                          "—" if f["r_star"] is None else f"{f['r_star']:.3f}"]
        print("| " + " | ".join(cells) + " |", flush=True)
    print(f"\n{solved}/{len(grid)} solve, {walks}/{len(grid)} walk 50 steps with the pelvis roll within ±6°, "
          f"{fixed}/{len(grid)} of those have a fixed point; cold solve median "
          f"{np.median(cold_t):.2f} s (max {max(cold_t):.2f}); warm median {np.median(warm_t):.2f} s "
          f"(max {max(warm_t):.2f})")


if __name__ == "__main__":
    main()
