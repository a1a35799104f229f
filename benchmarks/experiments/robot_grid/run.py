"""A robot's flat-foot action-space grid, point by point: does each gait solve, walk and settle on an orbit?

``run``: for a robot spec (a shipped name, a ``.toml``) or a model (``.xml``/``.urdf``, put through ``robot init``
first, with ``--robot KEY=VALUE`` overriding :class:`robustgait.config.RobotConfig` fields, e.g.
``--robot bandwidth=4`` or ``--robot scale.step_duration=2.0``), ``--points`` points of its ``[action_space]`` grid,
evenly spaced in grid order (all of them when the grid is smaller), each

* solved cold by the gait generator (IPOPT, then its physics check): status, iterations, seconds;
* walked ``--steps`` steps (default 300) with the spec's simulator (PD + feedforward): steps walked, fall reason,
  tracking RMS and max |q − y_d|, torque saturation (fraction of joint-steps at a limit);
* the orbit of its switching states — the product's own classification (:func:`robustgait.certificate.find_orbit`
  of a ``Walked``, the one rule of walk, certify and studies: a band the states enter and hold, its period and
  scatter σ in band coordinates). ``outcome``: ``p1``, ``p2``, ``p4`` (settled, of that period), ``unsettled``,
  ``fell``, ``nosolve``.

One JSON line per point on stdout (and ``--out FILE``), in completion order. Two worker processes (``--workers``),
each niced and pinned to one BLAS thread, each building its own generator.

``report``: the table for benchmarks/README.md from one or more of those files, and the counts.

    python benchmarks/experiments/robot_grid/run.py run ../shared/robots/booster_t1/t1.xml --points 60 --out t1.jsonl
    python benchmarks/experiments/robot_grid/run.py run exo --points 24 --out exo.jsonl
    python benchmarks/experiments/robot_grid/run.py report t1.jsonl [--rows]
"""

from __future__ import annotations

import os

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse
import dataclasses
import json
import tempfile
import time
from collections import Counter
from concurrent.futures import ProcessPoolExecutor, as_completed
from pathlib import Path
from typing import Any

import numpy as np

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
    from robustgait.io.robotfile import write_spec
    from robustgait.robotinit.draft import draft_spec
    from robustgait.robotinit.writer import render

    target = out_dir / (Path(robot).stem + ".toml")
    write_spec(target, render(draft_spec(robot, robot_config(overrides)), target))
    return str(target)


def _init(spec: str) -> None:
    os.nice(10)
    from robustgait import load_robot
    from robustgait.gaitgen import GaitGenerator

    robot = load_robot(spec)
    _STATE.update(robot=robot, gen=GaitGenerator(robot))


def worst_joints(robot: Any, stats: Any) -> dict[str, Any]:
    """The joint with the most saturation and the one with the largest error (names, fraction, rad), from the walk's
    per-joint totals (a :class:`robustgait.sim.controller.TrackingStats` passed to ``walk``): which servo saturates
    is what a failing point needs said."""
    if stats.saturation is None or stats.error_max is None:
        return {}
    sat, err = stats.saturation / max(stats.steps, 1), stats.error_max
    names = robot.spec.joints
    i, k = int(np.argmax(sat)), int(np.argmax(err))
    return {"sat_joint": names[i], "sat_joint_fraction": float(sat[i]), "max_joint": names[k]}


def point(index: int, steps: int) -> dict[str, Any]:
    """One grid point: solve, walk, orbit (module docstring)."""
    from robustgait import walk
    from robustgait.certificate import Walked, find_orbit
    from robustgait.config import CertifyConfig, SimConfig
    from robustgait.learn.space import ActionSpace
    from robustgait.sim.controller import TrackingStats

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
    stats = TrackingStats()  # the walk's per-joint totals, for worst_joints
    w = walk(robot, res.gait, SimConfig(step_cap=steps), tracking=stats)
    out.update(steps=w.steps_taken, fall=w.fall_reason, walk_seconds=round(time.perf_counter() - t1, 2),
               rms=w.tracking.get("rms"), max=w.tracking.get("max"),
               saturation=w.tracking.get("saturation_fraction"), speed=w.mean_speed,
               **worst_joints(robot, stats))
    if w.steps_taken < steps:
        out["outcome"] = "fell"
        return out
    o = find_orbit(Walked(robot, res.gait, w), CertifyConfig())
    out.update(outcome=f"p{o.period}" if o.ok else str(o.status), orbit_steps=o.steps, settled=o.settled,
               period=o.period if o.ok else None, sigma=o.sigma, orbit_reason=o.reason)
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
    space = ActionSpace.from_robot(robot, "flat")
    n = space.size if args.points is None else min(args.points, space.size)
    indices = [int(i) for i in np.unique(np.linspace(0, space.size - 1, n).round().astype(int))]
    head = {"robot": robot.name, "spec": spec, "grid": space.size, "points": len(indices), "steps": args.steps,
            "leg_length": leg, "timestep": robot.dt,
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
        futures = [pool.submit(point, i, args.steps) for i in indices]
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
    walked = sum(v for k, v in c.items() if k not in ("nosolve", "fell"))
    settled = sum(v for k, v in c.items() if k.startswith("p"))
    periods = " / ".join(str(c[f"p{k}"]) for k in (1, 2, 4))
    sat = [r["saturation"] for r in rows if r.get("saturation") is not None]
    return (f"| {head.get('robot')} | {head.get('timestep')} | {n} of {head.get('grid')} | {pct(solved, n)} | "
            f"{pct(walked, n)} | {pct(settled, n)} | {periods} | {c['unsettled']} | {c['fell']} | "
            f"{np.median(sat) * 100 if sat else float('nan'):.2f} % | {foot.get('seconds', float('nan')):.0f} |")


def report(args: argparse.Namespace) -> None:
    print("| robot | dt [s] | points | solve | walked all steps | settled | p1 / p2 / p4 | unsettled | fell | "
          "median sat. | seconds |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    loaded = [load(p) for p in args.files]
    for head, rows, foot in loaded:
        print(summary(head, rows, foot))
    if not args.rows:
        return
    for (head, rows, _), path in zip(loaded, args.files, strict=True):
        print(f"\n{head.get('robot')} ({path}; options {head.get('robot_options')}):\n")
        print("| # | L [m] | T [s] | W [m] | h [m] | outcome | steps | fall | settled at | σ | RMS [mrad] | "
              "sat. (most: joint, its steps) | solve [s] |")
        print("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
        for r in rows:
            sigma = f"{r['sigma']:.2g}" if r.get("sigma") is not None else ""
            rms = f"{r['rms'] * 1e3:.1f}" if r.get("rms") is not None else ""
            sat = f"{r['saturation'] * 100:.2f} %" if r.get("saturation") is not None else ""
            if r.get("sat_joint_fraction"):
                sat += f" ({r['sat_joint']} {r['sat_joint_fraction'] * 100:.1f} %)"
            fall = r.get("fall") or (r.get("status") if r["outcome"] == "nosolve" else "")
            print(f"| {r['index']} | {r['step_length']:g} | {r['step_duration']:g} | {r['step_width']:g} | "
                  f"{r['step_height']:g} | {r['outcome']} | {r.get('steps', '')} | {fall} | {r.get('settled') or ''} "
                  f"| {sigma} | {rms} | {sat} | {r['solve_seconds']} |")


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="command", required=True)
    r = sub.add_parser("run", help="solve, walk and classify the orbit of grid points (JSON lines)")
    r.add_argument("robot", help="a shipped robot, a spec .toml, or a model .xml/.urdf (run through robot init)")
    r.add_argument("--points", type=int, default=None, help="grid points, evenly spaced in grid order (all)")
    r.add_argument("--steps", type=int, default=300)
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
