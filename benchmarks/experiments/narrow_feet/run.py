"""Step-to-step balance on a narrow-footed humanoid (``docs/simulation.md``, "Step-to-step balance";
``docs/your-robot.md``, "When your robot's feet are narrow").

``build DIR [--width W]``: Booster T1 from ../shared with each sole replaced by four 5 mm contact spheres on a
0.19 × W m footprint (default 0.04; ``tests/models.py``), and the spec ``robot init`` writes for it (``DIR/t1.toml``).

``default DIR``: as a user would, with the CLI: the default gait generated with the shipped defaults (the H-LIP
regulator on by the narrow-sole rule), walked ``--steps`` steps undisturbed, certified with the defaults; and the same
gait generated with ``sim.regulator.mode=off``: does the walk check refuse it, with which reason? Prints one JSON.

How the regulator's defaults were chosen (each ``--variant`` a ``key=value;…`` of ``sim.regulator``, mode on unless
given, e.g. ``mode=off`` or ``gain_scale=0.1;carry_tau=0.4``):

* ``sweep DIR``: the default gait and ``--grid`` points of the robot's grid, generated, then walked ``--steps`` steps
  undisturbed under each variant: steps walked, one JSON line per gait;
* ``pushes DIR``: the default gait (``DIR/gait.json``) under each variant, from its 6th switching state pushed with
  1–5 N s in 12 directions (an instant velocity change J/m at the step start), each walked the pushed step and 20
  more: falls per magnitude, one JSON line per variant.

``exo``: the shipped exo's stored gait certified with the regulator off and forced on, ``--seeds`` perturbation
seeds each: J* on against J* off and its spread over seeds. Prints one JSON.

The grid (≥ 10 gaits: walks 300 steps? certified? falls within 20 steps among pushes below J*):
``benchmarks/experiments/recovery_horizon/run.py run --robot DIR/t1.toml --grid 12 --out
benchmarks/experiments/narrow_feet/data/t1_narrow.jsonl``, then
``benchmarks/experiments/recovery_horizon/run.py report`` on it.

    python benchmarks/experiments/narrow_feet/run.py build /tmp/t1_narrow
    python benchmarks/experiments/narrow_feet/run.py default /tmp/t1_narrow > \\
        benchmarks/experiments/narrow_feet/data/default.json
    python benchmarks/experiments/narrow_feet/run.py exo > benchmarks/experiments/narrow_feet/data/exo.json
"""

from __future__ import annotations

import argparse
import json
import sys
from datetime import date
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))  # benchmarks/common.py
from common import EXO_GAIT, REPO, SHARED, cli, git_commit, grid_params

T1 = SHARED / "robots" / "booster_t1" / "t1.xml"


def _stamp() -> dict[str, str]:
    commit = git_commit()
    return {"commit": commit, "date": str(date.today())}


def build(out: Path, width: float) -> None:
    sys.path.insert(0, str(REPO))
    from tests.models import narrow_t1_xml

    if not T1.is_file():
        raise SystemExit(f"{T1} is absent: the benchmark needs ../shared/robots/booster_t1")
    xml = narrow_t1_xml(T1, out, width)
    code, text, _ = cli("robot", "init", str(xml), "-o", str(out / "t1.toml"))
    print(text, end="")
    if code:
        raise SystemExit(code)


def default(d: Path, steps: int) -> dict[str, Any]:
    robot = str(d / "t1.toml")
    row: dict[str, Any] = {**_stamp(), "robot": robot}
    code, text, sec = cli("gait", "generate", "--robot", robot, "-o", str(d / "gait.json"))
    row["generate"] = {"exit": code, "seconds": round(sec, 1), "walk_check": _line(text, "walk check")}
    code, text, sec = cli("walk", "--robot", robot, str(d / "gait.json"), "--steps", str(steps), "--json")
    w = json.loads(text.strip().splitlines()[-1]) if code == 0 else {}
    row["walk"] = {"exit": code, "seconds": round(sec, 1), "steps_taken": w.get("steps_taken"),
                   "fell": w.get("fell"), "controller": w.get("controller")}
    code, text, sec = cli("certify", "--robot", robot, str(d / "gait.json"), "--json")
    c = json.loads(text.strip().splitlines()[-1]) if code == 0 else {}
    row["certify"] = {"exit": code, "seconds": round(sec, 1), "status": c.get("status"),
                      "j_star": c.get("value", c.get("j_star", c.get("r_star"))),
                      "error": None if code == 0 else text.strip().splitlines()[-1]}
    code, text, sec = cli("gait", "generate", "--robot", robot, "-o", str(d / "gait_off.json"), "--override",
                           "sim.regulator.mode=off")
    row["generate_off"] = {"exit": code, "seconds": round(sec, 1), "message": text.strip().splitlines()[-1],
                           "file_written": (d / "gait_off.json").exists()}
    return row


def _line(text: str, start: str) -> str | None:
    return next((ln for ln in text.splitlines() if ln.startswith(start)), None)


def exo(seeds: int) -> dict[str, Any]:
    row: dict[str, Any] = {**_stamp(), "gait": str(EXO_GAIT.relative_to(REPO))}
    for mode in ("off", "on"):
        runs = []
        for seed in range(seeds):
            code, text, sec = cli("certify", "--robot", "exo", str(EXO_GAIT), "--json", "--override",
                                   f"sim.regulator.mode={mode}", "--override", f"certify.seed={seed}")
            c = json.loads(text.strip().splitlines()[-1]) if code == 0 else {}
            runs.append({"seed": seed, "exit": code, "status": c.get("status"),
                         "j_star": c.get("value", c.get("j_star", c.get("r_star"))), "seconds": round(sec, 1)})
        row[mode] = runs
    return row


def _variant(text: str) -> Any:
    """A RegulatorConfig from ``key=value;key=value`` (mode on unless given)."""
    from robustgait.config.regulator import RegulatorConfig

    kw: dict[str, Any] = {"mode": "on"}
    for item in filter(None, text.split(";")):
        key, value = item.split("=")
        kw[key] = value if key in ("mode", "gain") else value in ("1", "true") if key == "predict" else float(value)
    return RegulatorConfig(**kw)


def _engine(robot: Any, gait: Any, variant: str) -> Any:
    from robustgait.config import SimConfig
    from robustgait.sim.engine import StepEngine

    return StepEngine(robot, gait, SimConfig(regulator=_variant(variant)))


def _walk(eng: Any, robot: Any, gait: Any, steps: int, keep: int = -1) -> tuple[int, Any]:
    """Steps walked (≤ steps) from the gait's initial state, and the switching state after step ``keep``."""
    qp, qv = gait.initial_state.qpos[None], gait.initial_state.qvel[None]  # the robot's full state
    stance, kept = gait.stance, None
    for i in range(steps):
        b = eng.step(qp, qv, stance)
        if b.fell[0]:
            return i, kept
        qp, qv, stance = b.qpos, b.qvel, ("left" if stance == "right" else "right")
        if i == keep:
            kept = (qp.copy(), qv.copy(), stance)
    return steps, kept


def sweep(d: Path, grid: int, steps: int, variants: list[str]) -> None:
    from robustgait import load_robot
    from robustgait.config import GaitParams
    from robustgait.gaitgen import GaitGenerator

    robot = load_robot(d / "t1.toml")
    gen = GaitGenerator(robot)
    import dataclasses

    points = grid_params(str(d / "t1.toml"), grid, "flat") if grid else []
    for params in [dataclasses.asdict(robot.default_params), *points]:
        res = gen.solve(GaitParams(**{k: params[k] for k in ("step_length", "step_duration", "step_width",
                                                              "step_height")}))
        row: dict[str, Any] = {**_stamp(), "params": {k: params[k] for k in ("step_length", "step_duration",
                                                                             "step_width", "step_height")}}
        if res.gait is not None:
            row["steps"] = {v: _walk(_engine(robot, res.gait, v), robot, res.gait, steps)[0] for v in variants}
        else:
            row["generation"] = res.status
        print(json.dumps(row), flush=True)


def pushes(d: Path, variants: list[str]) -> None:
    import numpy as np

    from robustgait import load_gait, load_robot

    robot = load_robot(d / "t1.toml")
    gait = load_gait(d / "gait.json", robot)
    mags, angles = np.arange(1.0, 6.0), np.arange(12) * np.pi / 6
    impulse = np.array([[m * np.cos(a), m * np.sin(a)] for m in mags for a in angles])
    for variant in variants:
        eng = _engine(robot, gait, variant)
        taken, kept = _walk(eng, robot, gait, 6, keep=5)
        row: dict[str, Any] = {**_stamp(), "variant": variant, "undisturbed_steps": taken}
        if kept is not None:
            q, v, stance = kept
            q, v = np.repeat(q, len(impulse), axis=0), np.repeat(v, len(impulse), axis=0)
            v[:, :2] += impulse / robot.mass  # an impulse J [N s] on the whole body: Δv = J / m at the step start
            alive = np.ones(len(impulse), dtype=bool)
            for _ in range(21):
                b = eng.step(q, v, stance)
                alive &= ~b.fell
                q, v = b.qpos, b.qvel  # a fallen sample's NaN state is a fall again at once, at no cost
                stance = "left" if stance == "right" else "right"
            fell = (~alive).reshape(len(mags), len(angles)).sum(axis=1)
            row["falls_of_12_per_impulse_Ns"] = {f"{m:g}": int(f) for m, f in zip(mags, fell, strict=True)}
        print(json.dumps(row), flush=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    b = sub.add_parser("build")
    b.add_argument("dir", type=Path)
    b.add_argument("--width", type=float, default=0.04, help="outer width of the sphere footprint [m] (0.015: a line "
                   "foot, its spheres 5 mm apart)")
    d = sub.add_parser("default")
    d.add_argument("dir", type=Path)
    d.add_argument("--steps", type=int, default=300)
    sw = sub.add_parser("sweep")
    sw.add_argument("dir", type=Path)
    sw.add_argument("--grid", type=int, default=12)
    sw.add_argument("--steps", type=int, default=300)
    sw.add_argument("--variant", action="append", required=True)
    pu = sub.add_parser("pushes")
    pu.add_argument("dir", type=Path)
    pu.add_argument("--variant", action="append", required=True)
    e = sub.add_parser("exo")
    e.add_argument("--seeds", type=int, default=3)
    args = ap.parse_args()
    if args.cmd == "build":
        build(args.dir, args.width)
    elif args.cmd == "sweep":
        sweep(args.dir, args.grid, args.steps, args.variant)
    elif args.cmd == "pushes":
        pushes(args.dir, args.variant)
    elif args.cmd == "default":
        print(json.dumps(default(args.dir, args.steps)))
    else:
        print(json.dumps(exo(args.seeds)))


if __name__ == "__main__":
    main()
