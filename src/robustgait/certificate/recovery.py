"""Recovery from a disturbance: has a pushed walk returned to its orbit's neighbourhood? (``docs/certificate.md``,
"Recovery".)

A push certificate that only asks "not fallen yet" certifies pushes after which the robot is still falling: on a
wandering orbit a pushed walk can stand for the certificate's steps and fall later. The push map therefore also asks
that the robot be back near its periodic orbit at the end of those steps: near x* in the base's velocity — its
linear and angular velocity in the heading frame (world axes turned by the base's yaw), the quantities a push
changes and a walking robot must bring back — each scaled to be dimensionless by the robot's own pendulum scales
(Froude scaling: v / √(g l), ω / √(g / l), l the leg length), so that one radius means the same on robots of any
size. Heading and position are not in it: a walking controller without heading feedback keeps the new heading a
push gives it, which is a recovered walk.

The neighbourhood's radius is the larger of a fixed radius ν and a multiple κ of the undisturbed orbit's own scatter
(the largest distance of its section states from x* over a few steps): a gait whose undisturbed states wander is not
asked to return closer than they do.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from robustgait.robots import Robot
from robustgait.rotations import quat_to_mat

FloatArray = NDArray[np.float64]


def heading_velocity(qpos: FloatArray, qvel: FloatArray) -> FloatArray:
    """The base twist in the heading frame (K, 6): [R_z(ψ)ᵀ ṗ, R_z(ψ)ᵀ R ω_B] (linear velocity of the base origin,
    then angular velocity; ψ the base's yaw, R its orientation; MuJoCo's qvel holds ṗ in the world and ω_B in the
    body frame). qpos (K, nq), qvel (K, nv)."""
    qpos, qvel = np.atleast_2d(qpos), np.atleast_2d(qvel)
    out = np.empty((qpos.shape[0], 6))
    for i in range(qpos.shape[0]):
        r = quat_to_mat(qpos[i, 3:7])
        psi = math.atan2(r[1, 0], r[0, 0])
        c, s = math.cos(psi), math.sin(psi)
        rz_t = np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]])
        out[i, :3] = rz_t @ qvel[i, :3]
        out[i, 3:] = rz_t @ (r @ qvel[i, 3:6])
    return out


def froude_scales(robot: Robot) -> FloatArray:
    """(6,) [√(g l)] × 3 [m/s] and [√(g / l)] × 3 [rad/s]: the velocity scales of a walker of leg length l."""
    s = robot.scale
    return np.array([s.speed] * 3 + [math.sqrt(s.gravity / s.leg_length)] * 3)


@dataclass(frozen=True)
class OrbitBand:
    """The neighbourhood of the orbit at x*: ``centre`` the heading-frame base twist of x* (6,), ``scales`` (6,) its
    Froude scales (:func:`froude_scales`), ``radius`` in those scaled units, ``scatter`` the undisturbed orbit's own
    largest scaled distance from x* (what κ multiplies)."""

    centre: FloatArray
    scales: FloatArray
    radius: float
    scatter: float

    @staticmethod
    def of(robot: Robot, star: tuple[FloatArray, FloatArray], undisturbed: FloatArray, radius: float,
           multiple: float) -> OrbitBand:
        """The band of x* = ``star`` (qpos (nq,), qvel (nv,)) from ``undisturbed`` section states (k, nq + nv) of the
        walk from x*: radius = max(``radius`` ν, ``multiple`` κ × their largest distance from x*)."""
        centre = heading_velocity(star[0][None], star[1][None])[0]
        band = OrbitBand(centre, froude_scales(robot), radius, 0.0)
        nq = robot.model.nq
        ok = np.isfinite(undisturbed).all(axis=1)
        scatter = float(band.distance(undisturbed[ok, :nq], undisturbed[ok, nq:]).max(initial=0.0))
        return OrbitBand(centre, band.scales, max(radius, multiple * scatter), scatter)

    def distance(self, qpos: FloatArray, qvel: FloatArray) -> FloatArray:
        """‖(x − x*) / scales‖ (K,) of states (K, nq), (K, nv): the scaled distance of their base twist from x*'s."""
        if np.atleast_2d(qpos).shape[0] == 0:
            return np.empty(0)
        return np.asarray(np.linalg.norm((heading_velocity(qpos, qvel) - self.centre) / self.scales, axis=1))

    def inside(self, qpos: FloatArray, qvel: FloatArray) -> NDArray[np.bool_]:
        """Whether states lie in the band (NaN states: False)."""
        with np.errstate(invalid="ignore"):
            return np.asarray(self.distance(qpos, qvel) <= self.radius)
