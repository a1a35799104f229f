"""A robot's flat-foot action-space grid, point by point: does each gait solve, walk and settle (issue 28, item 6)?

``run``: for a robot spec (a shipped name, a ``.toml``) or a model (``.xml``/``.urdf``, put through ``robot init``
first, with ``--robot KEY=VALUE`` overriding :class:`robustgait.config.RobotConfig` fields, e.g.
``--robot bandwidth=4`` or ``--robot scale.step_duration=2.0``), ``--points`` points of its ``[action_space]`` grid,
evenly spaced in grid order (all of them when the grid is smaller), each

* solved cold by the gait generator (IPOPT, then its physics check): status, iterations, seconds;
* walked ``--steps`` steps (default 300) with the spec's simulator (PD + feedforward): steps walked, fall reason,
  tracking RMS and max |q − y_d|, torque saturation (fraction of joint-steps at a limit);
* the step map's orbit, from the walk's switching events written in the canonical stance
  (:func:`robustgait.certificate.poincare.canonical_reduced_events`, base angular velocity in the heading frame): over
  the last ``--window`` (20) iterates, r1 = max ‖x_{k+1} − x_k‖ and r2 = max ‖x_{k+2} − x_k‖. ``p1``: r1 < tol (a fixed
  point of the step map); ``p2``: r2 < tol ≤ r1 (a period-two orbit: left and right steps alternate, a fixed point
  of the stride map); ``grid``: neither, but min(r1, r2) < tol + 2 × the event grid's floor (below); ``wander``:
  none of these; ``fell``; ``nosolve``. The floor: the largest change of the reduced state over the one physics
  step before each of the last ``--window`` touchdowns — touchdowns are found on the physics-step grid, so an
  iterate is defined only to within it, and the walk may cycle through neighbouring grid offsets (Booster T1 at
  1 ms: period-four orbits, r4 = 0, r1 ≈ 0.026 rad/s, for 200 steps, then another such cycle). ``trend``:
  min(r1, r2) over the windows that end at each third of the walk (decreasing: a slowly converging orbit; flat:
  one that does not settle). ``certify_orbit``: the walk's own verdict (:func:`robustgait.sim.walk.walk_orbit`,
  the certificate's ``fp_*`` options: section coordinates, the first window of 20 within ``fp_tol``).

The tolerance is exo's certificate's (5e-3 rad/s on the base angular velocity, ``certify.tol``) scaled with the
rates, by √(g/l) relative to exo's leg length 0.93 m (T1, l = 0.558 m: 6.45e-3 rad/s); ``--tol`` sets it.

One JSON line per point on stdout (and ``--out FILE``), in completion order. Two worker processes (``--workers``),
each niced and pinned to one BLAS thread, each building its own generator.

``report``: the table for benchmarks/README.md from one or more of those files, and the counts.

    python benchmarks/bench_robot_grid.py run ../shared/robots/booster_t1/t1.xml --points 60 --out t1.jsonl
    python benchmarks/bench_robot_grid.py run exo --points 24 --out exo.jsonl
    python benchmarks/bench_robot_grid.py report t1.jsonl [--rows]
"""

from __future__ import annotations

import os

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse
import dataclasses
import json
import math
import sys
import tempfile
import time
from collections import Counter
from concurrent.futures import ProcessPoolExecutor, as_completed
from pathlib import Path
from typing import Any

import numpy as np

EXO_LEG = 0.93  # exo's leg length [m], where the certificate's tolerance was set
EXO_TOL = 5e-3  # exo's certify.tol [rad/s]
MODEL_SUFFIXES = (".xml", ".mjcf", ".urdf")

_STATE: dict[str, Any] = {}


def robot_config(overrides: list[str]) -> Any:
    """A :class:`RobotConfig` with ``KEY=VALUE`` overrides (VALUE read as JSON; ``scale.KEY`` for ScaleRules)."""
    from robustgait.config import RobotConfig

    config = RobotConfig()
    for item in overrides:
        key, _, text = item.partition("=")
        raw = json.loads(text)
        value: Any = tuple(raw) if isinstance(raw, list) else raw
        if key.startswith("scale."):
            config = dataclasses.replace(config, scale=dataclasses.replace(config.scale, **{key[6:]: value}))
        else:
            config = dataclasses.replace(config, **{key: value})
    return config


def spec_path(robot: str, overrides: list[str], out_dir: Path) -> str:
    """The spec to run: ``robot`` itself, or the spec ``robot init`` writes for a model (into ``out_dir``)."""
    if Path(robot).suffix.lower() not in MODEL_SUFFIXES:
        return robot
    from robustgait.inspection.draft import draft_spec
    from robustgait.inspection.writer import render
    from robustgait.io.robotinit import write_spec

    target = out_dir / (Path(robot).stem + ".toml")
    write_spec(target, render(draft_spec(robot, robot_config(overrides)), target))
    return str(target)


def _init(spec: str) -> None:
    os.nice(10)
    from robustgait import load_robot
    from robustgait.gaitgen import GaitGenerator

    robot = load_robot(spec)
    _STATE.update(robot=robot, gen=GaitGenerator(robot))


def orbit(x: np.ndarray, window: int, tol: float) -> tuple[str, float, float]:
    """(``p1``/``p2``/``wander``, r1, r2) of the reduced iterates x (n, 3) over the last ``window`` (module
    docstring)."""
    r1 = float(np.linalg.norm(np.diff(x, axis=0), axis=1)[-window:].max())
    r2 = float(np.linalg.norm(x[2:] - x[:-2], axis=1)[-window:].max())
    return ("p1" if r1 < tol else "p2" if r2 < tol else "wander"), r1, r2


def per_joint_stats() -> Any:
    """A :class:`TrackingStats` whose summary also gives each joint's saturation fraction and largest error (the
    benchmark puts it in the walk's place: which servo saturates is what a failing point needs said)."""
    from robustgait.sim.controller import TrackingStats

    class PerJoint(TrackingStats):
        def summary(self) -> dict[str, Any]:
            out: dict[str, Any] = dict(super().summary())
            if self.saturation is not None and self.error_max is not None:
                out["joint_saturation"] = (self.saturation / max(self.steps, 1)).tolist()
                out["joint_max"] = self.error_max.tolist()
            return out

    return PerJoint


def worst_joints(robot: Any, tracking: dict[str, Any]) -> dict[str, Any]:
    """The joint with the most saturation and the one with the largest error (names, fraction, rad)."""
    if "joint_saturation" not in tracking:
        return {}
    sat, err = np.asarray(tracking["joint_saturation"]), np.asarray(tracking["joint_max"])
    names = robot.spec.joints
    i, k = int(np.argmax(sat)), int(np.argmax(err))
    return {"sat_joint": names[i], "sat_joint_fraction": float(sat[i]), "max_joint": names[k]}


def grid_floor(robot: Any, trajectory: np.ndarray, events: list[Any], window: int) -> float:
    """The largest change of the reduced state over the one physics step before each of the last ``window``
    touchdowns, ‖x(t_e) − x(t_e − h)‖ [rad/s]: touchdowns are found on the physics-step grid, so an iterate is
    only defined to within it, and two iterates whose touchdowns fall one step apart differ by about that much
    (mirroring flips signs of components only: the norm needs no canonical stance)."""
    from robustgait.certificate.reduced import reduce_state

    nq = robot.model.nq
    times = trajectory[:, 0]
    out = 0.0
    for e in events[-window:]:
        k = int(np.argmin(np.abs(times - e.time)))
        rows = trajectory[[k - 1, k]]
        x = reduce_state(rows[:, 1:1 + nq], rows[:, 1 + nq:1 + nq + robot.model.nv], "heading")
        out = max(out, float(np.linalg.norm(x[1] - x[0])))
    return out


def point(index: int, steps: int, window: int, tol: float) -> dict[str, Any]:
    """One grid point: solve, walk, orbit (module docstring)."""
    from robustgait import walk
    from robustgait.certificate.poincare import canonical_reduced_events
    from robustgait.config import SimConfig
    from robustgait.learn.space import ActionSpace

    robot, gen = _STATE["robot"], _STATE["gen"]
    params = ActionSpace.from_robot(robot, "flat").params(index)
    out: dict[str, Any] = {"index": index, **{k: getattr(params, k) for k in
                                              ("step_length", "step_duration", "step_width", "step_height")}}
    t0 = time.perf_counter()
    res = gen.solve(params)
    out.update(status=res.status, iterations=res.iterations, solve_seconds=round(time.perf_counter() - t0, 2))
    if res.gait is None:
        out.update(outcome="nosolve", reason=res.reason[:200])
        return out
    t1 = time.perf_counter()
    # the module (robustgait.sim.walk the attribute is the function): the benchmark's per-joint counts
    setattr(sys.modules[walk.__module__], "TrackingStats", per_joint_stats())  # noqa: B010
    w = walk(robot, res.gait, SimConfig(step_cap=steps), keep_trajectory=True)
    out.update(steps=w.steps_taken, fall=w.fall_reason, walk_seconds=round(time.perf_counter() - t1, 2),
               rms=w.tracking.get("rms"), max=w.tracking.get("max"),
               saturation=w.tracking.get("saturation_fraction"), speed=w.mean_speed,
               **worst_joints(robot, w.tracking))
    if w.steps_taken < steps:
        out["outcome"] = "fell"
        return out
    x = canonical_reduced_events(robot, res.gait, w.events, "heading")
    kind, r1, r2 = orbit(x, window, tol)
    assert w.trajectory is not None
    floor = grid_floor(robot, w.trajectory, w.events, window)
    if kind == "wander" and min(r1, r2) < tol + 2 * floor:
        kind = "grid"
    # min(r1, r2) over the windows ending at each third of the walk: falling = converging slowly, flat = not
    trend = [min(orbit(x[:n], window, tol)[1:]) for n in (len(x) // 3, 2 * len(x) // 3, len(x))]
    if w.orbit is not None:  # the product's verdict (certify.fp_*: section coordinates, first settled window)
        out["certify_orbit"] = ("settled" if w.orbit.converged else "period_two" if w.orbit.period_two
                                else "none")
    out.update(outcome=kind, r1=r1, r2=r2, floor=floor, trend=trend, x_last=[round(float(v), 5) for v in x[-1]])
    return out


def run(args: argparse.Namespace) -> None:
    from robustgait import load_robot
    from robustgait.learn.space import ActionSpace

    tmp = tempfile.TemporaryDirectory(prefix="bench_robot_grid_")
    out_dir = Path(args.spec_dir) if args.spec_dir else Path(tmp.name)
    out_dir.mkdir(parents=True, exist_ok=True)
    spec = spec_path(args.robot, args.robot_option, out_dir)
    robot = load_robot(spec)
    leg = robot.scale.leg_length
    tol = args.tol if args.tol is not None else EXO_TOL * math.sqrt(EXO_LEG / leg)
    space = ActionSpace.from_robot(robot, "flat")
    n = space.size if args.points is None else min(args.points, space.size)
    indices = [int(i) for i in np.unique(np.linspace(0, space.size - 1, n).round().astype(int))]
    head = {"robot": robot.name, "spec": spec, "grid": space.size, "points": len(indices), "steps": args.steps,
            "window": args.window, "tol": tol, "leg_length": leg, "timestep": robot.dt,
            "robot_options": args.robot_option}
    sink = open(args.out, "w", encoding="utf-8") if args.out else None

    def emit(d: dict[str, Any]) -> None:
        print(json.dumps(d), flush=True)
        if sink:
            sink.write(json.dumps(d) + "\n")
            sink.flush()

    emit({"header": head})
    t0 = time.perf_counter()
    with ProcessPoolExecutor(args.workers, initializer=_init, initargs=(spec,)) as pool:
        futures = [pool.submit(point, i, args.steps, args.window, tol) for i in indices]
        for f in as_completed(futures):
            emit(f.result())
    emit({"footer": {"seconds": round(time.perf_counter() - t0, 1)}})
    if sink:
        sink.close()
    tmp.cleanup()


def load(path: str) -> tuple[dict[str, Any], list[dict[str, Any]], dict[str, Any]]:
    rows, head, foot = [], {}, {}
    for line in Path(path).read_text(encoding="utf-8").splitlines():
        if not line.strip():
            continue
        d = json.loads(line)
        if "header" in d:
            head = d["header"]
        elif "footer" in d:
            foot = d["footer"]
        else:
            rows.append(d)
    return head, sorted(rows, key=lambda r: r["index"]), foot


def pct(k: int, n: int) -> str:
    return f"{k}/{n} ({100 * k / n:.0f} %)" if n else "0/0"


def summary(head: dict[str, Any], rows: list[dict[str, Any]], foot: dict[str, Any]) -> str:
    c = Counter(r["outcome"] for r in rows)
    n = len(rows)
    solved = n - c["nosolve"]
    walked = c["p1"] + c["p2"] + c["grid"] + c["wander"]
    settled = c["p1"] + c["p2"]
    sat = [r["saturation"] for r in rows if r.get("saturation") is not None]
    return (f"| {head.get('robot')} | {head.get('timestep')} | {n} of {head.get('grid')} | {pct(solved, n)} | "
            f"{pct(walked, n)} | {pct(settled, n)} | {c['p1']} / {c['p2']} | {pct(settled + c['grid'], n)} | "
            f"{c['wander']} | {c['fell']} | "
            f"{head.get('tol', float('nan')):.3g} | {np.median(sat) * 100 if sat else float('nan'):.2f} % | "
            f"{foot.get('seconds', float('nan')):.0f} |")


def report(args: argparse.Namespace) -> None:
    print("| robot | dt [s] | points | solve | walked all steps | settled | p1 / p2 | settled or grid | wander | "
          "fell | tol [rad/s] | median sat. | seconds |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    loaded = [load(p) for p in args.files]
    for head, rows, foot in loaded:
        print(summary(head, rows, foot))
    if not args.rows:
        return
    for (head, rows, _), path in zip(loaded, args.files, strict=True):
        print(f"\n{head.get('robot')} ({path}; options {head.get('robot_options')}):\n")
        print("| # | L [m] | T [s] | W [m] | h [m] | outcome | steps | fall | r1 / r2 [rad/s] | floor | RMS [mrad] | "
              "sat. (most: joint, its steps) | solve [s] |")
        print("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
        for r in rows:
            orbit_r = f"{r['r1']:.2g} / {r['r2']:.2g}" if "r1" in r else ""
            floor = f"{r['floor']:.2g}" if "floor" in r else ""
            rms = f"{r['rms'] * 1e3:.1f}" if r.get("rms") is not None else ""
            sat = f"{r['saturation'] * 100:.2f} %" if r.get("saturation") is not None else ""
            if r.get("sat_joint_fraction"):
                sat += f" ({r['sat_joint']} {r['sat_joint_fraction'] * 100:.1f} %)"
            fall = r.get("fall") or (r.get("status") if r["outcome"] == "nosolve" else "")
            print(f"| {r['index']} | {r['step_length']:g} | {r['step_duration']:g} | {r['step_width']:g} | "
                  f"{r['step_height']:g} | {r['outcome']} | {r.get('steps', '')} | {fall} | {orbit_r} | {floor} | "
                  f"{rms} | {sat} | {r['solve_seconds']} |")


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="command", required=True)
    r = sub.add_parser("run", help="solve, walk and classify the orbit of grid points (JSON lines)")
    r.add_argument("robot", help="a shipped robot, a spec .toml, or a model .xml/.urdf (run through robot init)")
    r.add_argument("--points", type=int, default=None, help="grid points, evenly spaced in grid order (all)")
    r.add_argument("--steps", type=int, default=300)
    r.add_argument("--window", type=int, default=20, help="iterates the orbit residuals are taken over")
    r.add_argument("--tol", type=float, default=None, help="orbit tolerance [rad/s] (exo's 5e-3 × √(0.93 m / l))")
    r.add_argument("--workers", type=int, default=2)
    r.add_argument("--robot", dest="robot_option", action="append", default=[], metavar="KEY=VALUE",
                   help="a RobotConfig override for robot init (JSON value; scale.KEY for ScaleRules)")
    r.add_argument("--spec-dir", default=None, help="keep the spec robot init writes here")
    r.add_argument("--out", default=None, help="also write the JSON lines to this file")
    p = sub.add_parser("report", help="markdown tables from run outputs")
    p.add_argument("files", nargs="+")
    p.add_argument("--rows", action="store_true", help="one row per point as well")
    args = ap.parse_args(argv)
    if args.command == "run":
        run(args)
    else:
        report(args)


if __name__ == "__main__":
    main()
