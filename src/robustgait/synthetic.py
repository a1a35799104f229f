"""Batched maps with known answers, to check an estimator of r* and its confidence statement (docs/design.md §6).

Both maps contract by ``gain`` < √(1 − α) around x* (such a sample never violates the DTBF condition, for
either barrier) except on a violating set where the sample falls (NaN image: violated for every r ≥ d, for
either barrier). Only the volume fraction of the violating set in a ball matters, and it is known exactly:

* :class:`ConeMap` — a thin cone of directions beyond a radius r0: the true r* is r0 (for r0 < r_max).
* :class:`BandMap` — thin bands of directions whose width grows with the distance, so that the violating
  fraction of B(r) is a + (3/4) c r at every r (n = 3): with c = 0 every ball has fraction a and the true
  r* is 0, which makes every certificate with ε < a wrong — the case that tests a confidence statement.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from robustgait.errors import RobustGaitError

FloatArray = NDArray[np.float64]


def _check_gain(gain: float) -> None:
    if not 0.0 <= gain < 0.97:  # < √(1 − α) for α ≤ 0.05: the contracting part never violates
        raise RobustGaitError(f"gain must be in [0, 0.97), got {gain!r}")


@dataclass(frozen=True)
class ConeMap:
    """P(x) = x* + gain (x − x*), except that x falls when ‖x − x*‖ > r0 and the angle between x − x* and
    ``axis`` is below ``half_angle`` [rad]. True r* = r0; violating fraction of B(r):
    f (1 − (r0/r)^n)₊ with f the cone's share of directions ((1 − cos θ)/2 for n = 3)."""

    x_star: FloatArray
    r0: float
    half_angle: float
    axis: FloatArray = field(default_factory=lambda: np.array([1.0, 2.0, 2.0]) / 3.0)
    gain: float = 0.5

    def __post_init__(self) -> None:
        _check_gain(self.gain)
        if np.asarray(self.x_star).shape != (3,) or np.asarray(self.axis).shape != (3,):
            raise RobustGaitError("ConeMap is 3-D: x_star and axis must have shape (3,)")
        if not (self.r0 > 0.0 and 0.0 < self.half_angle < math.pi / 2):
            raise RobustGaitError("need r0 > 0 and 0 < half_angle < π/2")

    @property
    def r_star(self) -> float:
        return float(self.r0)

    @property
    def cone_fraction(self) -> float:
        return (1.0 - math.cos(self.half_angle)) / 2.0

    def violating_fraction(self, r: float) -> float:
        return 0.0 if r <= self.r0 else self.cone_fraction * (1.0 - (self.r0 / r) ** 3)

    def __call__(self, x: ArrayLike) -> FloatArray:
        dx = np.asarray(x, dtype=np.float64) - self.x_star
        d = np.linalg.norm(dx, axis=1)
        axis = np.asarray(self.axis) / np.linalg.norm(self.axis)
        inside_cone = dx @ axis > math.cos(self.half_angle) * d
        out = self.x_star + self.gain * dx
        out[(d > self.r0) & inside_cone] = np.nan
        return np.asarray(out, dtype=np.float64)


@dataclass(frozen=True)
class BandMap:
    """P(x) = x* + gain (x − x*), except that x falls when frac(K (u_z + 1)/2) < a + c ‖x − x*‖, u = the unit
    direction of x − x* (K = ``bands``). For uniform directions in 3-D u_z ~ U(−1, 1) (Archimedes), so a
    fraction a + c d of the sphere of radius d falls and the violating fraction of B(r) is a + (3/4) c r."""

    x_star: FloatArray
    a: float
    c: float = 0.0
    bands: int = 40
    gain: float = 0.5
    r_max: float = 2.0

    def __post_init__(self) -> None:
        _check_gain(self.gain)
        if np.asarray(self.x_star).shape != (3,):
            raise RobustGaitError("BandMap is 3-D: x_star must have shape (3,)")
        if not (0.0 <= self.a and 0.0 <= self.c and self.a + self.c * self.r_max <= 1.0 and self.bands >= 1):
            raise RobustGaitError("need a, c ≥ 0, a + c r_max ≤ 1 and bands ≥ 1")

    @property
    def r_star(self) -> float:
        return 0.0 if self.a > 0.0 or self.c > 0.0 else float(self.r_max)

    def violating_fraction(self, r: float) -> float:
        return self.a + 0.75 * self.c * r if r > 0.0 else self.a

    def __call__(self, x: ArrayLike) -> FloatArray:
        dx = np.asarray(x, dtype=np.float64) - self.x_star
        d = np.linalg.norm(dx, axis=1)
        uz = dx[:, 2] / np.where(d > 0.0, d, 1.0)
        falls = np.mod(self.bands * (uz + 1.0) / 2.0, 1.0) < self.a + self.c * d
        out = self.x_star + self.gain * dx
        out[falls] = np.nan
        return np.asarray(out, dtype=np.float64)
