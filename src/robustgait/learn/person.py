"""Simulated persons (``--metric simulated-person``; docs/person.md): the oracle of tests and benchmarks that stands in
for a person ranking gaits by what they feel, as CoSpar (Tucker et al., ICRA 2020) and ROIAL (Li et al., RA-L 2021)
evaluate their learners on synthetic users before they meet real ones.

A person has a hidden utility over a gait's comfort figures (``robustgait.sim.comfort``) — a preferred speed and a
dislike of pelvis acceleration and of foot impacts, with person-specific weights drawn from its seed
(:class:`~robustgait.config.SimulatedPersonConfig`) — and answers a batch with a noisy ranking: a Plackett–Luce draw
(each pair in it is ordered as Bradley–Terry says, P(a ≻ b) = σ((u_a − u_b)/noise)), in which two neighbours of
nearly equal utility are merged into one rank ("cannot tell") with probability cannot_tell · exp(−|Δu|/noise).
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from robustgait.config import SimulatedPersonConfig
from robustgait.errors import RobustGaitError

_STREAM = 29  # the seed stream of persons: a value no learner's stream uses, so persons and learners draw apart


@dataclass(frozen=True)
class SimulatedPerson:
    """One simulated person: its preferred speed [m/s] and weights, drawn with :meth:`from_config`."""

    config: SimulatedPersonConfig
    preferred_speed: float
    speed_weight: float
    acceleration_weight: float
    impact_weight: float

    @classmethod
    def from_config(cls, config: SimulatedPersonConfig) -> SimulatedPerson:
        """The person of ``config.seed``: v* and the weights uniform in their configured ranges."""
        rng = np.random.default_rng([config.seed, _STREAM])
        draws = [float(rng.uniform(*r)) for r in (config.preferred_speed, config.speed_weight,
                                                   config.acceleration_weight, config.impact_weight)]
        return cls(config, *draws)

    def utility(self, comfort: Mapping[str, Any] | None) -> float:
        """u = −w_v ((v − v*)/s_v)² − w_a (a_z + a_y)/s_a − w_i i/s_i from a walk's comfort figures (speed, vertical and
        lateral pelvis acceleration RMS, impact in body weights; an impact not measured counts 0); −inf without
        figures (a gait that did not walk the measured steps)."""
        if not comfort or comfort.get("speed") is None:
            return -math.inf
        c = self.config
        speed = (float(comfort["speed"]) - self.preferred_speed) / c.speed_scale
        acc = (float(comfort["pelvis_acc_vertical_rms"]) + float(comfort["pelvis_acc_lateral_rms"])) / (
            c.acceleration_scale)
        impact = float(comfort.get("impact_force_ratio") or 0.0) / c.impact_scale
        return -self.speed_weight * speed**2 - self.acceleration_weight * acc - self.impact_weight * impact

    def rank(self, utilities: Sequence[float], seed: Sequence[int]) -> list[int]:
        """The person's answer for gaits of ``utilities``: a rank per gait (0 the best; equal: cannot tell), drawn
        with a generator seeded from (person seed, ``seed``) — the same question gets the same answer."""
        u = np.asarray(utilities, dtype=float)
        if u.size == 0:
            return []
        if not np.isfinite(u).all():
            raise RobustGaitError("a simulated person is shown a gait without comfort figures")
        rng = np.random.default_rng([self.config.seed, _STREAM, *seed])
        noise = self.config.noise
        order = np.argsort(-(u / noise + rng.gumbel(size=u.size)), kind="stable")  # Plackett–Luce
        ranks = [0] * u.size
        tier = 0
        for prev, cur in itertools.pairwise(order):
            tie = self.config.cannot_tell * math.exp(-abs(u[prev] - u[cur]) / noise)
            if rng.random() >= tie:
                tier += 1
            ranks[int(cur)] = tier
        return ranks
