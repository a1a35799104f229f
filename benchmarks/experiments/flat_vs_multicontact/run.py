"""Flat-foot against multi-contact, robustness-optimized (issue 19, item 5): the paper's headline comparison.

Takes the best gait (the learner's recommendation) of a flat-foot and of a multi-contact robustness study of
one robot and measures, for each:

- r* re-certified with fresh seeds (``study compare``: study A's certificate, seeds ``--seed-base`` …);
- every disturbance kind of ``validate`` (``--trials`` each, seed 0, common random numbers): success rate with
  its Wilson interval and the critical size s₅₀ ± s.e. (logistic fit);
- the orbit's scatter: the orbit search (:func:`robustgait.certificate.search.find_orbit`) — its status, period and
  band scatter σ (band coordinates) — and how far successive switching states of its band (the settling window and
  the hold, canonical) stay apart in the base angular velocity ω (heading frame), median and max (a point
  certificate cannot certify a ball smaller than it). This replaces the old measure over steps 41–80 of the step
  map iterated by the removed fixed-point search: the band's states are the walk's own after it settled;
- a 50-step walk: mean speed against L/T, pelvis roll range, and the soles' pitch at touchdown (toe up, the
  heel strike of a multi-contact gait) and at lift-off (toe down, its toe-off), medians over steps 10–40, from
  the walked trajectory (not from the gait's design): a touchdown ends, a lift-off starts, a flight of ≥ 50 ms
  without contact in the robot's sole contact sensors (those the simulator's touchdown guard reads);
- tiles of one step and a video (``--gif-steps`` steps; skipped with ``--no-media``).

Writes ``OUT/compare_<robot>.json``, the media as ``OUT/<robot>_best_{flat,multicontact}{_tiles.png,.gif}``, and
prints Markdown rows for docs/studies.md.

    python benchmarks/experiments/flat_vs_multicontact/run.py --robot exo --flat runs/rob_exo --mc runs/mc_exo \\
        --out docs/media \
        [--trials 200] [--seeds 5] [--seed-base 1000] [--gif-steps 4] [--no-media]
    python benchmarks/experiments/flat_vs_multicontact/run.py --table docs/media/compare_exo.json [--redo-walk] \\
          # the table again
"""

from __future__ import annotations

import os
import sys

os.environ.setdefault("MUJOCO_GL", "egl")  # before mujoco is imported: the tiles and videos render offscreen

import argparse
import datetime
import json
import platform
import time
from pathlib import Path
from typing import Any

import mujoco
import numpy as np

from robustgait import load_gait, load_robot, walk
from robustgait.certificate import Walking, find_orbit
from robustgait.certificate.reduced import reduce_state
from robustgait.config import KINDS, CertifyConfig, CompareConfig, ValidateConfig
from robustgait.gait import Gait
from robustgait.io.studyfile import load_config
from robustgait.report.tiles import render_tiles
from robustgait.robots import Robot
from robustgait.robots.model import CONTACT_SENSORS
from robustgait.rotations import quat_to_mat, roll_pitch_yaw
from robustgait.study.compare import compare_studies
from robustgait.study.outcome import known_figure
from robustgait.study.status import study_status
from robustgait.validate import validate_gait

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))  # benchmarks/common.py
from common import git_commit

WINDOW = (10, 40)  # steps whose touchdowns and lift-offs are measured (on the orbit, before the cap)
# a foot is in flight when it has no contact for this long [s]: a sole rolling on an edge of soft contacts
# loses and regains contact for a few physics steps (flicker), which is not a touchdown
MIN_FLIGHT = 0.05


def flights(contact: np.ndarray, min_len: int) -> list[tuple[int, int]]:  # type: ignore[type-arg]
    """(first, last) sample indices of the runs without contact that last at least ``min_len`` samples."""
    out, start = [], None
    for k, c in enumerate(contact):
        if not c and start is None:
            start = k
        elif c and start is not None:
            if k - start >= min_len:
                out.append((start, k - 1))
            start = None
    if start is not None and len(contact) - start >= min_len:
        out.append((start, len(contact) - 1))
    return out


def foot_contacts(robot: Robot, trajectory: np.ndarray) -> dict[str, np.ndarray]:  # type: ignore[type-arg]
    """Per side, (T,) bool: the sole touches the floor — the robot's own sole contact sensors, which the
    simulator's touchdown guard reads (:data:`robustgait.robots.model.CONTACT_SENSORS`)."""
    m, d = robot.model, robot.new_data()
    adr = {side: robot.sensor_adr[CONTACT_SENSORS[i]] for i, side in enumerate(("left", "right"))}
    out = {side: np.zeros(len(trajectory), bool) for side in adr}
    for k, state in enumerate(trajectory):
        mujoco.mj_setState(m, d, state, mujoco.mjtState.mjSTATE_FULLPHYSICS)
        mujoco.mj_forward(m, d)
        for side, a in adr.items():
            out[side][k] = d.sensordata[a] > 0
    return out


def sole_forward_axis(robot: Robot, gait: Gait) -> tuple[int, float]:
    """The sole geom's local axis that points forward (and its sign) in the gait's initial state: the axis most
    aligned with the base's heading (a sole geom's frame need not be the foot's: Atalante's length is its z)."""
    m, d = robot.model, robot.new_data()
    assert gait.initial_state is not None
    d.qpos[:] = gait.initial_state.qpos
    mujoco.mj_kinematics(m, d)
    heading = quat_to_mat(d.qpos[3:7])[:, 0] * np.array([1.0, 1.0, 0.0])
    r = d.geom_xmat[robot.sole_geom_id[gait.stance]].reshape(3, 3)
    dots = heading @ r
    i = int(np.argmax(np.abs(dots)))
    return i, float(np.sign(dots[i]))


def sole_pitch(robot: Robot, d: mujoco.MjData, state: np.ndarray, side: str,  # type: ignore[type-arg]
               axis: tuple[int, float]) -> float:
    """Toe-up pitch [deg] of a sole in a full-physics ``state`` (positive: toe above heel; ``d``: scratch data);
    ``axis``: its forward axis (:func:`sole_forward_axis`)."""
    mujoco.mj_setState(robot.model, d, state, mujoco.mjtState.mjSTATE_FULLPHYSICS)
    mujoco.mj_kinematics(robot.model, d)
    r = d.geom_xmat[robot.sole_geom_id[side]].reshape(3, 3)
    return float(np.degrees(np.arcsin(np.clip(axis[1] * r[2, axis[0]], -1.0, 1.0))))


def walk_figures(robot: Robot, gait: Gait, steps: int = 50) -> dict[str, Any]:
    """Speed, pelvis roll and sole pitch at touchdown / lift-off of a ``steps``-step walk (see the module doc)."""
    w = walk(robot, gait, steps=steps, keep_trajectory=True)
    p = gait.params
    assert p is not None and w.trajectory is not None
    tr = w.trajectory
    roll = np.degrees(roll_pitch_yaw(tr[:, 4:8])[:, 0])
    out: dict[str, Any] = {"steps": w.steps_taken, "fall": w.fall_reason, "speed": w.mean_speed,
                           "speed_design": p.step_length / p.duration,
                           "roll": [float(roll.min()), float(roll.max())]}
    if w.steps_taken < WINDOW[1]:
        return out
    t0, t1 = w.events[WINDOW[0] - 1].time, w.events[WINDOW[1] - 1].time
    sel = np.flatnonzero((tr[:, 0] >= t0) & (tr[:, 0] <= t1))
    contact = foot_contacts(robot, tr[sel])
    min_flight = round(MIN_FLIGHT / robot.dt)
    axis, d = sole_forward_axis(robot, gait), robot.new_data()
    touchdown, liftoff = [], []
    for side, c in contact.items():
        for first, last in flights(c, min_flight):
            if first > 0:
                liftoff.append(-sole_pitch(robot, d, tr[sel[first - 1]], side, axis))
            if last + 1 < len(c):
                touchdown.append(sole_pitch(robot, d, tr[sel[last + 1]], side, axis))
    out["touchdown_toe_up"] = float(np.median(touchdown)) if touchdown else None
    out["liftoff_toe_down"] = float(np.median(liftoff)) if liftoff else None
    out["touchdowns"], out["liftoffs"] = len(touchdown), len(liftoff)
    return out


def gait_figures(robot: Robot, gait: Gait) -> dict[str, Any]:
    """:func:`walk_figures` and, under ``scatter``, :func:`orbit_scatter`."""
    return walk_figures(robot, gait) | {"scatter": orbit_scatter(robot, gait)}


def orbit_scatter(robot: Robot, gait: Gait) -> dict[str, Any]:
    """How far the walk's orbit is from a period-1 fixed point: the orbit search's status, period, settling step and
    band scatter σ (band coordinates), and ‖x̄_k+1 − x̄_k‖ of the certificate's reduced state (the base angular
    velocity, heading frame) over the band's successive switching states (canonical; median and max, rad/s). A
    certificate around a point cannot hold on a ball smaller than this scatter (docs/gaitgen.md)."""
    cfg = CertifyConfig(disturbance="state")
    orbit = find_orbit(Walking(robot, gait), cfg)
    out: dict[str, Any] = {"status": str(orbit.status), "steps": orbit.steps, "period": orbit.period,
                           "settled": orbit.settled, "sigma": orbit.sigma, "median": float("nan"),
                           "max": float("nan")}
    if orbit.states is None or len(orbit.states) < 2:
        return out
    nq = robot.model.nq
    omega = reduce_state(orbit.states[:, :nq], orbit.states[:, nq:], cfg.frame)
    r = np.linalg.norm(np.diff(omega, axis=0), axis=1)
    return out | {"states": len(orbit.states), "median": float(np.median(r)), "max": float(r.max())}


def best_gait(directory: Path) -> tuple[Robot, Gait, dict[str, Any]]:
    setup = load_config(directory)
    best = study_status(directory)["best"]
    robot = load_robot(setup.robot)
    return robot, load_gait(directory / best["gait_file"], robot), best


def fmt_rate(s: dict[str, Any]) -> str:
    return f"{s['k']}/{s['n']} [{s['low']:.2f}, {s['high']:.2f}]"


def fmt_critical(c: dict[str, Any]) -> str:
    if c.get("s50") is None:
        return "— (" + (c.get("note") or "not identified") + ")"
    se = c.get("s50_se")
    gap = "" if c.get("converged", True) else " (gap)"
    return f"{c['s50']:.3g}" + ("" if se is None else f" ± {se:.2g}") + gap


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--robot", help="label of the robot in the outputs (exo, atalante)")
    ap.add_argument("--flat", type=Path, help="flat-foot robustness study directory")
    ap.add_argument("--mc", type=Path, help="multi-contact robustness study directory")
    ap.add_argument("--out", type=Path)
    ap.add_argument("--table", type=Path, help="only print the table of a compare_<robot>.json written before")
    ap.add_argument("--redo-walk", action="store_true", help="with --table: measure the walk figures again")
    ap.add_argument("--trials", type=int, default=200)
    ap.add_argument("--seeds", type=int, default=5)
    ap.add_argument("--seed-base", type=int, default=1000)
    ap.add_argument("--gif-steps", type=int, default=4)
    ap.add_argument("--no-media", action="store_true")
    args = ap.parse_args()
    if args.table is not None:
        record = json.loads(args.table.read_text())
        if args.redo_walk:  # the walk figures again (cheap), e.g. after a change of their definition
            for name, study in zip(record["gaits"], record["compare"]["studies"], strict=True):
                robot, gait, _ = best_gait(Path(study["directory"]))
                record["gaits"][name]["walk"] = gait_figures(robot, gait)
            args.table.write_text(json.dumps(record, indent=1, default=float))
        print_table(record)
        return
    if None in (args.robot, args.flat, args.mc, args.out):
        ap.error("--robot, --flat, --mc and --out are required (or --table)")
    args.out.mkdir(parents=True, exist_ok=True)
    commit = git_commit()
    print(f"# flat_vs_multicontact {args.robot}: {datetime.date.today()}, main {commit}, "
          f"{platform.processor() or 'cpu'}, {os.cpu_count()} cores, load {os.getloadavg()[0]:.1f}", flush=True)

    t = time.perf_counter()
    cmp = compare_studies(args.flat, args.mc, CompareConfig(seeds=args.seeds, seed_base=args.seed_base))
    print(f"study compare: {time.perf_counter() - t:.0f} s ({cmp['method']}, seeds {cmp['seeds']})", flush=True)
    record: dict[str, Any] = {"robot": args.robot, "date": str(datetime.date.today()), "commit": commit,
                              "compare": cmp, "gaits": {}}
    for name, directory, r in (("flat", args.flat, cmp["studies"][0]), ("multicontact", args.mc, cmp["studies"][1])):
        robot, gait, best = best_gait(directory)
        t = time.perf_counter()
        wf = gait_figures(robot, gait)
        print(f"{name}: walk figures {time.perf_counter() - t:.0f} s", flush=True)
        t = time.perf_counter()
        v = validate_gait(robot, gait, ValidateConfig(trials=args.trials), kinds=list(KINDS))
        print(f"{name}: validation {time.perf_counter() - t:.0f} s (load {os.getloadavg()[0]:.1f})", flush=True)
        (args.out / f"validate_{args.robot}_{name}.json").write_text(v.to_json(trials=False))
        media = {}
        if not args.no_media:
            tiles = args.out / f"{args.robot}_best_{name}_tiles.png"
            render_tiles(robot, gait, tiles)
            gif = args.out / f"{args.robot}_best_{name}.gif"
            walk(robot, gait, steps=args.gif_steps, video=gif)
            media = {"tiles": tiles.name, "video": gif.name}
        record["gaits"][name] = {"params": best["params"], "study_r_star": known_figure(best),
                                 "r_star": r["values"],
                                 "walk": wf, "validation": {k: kr.summary() for k, kr in v.kinds.items()},
                                 "certificate_r_star": v.certificate.radius, "media": media}
    (args.out / f"compare_{args.robot}.json").write_text(json.dumps(record, indent=1, default=float))
    print_table(record)


def print_table(record: dict[str, Any]) -> None:
    """Markdown rows of a ``compare_<robot>.json`` record (gaits as columns)."""
    g, seeds = record["gaits"], record["compare"]["seeds"]
    print("\n| | " + " | ".join(g) + " |\n|---|" + "---|" * len(g))

    def row(label: str, f: Any) -> None:
        print(f"| {label} | " + " | ".join(f(g[n]) for n in g) + " |")

    row("gait (L, T, W, h, ρ)", lambda x: ", ".join(f"{x['params'][k]:g}" for k in
                                                     ("step_length", "step_duration", "step_width", "step_height",
                                                      "rolling_fraction") if k in x["params"]))
    row(f"r* seeds {seeds[0]}–{seeds[-1]} [rad/s]",
        lambda x: f"{np.mean(x['r_star']):.3f} ± {np.std(x['r_star'], ddof=1):.3f}")
    first = next(iter(g.values()))
    for kind in first["validation"]:
        row(f"{kind}: success", lambda x, k=kind: fmt_rate(x["validation"][k]["success"]))
        row(f"{kind}: s₅₀ [{first['validation'][kind]['unit']}]",
            lambda x, k=kind: fmt_critical(x["validation"][k]["critical"]))
    row("orbit (period, σ in band coordinates)", lambda x: "—" if "period" not in x["walk"]["scatter"] else
        f"{x['walk']['scatter']['status']}, period {x['walk']['scatter']['period']}, σ "
        + ("—" if x["walk"]["scatter"]["sigma"] is None else f"{x['walk']['scatter']['sigma']:.2g}"))
    row("orbit scatter ‖x̄ₖ₊₁ − x̄ₖ‖ [rad/s] (band states; records before the orbit search: steps 41–80)",
        lambda x: f"median {x['walk']['scatter']['median']:.2g}, max {x['walk']['scatter']['max']:.2g}")
    row("speed [m/s] (L/T)", lambda x: f"{x['walk']['speed']:.3f} ({x['walk']['speed_design']:.3f})")
    row("pelvis roll [deg]", lambda x: "{:+.1f} … {:+.1f}".format(*x["walk"]["roll"]))
    row("sole toe-up at touchdown [deg]", lambda x: "—" if x["walk"].get("touchdown_toe_up") is None
        else f"{x['walk']['touchdown_toe_up']:.1f}")
    row("sole toe-down at lift-off [deg]", lambda x: "—" if x["walk"].get("liftoff_toe_down") is None
        else f"{x['walk']['liftoff_toe_down']:.1f}")


if __name__ == "__main__":
    main()
