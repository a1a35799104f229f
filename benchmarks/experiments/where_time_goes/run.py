"""Where a certificate's and a study evaluation's time goes, as seconds and physics steps, in one run.

``certify``: the default certificate of ``--gait`` on ``--robot`` — the engine's construction, the orbit search (its
walk and the stability probe), the pushes (seconds, physics steps — the verification batches' among them — and
steps per push; each round's kind, size and verdict), the certificate's JSON, and the simulated steps/s against
MuJoCo's raw single-thread speed on the same model (``mj_step`` under the step's controls). Every figure is the
certificate's own (``GaitCertificate.seconds``, its physics-step counts, its rounds) or timed around a public call:
nothing in the package is wrapped or replaced.

``evaluate``: one study evaluation of ``--params`` (L T W h) with a generator built once (as a study worker):
generation, the walk to the step cap, the certificate (``Evaluation.seconds``).

    python benchmarks/experiments/where_time_goes/run.py --robot exo --gait tests/data/exo_gait.json [--params \\
        0.22 0.7 0.24 0.06]
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path
from typing import Any

import mujoco
import numpy as np

from robustgait import CertifyConfig, Config, GaitParams, SimConfig, certify_gait, load_gait, load_robot
from robustgait.robots import Robot
from robustgait.sim.engine import StepEngine

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))  # benchmarks/common.py
from common import git_commit


def raw_speed(robot: Robot, gait: Any, qpos: np.ndarray, qvel: np.ndarray) -> float:
    """MuJoCo's own single-thread speed [steps/s]: ``mj_step`` over one step of the gait from x* under its controls."""
    with StepEngine(robot, gait, SimConfig(n_threads=1)) as eng:
        b = eng.step(qpos[None], qvel[None], gait.stance, record=True)
        state, ctrl = eng.full_states(qpos[None], qvel[None])[0], b.controls[0]
    d = mujoco.MjData(robot.model)
    best = 0.0
    for _ in range(3):
        mujoco.mj_setState(robot.model, d, state, mujoco.mjtState.mjSTATE_FULLPHYSICS)
        t0 = time.perf_counter()
        for row in ctrl:
            d.ctrl[:] = row
            mujoco.mj_step(robot.model, d)
        best = max(best, len(ctrl) / (time.perf_counter() - t0))
    return best


def profile_certify(robot: Robot, gait: Any) -> dict[str, Any]:
    """The default certificate of ``gait``, timed from outside, split by what the certificate itself reports
    (``GaitCertificate.seconds``, its physics-step counts and its rounds): nothing in the package is wrapped."""
    t0 = time.perf_counter()
    cert = certify_gait(robot, gait, CertifyConfig(), SimConfig())
    total = time.perf_counter() - t0
    t0 = time.perf_counter()
    text = json.dumps(cert.to_dict())
    io_seconds = time.perf_counter() - t0
    c = cert.certificate
    rounds = [] if c is None else [(r.kind, r.n_samples, r.passed) for r in c.rounds]
    out = {"status": cert.status.value, "j_star": cert.value, "total_s": total, "orbit_s": cert.seconds["orbit"],
           "orbit_physics": cert.orbit_physics_steps, "sampling_s": cert.seconds["sampling"],
           "sampling_physics": cert.physics_steps, "verify_physics": cert.verify_physics_steps,
           "pushes": sum(n for _, n, _ in rounds), "json_s": io_seconds, "json_bytes": len(text), "rounds": rounds,
           "period": cert.orbit.period if cert.orbit else None}
    if cert.orbit is not None and cert.orbit.qpos is not None:
        out["raw_steps_per_s_1thread"] = raw_speed(robot, gait, cert.orbit.qpos, cert.orbit.qvel)
    return out


def profile_evaluate(spec: str, params: list[float]) -> dict[str, Any]:
    from robustgait.gaitgen import GaitGenerator
    from robustgait.study.evaluate import evaluate

    robot = load_robot(spec)
    cfg = Config()
    t0 = time.perf_counter()
    gen = GaitGenerator(robot, cfg.generate)
    build = time.perf_counter() - t0
    p = GaitParams(step_length=params[0], step_duration=params[1], step_width=params[2], step_height=params[3])
    t0 = time.perf_counter()
    ev = evaluate(robot, p, cfg, generator=gen)
    d = ev.to_dict()
    return {"build_s": build, "total_s": time.perf_counter() - t0, "seconds": d.get("seconds"),
            "status": (d.get("certificate") or {}).get("status"), "j_star": (d.get("certificate") or {}).get("j_star")}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--robot", required=True)
    ap.add_argument("--gait", required=True)
    ap.add_argument("--params", type=float, nargs=4, default=None, help="also profile one evaluation: L T W h")
    ap.add_argument("--out", default="")
    args = ap.parse_args()
    commit = git_commit()
    print(f"# where_time_goes {time.strftime('%Y-%m-%d %H:%M')} at {commit}, load {os.getloadavg()[0]:.1f}: "
          f"{args.robot}, {Path(args.gait).name}")
    robot = load_robot(args.robot)
    gait = load_gait(args.gait, robot)
    t0 = time.perf_counter()
    StepEngine(robot, gait, SimConfig()).close()
    row: dict[str, Any] = {"robot": args.robot, "gait": Path(args.gait).name, "timestep": robot.dt,
                           "engine_s": time.perf_counter() - t0, "certify": profile_certify(robot, gait)}
    c = row["certify"]
    steps = c["orbit_physics"] + c["sampling_physics"]
    raw = c.get("raw_steps_per_s_1thread", 0.0)
    print(f"certificate: {c['status']}, J* {c['j_star']:.3f} N s, {c['total_s']:.1f} s, {steps / 1e6:.2f} M physics "
          f"steps ({steps / c['total_s']:.0f} steps/s; MuJoCo alone, 1 thread: {raw:.0f})")
    print(f"  orbit search: {c['orbit_s']:.1f} s, {c['orbit_physics'] / 1e6:.3f} M steps (period {c['period']})")
    print(f"  pushes: {c['pushes']} in {len(c['rounds'])} rounds, {c['sampling_s']:.1f} s, "
          f"{c['sampling_physics'] / 1e6:.2f} M steps ({c['verify_physics'] / 1e6:.2f} M of them verification), "
          f"{c['sampling_physics'] / max(c['pushes'], 1):.0f} steps/push; certificate JSON {c['json_s'] * 1e3:.0f} ms")
    for kind, n, passed in c["rounds"]:
        print(f"    {kind:<8} {n:4d} pushes" + ("" if passed is None else f"  passed {passed}"))
    if args.params:
        row["evaluate"] = profile_evaluate(args.robot, args.params)
        print(f"evaluation {args.params}: generator build {row['evaluate']['build_s']:.1f} s, then "
              f"{row['evaluate']['total_s']:.1f} s: {row['evaluate']['seconds']}")
    if args.out:
        with open(args.out, "a") as f:
            f.write(json.dumps({**row, "commit": commit, "date": time.strftime("%Y-%m-%d %H:%M")}) + "\n")


if __name__ == "__main__":
    main()
