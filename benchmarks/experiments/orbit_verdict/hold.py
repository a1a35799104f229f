"""The orbit rule's hold test, as it is and with the band's own half-width as the move it allows.

The rule (:class:`robustgait.certificate.orbit.Watch`) finds a band, then watches it hold ``orbit.hold_steps`` steps:
every window's phase centres must stay within ``orbit.settle_multiple`` × max(``orbit.floor``, σ) of the band's. On
a gait whose band is tight (σ of a few thousandths) that allows a few thousandths, where the band a pushed walk must
come back to is max(ν, κ σ) wide (ν = ``push.recovery_radius``). The variant here allows each coordinate's centre a
move up to that half-width. Per gait file: the undisturbed walk of ``--steps`` (300) steps, whether it fell, and the
verdict of each rule on its switching states (the same states for both), one JSON line each:

    python benchmarks/experiments/orbit_verdict/hold.py SPEC 'DIR/*.json' [--steps 300]
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
from robustgait.sim import walk
from robustgait.sim.walk import canonical_event_states


class BandHold(rule.Watch):
    """The orbit rule with the hold test against the band's half-width max(ν, κ σ) per coordinate."""

    def add(self, z: Any) -> bool:
        if self.found is None or self.done:
            return super().add(z)
        self.z.append(np.asarray(z, dtype=float))
        cfg, f = self.cfg, self.found
        if self.held % cfg.window == 0:
            w = np.array(self.z[-cfg.window:])
            steps = self.steps - cfg.window + 1 + np.arange(cfg.window)
            centres, _ = rule.phase_stats(w, steps, f.period)
            ratio = float((np.abs(centres - f.band.centres) / f.band.half_width).max())
            if ratio > 1.0:
                self.left = (int(steps[0]), ratio, 1.0)
        return self.done


def verdict(watch: rule.Watch, z: np.ndarray) -> str:
    for row in z:
        if watch.add(row):
            break
    return str(watch.orbit(None)[0].status.value)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("spec")
    ap.add_argument("gaits", help="a glob of gait files")
    ap.add_argument("--steps", type=int, default=300)
    args = ap.parse_args()
    cfg = Config()
    c = cfg.certify
    robot = load_robot(args.spec)
    period = rule.min_period(robot, c.map)
    for path in sorted(glob.glob(args.gaits)):
        gait = load_gait(path, robot)
        w = walk(robot, gait, cfg.sim, steps=args.steps)
        q, v = canonical_event_states(robot, gait, w.events)
        z = band_coordinates(robot, q, v)
        watches = {name: cls(c.orbit, period, c.push.recovery_radius, c.push.recovery_scatter)
                   for name, cls in (("now", rule.Watch), ("band", BandHold))}
        row = {"commit": git_commit(), "robot": robot.name, "gait": Path(path).name, "steps": w.steps_taken,
               "fell": w.fell} | {name: verdict(watch, z) for name, watch in watches.items()}
        print(json.dumps(row), flush=True)


if __name__ == "__main__":
    main()
