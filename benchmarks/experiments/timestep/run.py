"""Which physics timestep a robot's certificate needs: walks, switching states and J* at several timesteps against a
fine reference, in one run.

For each gait and each timestep h (the reference ``--reference`` first):

* the walk: ``--steps`` steps from the gait's start (falls, the orbit its switching states settle on: period, σ),
  its wall time and physics steps;
* the orbit's band centres against the reference's, in band coordinates (angles in rad, velocities over √(g l) or
  √(g/l); the recovery band's floor is 0.03): the largest coordinate difference under the best phase shift;
* the step map at the reference's x*: one step (the orbit's period of steps) from the same state at h and at the
  reference — the largest band-coordinate difference of the switching states (the map's error at h);
* with ``--certify``: the default certificate (J*, pushes, physics steps, seconds), with ``--seeds N`` for the
  certificate seeds 0 … N − 1 (J*'s spread over seeds).

Every other option is the robot's. Rows go to ``--out`` (JSON lines) and a table is printed.

    python benchmarks/experiments/timestep/run.py --robot t1.toml --gait slow.json --gait default.json \
        --timesteps 0.0005 0.001 0.001spd --reference 0.00025 --certify
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from robustgait import CertifyConfig, SimConfig, certify_gait, load_gait, load_robot, walk
from robustgait.certificate import Walked, find_orbit
from robustgait.certificate.band import band_coordinates
from robustgait.io.robotfile import read_mjcf
from robustgait.robots import Robot
from robustgait.sim.engine import StepEngine

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))  # benchmarks/common.py
from common import git_commit


def at_timestep(spec: str, h: float, stable: bool) -> Robot:
    """The robot of ``spec`` with its ``[sim]`` timestep set to ``h`` [s] and ``stable_pd`` to ``stable`` (stable PD
    servos: :func:`robustgait.robots.model.servo_damping`); everything else as the spec says."""
    s = replace(load_robot(spec).spec, timestep=h, stable_pd=stable)
    return Robot(s, read_mjcf(s))


def setting(text: str) -> tuple[float, bool]:
    """``H`` or ``Hspd``: a timestep H [s], and whether the servos are stable PD (:func:`at_timestep`)."""
    return float(text.removesuffix("spd")), text.endswith("spd")


def centre_difference(a: np.ndarray, b: np.ndarray) -> float:
    """Largest |a − b| over phases and coordinates of two bands' centres (k_a, d), (k_b, d), both tiled to the least
    common multiple of their periods, under the best cyclic phase shift."""
    n = math.lcm(a.shape[0], b.shape[0])
    ta, tb = np.tile(a, (n // a.shape[0], 1)), np.tile(b, (n // b.shape[0], 1))
    return float(min(np.max(np.abs(ta - np.roll(tb, s, axis=0))) for s in range(n)))


def map_error(robot: Robot, gait: Any, qpos: np.ndarray, qvel: np.ndarray, steps: int, sim: SimConfig
              ) -> np.ndarray:
    """Band coordinates (d,) of the switching state after ``steps`` steps from (qpos, qvel), a state that starts a
    step of the gait's stance (NaN if it fell)."""
    with StepEngine(robot, gait, sim) as eng:
        q, v = qpos[None], qvel[None]
        stance = gait.stance
        for _ in range(steps):
            b = eng.step(q, v, stance)
            if b.fell[0]:
                return np.full(band_coordinates(robot, qpos, qvel).shape[1], np.nan)
            q, v = b.qpos, b.qvel
            stance = "left" if stance == "right" else "right"
        # written for the gait's stance, as the band is
        if stance != gait.stance:
            q, v = robot.mirror_state(q, v)
        return band_coordinates(robot, q, v)[0]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--robot", required=True, help="a shipped robot's name or a spec .toml")
    ap.add_argument("--gait", action="append", required=True)
    ap.add_argument("--timesteps", type=setting, nargs="+", required=True,
                    help="timesteps to compare, each H [s] or Hspd (stable PD)")
    ap.add_argument("--reference", type=setting, required=True)
    ap.add_argument("--steps", type=int, default=300)
    ap.add_argument("--certify", action="store_true")
    ap.add_argument("--seeds", type=int, default=1, help="with --certify: certificate seeds 0 … N−1")
    ap.add_argument("--out", default="")
    args = ap.parse_args()
    commit = git_commit()
    print(f"# timestep {time.strftime('%Y-%m-%d %H:%M')} at {commit}: {args.robot}")
    sim = SimConfig()
    rows: list[dict[str, Any]] = []
    for gpath in args.gait:
        ref: dict[str, Any] = {}
        for h, r in [args.reference, *args.timesteps]:
            robot = at_timestep(args.robot, h, r)
            gait = load_gait(gpath, robot)
            t0 = time.perf_counter()
            res = walk(robot, gait, sim, steps=args.steps)
            wall = time.perf_counter() - t0
            orbit = find_orbit(Walked(robot, gait, res), CertifyConfig())
            row: dict[str, Any] = {"gait": Path(gpath).name, "timestep": h, "stable_pd": r, "steps": res.steps_taken,
                                   "fell": res.fell, "fall_reason": res.fall_reason, "walk_s": round(wall, 2),
                                   "walk_physics": res.physics_steps, "orbit": orbit.status.value,
                                   "period": orbit.period, "sigma": orbit.sigma}
            centres = None if orbit.band is None else orbit.band.centres
            if (h, r) == args.reference:
                ref = {"centres": centres, "orbit": orbit}
                if orbit.qpos is not None:
                    ref["image"] = map_error(robot, gait, orbit.qpos, orbit.qvel, orbit.period, sim)
            else:
                if centres is not None and ref.get("centres") is not None:
                    row["centre_diff"] = centre_difference(centres, ref["centres"])
                o = ref.get("orbit")
                if o is not None and o.qpos is not None:
                    img = map_error(robot, gait, o.qpos, o.qvel, o.period, sim)
                    row["map_diff"] = float(np.max(np.abs(img - ref["image"])))
            if args.certify and (h, r) != args.reference:
                for seed in range(args.seeds):
                    t0 = time.perf_counter()
                    c = certify_gait(robot, gait, CertifyConfig(seed=seed), sim)
                    one = dict(status=c.status.value, j_star=c.value, certify_s=round(time.perf_counter() - t0, 1),
                               pushes=c.certificate.n_samples if c.certificate else 0,
                               certify_physics=c.physics_steps + c.orbit_physics_steps)
                    if seed == 0:
                        row.update(one)
                    row.setdefault("seeds", []).append({"seed": seed, **one})
            rows.append(row)
            print(json.dumps(row), flush=True)
            if args.out:
                with open(args.out, "a") as f:
                    f.write(json.dumps({**row, "commit": commit}) + "\n")
    print("\n| gait | h [ms] | walked | orbit (period, σ) | centres vs ref | map vs ref | J* [N s] | certify s |")
    print("|---|---|---|---|---|---|---|---|")
    for r in rows:
        sig = "" if r["sigma"] is None else f"{r['sigma']:.2g}"
        h = f"{r['timestep'] * 1e3:g}{' SPD' if r['stable_pd'] else ''}"
        walked = f"{r['steps']}{' fell ' + str(r['fall_reason']) if r['fell'] else ''}"
        print(f"| {r['gait']} | {h} | {walked} | {r['orbit']} ({r['period']}, {sig}) | "
              f"{r.get('centre_diff', float('nan')):.3g} | "
              f"{r.get('map_diff', float('nan')):.3g} | {r.get('j_star', float('nan')):.3f} | "
              f"{r.get('certify_s', float('nan'))} |")
    if any(len(r.get("seeds", [])) > 1 for r in rows):
        print("\n| gait | h [ms] | J* over seeds [N s]: mean (range) | seconds: mean |")
        print("|---|---|---|---|")
        for r in rows:
            if len(r.get("seeds", [])) > 1:
                js = [x["j_star"] for x in r["seeds"]]
                secs = [x["certify_s"] for x in r["seeds"]]
                print(f"| {r['gait']} | {r['timestep'] * 1e3:g}{' SPD' if r['stable_pd'] else ''} | "
                      f"{np.mean(js):.3f} ({min(js):.3f}–{max(js):.3f}) | {np.mean(secs):.1f} |")


if __name__ == "__main__":
    main()
