"""Tracking controller (docs/design.md §5): joint PD on the Bézier outputs, optionally + feedforward torque.

The robot's actuators are affine servos u = kp (c − q) − kd q̇ (see :mod:`robustgait.robots.spec`). With
the control c chosen as

    c(t) = y_d(τ) + (kd ẏ_d(τ) + u_ff(τ)) / kp,   τ = (t − t₀) / T,

the applied torque is exactly u = kp (y_d − q) + kd (ẏ_d − q̇) + u_ff, clamped to the torque limits. The
control depends on time alone (time-based phase), so one step's controls are one (H, m) time series shared
by every sample until its switching event.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from robustgait.bezier import bezier, bezier_derivative
from robustgait.errors import RobustGaitError
from robustgait.gait import Gait
from robustgait.robots import Robot


def desired_outputs(gait: Gait, tau: NDArray[np.float64], domain: int = 0
                    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """y_d and dy_d/dt of domain ``domain`` of a gait at phases τ (K,) of that domain: (K, m) each.

    Past τ = 1 the outputs continue along their tangent at τ = 1, y_d(τ) = y_d(1) + ẏ_d(1) (τ − 1) T, so a
    swing foot that has not touched down yet keeps descending at its landing velocity (docs/design.md §4:
    touchdown margin) instead of hovering.
    """
    dom = gait.domains[domain]
    tau = np.asarray(tau, dtype=float)
    t = np.clip(tau, 0.0, 1.0)
    y = bezier(dom.beta, t)
    dy = bezier_derivative(dom.beta, t) / dom.duration
    late = tau > 1.0
    y[late] += dy[late] * ((tau[late] - 1.0) * dom.duration)[:, None]
    return y, dy


def feedforward_torque(gait: Gait, tau: NDArray[np.float64], domain: int = 0) -> NDArray[np.float64]:
    """u_ff(τ) (K, m): a domain's feedforward torques, linearly interpolated in τ (zero if it has none)."""
    dom = gait.domains[domain]
    t = np.clip(tau, 0.0, 1.0)
    if dom.ff_tau is None or dom.ff_torque is None:
        return np.zeros((t.size, dom.beta.shape[0]))
    return np.stack([np.interp(t, dom.ff_tau, dom.ff_torque[:, j]) for j in range(dom.ff_torque.shape[1])],
                    axis=-1)


def step_controls(robot: Robot, gait: Gait, n_steps: int, *, feedforward: bool = True,
                  domain: int = 0) -> NDArray[np.float64]:
    """Servo controls c_k (n_steps, nu) for physics steps k = 0..n_steps−1 of a domain that starts at τ = 0.

    c_k = y_d(τ_k) + (kd ẏ_d(τ_k) + u_ff(τ_k)) / kp with τ_k = k Δt / T_d (module docstring) for the planned joints;
    a held joint's servo holds its angle (:meth:`Robot.servo_controls`). ``gait`` must be written for the stance of
    this step (use :meth:`Gait.mirrored` for the other leg).
    """
    if not 0 <= domain < len(gait.domains):
        raise RobustGaitError(f"the gait has {len(gait.domains)} domains, no domain {domain}")
    tau = np.arange(n_steps, dtype=np.float64) * (robot.dt / gait.domains[domain].duration)
    y, dy = desired_outputs(gait, tau, domain)
    u = feedforward_torque(gait, tau, domain) if feedforward else 0.0
    return robot.servo_controls(y + (robot.kd * dy + u) / robot.kp)


@dataclass
class TrackingStats:
    """Tracking totals over physics steps (per joint, output order): ``steps`` controlled, ``saturation`` the steps
    whose commanded torque exceeded the joint's torque limit (the servo clamps it), ``error_sq`` the sum of
    (q − y_d)², ``error_max`` the largest |q − y_d|. Filled by the feedback engine from its law, or by
    :func:`pd_tracking` from a recorded PD trajectory (the same definitions)."""

    steps: int = 0
    saturation: NDArray[np.int64] | None = None
    error_sq: NDArray[np.float64] | None = None
    error_max: NDArray[np.float64] | None = None

    def add(self, steps: int, saturation: NDArray[np.int64], error_sq: NDArray[np.float64],
            error_max: NDArray[np.float64]) -> None:
        self.steps += int(steps)
        self.saturation = saturation.copy() if self.saturation is None else self.saturation + saturation
        self.error_sq = error_sq.copy() if self.error_sq is None else self.error_sq + error_sq
        self.error_max = error_max.copy() if self.error_max is None else np.maximum(self.error_max, error_max)

    @property
    def rms(self) -> NDArray[np.float64]:
        """RMS tracking error per joint [rad]."""
        assert self.error_sq is not None
        return np.asarray(np.sqrt(self.error_sq / max(self.steps, 1)))

    def summary(self) -> dict[str, float]:
        """Scalars: RMS over all joints [rad], the largest error [rad], the saturation count (joint-steps) and
        fraction."""
        if self.error_sq is None or self.saturation is None or self.error_max is None:
            return {"steps": 0, "rms": 0.0, "max": 0.0, "saturation": 0, "saturation_fraction": 0.0}
        return {"steps": self.steps, "rms": float(np.sqrt(self.error_sq.sum() / max(self.steps, 1)
                                                          / self.error_sq.size)),
                "max": float(self.error_max.max()), "saturation": int(self.saturation.sum()),
                "saturation_fraction": float(self.saturation.sum() / max(self.steps * self.saturation.size, 1))}

    def reset(self) -> None:
        self.steps, self.saturation, self.error_sq, self.error_max = 0, None, None, None


def pd_tracking(robot: Robot, gait: Gait, before: NDArray[np.float64], domain: int = 0, *,
                feedforward: bool = True, controls: NDArray[np.float64] | None = None
                ) -> tuple[int, NDArray[np.int64], NDArray[np.float64], NDArray[np.float64]]:
    """Tracking of the servo PD over one recorded domain: ``before`` (n, nstate) are the full-physics states at the
    start of its physics steps k = 0..n−1 (MuJoCo's ``mjSTATE_FULLPHYSICS``: time, qpos, qvel, ...), ``gait`` the
    gait of this step's stance. At each: e = q − y_d(τ_k) and the commanded torque τ = kp (y_d − q) + kd (ẏ_d − q̇)
    + u_ff (the PD the servos apply before their clamp) — or, given the applied ``controls`` (n, nu) of those steps
    (the step regulator's references), the servos' τ = kp (c − q) − kd q̇ —, saturated when |τ| exceeds the torque
    limit. Returns
    (n, saturation (m,), Σ e² (m,), max |e| (m,)) for :meth:`TrackingStats.add`."""
    n = before.shape[0]
    nq = robot.model.nq
    q = before[:, 1 + robot.qpos_idx]
    qd = before[:, 1 + nq + robot.dof_idx]
    tau_k = np.arange(n, dtype=np.float64) * (robot.dt / gait.domains[domain].duration)
    y, dy = desired_outputs(gait, tau_k, domain)
    if controls is not None:  # the servos' own law on the applied controls: u = kp (c − q) − kd q̇
        m = q.shape[1]
        u = robot.kp * (controls[:n, :m] - q) - robot.kd * qd
    else:
        u = robot.kp * (y - q) + robot.kd * (dy - qd)
        if feedforward:
            u = u + feedforward_torque(gait, tau_k, domain)
    e = q - y
    return (n, (np.abs(u) > robot.torque_limit).sum(axis=0), (e * e).sum(axis=0),
            np.abs(e).max(axis=0, initial=0.0))
