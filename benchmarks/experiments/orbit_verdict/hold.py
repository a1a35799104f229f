"""The orbit rule's hold test, as it is and two variants that accept more.

The rule (:class:`robustgait.certificate.orbit.Watch`) finds a band, then watches it hold ``orbit.hold_steps`` steps:
every window's phase centres must stay within ``orbit.settle_multiple`` × max(``orbit.floor``, σ) of the band's. On
a gait whose band is tight (σ of a few thousandths) that allows a few thousandths, where the band a pushed walk must
come back to is max(ν, κ σ) wide (ν = ``push.recovery_radius``). Variants:

* ``band``: each coordinate's centre may move up to that half-width (:class:`BandHold`);
* ``horizon``: a window that moved more than today's bound but within the half-width does not decide; the walk is
  watched to ``--horizon`` (300) steps and holds if every later window stays within the half-width and it does not
  fall (:class:`HorizonHold`).

Per gait: the undisturbed walk of ``--steps`` (300) steps, whether it fell, each rule's verdict on its switching
states (the same states for all) with the step it answered at, and every hold window's largest centre move from the
band (``moves``: first step, move, move / half-width), one JSON line each:

    python benchmarks/experiments/orbit_verdict/hold.py SPEC 'DIR/*.json' [--steps 300]
    python benchmarks/experiments/orbit_verdict/hold.py --exo-slopes   # exo's stored gait on tilted floors
"""

from __future__ import annotations

import argparse
import glob
import json
import sys
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))  # benchmarks/common.py
from common import git_commit
from robustgait import Config, load_gait, load_robot
from robustgait.certificate import orbit as rule
from robustgait.certificate.band import band_coordinates
from robustgait.certificate.orbit import canonical_event_states
from robustgait.sim import walk


class BandHold(rule.Watch):
    """The orbit rule with the hold test against the band's half-width max(ν, κ σ) per coordinate."""

    def hold_window(self, centres: np.ndarray) -> tuple[float, float] | None:
        assert self.found is not None
        ratio = float((np.abs(centres - self.found.band.centres) / self.found.band.half_width).max())
        return (ratio, 1.0) if ratio > 1.0 else None


class HorizonHold(rule.Watch):
    """The orbit rule with a hold window that moved within the band's half-width watched on to ``horizon`` steps."""

    horizon = 300

    def __init__(self, *args: Any) -> None:
        super().__init__(*args)
        self.wandered = False

    @property
    def done(self) -> bool:
        if self.found is not None and self.left is None and self.wandered:
            return self.steps >= self.horizon
        return bool(super().done)

    def hold_window(self, centres: np.ndarray) -> tuple[float, float] | None:
        assert self.found is not None
        band = self.found.band
        dev = np.abs(centres - band.centres)
        if (dev / band.half_width).max() > 1.0:
            return float(dev.max()), 1.0
        if super().hold_window(centres) is not None:
            self.wandered = True
        return None


def verdict(watch: rule.Watch, z: np.ndarray, fell: str | None) -> str:
    """The rule's status on z and the step it answered at (a walk that fell before its answer: its fall)."""
    for row in z:
        if watch.add(row):
            break
    done = watch.done
    return f"{watch.orbit(None if done else fell)[0].status.value}@{watch.steps}"


def window_moves(watch: rule.Watch, z: np.ndarray) -> tuple[float | None, list[tuple[int, float, float]]]:
    """Today's allowed move (settle_multiple × max(floor, σ) of the band found) and every whole window after the band
    was found: its first step, the largest move of its phase centres from the band's, and that move over the
    half-width (the largest ratio over coordinates)."""
    found = next((i for i, row in enumerate(z) if watch.add(row) or watch.found is not None), None)
    f = watch.found
    if found is None or f is None:
        return None, []
    w, out = watch.cfg.window, []
    for s in range(found + 1, len(z) - w + 1, w):
        steps = watch.first_step + s + np.arange(w)
        centres, _ = rule.phase_stats(z[s:s + w], steps, f.period)
        dev = np.abs(centres - f.band.centres)
        out.append((int(steps[0]), round(float(dev.max()), 4), round(float((dev / f.band.half_width).max()), 3)))
    return round(watch.cfg.settle_multiple * max(watch.cfg.floor, f.band.sigma), 4), out


def judge(robot: Any, gait: Any, cfg: Config, steps: int, label: str) -> dict[str, Any]:
    c = cfg.certify
    w = walk(robot, gait, cfg.sim, steps=steps)
    q, v = canonical_event_states(robot, gait, w.events)
    z = band_coordinates(robot, q, v)
    period = rule.min_period(robot, c.map)

    def watch(cls: type[rule.Watch]) -> rule.Watch:
        return cls(c.orbit, period, c.push.recovery_radius, c.push.recovery_scatter)

    fell = w.fall_reason if w.fell else None
    allowed, moves = window_moves(watch(rule.Watch), z)
    return {"commit": git_commit(), "robot": robot.name, "gait": label, "steps": w.steps_taken, "fell": w.fell,
            **{name: verdict(watch(cls), z, fell) for name, cls in (("now", rule.Watch), ("band", BandHold),
                                                                    ("horizon", HorizonHold))},
            "allowed_now": allowed, "moves": moves}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("spec", nargs="?")
    ap.add_argument("gaits", nargs="?", help="a glob of gait files")
    ap.add_argument("--steps", type=int, default=300)
    ap.add_argument("--exo-slopes", action="store_true", help="exo's stored gait on floors tilted by (slope, "
                    "azimuth off downhill) = (3.5°, 6°) (the slow test's gait that falls at 245), (3°, 6°), "
                    "(2.5°, 6°), (3.5°, 3°), (3.5°, 10°)")
    args = ap.parse_args()
    cfg = Config()
    if args.exo_slopes:
        gait_file = Path(__file__).resolve().parents[3] / "tests" / "data" / "exo_gait.json"
        for slope, azimuth in ((3.5, 6.0), (3.0, 6.0), (2.5, 6.0), (3.5, 3.0), (3.5, 10.0)):
            robot = load_robot("exo")  # a model of its own: gravity tilted
            s, a = np.radians(slope), np.radians(azimuth)
            robot.model.opt.gravity[:] = 9.81 * np.array([np.sin(s) * np.cos(a), np.sin(s) * np.sin(a), -np.cos(s)])
            print(json.dumps(judge(robot, load_gait(gait_file, robot), cfg, args.steps,
                                   f"exo_gait slope {slope} azimuth {azimuth}")), flush=True)
        return
    if args.spec is None or args.gaits is None:
        ap.error("give SPEC and a glob of gait files, or --exo-slopes")
    robot = load_robot(args.spec)
    for path in sorted(glob.glob(args.gaits)):
        print(json.dumps(judge(robot, load_gait(path, robot), cfg, args.steps, Path(path).name)), flush=True)


if __name__ == "__main__":
    main()
