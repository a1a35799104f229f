"""``robustgait robot init`` and ``robot check`` (issue 28): the gain and scaling rules against the hand-written exo
and Atalante specs, and Booster T1 end to end.

``rules``: for exo (src/robustgait/robots/exo) and Atalante (robots/atalante/spec.toml, ../shared/atalante), the
reflected inertias of every joint in the spec's posture (swing: M_jj; stance: foot welded), the gains the rule gives
with the spec's own torque limits (kp = min(I_stance ω², τ/e), kd = 2ζ√(kp I_swing), robot.* defaults) beside the
spec's hand-tuned kp and kd, the natural frequency and damping ratio the hand-tuned gains imply; then every value
the scaling rules give (robot.scale) beside the spec's.

``t1``: robot init and robot check on ../shared/robots/booster_t1/t1.xml (times), then flat-foot gaits generated
with the written spec — its [gait] default and the corners of its action space's step length × duration — each
walked ``--steps`` steps: steps walked, tracking RMS and max, saturation.

    python benchmarks/experiments/robot_init/run.py rules
    python benchmarks/experiments/robot_init/run.py t1 [--steps 50] [--out DIR] [--tracking-error 0.1 --default-only]
"""

from __future__ import annotations

import argparse
import math
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))  # benchmarks/common.py
from common import ATALANTE_SPEC, REPO, SHARED

T1 = SHARED / "robots" / "booster_t1" / "t1.xml"
ROBOTS = {"exo": ("exo", REPO / "src" / "robustgait" / "robots" / "exo" / "spec.toml"),
          "atalante": (str(ATALANTE_SPEC), ATALANTE_SPEC)}


def gain_rule(name: str, ref: str) -> None:
    from robustgait import load_robot
    from robustgait.config import RobotConfig
    from robustgait.inspection.check import inspected, standing_qpos
    from robustgait.inspection.gains import joint_loads, pd_gains
    from robustgait.robots.spec import SIDES

    robot = load_robot(ref)
    rm = inspected(robot)
    c = RobotConfig()
    m = robot.model
    q = standing_qpos(robot, rm)
    feet = {s: int(m.geom_bodyid[robot.sole_geom_id[s]]) for s in SIDES}
    loads = joint_loads(rm, q, feet)
    print(f"\n{name}: gain rule ({c.bandwidth:g} Hz, ζ {c.damping_ratio:g}, cap τ/{c.tracking_error:g} rad) with the "
          f"spec's torque limits, vs the spec's hand-tuned gains (timestep {robot.dt:g} s, "
          f"{robot.spec.integrator or 'MJCF'} integrator)")
    print("| joint | I_swing | I_stance | τ_max | kp rule | kp spec | kd rule | kd spec | spec: f_stance Hz | spec: "
          "ζ_swing | spec: τ/kp rad |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    ratios_kp, ratios_kd = [], []
    for i, jn in enumerate(robot.spec.joints[:6]):
        j = m.joint(jn).id
        load = loads[j]
        tau, kp, kd = robot.torque_limit[i], robot.kp[i], robot.kd[i]
        g = pd_gains(load, float(tau), c.bandwidth, c.damping_ratio, c.tracking_error, robot.dt,
                     robot.spec.integrator or "euler")
        ratios_kp.append(g.kp / kp)
        ratios_kd.append(g.kd / kd)
        print(f"| {jn} | {load.swing:.3g} | {load.stance:.3g} | {tau:g} | {g.kp:.4g} ({g.bound}) | {kp:g} | "
              f"{g.kd:.3g} | {kd:g} | {math.sqrt(kp / load.stance) / (2 * math.pi):.3g} | "
              f"{kd / (2 * math.sqrt(kp * load.swing)):.2g} | {tau / kp:.3g} |")
    print(f"rule / spec: kp {min(ratios_kp):.2f}–{max(ratios_kp):.2f} (geometric mean "
          f"{math.exp(np.mean(np.log(ratios_kp))):.2f}), kd {min(ratios_kd):.2f}–{max(ratios_kd):.2f} "
          f"(geometric mean {math.exp(np.mean(np.log(ratios_kd))):.2f})")


def scale_rules(name: str, ref: str, spec_path: Path) -> None:
    import tomllib

    from robustgait import load_robot
    from robustgait.config import GaitParams, RobotConfig, RobotScale
    from robustgait.inspection.check import inspected, standing_qpos
    from robustgait.inspection.discover import find_legs
    from robustgait.inspection.scale import scale

    robot = load_robot(ref)
    rm = inspected(robot)
    c = RobotConfig()
    legs = find_legs(rm, c.foot_level, c.sole_tolerance)
    q = standing_qpos(robot, rm)
    size = RobotScale(leg_length=legs.leg_length, standing_height=float(q[2]), mass=robot.mass, gravity=9.81,
                     hip_spacing=legs.hip_spacing, sole_length=legs.left.sole.length, sole_width=legs.left.sole.width)
    s = scale(size, c.scale)
    raw = tomllib.loads(spec_path.read_text())
    quality, space = raw.get("gait_quality", {}), raw.get("action_space", {})
    gen = {**robot.spec.generation}
    default = GaitParams().resolved("flat")
    rows = [("gait step_length", s.gait["step_length"], default.step_length),
            ("gait step_duration", s.gait["step_duration"], default.step_duration),
            ("gait step_width", s.gait["step_width"], default.step_width),
            ("gait step_height", s.gait["step_height"], default.step_height)]
    rows += [(f"action_space {k}", list(v), space.get(k)) for k, v in s.action_space.items()]
    rows += [(f"action_space.multicontact {k}", list(v), space.get("multicontact", {}).get(k))
             for k, v in s.multicontact_action_space.items()]
    rows += [("pelvis_angular_velocity", s.angular_velocity, quality.get("pelvis_angular_velocity")),
             ("joint_velocity", s.joint_velocity, quality.get("joint_velocity")),
             ("pelvis_height", list(s.pelvis_height), quality.get("pelvis_height")),
             ("fall min_base_height", s.fall_height, raw.get("fall", {}).get("min_base_height"))]
    rows += [(f"generation {k}", v, gen.get(k)) for k, v in s.generation.items()]
    print(f"\n{name}: scaling rules (l = {size.leg_length:.3g} m, h = {size.standing_height:.3g} m, "
          f"{size.mass:.4g} kg, hips {size.hip_spacing:.3g} m, sole {size.sole_length:.3g} × {size.sole_width:.3g} m) "
          "vs its spec (gait: GaitParams defaults, which the spec's studies used)")
    print("| value | rule | spec |")
    print("|---|---|---|")
    for key, rule, spec in rows:
        print(f"| {key} | {rule} | {spec if spec is not None else '(unset)'} |")


def rules(_: argparse.Namespace) -> None:
    for name, (ref, path) in ROBOTS.items():
        if name == "atalante" and not (SHARED / "atalante" / "loadedExo.xml").is_file():
            print("atalante: ../shared/atalante is not beside the repository: skipped")
            continue
        gain_rule(name, ref)
        scale_rules(name, ref, path)


def cli(*argv: str) -> tuple[float, str]:
    t = time.perf_counter()
    out = subprocess.run([sys.executable, "-m", "robustgait.cli", *argv], capture_output=True, text=True, check=False)
    if out.returncode not in (0, 1):
        raise SystemExit(out.stderr)
    return time.perf_counter() - t, out.stdout


def t1(args: argparse.Namespace) -> None:
    if not T1.is_file():
        raise SystemExit(f"{T1} is not here")
    from robustgait import GaitGenerator, load_robot, walk
    from robustgait.config import GaitParams, SimConfig

    out = Path(args.out or tempfile.mkdtemp(prefix="t1-"))
    spec = out / "t1.toml"
    extra = ["--tracking-error", str(args.tracking_error)] if args.tracking_error else []
    secs, text = cli("robot", "init", str(T1), "-o", str(spec), *extra)
    print(f"$ robustgait robot init {T1.name} -o {spec.name} {' '.join(extra)}  ({secs:.2f} s)\n{text}")
    secs, text = cli("robot", "check", str(spec))
    print(f"$ robustgait robot check {spec.name}   ({secs:.2f} s)\n{text}")
    robot = load_robot(spec)
    t = time.perf_counter()
    gen = GaitGenerator(robot)
    print(f"flat-foot generator built in {time.perf_counter() - t:.1f} s")
    space = robot.spec.action_space or {}
    base = robot.default_params
    gaits = [("default", base)]
    for lk in (() if args.default_only else ("low", "high")):
        for dk in ("low", "high"):
            gaits.append((f"length {lk}, duration {dk}", GaitParams(
                step_length=getattr(space["step_length"], lk), step_duration=getattr(space["step_duration"], dk),
                step_width=base.step_width, step_height=base.step_height)))
    print("| gait | L [m] | T [s] | solve | steps | fall | speed [m/s] | RMS [mrad] | max [mrad] | saturation |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for label, params in gaits:
        res = gen.solve(params)
        p = res.params or params
        if res.gait is None:
            print(f"| {label} | {p.step_length:g} | {p.duration:g} | {res.status} | | | | | | |")
            continue
        w = walk(robot, res.gait, SimConfig(step_cap=args.steps))
        tr = w.tracking
        print(f"| {label} | {p.step_length:g} | {p.duration:g} | {res.solve_seconds:.1f} s | {w.steps_taken}/"
              f"{args.steps} | {w.fall_reason or '—'} | {w.mean_speed:.3f} | {1e3 * tr['rms']:.3g} | "
              f"{1e3 * tr['max']:.3g} | {100 * tr['saturation_fraction']:.2g} % |")


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = p.add_subparsers(dest="what", required=True)
    sub.add_parser("rules").set_defaults(func=rules)
    t = sub.add_parser("t1")
    t.add_argument("--steps", type=int, default=50)
    t.add_argument("--out", help="directory of the written spec (default: a temporary one)")
    t.add_argument("--tracking-error", type=float, help="robot init's --tracking-error (default: the config's)")
    t.add_argument("--default-only", action="store_true", help="walk the spec's default gait only")
    t.set_defaults(func=t1)
    args = p.parse_args()
    args.func(args)


if __name__ == "__main__":
    main()
