"""The feedback engine (sim/feedback.py) against the rollout engine, and passivity-based vs PD tracking, on
the shipped exo with its default flat-foot gait (tests/data/exo_gait.json).

Speed: for K start states on the switching surface (the PD walk's state after 10 steps, base angular velocity
perturbed uniformly in a ball of 0.3 rad/s, as a certificate's samples) it times, in one run and interleaved,
``StepEngine.step`` (mujoco.rollout, open loop), ``FeedbackEngine.step`` with the PD law and with the
passivity-based law, each sample to its touchdown or fall, and prints simulated physics steps per second and
the ratios feedback / rollout (goal ≥ 0.3, stretch ≥ 0.6), plus the largest state difference between the PD
through the feedback engine and the rollout engine.

Tracking: walks the gait ``--steps`` steps with the PD and with the passivity-based law (spec gains) and
prints steps walked, speed, RMS and max of q − q_d over all joints and steps, and the torque saturation count
(steps × joints whose commanded torque exceeded the limit). ``--variants`` adds the passivity law with
direct-torque actuation and with explicit damping (see sim/feedback.py, "Actuation").

    python benchmarks/bench_feedback.py [--k 200] [--repeat 3] [--threads 0] [--steps 50] [--variants]

Gain scan (``--scan``): walks a gait ``--steps`` steps with the passivity law for every uniform Λ in ``--lam``
and K_D = c·kd (the spec's PD damping) for every c in ``--c``, beside the PD and the law with the PD's own
stiffness (Λ = kp/kd, K_D = kd), and prints steps walked, tracking RMS / max and saturation per pair — how the
``[controller.passivity]`` gains of a robot spec are chosen (docs/feedback.md).

    python benchmarks/bench_feedback.py --scan [--robot exo|SPEC.toml] [--gait FILE] [--lam 10 20 40]
        [--c 1 2 3] [--steps 10]
"""

from __future__ import annotations

import argparse
import os
import platform
import time
from pathlib import Path
from typing import Any

import mujoco
import numpy as np

from bench_rollout import start_states  # the same K start states as the rollout benchmark
from robustgait import CertifyConfig, SimConfig, StepEngine, load_gait, load_robot, walk
from robustgait.gait import Gait
from robustgait.poincare import FixedPointFailure, ReturnMap
from robustgait.robots import Robot
from robustgait.sim.feedback import FeedbackEngine, PDController
from robustgait.sim.passivity import PassivityController, PassivityGains
from robustgait.sim.walk import WalkResult

REPO = Path(__file__).resolve().parents[1]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--k", type=int, nargs="+", default=[200])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--threads", type=int, default=0, help="0 = one per core")
    ap.add_argument("--steps", type=int, default=50, help="walk length for the tracking comparison (0: skip)")
    ap.add_argument("--variants", action="store_true", help="also walk the passivity law's actuation variants")
    ap.add_argument("--scan", action="store_true", help="gain scan of the passivity law instead (see above)")
    ap.add_argument("--robot", default="exo", help="--scan: robot name or spec file")
    ap.add_argument("--gait", default="", help="--scan: gait file (default: the robot's stored test gait)")
    ap.add_argument("--lam", type=float, nargs="+", default=[10.0, 20.0, 40.0], help="--scan: uniform Λ [1/s]")
    ap.add_argument("--c", type=float, nargs="+", default=[1.0, 2.0, 3.0], help="--scan: K_D = c · kd")
    args = ap.parse_args()
    if args.scan:
        scan(args)
        return
    robot = load_robot("exo")
    gait = load_gait(REPO / "tests" / "data" / "exo_gait.json", robot)
    config = SimConfig(n_threads=args.threads)
    print(f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores, load "
          f"{os.getloadavg()[0]:.2f}; mujoco {mujoco.__version__}; threads {config.threads}; timestep {robot.dt} s; "
          f"chunk {config.chunk_steps}")
    warm = walk(robot, gait, steps=10, config=config)
    ev = warm.events[-1]
    stance = "left" if ev.stance == "right" else "right"
    engines = {"rollout": StepEngine(robot, gait, config),
               "feedback PD": FeedbackEngine(robot, gait, PDController(), config),
               "feedback passivity": FeedbackEngine(robot, gait, PassivityController(), config)}
    for k in args.k:
        qpos, qvel = start_states(np.array(ev.qpos), np.array(ev.qvel), k)
        times: dict[str, list[float]] = {name: [] for name in engines}
        out = {}
        for _ in range(args.repeat):
            for name, eng in engines.items():
                t = time.perf_counter()
                out[name] = eng.step(qpos, qvel, stance)
                times[name].append(time.perf_counter() - t)
        ref = out["rollout"]
        print(f"\nK = {k} start states ({stance} stance), best of {args.repeat}:")
        rates = {}
        for name, batch in out.items():
            rates[name] = batch.physics_steps / min(times[name])
            line = (f"  {name:<19} {rates[name]:>9.0f} physics steps/s  ({batch.physics_steps} steps, "
                    f"{min(times[name]):.2f} s, falls {int(batch.fell.sum())})")
            if name != "rollout":
                line += f"  ratio to rollout {rates[name] / rates['rollout']:.2f}"
            print(line)
        pd = out["feedback PD"]
        same = (pd.fall_reason == ref.fall_reason) and np.array_equal(pd.duration, ref.duration)
        ok = ~ref.fell
        err = max(np.abs(pd.qpos[ok] - ref.qpos[ok]).max(initial=0.0),
                  np.abs(pd.qvel[ok] - ref.qvel[ok]).max(initial=0.0))
        print(f"  PD feedback vs rollout: max |state difference| {err:.2e}, same events and fall reasons: {same}")
    for eng in engines.values():
        eng.close()
    if args.steps <= 0:
        return
    print(f"\nTracking along the default gait, {args.steps}-step walks (q − q_d over all joints and steps):")
    laws: list[tuple[str, object]] = [("PD (+ feedforward)", PDController()),
                                      ("passivity", PassivityController())]
    if args.variants:
        laws += [("passivity, explicit damping", PassivityController(implicit_damping=False)),
                 ("passivity, torque motors", PassivityController(actuation="motor"))]
    for name, ctl in laws:
        res, s, dt = tracked_walk(robot, gait, ctl, config, args.steps)
        print(f"  {name:<28} walked {res.steps_taken}/{args.steps} (fall: {res.fall_reason}), speed "
              f"{res.mean_speed:.4f} m/s | RMS {s['rms'] * 1e3:.3f} mrad, max {s['max'] * 1e3:.2f} mrad | "
              f"saturation {s['saturation']} of {s['steps'] * robot.n_joints} joint-steps "
              f"({100 * s['saturation_fraction']:.3f} %) | {dt:.1f} s")


def tracked_walk(robot: Robot, gait: Gait, ctl: object, config: SimConfig, steps: int
                 ) -> tuple[WalkResult, dict[str, Any], float]:
    """A walk through the feedback engine under one law: the result, its tracking summary and the wall time."""
    with FeedbackEngine(robot, gait, ctl, config) as eng:  # type: ignore[arg-type]
        t = time.perf_counter()
        res = walk(robot, gait, steps=steps, engine=eng)
        return res, eng.stats.summary(), time.perf_counter() - t  # type: ignore[attr-defined]


def scan(args: argparse.Namespace) -> None:
    """The gain scan of ``--scan``: one walk per (Λ, c), the PD and the PD-matched law as references."""
    robot = load_robot(args.robot)
    gait = load_gait(args.gait or REPO / "tests" / "data" / "exo_gait.json", robot)
    config = SimConfig(n_threads=1)
    print(f"gain scan: robot {robot.name}, gait {args.gait or 'tests/data/exo_gait.json'}, {args.steps}-step "
          f"walks; load {os.getloadavg()[0]:.2f}; mujoco {mujoco.__version__}")
    n = robot.n_joints
    laws: list[tuple[str, object]] = [("PD (+ feedforward)", PDController()),
                                      ("passivity, PD-matched (Λ = kp/kd, K_D = kd)",
                                       PassivityController(PassivityGains.matching_pd(robot)))]
    for lam in args.lam:
        for c in args.c:
            gains = PassivityGains((lam,) * n, tuple(float(c * v) for v in robot.kd))
            laws.append((f"passivity Λ = {lam:g}/s, K_D = {c:g} kd", PassivityController(gains)))
    for name, ctl in laws:
        res, s, dt = tracked_walk(robot, gait, ctl, config, args.steps)
        fp = fixed_point(robot, gait, ctl, config) if res.fall_reason is None else "—"
        print(f"  {name:<44} walked {res.steps_taken:>3}/{args.steps} ({res.fall_reason or 'no fall'}) | RMS "
              f"{s['rms'] * 1e3:7.3f} mrad, max {s['max'] * 1e3:7.2f} mrad | saturation "
              f"{100 * s['saturation_fraction']:6.3f} % | fixed point: {fp} | {dt:.1f} s", flush=True)


def fixed_point(robot: Robot, gait: Gait, ctl: object, config: SimConfig) -> str:
    """Whether the step map under this law has a fixed point (the certificate's first need), and where."""
    pmap = ReturnMap(robot, gait, CertifyConfig(), SimConfig(n_threads=1))
    pmap.engine.close()
    pmap.engine = FeedbackEngine(robot, gait, ctl, config)  # type: ignore[arg-type]
    try:
        with pmap:
            fp = pmap.find_fixed_point()
    except FixedPointFailure as e:
        detail = str(e).rsplit("(", 1)[-1].rstrip(")") if e.status == "no_fixed_point" else f"step {e.steps}"
        return f"none, {e.status} ({detail})"
    return f"step {fp.steps}, residual {fp.residual:.1e}, ‖ω*‖ {np.linalg.norm(fp.omega):.3f} rad/s"


if __name__ == "__main__":
    main()
