"""Certificates r*: precision and cost of the estimators on real gaits, coverage of the confidence statement on
maps with known answers, both barriers, and the sampler's speed against raw ``mujoco.rollout``.

    python benchmarks/bench_certify.py [all|seeds|coverage|barrier|speed|horizon|states|push|push-gaits|push-sweep|
        orbit] [options]

* ``seeds`` (issue 7 acceptance): the default ``exo`` gait (regenerated here with the API from the default
  ``GaitParams``, or ``--exo-gait FILE``; ``--step-length`` etc. change the parameters) and the Atalante FROST
  gait, ``--seeds`` seeds each, methods ``uniform`` (N = 200) and ``sequential`` (defaults): mean, sd, CV and
  range of r*, the statement's bound, samples, physics steps, wall time. After every certificate raw
  ``mujoco.rollout`` (same model and threads, 100 states near x*, zero control) measures the machine's speed
  under the same load: the sampler/raw ratio, measured in the run (wall times are this machine's, as measured).
* ``coverage``: ``--runs`` sequential certificates of each synthetic map (:mod:`robustgait.certificate.synthetic`):
  fraction of runs whose true violating fraction in B(r*) exceeds ε (must be ≤ β) — and the same for a naive
  rule that ignores the data-dependent choice of r*, to show the check can fail.
* ``barrier``: r* with H = r² − ‖x − x*‖² (``ball``) and the paper's H = r − ‖x − x*‖² on the Atalante gait.
* ``speed``: the Atalante gait's four (map × reconstruction) uniform certificates (``map``: the shortest map the orbit
  is searched on; each row gives the orbit's period, settling step and σ, and the orbit search's seconds), then the
  sampler against raw ``mujoco.rollout`` on the same batch (ratio), and determinism of the JSON over ``--repeat``
  runs.
* ``horizon`` (issue 18 item 1): sequential certificates of horizon K = 1, 2, 3 (``--horizons``) on the thin
  gaits of ``benchmarks/data/learner_table_exo.jsonl`` (table r* < 0.05) and the default flat-foot and multi-contact
  exo gaits: r*, the excursion, samples, physics steps, wall time. Then the event-logic check: ``--probe`` states
  uniform in B(r_max) walked one step: fall reasons, touchdown phase τ of the others (a touchdown held back by
  ``min_switch_tau`` shows as τ at that bound; a step cut at ``max_step_tau`` as ``no_touchdown``), and the τ of
  the samples whose image is farther from x̄* than they started against the τ of the others.
* ``states`` (issue 18 item 7): on the default exo gait, ``--seeds`` sequential certificates of each state × set
  and the push certificate, one after the other in the same run: r*, E*, wall time and its ratio to ``omega``'s.
* ``push`` (issue 18 item 7, J*'s cost): on the default exo gait (or ``--exo-gait``), ``--seeds`` omega/ball
  certificates, then the push certificate J* for each ``--push-variants`` tuple (first round / exploration /
  exploration after a failed verification / ``push.horizon``, the steps after the pushed one; the first tuple is the
  shipped default certificate), same run: J*, samples, physics steps of the sampling and of the orbit search, wall,
  the orbit search's seconds, and the wall's ratio to omega/ball's.
* ``push-gaits`` (issue 18 item 7 over many gaits; not part of ``all``): per gait of ``--gaits`` (a glob, e.g. the
  gait files of studies; ``--limit`` of them evenly spaced), omega/ball, then J* for each ``--gait-variants``
  (``name:verify_chunk/horizon[/explore_after_failure]``; default: whole verification batches,
  ``push.verify_chunk = 0``, and as shipped, chunked; both at the shipped horizon of 20), one after the other in
  one worker: their wall-time and physics-step ratios and verification attempts; then each variant's check against
  the gaits' validation pushes in ``benchmarks/data/bench_predict_exo.jsonl`` (pushes ≤ J* that fell).
* ``push-sweep`` (not part of ``all``): where one exo gait's pushes fail (the default gait or ``--exo-gait``): its
  orbit (:func:`robustgait.certificate.search.find_orbit`), its J* (the default push certificate's estimator on the
  push map from the orbit's x* and band), the failures the estimator met below ``--near`` × J* (direction, phase,
  the step it fell in or that it was not back in the band, reason), and grids of outcomes over 24 directions × 13
  phases at ``--sweep`` × J* (``PushMap.walk`` at explicit phases: recovered, fell in step n, or not back in the band
  within ``push.horizon``).
* ``orbit`` (not part of ``all``): ρ, a diagnostic and never a gate — :mod:`bench_orbit` (``--only``, ``--extra``,
  ``--fd-steps``): per gait (the stored default exo gait tests/data/exo_gait.json or ``--exo-gait``, the stored
  multi-contact exo gait, the Atalante FROST gait and ``--extra ROBOT=FILE``) the orbit search's verdict with
  ``orbit.linearization`` and its diagnostic.

The fixed-point search these modes used (``ReturnMap.find_fixed_point``) was replaced by the orbit search: every mode
now takes the orbit from :func:`robustgait.certificate.search.find_orbit` and its maps from
:class:`robustgait.certificate.returnmap.FullStateMap` (the orbit's period) and
:class:`robustgait.certificate.reducedmap.ReducedMap` (the reduced map). Removed with it: ``orbit``'s comparison of
fixed-point rules (the rule before the orbit check against the window and window + Newton refinement), their J*
(``--seed``), ``--newton``, ``--orbit-parts`` and ``--survey`` (its gaits go to ``--extra``); ``push``'s and
``push-gaits``' fourth field is now ``push.horizon`` (steps after the pushed one, default 20) instead of the fixed
``push.steps``.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import platform
import time
from dataclasses import replace
from pathlib import Path

import mujoco
import numpy as np
from mujoco import rollout

from bench_orbit import add_orbit_arguments, cmd_orbit  # ρ's measurement (its own module: this one is long enough)
from robustgait import load_gait, load_robot
from robustgait.certificate.barrier import distances, sample_ball, solve_radius
from robustgait.certificate.certify import GaitCertificate, certify_gait
from robustgait.certificate.estimators import certify_map_sequential
from robustgait.certificate.orbit import Orbit
from robustgait.certificate.reduced import ReducedState
from robustgait.certificate.reducedmap import ReducedMap
from robustgait.certificate.returnmap import FullStateMap
from robustgait.certificate.search import find_orbit
from robustgait.certificate.synthetic import BandMap, ConeMap
from robustgait.config import CertifyConfig, GaitParams, GenerationConfig, SequentialConfig, SimConfig
from robustgait.errors import RobustGaitError
from robustgait.gait import Gait
from robustgait.robots import Robot
from robustgait.sim.engine import StepEngine
from robustgait.sim.factory import make_engine

REPO = Path(__file__).resolve().parents[1]
ATALANTE = REPO.parent / "shared" / "atalante"
COMBOS = (("step", "holonomic"), ("step", "angular-only"), ("stride", "holonomic"), ("stride", "angular-only"))


def load() -> str:
    return "load average " + " ".join(f"{v:.2f}" for v in os.getloadavg())


def gaits(args: argparse.Namespace) -> dict[str, tuple[Robot, Gait]]:
    """The default exo gait (regenerated, or --exo-gait) and the Atalante FROST gait (if ../shared is there)."""
    out = {}
    exo = load_robot("exo")
    if args.exo_gait:
        out["exo"] = (exo, load_gait(args.exo_gait, exo))
    else:
        from robustgait.gaitgen import generate_gait

        p = GaitParams(args.step_length, args.step_duration, args.step_width, args.step_height)
        res = generate_gait(exo, p)
        if res.gait is None:
            raise SystemExit(f"exo gait generation failed: {res.status} {res.reason}")
        print(f"exo gait regenerated: {p} ({res.status}, {res.iterations} iterations)")
        out["exo"] = (exo, res.gait)
    if (ATALANTE / "loadedExo.xml").is_file():
        robot = load_robot(REPO / "examples" / "atalante.toml")
        out["atalante"] = (robot, load_gait(ATALANTE / "jt_bez_2023-09-10.yaml", robot))
    else:
        print("../shared/atalante is missing: the Atalante gait is skipped")
    return out


class OrbitMaps:
    """A gait's orbit (:func:`robustgait.certificate.search.find_orbit`) and a state certificate's maps on it, on one
    engine: ``fmap`` the full-state map of the orbit's period, ``reduced`` the reduced state of ``config`` set up at
    x*, ``pmap`` the reduced map of ``config.horizon`` maps. A context manager (closes the engine); raises
    :class:`RobustGaitError` when the gait has no orbit (``orbit`` is then still set)."""

    def __init__(self, robot: Robot, gait: Gait, config: CertifyConfig, sim: SimConfig):
        self.engine: StepEngine = make_engine(robot, gait, sim)
        try:
            self.orbit: Orbit = find_orbit(robot, gait, config, sim, engine=self.engine)
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
    r = np.array([g.r_star for g in gcs])
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
    print(f"## seeds: {args.seeds} seeds per gait and method; {load()}")
    print("| gait, method | mean r* | sd | CV | range | bound: median (max) | samples: mean (range) | physics steps | "
          "wall: mean (max) | sampler/raw | raw rollout [steps/s], median |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for gname, (robot, gait) in gaits(args).items():
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
                    print(f"  {gname} {method} seed {seed}: r* {gc.r_star:.4f} bound {c.violation_bound:.4f} "
                          f"N {c.n_samples} {gc.seconds['total']:.1f} s (raw {speeds[-1]:.0f} steps/s)  {tr}",
                          flush=True)
            print(summary(f"{gname}, {method}", gcs, speeds), flush=True)
        raw.close()
        print(f"  ({gname} done; {load()})")


def _naive(P: ConeMap | BandMap, seed: int, eps: float, beta: float, budget: int) -> float | None:
    """A rule with no correction for the data-dependent r*: rounds of 50 uniform in B(r̂), stop as soon as
    ⌈ln β / ln(1 − ε)⌉ samples lie in B(r̂) (they all satisfy, r̂ being feasible). Returns r̂, None if never."""
    need = math.ceil(math.log(beta) / math.log1p(-eps))
    rng = np.random.default_rng(seed)
    x0 = sample_ball(200, 3, 2.0, P.x_star, rng)
    x1 = P(x0)
    while True:
        d, p = distances(x0, x1, P.x_star)
        r = solve_radius(d, p, alpha=0.05, r_max=2.0).r_star
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
    print(f"## coverage: {args.runs} runs per map, epsilon = {eps:g}, beta = {beta:g}, budget {args.budget}; {load()}")
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
                fails += P.violating_fraction(c.r_star) > eps
            rs.append(c.r_star)
            ns.append(c.n_samples)
        naive = [_naive(P, seed, eps, beta, args.budget) for seed in range(args.runs)]
        naive_fails = sum(r is not None and P.violating_fraction(r) > eps for r in naive)
        lo, hi = _wilson(fails, args.runs)
        print(f"| {name} | {certified} | {fails / args.runs:.4f} (95 % CI {lo:.4f}–{hi:.4f}) | "
              f"{naive_fails / args.runs:.3f} | {np.median(rs):.4g} ({min(rs):.3g}–{max(rs):.3g}) | "
              f"{np.median(ns):.0f} |  ({time.perf_counter() - t0:.0f} s)", flush=True)


def _wilson(k: int, n: int, z: float = 1.96) -> tuple[float, float]:
    p = k / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    return max(0.0, centre - half), min(1.0, centre + half)


def cmd_barrier(args: argparse.Namespace) -> None:
    sim = SimConfig(n_threads=args.threads)
    print(f"## barrier: ball H = r² − ‖x − x*‖² vs paper H = r − ‖x − x*‖² (step map, holonomic); {load()}")
    print("| gait | method | seeds | r* ball: mean (range) | r* paper: mean (range) |")
    print("|---|---|---|---|---|")
    for gname, (robot, gait) in gaits(args).items():
        for method, seeds in (("uniform", [0]), ("sequential", list(range(args.barrier_seeds)))):
            res = {}
            for barrier in ("ball", "paper"):
                cfg = CertifyConfig(method=method, barrier=barrier, disturbance="state")  # type: ignore[arg-type]
                res[barrier] = np.array([certify_gait(robot, gait, replace(cfg, seed=s), sim).r_star for s in seeds])
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
    return (f"{gc.config.map:6s} {gc.config.reconstruction:12s} r* {c.r_star:.4f}{'' if c.attained else ' (sup)'}  "
            f"x* [{x}] after step {fp.step:3d}  orbit period {o.period}, settled at step {o.settled}, σ "
            f"{o.sigma:.2g}  map residual {gc.map_residual:.2e}  fell {int(c.fell.sum()):3d}  inside "
            f"{c.n_inside:3d}  orbit {s['orbit']:.2f} s  sampling {s['sampling']:.2f} s  "
            f"({s['sim_steps_per_s']:.0f} steps/s)")


def cmd_speed(args: argparse.Namespace) -> None:
    if not (ATALANTE / "loadedExo.xml").is_file():
        print("speed: ../shared/atalante is missing, skipped")
        return
    robot = load_robot(REPO / "examples" / "atalante.toml")
    gait = load_gait(ATALANTE / "jt_bez_2023-09-10.yaml", robot)
    sim = SimConfig(n_threads=args.threads)
    threads = sim.threads
    n = args.samples
    print(f"## speed: N = {n}, r_max = 2, alpha = 0.05, seed 0, heading frame, uniform; threads {threads}; {load()}")

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
    rows = [json.loads(line) for line in (REPO / "benchmarks" / "data" / "learner_table_exo.jsonl").open()]
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
    print(f"## horizon: sequential certificates (the defaults: ε 0.02, β 0.05), K = {ks}; {len(cases)} gaits; {load()}")
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
            cells.append(f"{gc.r_star:.4f}{ex} | {n}, {gc.seconds['total']:.0f} s")
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
    print(f"## states: default exo gait, {args.seeds} seeds each, sequential; {load()}")
    print("| certificate | r* mean (range) | E* [J] | samples | physics steps | wall: mean (range) | "
          "ratio to omega/ball |")
    print("|---|---|---|---|---|---|---|")
    base = None
    for cfg in choices:
        gcs = [certify_gait(exo, res.gait, replace(cfg, seed=s), sim) for s in range(args.seeds)]
        r = np.array([g.r_star for g in gcs])
        wall = np.array([g.seconds["total"] for g in gcs])
        base = wall.mean() if base is None else base
        energy = [g.energy for g in gcs if g.energy is not None]
        name = "push (J*, N s)" if cfg.disturbance == "push" else f"{cfg.state}/{cfg.set}"
        print(f"| {name} | {r.mean():.4g} ({r.min():.4g}–{r.max():.4g}) | "
              f"{np.mean(energy) if energy else float('nan'):.3g} | "
              f"{np.mean([g.certificate.n_samples for g in gcs if g.certificate]):.0f} | "
              f"{np.mean([g.physics_steps for g in gcs]) / 1e6:.2f} M | {wall.mean():.1f} s ({wall.min():.1f}–"
              f"{wall.max():.1f}) | {wall.mean() / base:.2f} |", flush=True)


def cmd_push(args: argparse.Namespace) -> None:
    """J*'s cost against the omega/ball certificate on the same gait (the default exo gait or ``--exo-gait``), same
    run, per push round sizes and steps; J*'s spread over ``--seeds``."""
    from robustgait.config.certify import PushConfig

    sim = SimConfig(n_threads=args.threads)
    exo, gait = gaits(args)["exo"]
    variants = [tuple(int(v) for v in t.split("/")) for t in args.push_variants.split(",")]
    print(f"## push: {args.exo_gait or 'default exo gait'}, {args.seeds} seeds each, sequential; J* per (first round / "
          f"exploration / exploration after a failure / horizon: steps after the pushed one) against omega/ball; "
          f"{load()}")
    print("| certificate | J* or r* mean (range) | samples | physics steps: sampling (orbit search) | wall: mean "
          "(range) | orbit search: mean | ratio to omega/ball |")
    print("|---|---|---|---|---|---|---|")
    cfgs = [("omega/ball", CertifyConfig(disturbance="state"))] + [
        (f"push {f}/{e}/{a}/{k}", CertifyConfig(disturbance="push", push=PushConfig(
            first_round=f, explore=e, explore_after_failure=a, horizon=k))) for f, e, a, k in variants]
    base = None
    for name, cfg in cfgs:
        gcs = [certify_gait(exo, gait, replace(cfg, seed=s), sim) for s in range(args.seeds)]
        failed = [g for g in gcs if not g.ok]
        if failed:
            print(f"| {name} | {failed[0].status}: {failed[0].reason} | | | | | |", flush=True)
            continue
        r = np.array([g.r_star for g in gcs])
        wall = np.array([g.seconds["total"] for g in gcs])
        base = wall.mean() if base is None else base
        print(f"| {name} | {r.mean():.4g} ({r.min():.4g}–{r.max():.4g}) | "
              f"{np.mean([g.certificate.n_samples for g in gcs if g.certificate]):.0f} | "
              f"{np.mean([g.physics_steps for g in gcs]) / 1e6:.2f} M "
              f"({np.mean([g.orbit_physics_steps for g in gcs]) / 1e6:.2f} M) | {wall.mean():.1f} s ({wall.min():.1f}–"
              f"{wall.max():.1f}) | {np.mean([g.seconds['orbit'] for g in gcs]):.1f} s | {wall.mean() / base:.2f} |",
              flush=True)


def _variants(spec: str) -> list[tuple[str, int, int, int | None]]:
    """``name:chunk/horizon[/after],…`` → [(name, push.verify_chunk, push.horizon, push.explore_after_failure or None
    for the default)]."""
    out = []
    for item in spec.split(","):
        name, _, rest = item.partition(":")
        chunk, horizon, *after = rest.split("/")
        out.append((name, int(chunk), int(horizon), int(after[0]) if after else None))
    return out


def _push_gait(job: tuple[str, str]) -> dict:
    """omega/ball, then J* for each variant (``--gait-variants``): one gait, one thread, one after the other (a
    worker of ``push-gaits``)."""
    from robustgait.config.certify import PushConfig

    path, spec = job
    exo = load_robot("exo")
    gait = load_gait(path, exo)
    sim = SimConfig(n_threads=1)
    out: dict = {"gait": Path(path).parent.name}
    runs = [("omega", CertifyConfig(disturbance="state"))] + [
        (name, CertifyConfig(disturbance="push", push=PushConfig(
            verify_chunk=chunk, horizon=horizon,
            explore_after_failure=PushConfig.explore_after_failure if after is None else after)))
        for name, chunk, horizon, after in _variants(spec)]
    for name, cfg in runs:
        t0 = time.perf_counter()
        gc = certify_gait(exo, gait, cfg, sim)
        if not gc.ok:
            return {**out, "error": f"{name}: {gc.status}"}
        out[name] = {"r_star": gc.r_star, "seconds": time.perf_counter() - t0, "physics": gc.physics_steps,
                     "samples": gc.certificate.n_samples if gc.certificate else 0,
                     "attempts": sum(r.kind == "verify" for r in gc.certificate.rounds) if gc.certificate else 0,
                     "bound": gc.certificate.violation_bound if gc.certificate else 1.0}
    return out


def _validation_check(rows: list[dict], names: list[str]) -> None:
    """For each variant, the validation pushes (``benchmarks/data/bench_predict_exo.jsonl``: 200 per gait, 20 steps
    after) with |J| ≤ that gait's J* that fell, with a Wilson interval — J*'s own check against ε."""
    table = REPO / "benchmarks" / "data" / "bench_predict_exo.jsonl"
    pushes = {}
    for line in table.read_text().splitlines():
        rec = json.loads(line)
        push = rec.get("kinds", {}).get("push")
        if push:
            pushes[rec["label"]] = (np.asarray(push["size"]), np.asarray(push["ok"], dtype=bool))
    for k in names:
        n = fell = 0
        for r in rows:
            if r["gait"] in pushes:
                size, walked = pushes[r["gait"]]
                inside = size <= r[k]["r_star"]
                n += int(inside.sum())
                fell += int((inside & ~walked).sum())
        if n:
            lo, hi = _wilson(fell, n)
            print(f"check {k}: {fell} of {n} validation pushes with |J| ≤ J* fell, {100 * fell / n:.1f} % "
                  f"[{100 * lo:.1f}, {100 * hi:.1f}] (95 % Wilson; ε = 2 %)")


def cmd_push_gaits(args: argparse.Namespace) -> None:
    """J*'s cost over many gaits: per gait (``--gaits`` glob, one per directory name, ``--limit`` evenly spaced),
    J* for each ``--gait-variants`` (verification chunk / horizon) against omega/ball on the same gait,
    same worker; then each variant's check on the gaits' validation pushes."""
    import glob
    from concurrent.futures import ProcessPoolExecutor

    from robustgait.study.executors import blas_threads

    paths = {Path(p).parent.name: p for p in sorted(glob.glob(args.gaits))}
    names = sorted(paths)
    if args.limit and args.limit < len(names):
        names = [names[i] for i in np.unique(np.round(np.linspace(0, len(names) - 1, args.limit)).astype(int))]
    variants = [v[0] for v in _variants(args.gait_variants)]
    print(f"## push-gaits: {len(names)} gaits of {args.gaits}, {args.workers} workers, one rollout thread each; "
          f"variants {args.gait_variants} (name:verify_chunk/horizon[/explore after a failure]); {load()}")
    print("| gait | omega r* (s) | " + " | ".join(f"J* {k} (samples, attempts, s, ratio; physics ratio)"
                                                for k in variants) + " |")
    print("|---|---|" + "---|" * len(variants))
    rows = []
    with blas_threads(1), ProcessPoolExecutor(args.workers) as pool:
        for r in pool.map(_push_gait, [(paths[n], args.gait_variants) for n in names]):
            if "error" in r:
                print(f"| {r['gait']} | {r['error']} |" + " |" * len(variants), flush=True)
                continue
            rows.append(r)
            o = r["omega"]
            print(f"| {r['gait']} | {o['r_star']:.3f} ({o['seconds']:.1f}) | " + " | ".join(
                f"{r[k]['r_star']:.2f} ({r[k]['samples']}, {r[k]['attempts']}, {r[k]['seconds']:.1f}, "
                f"{r[k]['seconds'] / o['seconds']:.2f}×; {r[k]['physics'] / o['physics']:.2f}×)"
                for k in variants) + " |", flush=True)
    if not rows:
        return
    for k in variants:
        ratio = np.array([r[k]["seconds"] / r["omega"]["seconds"] for r in rows])
        phys = np.array([r[k]["physics"] / r["omega"]["physics"] for r in rows])
        attempts = np.array([r[k]["attempts"] for r in rows])
        print(f"J* {k}: time over omega/ball median {np.median(ratio):.2f}× ({ratio.min():.2f}–{ratio.max():.2f}), "
              f"≤ 2× on {int((ratio <= 2).sum())} of {ratio.size}; physics steps median {np.median(phys):.2f}× "
              f"(≤ 2× on {int((phys <= 2).sum())}); samples median {np.median([r[k]['samples'] for r in rows]):.0f}; "
              f"verification attempts 1/2/3+: {int((attempts == 1).sum())}/{int((attempts == 2).sum())}/"
              f"{int((attempts >= 3).sum())}")
    for k in variants[1:]:
        dj = np.array([r[k]["r_star"] - r[variants[0]]["r_star"] for r in rows])
        print(f"J* {k} − {variants[0]}: median {np.median(dj):+.2f} N s ({dj.min():+.2f} to {dj.max():+.2f})")
    _validation_check(rows, variants)
    print(load())


def cmd_push_sweep(args: argparse.Namespace) -> None:
    """Where a gait's pushes fail: its J* (default certificate), the failures the estimator met below ``--near`` × J*
    (impulse, direction, phase, the step it fell in or that it did not come back to the band, and the reason), then
    pushes at fixed impulses (``--sweep`` × J*) over 24 directions × 13 phases of the validation's range: a grid of
    outcomes (:meth:`robustgait.certificate.push.PushMap.walk` at explicit phases)."""
    from robustgait.certificate.push import PushMap, push_phase
    from robustgait.config import ValidateConfig

    robot, gait = gaits(args)["exo"]
    cfg = CertifyConfig()
    vcfg = ValidateConfig()
    engine = make_engine(robot, gait, SimConfig(n_threads=args.threads))
    try:
        t0 = time.perf_counter()
        orbit = find_orbit(robot, gait, cfg, validate=vcfg, engine=engine)
        if not orbit.ok or orbit.qpos is None or orbit.qvel is None:
            raise SystemExit(f"push-sweep: no orbit ({orbit.status}: {orbit.reason})")
        print(f"## push-sweep: orbit in {time.perf_counter() - t0:.1f} s: {orbit.describe()}")
        pm = PushMap(engine, orbit.qpos, orbit.qvel, orbit.band, vcfg, cfg.push)
        t0 = time.perf_counter()
        cert = certify_map_sequential(pm, np.zeros(2), cfg)
        j_star = cert.r_star
        d = np.linalg.norm(cert.samples, axis=1)
        near = np.flatnonzero(cert.fell & (d < args.near * j_star))
        attempts = sum(r.kind == "verify" for r in cert.rounds)
        print(f"{args.exo_gait or 'the default exo gait'}: J* {j_star:.2f} N s ({cert.n_samples} pushes, {attempts} "
              f"verification attempts, {time.perf_counter() - t0:.1f} s; horizon {cfg.push.horizon} steps after the "
              f"pushed one, back in the band for {cfg.push.recovery_steps} steps); failures below {args.near} J*: "
              f"{near.size}")
        if near.size:
            j = cert.samples[near]
            phase = push_phase(j, *vcfg.push_phase)
            _, reasons, steps, _ = pm.walk(j, phase)
            for k in np.argsort(d[near]):
                what = f"fell in step {steps[k]}" if steps[k] > 0 else "not back in the band"
                print(f"  |J| {d[near][k]:6.2f} N s, direction {math.degrees(math.atan2(j[k, 1], j[k, 0])):5.0f}°, "
                      f"phase {phase[k]:.2f}: {what} ({reasons[k]})")
        directions = np.arange(-180, 180, 15)
        phases = np.linspace(vcfg.push_phase[0], vcfg.push_phase[1], 13)
        dd, pp = np.meshgrid(np.radians(directions), phases, indexing="ij")
        for f in (float(x) for x in args.sweep.split(",")):
            mag = f * j_star
            j = mag * np.stack([np.cos(dd.ravel()), np.sin(dd.ravel())], axis=1)
            alive, _, steps, recovered = pm.walk(j, pp.ravel())
            fell = steps > 0
            cells = np.where(alive, ".", np.where(fell, np.minimum(steps, 9).astype(str), "o")).reshape(dd.shape)
            print(f"|J| = {f:g} J* = {mag:.2f} N s: {int((~alive).sum())} of {alive.size} pushes fail "
                  f"({100 * (~alive).mean():.1f} %: {int(fell.sum())} fall, {int((~alive & ~fell).sum())} not back "
                  f"in the band); recovered by step {np.median(recovered[alive]) if alive.any() else float('nan'):.0f} "
                  f"(median); rows: direction in the heading frame (0° forward, 90° left), columns: phase "
                  f"{phases[0]:.2f} … {phases[-1]:.2f}; '.' recovered, digit: the step it fell in, 'o': walked but "
                  f"not back in the band within the horizon")
            for a, deg in enumerate(directions):
                print(f"  {deg:5d}°  " + "".join(cells[a]))
    finally:
        engine.close()
    print(load())


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("part", nargs="?", default="all",
                    choices=("all", "seeds", "coverage", "barrier", "speed", "horizon", "states", "push",
                             "push-gaits", "push-sweep", "orbit"))
    ap.add_argument("--seeds", type=int, default=10, help="seeds: seeds per gait and method (default 10)")
    ap.add_argument("--methods", default="uniform,sequential")
    ap.add_argument("--epsilon", type=float, default=0.02)
    ap.add_argument("--budget", type=int, default=3000)
    ap.add_argument("--exo-gait", help="use this exo gait file instead of regenerating the default one")
    defaults = GaitParams().resolved("flat")
    for name in ("step_length", "step_duration", "step_width", "step_height"):
        ap.add_argument(f"--{name.replace('_', '-')}", type=float, default=getattr(defaults, name),
                        help=f"exo gait parameter (default {getattr(defaults, name)})")
    ap.add_argument("--runs", type=int, default=1000, help="coverage: runs per synthetic map (default 1000)")
    ap.add_argument("--barrier-seeds", type=int, default=3, help="barrier: sequential seeds (default 3)")
    ap.add_argument("--repeat", type=int, default=5, help="speed: repeats (median; >= 2)")
    ap.add_argument("--samples", type=int, default=200, help="speed: N")
    ap.add_argument("--threads", type=int, default=0, help="0 = one per core")
    ap.add_argument("--horizons", default="1,2,3", help="horizon: K values (default 1,2,3)")
    ap.add_argument("--start", type=int, default=0, help="horizon: skip the first N gaits (a resumed run)")
    ap.add_argument("--probe", type=int, default=400, help="horizon: states walked one step per gait (default 400)")
    ap.add_argument("--push-variants", default="50/100/50/20,100/200/100/20,50/100/50/10",
                    help="push: first-round/explore/explore-after-failure/horizon tuples (the shipped one first; "
                         "horizon: push.horizon, steps after the pushed one)")
    ap.add_argument("--gaits", default="", help="push-gaits: a glob of gait files (one per directory name)")
    ap.add_argument("--limit", type=int, default=0, help="push-gaits: at most N gaits, evenly spaced by name")
    ap.add_argument("--workers", type=int, default=2, help="push-gaits: worker processes")
    ap.add_argument("--gait-variants", default="whole:0/20,chunked:25/20",
                    help="push-gaits: J* variants name:verify_chunk/horizon[/explore_after_failure] (default "
                         "whole:0/20,chunked:25/20)")
    ap.add_argument("--near", type=float, default=1.2, help="push-sweep: list the falls below this × J* (1.2)")
    ap.add_argument("--sweep", default="0.8,1.0,1.1", help="push-sweep: impulses of the grids, × J* (0.8,1.0,1.1)")
    add_orbit_arguments(ap)  # orbit: --only, --extra, --fd-steps (bench_orbit)
    ap.add_argument("-v", "--verbose", action="store_true", help="seeds: one line per certificate")
    args = ap.parse_args()
    if args.repeat < 2:
        ap.error("--repeat must be >= 2 (the determinism check compares repeats)")
    print(f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores; mujoco "
          f"{mujoco.__version__}; numpy {np.__version__}; {load()}")
    for part, fn in (("seeds", cmd_seeds), ("coverage", cmd_coverage), ("barrier", cmd_barrier), ("speed", cmd_speed),
                     ("horizon", cmd_horizon), ("states", cmd_states), ("push", cmd_push),
                     ("push-gaits", cmd_push_gaits), ("push-sweep", cmd_push_sweep), ("orbit", cmd_orbit)):
        if args.part == part or (args.part == "all" and part not in ("push-gaits", "push-sweep", "orbit")):
            fn(args)


if __name__ == "__main__":
    main()
