"""The certified map on reduced states: P^K(x̄) = Φ(Δ^K(ι(x̄))), batched (``docs/certificate.md``, "The maps").

Δ is the full-state map of the orbit's period (:class:`.returnmap.FullStateMap`), ι the reconstruction of a full
state from a reduced one and Φ the reduced coordinates (:class:`.reduced.ReducedState`, set up at x*), K the
certificate's ``horizon``. A sample that falls within the K maps is a NaN row.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

from robustgait.certificate.reduced import ReducedState
from robustgait.certificate.returnmap import FullStateMap

FloatArray = NDArray[np.float64]


class ReducedMap:
    """P^K: (N, n) → (N, n) on the reduced state ``reduced`` (set up at x*), K = ``horizon`` maps of ``fmap``; NaN rows
    where the sample fell. The iterates P^1 … P^K of the last call are kept in ``last_path`` (K, N, n)."""

    def __init__(self, fmap: FullStateMap, reduced: ReducedState, horizon: int):
        self.fmap, self.reduced, self.horizon = fmap, reduced, horizon
        self.last_path: FloatArray | None = None

    @property
    def dim(self) -> int:
        return self.reduced.dim

    @property
    def physics_steps(self) -> int:
        return self.fmap.physics_steps

    def reconstruct(self, xbar: FloatArray) -> tuple[FloatArray, FloatArray]:
        """ι(x̄): full canonical states (N, nq), (N, nv) from reduced states (N, n)."""
        return self.reduced.iota(np.atleast_2d(np.asarray(xbar, dtype=float)))

    def __call__(self, xbar: FloatArray, progress: Callable[[int], None] | None = None) -> FloatArray:
        """P^K(x̄) for a batch (N, n); ``progress`` on the last map's last phase."""
        red = self.reduced
        qpos, qvel = self.reconstruct(xbar)
        path = np.full((self.horizon, qpos.shape[0], red.dim), np.nan)
        for j in range(self.horizon):
            qpos, qvel, _ = self.fmap(qpos, qvel, progress=progress if j == self.horizon - 1 else None)
            ok = np.isfinite(qvel).all(axis=1)
            if ok.any():
                path[j, ok] = red.phi(qpos[ok], qvel[ok])
        self.last_path = path
        return path[-1].copy()
