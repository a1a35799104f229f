"""The Hybrid Linear Inverted Pendulum (H-LIP) and its step-to-step stepping law (``docs/simulation.md``, "Step-to-step
balance").

Reference: X. Xiong and A. D. Ames, "3-D Underactuated Bipedal Walking via H-LIP Based Gait Synthesis and Stepping
Stabilization", IEEE Transactions on Robotics 38(4), 2022, doi:10.1109/TRO.2022.3150219 (arXiv:2101.09588).

Model, per horizontal direction: x = [p, v], p the centre of mass (CoM) relative to the stance contact [m], v its
velocity [m/s]; the CoM height z0 above the contact is constant and λ = √(g / z0) [1/s].

* single support (SSP): ẋ = A_S x, A_S = [[0, 1], [λ², 0]];
* double support (DSP) of duration T_D: the velocity is constant, x ← [[1, T_D], [0, 1]] x;
* foot switch with step u (new stance contact minus old) [m]: p ← p − u.

Sampled at the pre-impact instant of each step, the step-to-step (S2S) dynamics are linear,
x_{k+1} = A x_k + B u_k, and the stepping law u_k = u* + K (x_k − x*) places the next foot from the error of the
CoM state against the orbit's. Every function below is one equation of the model; none depends on a robot.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray


def pendulum_rate(z0: float, gravity: float) -> float:
    """λ = √(g / z0) [1/s]: the H-LIP's rate, from the CoM height z0 [m] above the contact and |g| [m/s²]."""
    if z0 <= 0.0 or gravity <= 0.0:
        raise ValueError(f"the pendulum needs z0 > 0 and g > 0, got z0 = {z0}, g = {gravity}")
    return math.sqrt(gravity / z0)


def ssp_flow(lam: float, t: NDArray[np.float64] | float) -> NDArray[np.float64]:
    """e^{A_S t} = [[cosh λt, sinh(λt)/λ], [λ sinh λt, cosh λt]] (…, 2, 2): the SSP flow over times t (…) [s]."""
    t = np.asarray(t, dtype=float)
    c, s = np.cosh(lam * t), np.sinh(lam * t)
    return np.stack([np.stack([c, s / lam], axis=-1), np.stack([lam * s, c], axis=-1)], axis=-2)


def s2s_matrices(lam: float, t_ssp: float, t_dsp: float) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The S2S dynamics x_{k+1} = A x_k + B u_k between pre-impact instants (Xiong & Ames 2022, eq. of the H-LIP
    S2S): A = e^{A_S T_S} [[1, T_D], [0, 1]] (2, 2), B = e^{A_S T_S} [−1, 0]ᵀ (2,)."""
    flow = ssp_flow(lam, t_ssp)
    return flow @ np.array([[1.0, t_dsp], [0.0, 1.0]]), flow @ np.array([-1.0, 0.0])


def deadbeat_gain(lam: float, t_ssp: float, t_dsp: float) -> NDArray[np.float64]:
    """The deadbeat stepping gain K = [1, T_D + coth(λ T_S) / λ] (2,): (A + B K)² = 0, so an error of the S2S state
    dies within two steps (det(A + BK) = 1 − k1 and tr(A + BK) = c (2 − k1) + λ s (T_D − k2), c = cosh λT_S,
    s = sinh λT_S, both zero)."""
    return np.array([1.0, t_dsp + 1.0 / (lam * math.tanh(lam * t_ssp))])


def lqr_gain(a: NDArray[np.float64], b: NDArray[np.float64], z0: float, lam: float) -> NDArray[np.float64]:
    """The discrete LQR stepping gain K = (R + BᵀPB)⁻¹ BᵀPA (2,), sign chosen so that u = u* + K (x − x*), with P
    the solution of the discrete Riccati equation of (A, B) and the dimensionless weights Q = diag(1/z0², 1/(λ z0)²),
    R = 1/z0²."""
    from scipy.linalg import solve_discrete_are

    q = np.diag([1.0 / z0**2, 1.0 / (lam * z0) ** 2])
    r = np.array([[1.0 / z0**2]])
    p = solve_discrete_are(a, b[:, None], q, r)
    return np.asarray(-(b @ p @ a) / (r[0, 0] + b @ p @ b))


def closed_loop_radius(a: NDArray[np.float64], b: NDArray[np.float64], k: NDArray[np.float64]) -> float:
    """Spectral radius of A + B K: the S2S error's contraction per step under the stepping law (< 1: stable)."""
    return float(np.max(np.abs(np.linalg.eigvals(a + np.outer(b, k)))))


def period1_orbit(lam: float, t_ssp: float, t_dsp: float, speed: float
                  ) -> tuple[NDArray[np.float64], float]:
    """The period-1 orbit at walking speed v_d [m/s] (sagittal): u* = v_d T, T = T_S + T_D, and x* = (I − A)⁻¹ B u*
    = [v*/σ1, v*] with σ1 = λ coth(λ T_S / 2) and v* = v_d T / (2/σ1 + T_D). Returns (x* (2,), u*)."""
    sigma1 = lam / math.tanh(lam * t_ssp / 2.0)
    u = speed * (t_ssp + t_dsp)
    v = u / (2.0 / sigma1 + t_dsp)
    return np.array([v / sigma1, v]), u


def period2_orbit(lam: float, t_ssp: float, t_dsp: float, speed: float, u_left: float
                  ) -> tuple[NDArray[np.float64], NDArray[np.float64], float, float]:
    """The period-2 orbit (lateral: left and right stance alternate) with u_L + u_R = 2 v_d T and a chosen u_L:
    x_L* = (I − A²)⁻¹ (A B u_L + B u_R), x_R* = A x_L* + B u_L. Returns (x_L* (2,), x_R* (2,), u_L, u_R)."""
    a, b = s2s_matrices(lam, t_ssp, t_dsp)
    u_right = 2.0 * speed * (t_ssp + t_dsp) - u_left
    x_left = np.linalg.solve(np.eye(2) - a @ a, a @ b * u_left + b * u_right)
    return np.asarray(x_left, dtype=float), np.asarray(a @ x_left + b * u_left, dtype=float), u_left, u_right


def predicted_preimpact(lam: float, x: NDArray[np.float64], t_left: NDArray[np.float64] | float
                        ) -> NDArray[np.float64]:
    """x̂⁻ = e^{A_S t_left} x (…, 2): the pre-impact state the SSP flow reaches from x (…, 2) in the t_left (…) [s]
    left of the step (t_left ≤ 0 is taken as 0: the state itself)."""
    flow = ssp_flow(lam, np.maximum(t_left, 0.0))
    # elementwise, not a BLAS product: a batch's rows are then bit for bit the rows computed one by one
    return np.stack([flow[..., 0, 0] * x[..., 0] + flow[..., 0, 1] * x[..., 1],
                     flow[..., 1, 0] * x[..., 0] + flow[..., 1, 1] * x[..., 1]], axis=-1)


def step_correction(k: NDArray[np.float64], lam: float, error: NDArray[np.float64],
                    t_left: NDArray[np.float64] | float) -> NDArray[np.float64]:
    """Δu = K e^{A_S t_left} (x − x*) (…,) [m]: the change of the next step from the CoM state error x − x* (…, 2)
    measured t_left (…) [s] before the nominal pre-impact instant, x* the orbit's state at the same instant."""
    x = predicted_preimpact(lam, error, t_left)
    return np.asarray(k[0] * x[..., 0] + k[1] * x[..., 1])
