"""The band of an orbit: where a walk's switching states lie, in coordinates that mean the same on every robot
(``docs/certificate.md``, "The orbit the gait walks" and "Recovery").

**Band coordinates** z (K, d), d = nq + nv − 4: the section state of :func:`.reduced.section_coordinates` (the full
canonical state without the base's x, y and yaw, under which the dynamics are equivariant) made dimensionless by the
robot's pendulum scales (Froude scaling, l the leg length, g gravity): base height / l; roll, pitch and joint angles
in radians; the base's linear velocity (heading frame) / √(g l); its angular velocity and the joint velocities /
√(g / l). One radius then means the same on a 0.5 m humanoid and a 0.9 m exoskeleton.

**A band** of an orbit of period k (in physical steps) is, per phase p = 0 … k − 1 (the state after j steps from the
band's start is in phase j mod k), a centre c_p (d,) and a per-coordinate scatter σ_p (d,) (the largest deviation of
the undisturbed walk's states of that phase from c_p). A state z is *in the band* of phase p when every coordinate
lies within its half-width w_p,i = max(ν, κ σ_p,i) of c_p,i: a floor ν, or κ times the orbit's own scatter where
the undisturbed walk scatters more (an attractor that is a noisy band, not a point). A walk back on its orbit may be
out of phase with it (:meth:`Band.distance_shifted`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from robustgait.certificate.reduced import section_coordinates
from robustgait.robots import Robot

FloatArray = NDArray[np.float64]


def band_scales(robot: Robot) -> FloatArray:
    """The divisors (d,) that make section coordinates dimensionless: [l, 1, 1, 1 × n_q, √(g l) × 3, √(g/l) × 3,
    √(g/l) × n_v] for the base height, roll, pitch, joint coordinates, base linear velocity, base angular velocity and
    joint velocities (l the leg length [m], g gravity [m/s²]); n_q = nq − 7 joint coordinates, n_v = nv − 6 joint
    velocities (they differ by one per ball joint of a closed chain: its quaternion's four against three rates)."""
    s = robot.scale
    rate = math.sqrt(s.gravity / s.leg_length)
    return np.concatenate([[s.leg_length, 1.0, 1.0], np.ones(robot.model.nq - 7), np.full(3, s.speed),
                           np.full(3 + robot.model.nv - 6, rate)])


def band_coordinates(robot: Robot, qpos: FloatArray, qvel: FloatArray) -> FloatArray:
    """z (K, d) of states qpos (K, nq), qvel (K, nv): section coordinates (positions not divided by a duration) over
    :func:`band_scales`. NaN states give NaN rows."""
    qpos, qvel = np.atleast_2d(qpos), np.atleast_2d(qvel)
    return np.asarray(section_coordinates(qpos, qvel, 1.0) / band_scales(robot))


@dataclass(frozen=True)
class Band:
    """The band of an orbit: ``centres`` (k, d) and ``scatter`` (k, d) per phase (band coordinates; module
    docstring), the floor ``radius`` ν and the multiple ``multiple`` κ of the scatter that set each coordinate's
    half-width max(ν, κ σ)."""

    centres: FloatArray
    scatter: FloatArray
    radius: float
    multiple: float

    @property
    def period(self) -> int:
        """Physical steps k of the orbit: the number of phases."""
        return int(self.centres.shape[0])

    @property
    def half_width(self) -> FloatArray:
        """w (k, d) = max(ν, κ σ) per phase and coordinate."""
        return np.maximum(self.radius, self.multiple * self.scatter)

    @property
    def sigma(self) -> float:
        """σ: the orbit's largest scatter over phases and coordinates (band coordinates)."""
        return float(self.scatter.max(initial=0.0))

    def _deviation(self, z: FloatArray, phase: int | NDArray[np.int64]
                   ) -> tuple[FloatArray, NDArray[np.int64], FloatArray]:
        """|z − c_p| (K, d) of states z (K, d) in phase(s) p (an int, or (K,)), the phases (K,), and a factor (K,): 1,
        or NaN for a state with a NaN coordinate."""
        z = np.atleast_2d(z)
        p = np.broadcast_to(np.asarray(phase, dtype=np.int64) % self.period, (z.shape[0],))
        return np.abs(z - self.centres[p]), p, np.where(np.isfinite(z).all(axis=1), 1.0, np.nan)

    def distance(self, z: FloatArray, phase: int | NDArray[np.int64]) -> FloatArray:
        """max_i |z_i − c_p,i| / w_p,i (K,) of states z (K, d) in phase(s) p (an int, or (K,)): ≤ 1 inside the band;
        NaN for a NaN state."""
        dev, p, nan = self._deviation(z, phase)
        with np.errstate(invalid="ignore"):
            return np.asarray(np.max(dev / self.half_width[p], axis=1, initial=0.0) * nan)

    def distance_shifted(self, z: FloatArray, step: int) -> FloatArray:
        """The band distance (K, k) of states z (K, d) after ``step`` steps from the band of phase (step + s) mod k,
        for every shift s = 0 … k − 1 (column 0: in phase, :meth:`distance`). A pushed walk may come back to its orbit
        one or more steps out of phase — a period-2 orbit whose two steps swapped — which is the same orbit; a run of
        states within distance 1 under one shift is a return (:func:`advance_runs`)."""
        return np.stack([self.distance(z, step + s) for s in range(self.period)], axis=1)

    def floor_needed(self, z: FloatArray, phase: int | NDArray[np.int64]) -> FloatArray:
        """The smallest floor ν (K,) under which states z (K, d) of phase(s) p lie in the band: the largest
        |z_i − c_p,i| over the coordinates outside κ σ_p,i (0 when none), since z is inside iff every such deviation is
        ≤ ν. Independent of this band's own ν, so one walk can be judged under every floor; NaN for a NaN state."""
        dev, p, nan = self._deviation(z, phase)
        with np.errstate(invalid="ignore"):
            outside = np.where(dev <= self.multiple * self.scatter[p], 0.0, dev)
            return np.asarray(outside.max(axis=1, initial=0.0) * nan)

    def inside(self, z: FloatArray, phase: int | NDArray[np.int64]) -> NDArray[np.bool_]:
        """Whether states z (K, d) of phase(s) p lie in the band (a NaN state does not)."""
        with np.errstate(invalid="ignore"):
            return np.asarray(self.distance(z, phase) <= 1.0)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready: ν, κ, σ, the period and, per phase, the largest scatter."""
        return {"radius": self.radius, "multiple": self.multiple, "sigma": self.sigma, "period": self.period,
                "phase_sigma": [float(s.max(initial=0.0)) for s in self.scatter]}


def advance_runs(band: Band, run: NDArray[np.int64], z: FloatArray, step: int) -> FloatArray:
    """One step of the recovery count: ``run`` (K, k), the consecutive steps each walk has been in ``band`` under
    each phase shift (:meth:`Band.distance_shifted`), is incremented where the states z (K, d) after ``step`` steps
    are in it and reset elsewhere (a NaN state, a fall, resets), in place; returns their shifted distances (K, k)."""
    shifted = band.distance_shifted(z, step)
    with np.errstate(invalid="ignore"):
        run[:] = np.where(shifted <= 1.0, run + 1, 0)
    return shifted
