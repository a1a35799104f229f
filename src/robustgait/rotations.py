"""Rotation helpers shared by the pipeline (MuJoCo's quaternion order w, x, y, z)."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray


def quat_to_mat(quat: ArrayLike) -> NDArray[np.float64]:
    """Rotation matrices (..., 3, 3) of quaternions (..., 4) in (w, x, y, z) order, normalized first as
    MuJoCo does: R = I + 2w[v]× + 2[v]×², v = (x, y, z)."""
    q = np.asarray(quat, dtype=float)
    w, x, y, z = np.moveaxis(q / np.linalg.norm(q, axis=-1, keepdims=True), -1, 0)
    return np.stack([
        np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], -1),
        np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], -1),
        np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], -1),
    ], -2)


def roll_pitch_yaw(quat: ArrayLike) -> NDArray[np.float64]:
    """Z-Y-X Euler angles (..., 3) = (roll φ, pitch θ, yaw ψ) [rad] of quaternions (..., 4), R = R_z(ψ) R_y(θ) R_x(φ):
    ψ = atan2(R₁₀, R₀₀) (the heading of the body's x axis), θ = asin(−R₂₀), φ = atan2(R₂₁, R₂₂) — roll and pitch are
    the tilts relative to the heading frame, whatever the yaw."""
    r = quat_to_mat(quat)
    return np.stack([np.arctan2(r[..., 2, 1], r[..., 2, 2]), np.arcsin(np.clip(-r[..., 2, 0], -1.0, 1.0)),
                     np.arctan2(r[..., 1, 0], r[..., 0, 0])], -1)
