"""Certificates of the Atalante FROST gait: r* for both maps × both reconstructions, sampler speed vs raw rollout.

For map ∈ {step, stride} × reconstruction ∈ {holonomic, angular-only} it runs ``certify_gait`` (N = 200,
r_max = 2, α = 0.05, seed 0, heading frame) and prints r*, x*, the fixed point's residual and steps, the map's
residual at x*, the samples that fell or lie inside B(r*), and the wall times. For the step map with the
holonomic reconstruction (the acceptance case) it repeats the certificate ``--repeat`` times and, after
each, times raw ``mujoco.rollout`` on the same model, the same thread count, the same batch (the N
reconstructed sample states), the same number of physics steps per sample (the sampler's total / N) and
zero control; it prints the medians of both speeds, their ratio (goal ≥ 0.8), the sampling wall time
(goal ≤ 10 s), and checks that every repeat gave the same JSON (without ``seconds``).

    python benchmarks/bench_certify.py [--repeat 5] [--threads 0] [--samples 200]
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import time
from pathlib import Path

import mujoco
import numpy as np
from mujoco import rollout

from robustgait import SimConfig, load_gait, load_robot
from robustgait.certify import CertifyConfig, GaitCertificate, certify_gait
from robustgait.poincare import ReturnMap

REPO = Path(__file__).resolve().parents[1]
ATALANTE = REPO.parent / "shared" / "atalante"
COMBOS = (("step", "holonomic"), ("step", "angular-only"), ("stride", "holonomic"), ("stride", "angular-only"))


def deterministic_json(gc: GaitCertificate) -> str:
    d = gc.to_dict()
    d.pop("seconds")
    return json.dumps(d, allow_nan=False)


def row(gc: GaitCertificate) -> str:
    c, fp, s = gc.certificate, gc.fixed_point, gc.seconds
    x = ", ".join(f"{v:.4f}" for v in fp.x_star)
    return (f"{gc.config.map:6s} {gc.config.reconstruction:12s} r* {c.r_star:.4f}{'' if c.attained else ' (sup)'}  "
            f"x* [{x}]  fp residual {fp.residual:.2e} after {fp.steps:3d} steps  map residual {gc.map_residual:.2e}  "
            f"fell {int(c.fell.sum()):3d}  inside {c.n_inside:3d}  fixed point {s['fixed_point']:.2f} s  "
            f"sampling {s['sampling']:.2f} s  ({s['sim_steps_per_s']:.0f} steps/s)")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5, help="repeats of the acceptance case's timing (median)")
    ap.add_argument("--threads", type=int, default=0, help="0 = one per core")
    ap.add_argument("--samples", type=int, default=200)
    args = ap.parse_args()
    if args.repeat < 2:
        ap.error("--repeat must be >= 2 (the determinism check compares repeats)")
    robot = load_robot(REPO / "examples" / "atalante.toml")
    gait = load_gait(ATALANTE / "jt_bez_2023-09-10.yaml", robot)
    sim = SimConfig(n_threads=args.threads)
    threads = sim.threads
    n = args.samples
    print(f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores; mujoco "
          f"{mujoco.__version__}; threads {threads}; model timestep {robot.dt} s; N = {n}, r_max = 2, "
          f"alpha = 0.05, seed 0, heading frame")

    def config(kind: str, rec: str) -> CertifyConfig:
        return CertifyConfig(n_samples=n, r_max=2.0, alpha=0.05, seed=0, map=kind,  # type: ignore[arg-type]
                             reconstruction=rec, sim=sim)  # type: ignore[arg-type]

    # the four certificates (the acceptance case first; it is also the first timing repeat)
    certs = {combo: certify_gait(robot, gait, config(*combo)) for combo in COMBOS}
    for combo in COMBOS:
        print(row(certs[combo]))

    # acceptance case: step map, holonomic reconstruction — sampler vs raw mujoco.rollout, and determinism
    cfg = config("step", "holonomic")
    runs = [certs[("step", "holonomic")]]
    raw = []
    with ReturnMap(robot, gait, kind="step", reconstruction="holonomic", sim=sim) as pmap, \
            rollout.Rollout(nthread=threads) as pool:
        fp = pmap.find_fixed_point(tol=cfg.fp_tol, min_steps=cfg.fp_min_steps, max_steps=cfg.fp_max_steps)
        assert np.array_equal(fp.x_star, runs[0].fixed_point.x_star)
        qpos, qvel = pmap.reconstruct(np.asarray(runs[0].certificate.samples))
        init = pmap.engine.full_states(qpos, qvel)
        nstep = int(np.ceil(runs[0].physics_steps / n))
        ctrl = np.zeros((n, nstep, robot.model.nu))
        datas = [robot.new_data() for _ in range(threads)]
        pool.rollout(robot.model, datas, init[:threads], ctrl[:threads, :10])  # start the threads
        for i in range(args.repeat):  # interleaved, so that load from other jobs hits both alike
            if i:
                runs.append(certify_gait(robot, gait, cfg))
            t0 = time.perf_counter()
            pool.rollout(robot.model, datas, init, ctrl)
            raw.append(n * nstep / (time.perf_counter() - t0))
    ours = float(np.median([g.seconds["sim_steps_per_s"] for g in runs]))
    wall = float(np.median([g.seconds["sampling"] for g in runs]))
    total = float(np.median([g.seconds["total"] for g in runs]))
    r = float(np.median(raw))
    ratios = [g.seconds["sim_steps_per_s"] / x for g, x in zip(runs, raw, strict=True)]
    print(f"step map, holonomic, median of {args.repeat}: sampler {ours:.0f} simulated steps/s, raw mujoco.rollout "
          f"{r:.0f} steps/s ({n} states x {nstep} steps, zero control)  ratio {ours / r:.2f} "
          f"({'met' if ours / r >= 0.8 else 'NOT met'}: goal >= 0.8); per repeat "
          f"{' '.join(f'{q:.2f}' for q in ratios)} (median {float(np.median(ratios)):.2f})")
    print(f"  sampling wall time {wall:.2f} s for N = {n} ({'met' if wall <= 10 else 'NOT met'}: goal <= 10 s); "
          f"certify total {total:.2f} s; {runs[0].physics_steps} physics steps "
          f"({runs[0].physics_steps / n:.0f}/sample)")
    ref = deterministic_json(runs[0])
    assert all(deterministic_json(g) == ref for g in runs[1:]), "same seed, different certificate JSON"
    print(f"determinism: {len(runs)} runs with seed 0 gave identical JSON (without 'seconds'), "
          f"{len(ref)} characters")


if __name__ == "__main__":
    main()
