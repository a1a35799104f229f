"""Humanoids nobody on this project tuned: MuJoCo Menagerie models through the whole pipeline, as a user would.

The Menagerie's models reference mesh files that this machine cannot download; ``strip`` makes the copy a user
without the meshes would make, the way ``../shared/robots/booster_t1`` was made: every mesh asset and mesh geom
removed (each body's inertial is explicit in these models, so the dynamics are the original's; the collision geometry
left is the original's primitives), a plane ``floor`` added if the model has none. Actuators, keyframes and sensors
stay: ``robot init`` reads torque limits from the actuators. No model is kept in the repository.

``strip SRC OUT``: the mesh-free copy of a Menagerie MJCF (``unitree_g1/g1.xml``, ``unitree_h1/h1.xml``,
``robotis_op3/op3.xml``, ``berkeley_humanoid/berkeley_humanoid.xml``, …), read with ``mujoco.MjSpec``.

``run MODEL DIR``: with the CLI, in DIR: ``robot init``, ``robot check``, ``gait generate`` (the defaults),
``walk --steps`` (300), ``certify``, ``validate --certificate`` (200 pushes); each stage's exit code, wall time and
outcome (or its one-line error), as one JSON line.

``sweep SPEC``: why a narrow-footed robot falls — the default gait with its step duration set to each of
``--durations`` (or its step width to each of ``--widths``), generated, then walked ``--steps`` steps under each share
κ of the H-LIP stepping gain in ``--shares`` (``sim.regulator.gain_scale``): steps walked, one JSON line per point.

``checkgrid SPEC DIR``: does the walk check's verdict hold at 300 steps? For ``--grid`` points of the robot's
action space (the studies' grid, ``benchmarks/common.grid_params``; 0: the default gait), with the CLI: ``gait
generate`` (the walk check, and its one retry with a joint margin), then, for a gait it wrote, ``walk --steps`` (300):
the check's outcome, whether it solved again and why, and the steps the written gait walks, one JSON line per point;
``--override KEY=VALUE`` (repeatable) is passed to ``gait generate`` (e.g. ``generate.springs=compliant``).

``evaluate SPEC --params L T W H [L T W H ...]``: a study's evaluation of each point
(:func:`robustgait.study.evaluate.evaluate`, the defaults: generate, walk to the cap, certify, and the one retry with a
joint margin after a fall at a joint limit): status, reason, J*, whether it was generated again and why, seconds.

``promise SPEC GAIT CERT``: the certificate's promise where it is made: ``validate --disturbance push`` with every
push drawn below J* (``validate.push_dv_max`` = J* / m, so the impulses are uniform in [0, J*] instead of up to the
default Δv_max, where few land below J* on a robot whose J* is small against its mass): pushes, falls within 20 steps,
and the falls' upper 95 % bound, as one JSON line.

``report [--data DIR]``: the current table, one line per robot, from ``DIR/pipeline.jsonl``, ``DIR/checkgrid.jsonl``
and ``DIR/promise.jsonl`` (default: this experiment's ``data/``): each robot's latest ``run``, ``checkgrid`` and
``promise`` rows, each with the commit it was measured at. A new measurement replaces that robot's rows there.

``growth SPEC GAIT``: the regulator's own growth probe (:func:`robustgait.sim.regulator.lateral_growth`) under
each share κ of ``--shares``: how much a lateral CoM error grows per step (``fell``: a probe walk fell) — does the
ankle hold it, or does it grow as on a point foot (e^{λT} per step)?

``soletilt SPEC``: how far the stance sole turns on the model's own contacts under the default gait. The gait is
solved again (:class:`robustgait.gaitgen.solve.GaitGenerator`, for its planned contact wrenches), and its first step
is walked open loop from its initial state with the walker's servo controls (:func:`robustgait.sim.controller.
step_controls`, no regulator). Every ``--every`` seconds it prints the stance sole's tilt (toe up > 0), the simulated
and planned centre of pressure along the sole (from the sole box's centre), and each sole contact's position,
penetration [mm] and normal force [N]. The last line is a JSON summary: a contact's stiffness (the median of force /
penetration), the sole's neutral point (the mean position of its loaded contacts at mid-step: all equally stiff, the
centre of pressure that leaves the sole flat) and its rotational stiffness about that point, k_rot = k sum (x_i -
x_bar)^2, beside the servo stiffness of the stance leg's last pitch joint; the planned centre of pressure's range.
``--timeconst S`` sets every geom's solref time constant to S first (in memory): the same step on stiffer contacts.

    python benchmarks/experiments/menagerie_humanoids/run.py strip ~/mujoco_menagerie/unitree_g1/g1.xml /tmp/g1.xml
    python benchmarks/experiments/menagerie_humanoids/run.py run /tmp/g1.xml /tmp/g1 >> \\
        benchmarks/experiments/menagerie_humanoids/data/pipeline.jsonl
    python benchmarks/experiments/menagerie_humanoids/run.py sweep /tmp/g1/spec.toml --durations 0.45 0.5 0.55 0.6
    python benchmarks/experiments/menagerie_humanoids/run.py checkgrid /tmp/g1/spec.toml /tmp/g1/grid --grid 12
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import sys
from datetime import date
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))  # benchmarks/common.py
from common import cli, git_commit, grid_params
from robustgait.io.certfile import certificate_radius


def strip(src: Path, out: Path) -> dict[str, Any]:
    import mujoco

    spec = mujoco.MjSpec.from_file(str(src))
    meshes = [g for g in spec.geoms if g.type == mujoco.mjtGeom.mjGEOM_MESH]
    for g in meshes:
        spec.delete(g)
    for m in list(spec.meshes):
        spec.delete(m)
    for t in list(spec.textures):  # image files that are not here either
        spec.delete(t)
    for mat in spec.materials:  # a material naming a deleted texture does not compile
        mat.textures = [""] * len(mat.textures)
    spec.meshdir = ""
    spec.texturedir = ""
    floor = any(g.type == mujoco.mjtGeom.mjGEOM_PLANE for g in spec.worldbody.geoms)
    if not floor:
        # explicit collision bits: a model whose default geom does not collide (contacts by <pair>) keeps its floor
        spec.worldbody.add_geom(name="floor", type=mujoco.mjtGeom.mjGEOM_PLANE, size=[0.0, 0.0, 0.05], contype=1,
                                conaffinity=1)
    model = spec.compile()
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(spec.to_xml())
    return {"source": str(src), "out": str(out), "mesh_geoms_removed": len(meshes), "floor_added": not floor,
            "nq": model.nq, "nu": model.nu, "mass": round(float(model.body_mass.sum()), 3)}


def _last(text: str) -> str:
    lines = text.strip().splitlines()
    return lines[-1] if lines else ""


def _json(code: int, text: str) -> dict[str, Any]:
    return json.loads(_last(text)) if code == 0 else {}


def run(model: Path, d: Path, steps: int) -> dict[str, Any]:
    d.mkdir(parents=True, exist_ok=True)
    spec, gait, cert = d / "spec.toml", d / "gait.json", d / "certificate.json"
    row: dict[str, Any] = {"commit": git_commit(), "date": str(date.today()), "model": model.name}

    def stage(name: str, *args: str, parse: bool = False) -> dict[str, Any]:
        code, text, sec = cli(*args)
        out: dict[str, Any] = {"exit": code, "seconds": round(sec, 1)}
        if code:
            out["error"] = _last(text)
        row[name] = out
        return _json(code, text) if parse else {"text": text}

    init = stage("init", "robot", "init", str(model), "-o", str(spec))
    if row["init"]["exit"]:
        return row
    row["init"]["balance"] = next((ln for ln in init["text"].splitlines() if ln.startswith("balance")), None)
    check = stage("check", "robot", "check", str(spec))
    row["check"]["failed"] = [ln.split(":")[0] for ln in check["text"].splitlines() if ": FAIL" in ln or "FELL" in ln]
    g = stage("generate", "gait", "generate", "--robot", str(spec), "-o", str(gait), "--json", parse=True)
    if row["generate"]["exit"]:
        return row
    row["generate"]["params"] = g.get("params")
    w = stage("walk", "walk", str(gait), "--robot", str(spec), "--steps", str(steps), "--json", parse=True)
    row["walk"] |= {"steps_taken": w.get("steps_taken"), "fell": w.get("fell"), "controller": w.get("controller"),
                    "orbit": (w.get("orbit") or {}).get("status")}
    c = stage("certify", "certify", str(gait), "--robot", str(spec), "-o", str(cert), "--json", parse=True)
    row["certify"] |= {"status": c.get("status"), "j_star": c.get("value", c.get("j_star", c.get("r_star")))}
    if row["certify"]["exit"] == 0 and c.get("status") == "ok":
        v = stage("validate", "validate", str(gait), "--robot", str(spec), "--certificate", str(cert),
                  "--disturbance", "push", "--json", parse=True)
        push = (v.get("kinds") or {}).get("push") or {}
        inside = (push.get("certificate_check") or {}).get("inside") or {}
        row["validate"] |= {"s50": (push.get("critical") or {}).get("s50"),
                            "success": (push.get("success") or {}).get("rate"),
                            "inside_fell": inside.get("k"), "inside": inside.get("n"),
                            "inside_fell_upper": inside.get("high")}
    return row


def sweep(spec: Path, durations: list[float], widths: list[float], shares: list[float], steps: int
          ) -> list[dict[str, Any]]:
    from robustgait import Config, load_robot
    from robustgait.gaitgen import GaitGenerator
    from robustgait.sim.walk import walk

    robot = load_robot(spec)
    cfg = Config(gait=robot.default_params)
    gen = GaitGenerator(robot, cfg.generate)
    points = [("step_duration", t) for t in durations] + [("step_width", w) for w in widths]
    rows = []
    for axis, value in points or [("step_duration", robot.default_params.step_duration)]:
        params = dataclasses.replace(robot.default_params, **{axis: value})
        res = gen.solve(params)
        row: dict[str, Any] = {"commit": git_commit(), "robot": robot.name, axis: value, "status": res.status}
        if res.gait is not None:
            for k in shares:
                sim = dataclasses.replace(cfg.sim, regulator=dataclasses.replace(cfg.sim.regulator, gain_scale=k))
                row[f"steps_k{k:g}"] = walk(robot, res.gait, sim, steps=steps).steps_taken
        rows.append(row)
        print(json.dumps(row), flush=True)
    return rows


LETTER = {"step_length": "L", "step_duration": "T", "step_width": "W", "step_height": "H"}


def checkgrid(spec: Path, d: Path, n: int, steps: int, overrides: tuple[str, ...] = ()) -> list[dict[str, Any]]:
    spec = spec.resolve() if spec.suffix else spec  # the CLI runs in the repository; a name (exo) stays one
    d = d.resolve()
    d.mkdir(parents=True, exist_ok=True)
    points: list[dict[str, float] | None] = list(grid_params(str(spec), n, "flat")) if n else [None]
    flags = {"step_length": "--step-length", "step_duration": "--step-duration", "step_width": "--step-width",
             "step_height": "--step-height"}
    rows = []
    for p in points:
        label = "default" if p is None else "_".join(f"{LETTER[k]}{v:g}" for k, v in p.items() if k in flags)
        gait = d / f"{label}.json"
        args = [f for k, v in (p or {}).items() if k in flags for f in (flags[k], f"{v:g}")]
        args += [f for o in overrides for f in ("--override", o)]
        code, text, sec = cli("gait", "generate", "--robot", str(spec), "-o", str(gait), *args, "--json")
        lines = reversed(text.strip().splitlines())
        summary: dict[str, Any] = next((json.loads(ln) for ln in lines if ln.startswith("{")), {})
        check = summary.get("walk_check") or {}
        retried = summary.get("retried")
        row: dict[str, Any] = {
            "commit": git_commit(), "robot": spec.stem, "label": label, "params": p, "exit": code,
            **({"overrides": list(overrides)} if overrides else {}),
            "seconds": round(sec, 1), "error": _last(text) if code else None,
            "check": {k: check.get(k) for k in ("taken", "fell", "orbit", "limit_joint", "cause")},
            "retried": None if retried is None else {
                "joint_margin": retried["joint_margin"],
                "first": {k: retried["first_walk_check"].get(k) for k in ("taken", "limit_joint", "cause")}}}
        if code == 0:
            code, text, sec = cli("walk", str(gait), "--robot", str(spec), "--steps", str(steps), "--json")
            w = _json(code, text)
            row["walk"] = {"steps_taken": w.get("steps_taken"), "fell": w.get("fell"),
                           "orbit": (w.get("orbit") or {}).get("status"), "seconds": round(sec, 1)}
        rows.append(row)
        print(json.dumps(row), flush=True)
    return rows


def study_evaluate(spec: Path, points: list[float]) -> list[dict[str, Any]]:
    from robustgait import Config, GaitParams, load_robot
    from robustgait.gaitgen import GaitGenerator
    from robustgait.study.evaluate import evaluate

    robot = load_robot(spec)
    cfg = Config(gait=robot.default_params)
    gen = GaitGenerator(robot, cfg.generate)
    rows = []
    for i in range(0, len(points), 4):
        length, duration, width, height = points[i:i + 4]
        params = GaitParams(step_length=length, step_duration=duration, step_width=width, step_height=height)
        ev = evaluate(robot, params, cfg, generator=gen)
        row = {"commit": git_commit(), "date": str(date.today()), "robot": robot.name, "params": params.to_dict(),
               "status": ev.status, "reason": ev.reason,
               "j_star": ev.value if ev.value is not None else ev.estimate, "steps_taken": ev.steps_taken,
               "retried": ev.retried,
               "joint_margin": (ev.gait.solver or {}).get("joint_margin") if ev.gait is not None else None,
               "seconds": {k: round(v, 1) for k, v in ev.seconds.items()}}
        rows.append(row)
        print(json.dumps(row), flush=True)
    return rows


def promise(spec: Path, gait: Path, cert: Path, trials: int, label: str) -> dict[str, Any]:
    from robustgait import load_robot

    j_star = certificate_radius(json.loads(cert.read_text()))
    dv = j_star / load_robot(spec).mass
    cmd = ("validate", str(gait), "--robot", str(spec), "--certificate", str(cert), "--disturbance", "push",
           "--trials", str(trials), "--override", f"validate.push_dv_max={dv:.6g}", "--json")
    code, text, sec = cli(*cmd)
    row: dict[str, Any] = {"commit": git_commit(), "date": str(date.today()), "robot": label,
                           "command": "robustgait " + " ".join(cmd), "exit": code, "seconds": round(sec, 1),
                           "j_star": j_star}
    if code:
        return row | {"error": _last(text)}
    push = json.loads(_last(text))["kinds"]["push"]
    inside = push["certificate_check"]["inside"]
    return row | {"trials": trials, "below_j_star": inside["n"], "below_j_star_fell": inside["k"],
                  "fell_upper_95": round(inside["high"], 4)}


def growth(spec: Path, gait_path: Path, shares: list[float]) -> list[dict[str, Any]]:
    from robustgait import Config, load_gait, load_robot
    from robustgait.sim.factory import make_engine
    from robustgait.sim.regulator import lateral_growth

    robot = load_robot(spec)
    gait = load_gait(gait_path, robot)
    cfg = Config().sim
    rows = []
    for share in shares:  # a given share: the engine does not settle its own
        sim = dataclasses.replace(cfg, regulator=dataclasses.replace(cfg.regulator, mode="on", gain_scale=share))
        with make_engine(robot, gait, sim) as engine:
            mu = lateral_growth(engine, repr(engine.config), share)
        row = {"commit": git_commit(), "robot": robot.name, "share": share, "growth": mu if np.isfinite(mu) else "fell"}
        rows.append(row)
        print(json.dumps(row), flush=True)
    return rows


def soletilt(spec: Path, every: float, timeconst: float | None) -> dict[str, Any]:
    """The stance sole's tilt and contacts over the default gait's first step (module docstring, ``soletilt``)."""
    import mujoco

    from robustgait import Config, load_robot
    from robustgait.gaitgen.solve import GaitGenerator
    from robustgait.robots.legs import axis_kinds
    from robustgait.sim.controller import step_controls
    from robustgait.sim.regulator import swing_dofs
    from robustgait.sim.walk import stance_sole_turn

    robot = load_robot(spec)
    m = robot.model
    if timeconst is not None:
        m.geom_solref[:, 0] = timeconst
    res = GaitGenerator(robot, Config().generate).solve(robot.default_params)
    if res.gait is None or res.nodes is None:
        raise SystemExit(f"the default gait does not solve: {res.reason}")
    gait, nodes = res.gait.closed(robot), res.nodes[0]  # a closed chain: its passive joints solved from its loops
    stance = gait.stance
    sole = robot.sole_boxes[stance]
    body = int(m.geom_bodyid[robot.sole_geom_id[stance]])
    lam = np.asarray(nodes.lam)
    torque_row = 3 if lam.shape[1] == 5 else 4  # n_y: a line foot's (f, n_y, n_z), a flat foot's (f, n)
    planned_cop = -lam[:, torque_row] / lam[:, 2]
    node_tau = np.linspace(0.0, 1.0, lam.shape[0])
    data, scratch = mujoco.MjData(m), mujoco.MjData(m)
    start = gait.initial_state
    assert start is not None  # a solved gait has its initial state
    data.qpos[:], data.qvel[:] = start.qpos, start.qvel
    n = round(gait.step_duration / m.opt.timestep)
    controls = step_controls(robot, gait, n)
    stride = max(1, round(every / m.opt.timestep))
    samples: list[dict[str, Any]] = []
    stiffness: list[tuple[float, float]] = []
    contacts: list[tuple[float, float, float]]
    for k in range(n):
        data.ctrl[:] = controls[k]
        mujoco.mj_step(m, data)
        if (k + 1) % stride:
            continue
        frame = sole.world_frame(data)
        centre = data.geom_xpos[sole.geom]
        contacts, fz, moment = [], 0.0, 0.0
        for i in range(data.ncon):
            c = data.contact[i]
            if body not in (int(m.geom_bodyid[c.geom1]), int(m.geom_bodyid[c.geom2])):
                continue
            f6 = np.zeros(6)
            mujoco.mj_contactForce(m, data, i, f6)
            normal = float(f6[0])
            x = float(frame[:, 0] @ (c.pos - centre))
            depth = -float(c.dist)
            contacts.append((round(x, 4), round(depth * 1e3, 2), round(normal, 1)))
            fz, moment = fz + normal, moment + normal * x
            if depth > 2e-5 and normal > 1.0:
                stiffness.append((x, normal / depth))
        tau = (k + 1) / n
        tilt = stance_sole_turn(robot, scratch, data.qpos, stance)  # the walk's own measure, toe up > 0
        samples.append({"tau": round(tau, 3), "tilt_deg": round(math.degrees(tilt), 3),
                        "cop": round(moment / fz, 4) if fz > 1.0 else None,
                        "planned_cop": round(float(np.interp(tau, node_tau, planned_cop)), 4),
                        "contacts": contacts})
        print(json.dumps(samples[-1]), flush=True)
    xs = np.array([x for x, _ in stiffness])
    ks = np.array([k for _, k in stiffness])
    x_bar = float(np.sum(ks * xs) / np.sum(ks)) if ks.size else float("nan")
    k_each = float(np.median(ks)) if ks.size else float("nan")
    # the sole as it stands at mid-step: its loaded contacts, equally stiff (the same solref), and their mean
    mid: list[tuple[float, float, float]] = next((s["contacts"] for s in samples if s["tau"] >= 0.5), [])
    at_mid = [x for x, _, normal in mid if normal > 1.0]
    x_mid = float(np.mean(at_mid)) if at_mid else float("nan")
    k_rot = k_each * float(sum((x - x_mid) ** 2 for x in at_mid))
    # the servo that turns the sole about its lateral axis: the stance chain's last pitch joint
    leg = swing_dofs(robot, stance)  # the planned joints from the base to the stance sole (either leg's)
    kinds = axis_kinds(m, tuple(int(m.dof_jntid[robot.dof_idx[j]]) for j in leg))
    pitches = [int(j) for j, kind in zip(leg, kinds, strict=True) if kind == "y"]
    servo = pitches[-1] if pitches else None
    kp = float(robot.kp[servo]) if servo is not None else float("nan")
    summary = {"commit": git_commit(), "date": str(date.today()), "robot": robot.name,
               "timeconst": timeconst, "timestep": m.opt.timestep, "contact_stiffness_n_per_mm": round(k_each / 1e3, 1),
               "contacts_at_mid_step": len(at_mid), "neutral_point": round(x_mid, 4),
               "stiffness_weighted_point": round(x_bar, 4), "k_rot_nm_per_rad": round(k_rot, 0),
               "servo_kp_nm_per_rad": round(kp, 0),
               "servo_joint": m.joint(int(m.dof_jntid[robot.dof_idx[servo]])).name if servo is not None else None,
               "tilt_end_deg": samples[-1]["tilt_deg"] if samples else None,
               "planned_cop_range": [round(float(planned_cop.min()), 4), round(float(planned_cop.max()), 4)]}
    print(json.dumps(summary))
    return summary


def _commits(rows: list[dict[str, Any]]) -> str:
    return ", ".join(sorted({str(r.get("commit")) for r in rows}))


def report(data: Path) -> None:
    """The current table (module docstring, ``report``)."""
    def read(name: str) -> dict[str, list[dict[str, Any]]]:
        out: dict[str, list[dict[str, Any]]] = {}
        for line in (data / name).read_text().splitlines():
            if line.strip():
                row = json.loads(line)
                out.setdefault(row["robot"], []).append(row)
        return out

    pipeline, grid, promised = read("pipeline.jsonl"), read("checkgrid.jsonl"), read("promise.jsonl")
    print("| robot | check failed | walk 300 | J* [N s] | validate: below J* fell | run at | 200 drawn below J* "
          "fell (upper 95 %) | at | grid: walk 300 steps | at |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for robot, (p, *_) in pipeline.items():
        check, walked, cert, val = (p.get(k) or {} for k in ("check", "walk", "certify", "validate"))
        j = cert.get("j_star")
        inside = f"{val['inside_fell']} of {val['inside']}" if val.get("inside") is not None else "—"
        pr = promised.get(robot, [])
        drawn = (f"{sum(r['below_j_star_fell'] for r in pr)} of {sum(r['below_j_star'] for r in pr)} "
                 f"({max(r['fell_upper_95'] for r in pr):.2%})") if pr else "not measured"
        g = grid.get(robot, [])
        ok = sum(1 for r in g if (r.get("walk") or {}).get("steps_taken", 0) >= 300)
        print(f"| {p['name']} | {', '.join(check.get('failed') or []) or 'none'} | "
              f"{walked.get('steps_taken', '—')} | {'refused' if j is None else f'{j:.3f}'} | {inside} | "
              f"{p.get('commit')} | {drawn} | {_commits(pr) if pr else '—'} | "
              f"{f'{ok} of {len(g)}' if g else 'not measured'} | {_commits(g) if g else '—'} |")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="cmd", required=True)
    s = sub.add_parser("strip")
    s.add_argument("src", type=Path)
    s.add_argument("out", type=Path)
    r = sub.add_parser("run")
    r.add_argument("model", type=Path)
    r.add_argument("dir", type=Path)
    r.add_argument("--steps", type=int, default=300)
    w = sub.add_parser("sweep")
    w.add_argument("spec", type=Path)
    w.add_argument("--durations", type=float, nargs="*", default=[])
    w.add_argument("--widths", type=float, nargs="*", default=[])
    w.add_argument("--shares", type=float, nargs="+", default=[0.0, 0.25, 0.5, 0.75, 1.0])
    w.add_argument("--steps", type=int, default=300)
    c = sub.add_parser("checkgrid")
    c.add_argument("spec", type=Path)
    c.add_argument("dir", type=Path)
    c.add_argument("--grid", type=int, default=12)
    c.add_argument("--steps", type=int, default=300)
    c.add_argument("--override", action="append", default=[], help="KEY=VALUE for gait generate (repeatable)")
    e = sub.add_parser("evaluate")
    e.add_argument("spec", type=Path)
    e.add_argument("--params", type=float, nargs="+", required=True, help="L T W H per point")
    pr = sub.add_parser("promise")
    pr.add_argument("spec", type=Path)
    pr.add_argument("gait", type=Path)
    pr.add_argument("cert", type=Path)
    pr.add_argument("--trials", type=int, default=200)
    pr.add_argument("--label", default="")
    rp = sub.add_parser("report")
    rp.add_argument("--data", type=Path, default=Path(__file__).resolve().parent / "data")
    g = sub.add_parser("growth")
    g.add_argument("spec", type=Path)
    g.add_argument("gait", type=Path)
    g.add_argument("--shares", type=float, nargs="+", default=[0.0, 1.0])
    t = sub.add_parser("soletilt")
    t.add_argument("spec", type=Path)
    t.add_argument("--every", type=float, default=0.02)
    t.add_argument("--timeconst", type=float, default=None)
    args = ap.parse_args()
    if args.cmd == "strip":
        print(json.dumps(strip(args.src, args.out)))
    elif args.cmd == "run":
        print(json.dumps(run(args.model, args.dir, args.steps)))
    elif args.cmd == "checkgrid":
        checkgrid(args.spec, args.dir, args.grid, args.steps, tuple(args.override))
    elif args.cmd == "evaluate":
        if len(args.params) % 4:
            ap.error("--params takes L T W H per point")
        study_evaluate(args.spec, args.params)
    elif args.cmd == "sweep":
        sweep(args.spec, args.durations, args.widths, args.shares, args.steps)
    elif args.cmd == "report":
        report(args.data)
    elif args.cmd == "promise":
        print(json.dumps(promise(args.spec, args.gait, args.cert, args.trials, args.label or str(args.spec))))
    elif args.cmd == "soletilt":
        soletilt(args.spec, args.every, args.timeconst)
    else:
        growth(args.spec, args.gait, args.shares)


if __name__ == "__main__":
    main()
