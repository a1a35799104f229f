"""How precise a certificate is and what it costs: r*'s spread over seeds and estimators on real gaits, the
confidence statement's coverage on maps with known answers, both barriers, the sampler against raw
``mujoco.rollout``, horizons K = 1, 2, 3 and each certified set's cost.

    python benchmarks/experiments/certificate_precision/run.py [all|seeds|coverage|barrier|speed|horizon|states] \\
        [options]

* ``seeds``: the default ``exo`` gait (generated here from the default ``GaitParams``, or ``--exo-gait FILE``;
  ``--step-length`` etc. change the parameters) and the Atalante FROST gait, ``--seeds`` seeds each, methods
  ``uniform`` (N = 200) and ``sequential`` (defaults): mean, sd, CV and range of r*, the statement's bound, samples,
  physics steps, wall time. After every certificate raw ``mujoco.rollout`` (same model and threads, 100 states near
  x*, zero control) measures the machine's speed under the same load: the sampler/raw ratio, measured in the run.
* ``coverage``: ``--runs`` sequential certificates of each synthetic map (:mod:`robustgait.certificate.synthetic`):
  fraction of runs whose true violating fraction in B(r*) exceeds ε (must be ≤ β) — and the same for a naive
  rule that ignores the data-dependent choice of r*, to show the check can fail.
* ``barrier``: r* with H = r² − ‖x − x*‖² (``ball``) and the paper's H = r − ‖x − x*‖² on the Atalante gait.
* ``speed``: the Atalante gait's four (map × reconstruction) uniform certificates (``map``: the shortest map the orbit
  is searched on; each row gives the orbit's period, settling step and σ, and the orbit search's seconds), then the
  sampler against raw ``mujoco.rollout`` on the same batch (ratio), and determinism of the JSON over ``--repeat``
  runs.
* ``horizon``: sequential certificates of horizon K = 1, 2, 3 (``--horizons``) on the thin gaits of the learners'
  table (``experiments/learners/data/table_exo.jsonl``, table r* < 0.05) and the default flat-foot and
  multi-contact exo gaits: r*, the excursion, samples, physics steps, wall time. Then the event-logic check:
  ``--probe`` states uniform in B(r_max) walked one step: fall reasons, touchdown phase τ of the others (a touchdown
  held back by ``min_switch_tau`` shows as τ at that bound; a step cut at ``max_step_tau`` as ``no_touchdown``), and
  the τ of the samples whose image is farther from x̄* than they started against the τ of the others.
* ``states``: on the default exo gait, ``--seeds`` sequential certificates of each state × set and the push
  certificate, one after the other in the same run: r*, E*, wall time and its ratio to ``omega``'s.

Every mode takes the orbit from :func:`robustgait.certificate.search.find_orbit` and its maps from
:class:`robustgait.certificate.returnmap.FullStateMap` (the orbit's period) and
:class:`robustgait.certificate.reducedmap.ReducedMap`. J*'s cost: ``experiments/push_cost``; ρ:
``experiments/orbit_verdict``.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import platform
import sys
import time
from dataclasses import replace
from pathlib import Path

import mujoco
import numpy as np
from mujoco import rollout

from robustgait import load_gait, load_robot
from robustgait.certificate import Walking, find_orbit
from robustgait.certificate.barrier import distances, sample_ball, solve_radius
from robustgait.certificate.certify import GaitCertificate, certify_gait
from robustgait.certificate.estimators import certify_map_sequential
from robustgait.certificate.orbit import Orbit
from robustgait.certificate.reduced import ReducedState
from robustgait.certificate.reducedmap import ReducedMap
from robustgait.certificate.returnmap import FullStateMap
from robustgait.certificate.synthetic import BandMap, ConeMap
from robustgait.config import CertifyConfig, GaitParams, GenerationConfig, SequentialConfig, SimConfig
from robustgait.errors import RobustGaitError
from robustgait.gait import Gait
from robustgait.robots import Robot
from robustgait.sim.engine import StepEngine
from robustgait.sim.factory import make_engine
from robustgait.validate.stats import wilson_interval

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))  # benchmarks/common.py
from common import ATALANTE_GAIT, ATALANTE_SPEC, REPO, add_gait_arguments, default_gaits, load_average

COMBOS = (("step", "holonomic"), ("step", "angular-only"), ("stride", "holonomic"), ("stride", "angular-only"))


class OrbitMaps:
    """A gait's orbit (:func:`robustgait.certificate.search.find_orbit`) and a state certificate's maps on it, on one
    engine: ``fmap`` the full-state map of the orbit's period, ``reduced`` the reduced state of ``config`` set up at
    x*, ``pmap`` the reduced map of ``config.horizon`` maps. A context manager (closes the engine); raises
    :class:`RobustGaitError` when the gait has no orbit (``orbit`` is then still set)."""

    def __init__(self, robot: Robot, gait: Gait, config: CertifyConfig, sim: SimConfig):
        self.engine: StepEngine = make_engine(robot, gait, sim)
        try:
            self.orbit: Orbit = find_orbit(Walking(robot, gait, sim, engine=self.engine), config)
            if not self.orbit.ok or self.orbit.qpos is None or self.orbit.qvel is None:
                raise RobustGaitError(f"no orbit: {self.orbit.status}: {self.orbit.reason}")
            self.fmap = FullStateMap(robot, gait, self.orbit.period, engine=self.engine)
            self.reduced = ReducedState.at(config.state, robot, self.orbit.qpos, self.orbit.qvel, gait.stance, config)
            self.pmap = ReducedMap(self.fmap, self.reduced, config.horizon)
        except BaseException:
            self.engine.close()
            raise

    def __enter__(self) -> OrbitMaps:
        return self

    def __exit__(self, *exc: object) -> None:
        self.engine.close()


class RawRollout:
    """Raw mujoco.rollout (zero control) on n states near a gait's x*: the machine's speed now."""

    def __init__(self, robot: Robot, gait: Gait, sim: SimConfig, n: int = 100, nstep: int = 500):
        self.robot, self.n, self.nstep = robot, n, nstep
        self.pool = rollout.Rollout(nthread=sim.threads)
        with OrbitMaps(robot, gait, CertifyConfig(disturbance="state"), sim) as om:
            red = om.reduced
            qpos, qvel = om.pmap.reconstruct(sample_ball(n, red.dim, 0.05, red.x_star, np.random.default_rng(0)))
            self.init = om.engine.full_states(qpos, qvel)
        self.ctrl = np.zeros((n, nstep, robot.model.nu))
        self.datas = [robot.new_data() for _ in range(sim.threads)]
        self.pool.rollout(robot.model, self.datas, self.init[:2], self.ctrl[:2, :10])  # start the threads

    def speed(self) -> float:
        t0 = time.perf_counter()
        self.pool.rollout(self.robot.model, self.datas, self.init, self.ctrl)
        return self.n * self.nstep / (time.perf_counter() - t0)

    def close(self) -> None:
        self.pool.close()


def summary(name: str, gcs: list[GaitCertificate], raw: list[float]) -> str:
    r = np.array([g.value for g in gcs])
    c = [g.certificate for g in gcs]
    bound = np.array([x.violation_bound for x in c if x is not None])
    n = np.array([x.n_samples for x in c if x is not None])
    wall = np.array([g.seconds["total"] for g in gcs])
    steps = np.array([g.physics_steps for g in gcs])
    ratio = np.array([g.seconds["sim_steps_per_s"] for g in gcs]) / np.array(raw)
    sd = r.std(ddof=1) if r.size > 1 else 0.0
    return (f"| {name} | {r.mean():.4f} | {sd:.4f} | {100 * sd / r.mean():.1f} % | {r.min():.4f}–{r.max():.4f} | "
            f"{100 * np.median(bound):.3g} % ({100 * bound.max():.3g} %) | {n.mean():.0f} ({n.min()}–{n.max()}) | "
            f"{steps.mean() / 1e3:.0f} k | {wall.mean():.1f} s ({wall.max():.1f}) | {np.median(ratio):.2f} | "
            f"{np.median(raw) / 1e3:.0f} k |")


def cmd_seeds(args: argparse.Namespace) -> None:
    sim = SimConfig(n_threads=args.threads)
    print(f"## seeds: {args.seeds} seeds per gait and method; {load_average()}")
    print("| gait, method | mean r* | sd | CV | range | bound: median (max) | samples: mean (range) | physics steps | "
          "wall: mean (max) | sampler/raw | raw rollout [steps/s], median |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for gname, (robot, gait) in default_gaits(args).items():
        raw = RawRollout(robot, gait, sim)
        for method in args.methods.split(","):
            cfg = CertifyConfig(method=method, disturbance="state", sequential=SequentialConfig(epsilon=args.epsilon,  # type: ignore[arg-type]
                                                                          budget=args.budget))
            gcs, speeds = [], []
            for seed in range(args.seeds):
                gc = certify_gait(robot, gait, replace(cfg, seed=seed), sim)
                speeds.append(raw.speed())  # right after: the same load
                if not gc.ok:
                    raise SystemExit(f"{gname}: {gc.status}: {gc.reason}")
                gcs.append(gc)
                if args.verbose:
                    c = gc.certificate
                    assert c is not None
                    tr = " ".join(f"{rd.kind[0]}{rd.samples_used}:{rd.r_hat:.4f}" for rd in c.rounds)
                    print(f"  {gname} {method} seed {seed}: r* {gc.value:.4f} bound {c.violation_bound:.4f} "
                          f"N {c.n_samples} {gc.seconds['total']:.1f} s (raw {speeds[-1]:.0f} steps/s)  {tr}",
                          flush=True)
            print(summary(f"{gname}, {method}", gcs, speeds), flush=True)
        raw.close()
        print(f"  ({gname} done; {load_average()})")


def _naive(P: ConeMap | BandMap, seed: int, eps: float, beta: float, budget: int) -> float | None:
    """A rule with no correction for the data-dependent r*: rounds of 50 uniform in B(r̂), stop as soon as
    ⌈ln β / ln(1 − ε)⌉ samples lie in B(r̂) (they all satisfy, r̂ being feasible). Returns r̂, None if never."""
    need = math.ceil(math.log(beta) / math.log1p(-eps))
    rng = np.random.default_rng(seed)
    x0 = sample_ball(200, 3, 2.0, P.x_star, rng)
    x1 = P(x0)
    while True:
        d, p = distances(x0, x1, P.x_star)
        r = solve_radius(d, p, alpha=0.05, r_max=2.0).radius
        if np.count_nonzero(d < r) >= need:
            return r
        if x0.shape[0] + 50 > budget or r == 0.0:
            return None
        new = sample_ball(50, 3, r, P.x_star, rng)
        x0, x1 = np.vstack([x0, new]), np.vstack([x1, P(new)])


def cmd_coverage(args: argparse.Namespace) -> None:
    eps, beta = args.epsilon, 0.05
    seq = SequentialConfig(epsilon=eps, budget=args.budget)
    xs = np.array([0.4, 0.2, 0.3])
    maps = {
        f"bands, fraction {1.05 * eps:g} in every ball (true r* = 0)": BandMap(xs, a=1.05 * eps),
        f"bands, fraction {0.5 * eps:g} + 0.75·{4 * eps:g}·r (true r* = 0)": BandMap(xs, a=0.5 * eps, c=4 * eps),
        "cone of 1 % of directions beyond r0 = 0.3 (true r* = 0.3)": ConeMap(xs, r0=0.3, half_angle=0.2003),
    }
    print(f"## coverage: {args.runs} runs per map, epsilon = {eps:g}, beta = {beta:g}, budget {args.budget}; "
          f"{load_average()}")
    print("| map | certified | true fraction > ε: sequential | naive rule | r*: median (range) | samples: median |")
    print("|---|---|---|---|---|---|")
    for name, P in maps.items():
        t0 = time.perf_counter()
        fails = certified = 0
        rs, ns = [], []
        for seed in range(args.runs):
            c = certify_map_sequential(P, xs, CertifyConfig(seed=seed, beta=beta, disturbance="state", sequential=seq))
            if c.violation_bound < 1.0:
                certified += 1
                fails += P.violating_fraction(c.radius) > eps
            rs.append(c.radius)
            ns.append(c.n_samples)
        naive = [_naive(P, seed, eps, beta, args.budget) for seed in range(args.runs)]
        naive_fails = sum(r is not None and P.violating_fraction(r) > eps for r in naive)
        lo, hi = wilson_interval(fails, args.runs)
        print(f"| {name} | {certified} | {fails / args.runs:.4f} (95 % CI {lo:.4f}–{hi:.4f}) | "
              f"{naive_fails / args.runs:.3f} | {np.median(rs):.4g} ({min(rs):.3g}–{max(rs):.3g}) | "
              f"{np.median(ns):.0f} |  ({time.perf_counter() - t0:.0f} s)", flush=True)


def cmd_barrier(args: argparse.Namespace) -> None:
    sim = SimConfig(n_threads=args.threads)
    print(f"## barrier: ball H = r² − ‖x − x*‖² vs paper H = r − ‖x − x*‖² (step map, holonomic); {load_average()}")
    print("| gait | method | seeds | r* ball: mean (range) | r* paper: mean (range) |")
    print("|---|---|---|---|---|")
    for gname, (robot, gait) in default_gaits(args).items():
        for method, seeds in (("uniform", [0]), ("sequential", list(range(args.barrier_seeds)))):
            res = {}
            for barrier in ("ball", "paper"):
                cfg = CertifyConfig(method=method, barrier=barrier, disturbance="state")  # type: ignore[arg-type]
                res[barrier] = np.array([certify_gait(robot, gait, replace(cfg, seed=s), sim).value for s in seeds])
            cells = " | ".join(f"{v.mean():.4f} ({v.min():.4f}–{v.max():.4f})" for v in res.values())
            print(f"| {gname} | {method} | {len(seeds)} | {cells} |", flush=True)


def deterministic_json(gc: GaitCertificate) -> str:
    d = gc.to_dict()
    d.pop("seconds")
    return json.dumps(d, allow_nan=False)


def row(gc: GaitCertificate) -> str:
    c, fp, o, s = gc.certificate, gc.fixed_point, gc.orbit, gc.seconds
    assert c is not None and fp is not None and o is not None and o.sigma is not None and gc.map_residual is not None
    x = ", ".join(f"{v:.4f}" for v in fp.omega)
    return (f"{gc.config.map:6s} {gc.config.reconstruction:12s} r* {c.radius:.4f}{'' if c.attained else ' (sup)'}  "
            f"x* [{x}] after step {fp.step:3d}  orbit period {o.period}, settled at step {o.settled}, σ "
            f"{o.sigma:.2g}  map residual {gc.map_residual:.2e}  fell {int(c.fell.sum()):3d}  inside "
            f"{c.n_inside:3d}  orbit {s['orbit']:.2f} s  sampling {s['sampling']:.2f} s  "
            f"({s['sim_steps_per_s']:.0f} steps/s)")


def cmd_speed(args: argparse.Namespace) -> None:
    if not (ATALANTE_SPEC).is_file():
        print("speed: ../shared/atalante is missing, skipped")
        return
    robot = load_robot(ATALANTE_SPEC)
    gait = load_gait(ATALANTE_GAIT, robot)
    sim = SimConfig(n_threads=args.threads)
    threads = sim.threads
    n = args.samples
    print(f"## speed: N = {n}, r_max = 2, alpha = 0.05, seed 0, heading frame, uniform; threads {threads}; "
          f"{load_average()}")

    def config(kind: str, rec: str) -> CertifyConfig:
        return CertifyConfig(method="uniform", disturbance="state", n_samples=n, r_max=2.0, alpha=0.05, seed=0,
                             map=kind, reconstruction=rec)  # type: ignore[arg-type]

    certs = {combo: certify_gait(robot, gait, config(*combo), sim) for combo in COMBOS}
    for combo in COMBOS:
        print(row(certs[combo]))
    cfg = config("step", "holonomic")
    runs = [certs[("step", "holonomic")]]
    raw = []
    first = runs[0].certificate
    assert first is not None and runs[0].fixed_point is not None
    with OrbitMaps(robot, gait, cfg, sim) as om, rollout.Rollout(nthread=threads) as pool:
        assert np.array_equal(om.orbit.fixed_point(cfg.frame).omega, runs[0].fixed_point.omega)
        qpos, qvel = om.pmap.reconstruct(np.asarray(first.samples))
        init = om.engine.full_states(qpos, qvel)
        nstep = int(np.ceil(runs[0].physics_steps / n))
        ctrl = np.zeros((n, nstep, robot.model.nu))
        datas = [robot.new_data() for _ in range(threads)]
        pool.rollout(robot.model, datas, init[:threads], ctrl[:threads, :10])  # start the threads
        for i in range(args.repeat):  # interleaved, so that load from other jobs hits both alike
            if i:
                runs.append(certify_gait(robot, gait, cfg, sim))
            t0 = time.perf_counter()
            pool.rollout(robot.model, datas, init, ctrl)
            raw.append(n * nstep / (time.perf_counter() - t0))
    ours = float(np.median([g.seconds["sim_steps_per_s"] for g in runs]))
    wall = float(np.median([g.seconds["sampling"] for g in runs]))
    r = float(np.median(raw))
    ratios = [g.seconds["sim_steps_per_s"] / x for g, x in zip(runs, raw, strict=True)]
    print(f"step map, holonomic, median of {args.repeat}: sampler {ours:.0f} simulated steps/s, raw mujoco.rollout "
          f"{r:.0f} steps/s ({n} states x {nstep} steps, zero control)  ratio {ours / r:.2f} "
          f"({'met' if ours / r >= 0.8 else 'NOT met'}: goal >= 0.8); per repeat "
          f"{' '.join(f'{q:.2f}' for q in ratios)}; sampling wall time {wall:.2f} s")
    ref = deterministic_json(runs[0])
    assert all(deterministic_json(g) == ref for g in runs[1:]), "same seed, different certificate JSON"
    print(f"determinism: {len(runs)} runs with seed 0 gave identical JSON (without 'seconds')")


def thin_gaits(limit: float = 0.05) -> list[GaitParams]:
    table = REPO / "benchmarks" / "experiments" / "learners" / "data" / "table_exo.jsonl"
    rows = [json.loads(line) for line in table.open()]
    return [GaitParams(**{k: v for k, v in r["params"].items() if k != "rolling_fraction"}) for r in rows
            if r["status"] == "certified" and r["r_star"] is not None and r["r_star"] < limit]


def probe_events(robot: Robot, gait: Gait, sim: SimConfig, n: int, radius: float) -> str:
    """One step from n states uniform in B(radius) of the omega/ball/1 map: fall reasons and touchdown phases."""
    cfg = CertifyConfig(disturbance="state")
    try:
        om = OrbitMaps(robot, gait, cfg, sim)
    except RobustGaitError as e:
        return str(e)
    with om:
        red = om.reduced
        x = sample_ball(n, red.dim, radius, red.x_star, np.random.default_rng(0))
        qpos, qvel = om.pmap.reconstruct(x)
        b = om.engine.step(qpos, qvel, gait.stance, domain=0)
        ok = np.array([r is None for r in b.fall_reason])
        mq, mv = robot.mirror_state(b.qpos[ok], b.qvel[ok])
        image = red.phi(mq, mv)
    reasons: dict[str, int] = {}
    for r in b.fall_reason:
        if r is not None:
            reasons[r] = reasons.get(r, 0) + 1
    tau = b.tau[ok]
    d0 = np.linalg.norm(x[ok] - red.x_star, axis=1)
    d1 = np.linalg.norm(image - red.x_star, axis=1)
    grows = d1 > d0
    held = np.abs(tau - sim.min_switch_tau) < 1.5 * robot.dt / gait.step_duration

    def med(a: np.ndarray) -> str:
        return f"{np.median(a):.3f}" if a.size else "–"

    return (f"r {radius:g}: falls {n - ok.sum()}/{n} {reasons or ''}; τ {tau.min():.3f}–{tau.max():.3f}, "
            f"{held.sum()} at min_switch_tau; τ median: growing {med(tau[grows])} ({grows.sum()}), "
            f"shrinking {med(tau[~grows])}")


def cmd_horizon(args: argparse.Namespace) -> None:
    from robustgait.gaitgen import generate_gait

    sim = SimConfig(n_threads=args.threads)
    exo = load_robot("exo")
    cases: list[tuple[str, GaitParams, tuple[str, ...]]] = [("default flat", GaitParams(), ("flat",)),
                                                           ("default multicontact", GaitParams(), ("multicontact",))]
    cases += [(f"L{p.step_length:.2f} T{p.step_duration:.1f} W{p.step_width:.2f} h{p.step_height:.2f}", p, ("flat",))
              for p in thin_gaits()]
    cases = cases[args.start:]
    ks = [int(k) for k in args.horizons.split(",")]
    print(f"## horizon: sequential certificates (the defaults: ε 0.02, β 0.05), K = {ks}; {len(cases)} gaits; "
          f"{load_average()}")
    print("| gait | " + " | ".join(f"r* K={k} (excursion) | samples, wall K={k}" for k in ks) + " | one step from "
          f"{args.probe} states in B(r), r in rad/s |")
    print("|---|" + "---|---|" * len(ks) + "---|")
    for name, params, domains in cases:
        res = generate_gait(exo, params.resolved(domains[0]), GenerationConfig(domains=domains[0]))  # type: ignore[arg-type]
        if res.gait is None:
            print(f"| {name} | generation failed: {res.status} {res.reason} |")
            continue
        cells = []
        for k in ks:
            gc = certify_gait(exo, res.gait, CertifyConfig(disturbance="state", horizon=k), sim)
            exc = gc.excursion
            ex = "" if not exc else " (" + ", ".join(f"{v:.2f}" for v in exc) + ")"
            n = gc.certificate.n_samples if gc.certificate else 0
            cells.append(f"{gc.value:.4f}{ex} | {n}, {gc.seconds['total']:.0f} s")
        probe = ("<br>".join(probe_events(exo, res.gait, sim, args.probe, r) for r in (0.05, 0.5, 2.0))
                 if domains == ("flat",) else "(flat-foot only)")
        print(f"| {name} | " + " | ".join(cells) + f" | {probe} |", flush=True)


def cmd_states(args: argparse.Namespace) -> None:
    from robustgait.gaitgen import generate_gait

    sim = SimConfig(n_threads=args.threads)
    exo = load_robot("exo")
    res = generate_gait(exo, GaitParams())
    assert res.gait is not None
    choices = [CertifyConfig(disturbance="state", state=s, set=k) for s in ("omega", "centroidal", "velocity")
               for k in ("ball", "ellipsoid")] + [CertifyConfig(disturbance="push")]
    print(f"## states: default exo gait, {args.seeds} seeds each, sequential; {load_average()}")
    print("| certificate | r* mean (range) | E* [J] | samples | physics steps | wall: mean (range) | "
          "ratio to omega/ball |")
    print("|---|---|---|---|---|---|---|")
    base = None
    for cfg in choices:
        gcs = [certify_gait(exo, res.gait, replace(cfg, seed=s), sim) for s in range(args.seeds)]
        r = np.array([g.value for g in gcs])
        wall = np.array([g.seconds["total"] for g in gcs])
        base = wall.mean() if base is None else base
        energy = [g.energy for g in gcs if g.energy is not None]
        name = "push (J*, N s)" if cfg.disturbance == "push" else f"{cfg.state}/{cfg.set}"
        print(f"| {name} | {r.mean():.4g} ({r.min():.4g}–{r.max():.4g}) | "
              f"{np.mean(energy) if energy else float('nan'):.3g} | "
              f"{np.mean([g.certificate.n_samples for g in gcs if g.certificate]):.0f} | "
              f"{np.mean([g.physics_steps for g in gcs]) / 1e6:.2f} M | {wall.mean():.1f} s ({wall.min():.1f}–"
              f"{wall.max():.1f}) | {wall.mean() / base:.2f} |", flush=True)



def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("part", nargs="?", default="all",
                    choices=("all", "seeds", "coverage", "barrier", "speed", "horizon", "states"))
    ap.add_argument("--seeds", type=int, default=10, help="seeds: seeds per gait and method (default 10)")
    ap.add_argument("--methods", default="uniform,sequential")
    ap.add_argument("--epsilon", type=float, default=0.02)
    ap.add_argument("--budget", type=int, default=3000)
    add_gait_arguments(ap)
    ap.add_argument("--runs", type=int, default=1000, help="coverage: runs per synthetic map (default 1000)")
    ap.add_argument("--barrier-seeds", type=int, default=3, help="barrier: sequential seeds (default 3)")
    ap.add_argument("--repeat", type=int, default=5, help="speed: repeats (median; >= 2)")
    ap.add_argument("--samples", type=int, default=200, help="speed: N")
    ap.add_argument("--threads", type=int, default=0, help="0 = one per core")
    ap.add_argument("--horizons", default="1,2,3", help="horizon: K values (default 1,2,3)")
    ap.add_argument("--start", type=int, default=0, help="horizon: skip the first N gaits (a resumed run)")
    ap.add_argument("--probe", type=int, default=400, help="horizon: states walked one step per gait (default 400)")
    ap.add_argument("-v", "--verbose", action="store_true", help="seeds: one line per certificate")
    args = ap.parse_args()
    if args.repeat < 2:
        ap.error("--repeat must be >= 2 (the determinism check compares repeats)")
    print(f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores; mujoco "
          f"{mujoco.__version__}; numpy {np.__version__}; {load_average()}")
    for part, fn in (("seeds", cmd_seeds), ("coverage", cmd_coverage), ("barrier", cmd_barrier), ("speed", cmd_speed),
                     ("horizon", cmd_horizon), ("states", cmd_states)):
        if args.part in (part, "all"):
            fn(args)


if __name__ == "__main__":
    main()
