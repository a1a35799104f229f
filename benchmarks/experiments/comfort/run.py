"""Comfort figures of a walk (docs/comfort.md): the figures of the default exo gait and the Atalante FROST gait, what
the low-pass does to the pelvis acceleration and jerk, how long a touchdown's impact lasts, and what measuring costs.

    python benchmarks/experiments/comfort/run.py figures [--steps 50]        # the table of docs/comfort.md
    python benchmarks/experiments/comfort/run.py filter [--steps 50]         # raw 1 kHz differences against low-passed
    python benchmarks/experiments/comfort/run.py impact                      # impact force against the window \\
        after touchdown
    python benchmarks/experiments/comfort/run.py timing [--repeat 7]         # a 50-step walk with and without comfort

Gaits: tests/data/exo_gait.json (the default ``robustgait gait generate --robot exo`` gait) on exo, and
../shared/atalante/jt_bez_2023-09-10.yaml on robots/atalante/spec.toml (skipped when absent). Walks of ``--steps``
steps with the default ComfortConfig (steps 6–25 measured).
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from robustgait import SimConfig, load_gait, load_robot, walk
from robustgait.config import ComfortConfig
from robustgait.gait import Gait
from robustgait.robots import Robot
from robustgait.rotations import roll_pitch_yaw
from robustgait.sim.comfort import FIGURES, lowpass, peak, rms

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))  # benchmarks/common.py
from common import ATALANTE_GAIT, ATALANTE_SPEC, EXO_GAIT, EXO_MULTICONTACT_GAIT, git_commit


def gaits() -> list[tuple[str, Robot, Gait]]:
    out = []
    exo = load_robot("exo")
    out.append(("exo, default gait", exo, load_gait(EXO_GAIT, exo)))
    if ATALANTE_GAIT.is_file():
        atalante = load_robot(ATALANTE_SPEC)
        out.append(("Atalante, FROST gait", atalante, load_gait(ATALANTE_GAIT, atalante)))
    else:
        print(f"({ATALANTE_GAIT} absent: Atalante skipped)")
    return out


def header() -> None:
    commit = git_commit()
    load = Path("/proc/loadavg").read_text().split()[0] if Path("/proc/loadavg").is_file() else "?"
    print(f"{time.strftime('%Y-%m-%d')}, commit {commit}, load average {load}")


def figures(steps: int) -> None:
    """Every figure of the default ComfortConfig, one column per gait (markdown)."""
    rows = [(name, robot, walk(robot, gait, SimConfig(step_cap=steps), comfort=ComfortConfig()))
            for name, robot, gait in gaits()]
    print("| figure | unit | " + " | ".join(n for n, _, _ in rows) + " |")
    print("|---|---|" + "---|" * len(rows))
    for key, (unit, _) in FIGURES.items():
        cells = []
        for _, _, res in rows:
            c = res.comfort
            v = None if c is None else getattr(c, key)
            if v is not None and unit == "rad":
                cells.append(f"{v:.4f} ({math.degrees(v):.2f}°)")
            else:
                cells.append("—" if v is None else f"{v:.4g}")
        print(f"| `{key}` | {unit} | " + " | ".join(cells) + " |")
    for name, robot, res in rows:
        c = res.comfort
        assert c is not None
        x = [e.qpos[0] for e in res.events[:11]]
        lengths = np.diff(x)
        print(f"{name}: step lengths of steps 2–11 [m]: " + ", ".join(f"{v:.4f}" for v in lengths))
        worst = max(c.torque_peak_joint, key=lambda j: c.torque_peak_joint[j])
        print(f"{name}: {res.steps_taken} steps walked ({res.fall_reason or 'no fall'}), measured steps "
              f"{c.first_step}–{c.first_step + c.steps - 1}, {c.touchdowns} touchdowns, mass {robot.mass:.1f} kg; "
              f"largest torque at {worst} ({c.torque_peak_joint[worst]:.4g} N m)")


def filtering(steps: int) -> None:
    """RMS and peak of the pelvis acceleration and jerk over the measured steps: raw 1 kHz finite differences against
    the zero-phase Butterworth low-pass at several cutoffs."""
    cfg = ComfortConfig()
    for name, robot, gait in gaits():
        res = walk(robot, gait, SimConfig(step_cap=steps), keep_trajectory=True)
        tr = res.trajectory
        assert tr is not None
        nq, dt = robot.model.nq, robot.dt
        t0 = res.events[cfg.skip_steps - 1].time
        t1 = res.events[cfg.skip_steps + cfg.steps - 1].time
        v = tr[:, 1 + nq:1 + nq + 3]
        yaw = roll_pitch_yaw(tr[:-1, 4:8])[:, 2]
        raw = np.diff(v, axis=0) / dt
        c, s = np.cos(yaw), np.sin(yaw)
        raw = np.stack([c * raw[:, 0] + s * raw[:, 1], -s * raw[:, 0] + c * raw[:, 1], raw[:, 2]], -1)
        window = (tr[1:, 0] > t0) & (tr[1:, 0] <= t1)
        print(f"\n{name}: steps {cfg.skip_steps + 1}–{cfg.skip_steps + cfg.steps}, RMS / peak "
              "(acceleration m/s², jerk m/s³; forward, lateral, vertical)")
        print("| low-pass | acceleration RMS | acceleration peak | jerk RMS | jerk peak |")
        print("|---|---|---|---|---|")
        for cutoff in (None, 50.0, 30.0, 20.0, 10.0, 5.0):
            a = raw if cutoff is None else lowpass(raw, dt, cutoff, cfg.filter_order)
            j = np.diff(a, axis=0) / dt if cutoff is None else np.gradient(a, dt, axis=0)
            aw, jw = a[window], j[window[:j.shape[0]]]
            cells = [" / ".join(f"{x:.3g}" for x in f(arr)) for arr in (aw,) for f in (rms, peak)]
            cells += [" / ".join(f"{x:.3g}" for x in f(arr)) for arr in (jw,) for f in (rms, peak)]
            label = "none (raw 1 kHz differences)" if cutoff is None else f"{cutoff:g} Hz"
            print(f"| {label} | " + " | ".join(cells) + " |")


def impact() -> None:
    """The impact force (largest per-touchdown peak of the landing sole's normal force) for growing windows after
    touchdown: the window must hold the peak, and a longer one must find nothing larger. Also exo's multi-contact
    gait (tests/data/exo_multicontact_gait.json), whose touchdown is the heel strike."""
    windows = (0.001, 0.002, 0.005, 0.01, 0.02, 0.05, 0.1, 0.2, 0.3)
    print("| gait | " + " | ".join(f"{1e3 * w:g} ms" for w in windows) + " |")
    print("|---|" + "---|" * len(windows))
    exo = load_robot("exo")
    multicontact = ("exo, multi-contact gait", exo, load_gait(EXO_MULTICONTACT_GAIT,
                                                               exo))
    for name, robot, gait in [*gaits(), multicontact]:
        cells = []
        for w in windows:
            c = walk(robot, gait, SimConfig(step_cap=30), comfort=ComfortConfig(impact_window=w)).comfort
            assert c is not None and c.impact_force is not None
            cells.append(f"{c.impact_force:.0f} N ({c.impact_force_ratio:.2f})")
        print(f"| {name} | " + " | ".join(cells) + " |")


def timing(repeat: int) -> None:
    """A 50-step walk with and without its comfort figures: process CPU time (least of ``repeat``: the machine is
    shared) and wall time (median)."""
    for name, robot, gait in gaits():
        cfg = SimConfig(step_cap=50)
        cpu: dict[str, list[float]] = {"without": [], "with": []}
        wall: dict[str, list[float]] = {"without": [], "with": []}
        for _ in range(repeat):
            for key, comfort in (("without", None), ("with", ComfortConfig())):
                c0, w0 = time.process_time(), time.perf_counter()
                walk(robot, gait, replace(cfg), comfort=comfort)
                cpu[key].append(time.process_time() - c0)
                wall[key].append(time.perf_counter() - w0)
        a, b = min(cpu["without"]), min(cpu["with"])
        print(f"{name}: CPU {a:.3f} s without, {b:.3f} s with comfort (+{100 * (b / a - 1):.1f} %); wall median "
              f"{np.median(wall['without']):.3f} / {np.median(wall['with']):.3f} s ({repeat} runs each)")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("what", choices=("figures", "filter", "impact", "timing"))
    ap.add_argument("--steps", type=int, default=50)
    ap.add_argument("--repeat", type=int, default=7)
    args = ap.parse_args()
    header()
    if args.what == "figures":
        figures(args.steps)
    elif args.what == "filter":
        filtering(args.steps)
    elif args.what == "impact":
        impact()
    else:
        timing(args.repeat)


if __name__ == "__main__":
    main()
