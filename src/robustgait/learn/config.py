"""Configuration of the learners (plain data: no torch here, so study configs load without it)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal

import numpy as np

from robustgait.errors import RobustGaitError

LearnerName = Literal["polar", "eubo", "random"]
LEARNERS: tuple[LearnerName, ...] = ("polar", "eubo", "random")


@dataclass(frozen=True)
class PreferenceModelConfig:
    """Hyperparameters of the preference GP.

    lengthscale: ℓ per action dimension (or one for all) in normalized units (a fraction of each axis'
    range); outputscale: s², the prior variance of the utility in units of the logistic likelihood's
    scale; hyperparameters: ``fixed`` (POLAR: the values above) or ``fit`` (BoTorch's default priors,
    maximized Laplace marginal likelihood by ``fit_gpytorch_mll`` — each iteration); jitter: added to
    the diagonal of covariances before Cholesky factorizations (relative to s²).
    """

    lengthscale: tuple[float, ...] = (0.4,)
    outputscale: float = 10.0
    hyperparameters: str = "fixed"
    jitter: float = 1e-6

    def __post_init__(self) -> None:
        if not self.lengthscale or any(not (np.isfinite(v) and v > 0) for v in self.lengthscale):
            raise RobustGaitError(f"lengthscales must be positive, got {self.lengthscale}")
        if not (np.isfinite(self.outputscale) and self.outputscale > 0):
            raise RobustGaitError(f"outputscale must be positive, got {self.outputscale}")
        if self.hyperparameters not in ("fixed", "fit"):
            raise RobustGaitError(f"hyperparameters must be 'fixed' or 'fit', got {self.hyperparameters!r}")

    def lengthscales(self, dim: int) -> tuple[float, ...]:
        if len(self.lengthscale) == 1:
            return self.lengthscale * dim
        if len(self.lengthscale) != dim:
            raise RobustGaitError(f"{len(self.lengthscale)} lengthscales for a {dim}-dimensional action space")
        return self.lengthscale



@dataclass(frozen=True)
class LearnerConfig:
    """Options of the learners.

    model: the preference GP. max_candidates: Thompson sampling draws jointly over the whole grid when it
    has at most this many points, else over this many (visited + neighbourhood of the best + uniformly
    random). neighbourhood: grid steps around the current best kept in the subset. max_redraws: draws per
    batch slot before taking the best point of the last draw not yet in the batch. eubo_samples: quasi-MC
    samples of qEUBO.
    """

    model: PreferenceModelConfig = field(default_factory=PreferenceModelConfig)
    max_candidates: int = 1000
    neighbourhood: int = 1
    max_redraws: int = 50
    eubo_samples: int = 256

    def __post_init__(self) -> None:
        if self.max_candidates < 2 or self.neighbourhood < 0 or self.max_redraws < 1 or self.eubo_samples < 1:
            raise RobustGaitError("need max_candidates ≥ 2, neighbourhood ≥ 0, max_redraws ≥ 1, eubo_samples ≥ 1")
