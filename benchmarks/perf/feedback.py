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

    python benchmarks/perf/feedback.py [--k 200] [--repeat 3] [--threads 0] [--steps 50] [--variants]

Gain scan (``--scan``): walks a gait ``--steps`` steps with the passivity law for every uniform Λ in ``--lam``
and K_D = c·kd (the spec's PD damping) for every c in ``--c``, beside the PD and the law with the PD's own
stiffness (Λ = kp/kd, K_D = kd), and prints steps walked, tracking RMS / max and saturation per pair — how the
``[controller.passivity]`` gains of a robot spec are chosen (docs/feedback.md) — and, for each law that walks, its
orbit (:func:`robustgait.certificate.search.find_orbit` on the feedback engine: settled step, period, band scatter
σ and ‖ω*‖, or its status when it has none; this replaces the removed fixed-point search's step and residual).

    python benchmarks/perf/feedback.py --scan [--robot exo|SPEC.toml] [--gait FILE] [--lam 10 20 40]
        [--c 1 2 3] [--steps 10] [--kinds latency,noise --trials 40]

``--kinds`` adds, per law that walks, the validation's success and s₅₀ for those disturbance kinds. Latency check
(``--delays``): one validation trial per command delay for the PD servos (the reference arrives late), the PD
computed centrally (its stiffness term arrives late) and the passivity law (spec gains).

    python benchmarks/perf/feedback.py --delays [0 1 2 3 5 8 12 20 40] [--robot …] [--gait …]
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
import time
from pathlib import Path
from typing import Any

import mujoco
import numpy as np

from robustgait import CertifyConfig, SimConfig, StepEngine, load_gait, load_robot, walk
from robustgait.certificate import Walking, find_orbit
from robustgait.errors import RobustGaitError
from robustgait.gait import Gait
from robustgait.robots import Robot
from robustgait.sim.feedback import FeedbackEngine, PDController
from robustgait.sim.passivity import PassivityController, PassivityGains
from robustgait.sim.walk import WalkResult

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # benchmarks/common.py
from common import EXO_GAIT, start_states


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
    ap.add_argument("--kinds", default="", help="--scan: also validate each law that walks against these "
                    "disturbance kinds (comma-separated, e.g. latency,noise): success and s50")
    ap.add_argument("--trials", type=int, default=40, help="--scan --kinds: trials per kind (seed 0)")
    ap.add_argument("--delays", type=float, nargs="*", default=None,
                    help="latency check instead: these command delays [ms] under each way latency enters")
    args = ap.parse_args()
    if args.scan:
        scan(args)
        return
    if args.delays is not None:
        delays(args)
        return
    robot = load_robot("exo")
    gait = load_gait(EXO_GAIT, robot)
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
    gait = load_gait(args.gait or EXO_GAIT, robot)
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
        orbit = orbit_summary(robot, gait, ctl, config) if res.fall_reason is None else "—"
        dist = disturbances(robot, gait, ctl, args) if res.fall_reason is None and args.kinds else ""
        print(f"  {name:<44} walked {res.steps_taken:>3}/{args.steps} ({res.fall_reason or 'no fall'}) | RMS "
              f"{s['rms'] * 1e3:7.3f} mrad, max {s['max'] * 1e3:7.2f} mrad | saturation "
              f"{100 * s['saturation_fraction']:6.3f} % | orbit: {orbit}{dist} | {dt:.1f} s", flush=True)


def disturbances(robot: Robot, gait: Gait, ctl: object, args: argparse.Namespace) -> str:
    """Success and s50 of ``--kinds`` under this law (validate_gait, seed 0; a 10-sample uniform certificate: the
    inside/outside check is not what is read here)."""
    from dataclasses import replace

    from robustgait.config import ValidateConfig
    from robustgait.robots.spec import PassivitySpec
    from robustgait.validate import validate_gait

    if isinstance(ctl, PassivityController):
        gains = ctl.gains or PassivityGains.from_robot(robot)
        robot.spec = replace(robot.spec, passivity=PassivitySpec(gains.lam, gains.kd))
        sim = SimConfig(controller="passivity", n_threads=1)
    else:
        sim = SimConfig(n_threads=1)
    try:
        v = validate_gait(robot, gait, ValidateConfig(trials=args.trials, seed=0), sim=sim,
                          kinds=args.kinds.split(","),
                          certify=CertifyConfig(method="uniform", disturbance="state", n_samples=10))
    except RobustGaitError as e:  # e.g. no orbit to start the trials from
        return f" | not validated: {str(e)[:60]}"
    out = []
    for k, kr in v.kinds.items():
        rate, fit = kr.success_rate(), kr.critical()
        scale = 1e3 if k in ("latency", "noise", "terrain") else 1.0
        s50 = "—" if fit.s50 is None else f"{fit.s50 * scale:.3g}"
        out.append(f"{k} {rate.k}/{rate.n}, s50 {s50}")
    return " | " + "; ".join(out)


def orbit_summary(robot: Robot, gait: Gait, ctl: object, config: SimConfig) -> str:
    """Whether the walk under this law has an orbit (the certificate's first need: settled in a band and stable under
    small pushes), and where: settled step, period, σ and ‖ω*‖, or its status and reason."""
    cfg = CertifyConfig(disturbance="state")
    with FeedbackEngine(robot, gait, ctl, config) as eng:  # type: ignore[arg-type]
        orbit = find_orbit(Walking(robot, gait, engine=eng), cfg)
    if not orbit.ok:
        return f"none, {orbit.status} after {orbit.steps} steps ({orbit.reason[:80]})"
    fp = orbit.fixed_point(cfg.frame)
    return (f"settled at step {orbit.settled}, period {orbit.period}, σ {orbit.sigma:.2g}, ‖ω*‖ "
            f"{np.linalg.norm(fp.omega):.3f} rad/s")


def delays(args: argparse.Namespace) -> None:
    """``--delays``: one validation trial per delay (20 steps after), for the PD servos (command latency: the
    reference arrives late, the servo loop does not), the same PD computed centrally (its stiffness term arrives
    late, the drives' damping does not) and the passivity law (spec gains; the law + drive damping as central)."""
    from robustgait.config import ValidateConfig
    from robustgait.validate.disturbances import Draws
    from robustgait.validate.run import Validator

    robot = load_robot(args.robot)
    gait = load_gait(args.gait or EXO_GAIT, robot)
    sizes = np.asarray(args.delays or [0, 1, 2, 3, 5, 8, 12, 20, 40], dtype=float) * 1e-3

    class CentralPD(PDController):
        latency = "torque"

    print(f"latency check: robot {robot.name}, one trial per delay, 20 steps after; load {os.getloadavg()[0]:.2f}")
    cases: list[tuple[str, str, object]] = [("PD servos (command latency)", "pd", None),
                                            ("PD computed centrally", "pd", CentralPD()),
                                            ("passivity (spec gains)", "passivity", None)]
    for name, controller, law in cases:
        sim = SimConfig(controller=controller, n_threads=1)
        with Validator(robot, gait, ValidateConfig(trials=sizes.size, steps_after=20), sim=sim,
                       certify=CertifyConfig(method="uniform", disturbance="state", n_samples=10)) as v:
            if law is not None:
                v.engine.close()
                v.engine = FeedbackEngine(robot, gait, law, sim)  # type: ignore[arg-type]
            r = v.run("latency", draws=Draws("latency", sizes, {}))
        cells = [f"{d * 1e3:g} ms " + ("walks" if ok else f"falls ({why}, step {st})")
                 for d, ok, why, st in zip(sizes, r.success, r.fall_reason, r.fall_step, strict=True)]
        print(f"  {name:<28} " + "; ".join(cells), flush=True)


if __name__ == "__main__":
    main()
