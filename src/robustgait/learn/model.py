"""The preference model (docs/design.md §7): a Gaussian-process utility over the normalized action grid, learned
from pairwise comparisons with the logistic likelihood and the Laplace approximation of the posterior
(BoTorch :class:`~botorch.models.PairwiseGP` with ``PairwiseLogitLikelihood``), and exact joint draws from
that posterior for Thompson sampling.

Prior: f ~ GP(0, k), k(x, x') = s² exp(−½ Σ_d (x_d − x'_d)² / ℓ_d²) (squared exponential with fixed
per-dimension lengthscales ℓ in normalized units, as POLAR uses). Likelihood of "w preferred to l":
P = σ(f_w − f_l) with σ the logistic function. POLAR writes σ((f_w − f_l)/c) with a preference noise c and
a signal variance s²_POLAR; the two are the same model with s² = s²_POLAR / c².
"""

from __future__ import annotations

import contextlib
import warnings
from collections.abc import Iterator, Sequence
from typing import Any

import numpy as np
import torch
from numpy.typing import NDArray

from robustgait.config import PreferenceModelConfig
from robustgait.errors import RobustGaitError

FloatArray = NDArray[np.float64]


@contextlib.contextmanager
def torch_threads(n: int = 1) -> Iterator[None]:
    """Run the block with ``n`` torch threads (restored after). The model's matrices are small (at most
    a thousand rows): one thread beats torch's default pool on a shared machine, where the pool's threads
    compete with the simulation workers (docs/studies.md)."""
    old = torch.get_num_threads()
    torch.set_num_threads(n)
    try:
        yield
    finally:
        torch.set_num_threads(old)


@contextlib.contextmanager
def numpy_seeded(seed: int) -> Iterator[None]:
    """Seed NumPy's global generator for the block and restore it after: PairwiseGP perturbs the start of
    its MAP search with ``np.random`` (botorch/models/pairwise_gp.py, ``_update``), which would otherwise make
    the posterior depend on whatever ran before."""
    state = np.random.get_state()  # noqa: NPY002 - BoTorch draws from the legacy global generator
    np.random.seed(seed % 2**32)  # noqa: NPY002
    try:
        yield
    finally:
        np.random.set_state(state)  # noqa: NPY002


def _kernel(cfg: PreferenceModelConfig, dim: int) -> Any:
    from gpytorch.kernels import RBFKernel, ScaleKernel

    k = ScaleKernel(RBFKernel(ard_num_dims=dim))
    k.base_kernel.lengthscale = torch.tensor([cfg.lengthscales(dim)], dtype=torch.float64)
    k.outputscale = torch.tensor(cfg.outputscale, dtype=torch.float64)
    for p in k.parameters():
        p.requires_grad_(False)
    return k.to(torch.float64)


def preference_model(x: FloatArray, comparisons: Sequence[tuple[int, int]], cfg: PreferenceModelConfig,
                     seed: int = 0) -> Any:
    """The Laplace posterior of the utility given datapoints ``x`` (n, d) (normalized, unique rows) and
    comparisons (winner, loser) as row indices of ``x``; with no comparisons, the prior. Returns a BoTorch
    :class:`PairwiseGP` (eval mode). ``seed`` fixes the MAP search's random start (see :func:`numpy_seeded`)."""
    from botorch.models import PairwiseGP
    from botorch.models.likelihoods.pairwise import PairwiseLogitLikelihood

    dim = x.shape[1]
    lik = PairwiseLogitLikelihood()
    if not comparisons:
        model = PairwiseGP(None, None, likelihood=lik, covar_module=_kernel(cfg, dim), jitter=cfg.jitter)
        return model.eval()
    X = torch.as_tensor(x, dtype=torch.float64)
    C = torch.as_tensor(np.asarray(comparisons, dtype=np.int64))
    with numpy_seeded(seed), warnings.catch_warnings():
        warnings.simplefilter("ignore")  # BoTorch's numerical notes (jitter added, fsolve progress)
        if cfg.hyperparameters == "fixed":
            model = PairwiseGP(X, C, likelihood=lik, covar_module=_kernel(cfg, dim), jitter=cfg.jitter)
        else:
            from botorch.exceptions.errors import ModelFittingError
            from botorch.fit import fit_gpytorch_mll
            from botorch.models.pairwise_gp import PairwiseLaplaceMarginalLogLikelihood

            model = PairwiseGP(X, C, likelihood=lik, jitter=cfg.jitter)
            with torch.random.fork_rng():  # the fit's restarts draw from torch's global generator
                torch.manual_seed(seed % 2**63)
                try:
                    fit_gpytorch_mll(PairwiseLaplaceMarginalLogLikelihood(model.likelihood, model))
                except ModelFittingError:  # keep the fixed hyperparameters rather than stop a study
                    model = PairwiseGP(X, C, likelihood=lik, covar_module=_kernel(cfg, dim), jitter=cfg.jitter)
    return model.eval()


def posterior_mean_cov(model: Any, x: FloatArray) -> tuple[torch.Tensor, torch.Tensor]:
    """Joint posterior of the utility at the rows of ``x`` (n, d): mean (n,) and covariance (n, n)."""
    with torch.no_grad(), warnings.catch_warnings():
        warnings.simplefilter("ignore")
        mvn = model.posterior(torch.as_tensor(x, dtype=torch.float64)).mvn
        return mvn.mean.reshape(-1).detach(), mvn.covariance_matrix.detach()


def posterior_mean(model: Any, x: FloatArray, chunk: int = 2048) -> FloatArray:
    """Posterior mean of the utility at the rows of ``x`` (n, d), in joint chunks of ≤ ``chunk`` points."""
    parts = [posterior_mean_cov(model, x[i:i + chunk])[0].numpy() for i in range(0, len(x), chunk)]
    return np.concatenate(parts) if parts else np.zeros(0)


def cholesky_root(cov: torch.Tensor, jitter: float = 1e-6) -> torch.Tensor:
    """L with L Lᵀ = Σ + δ I, δ = ``jitter`` · mean(diag Σ), escalated ×10 (up to 5 times) while Σ + δ I is
    numerically indefinite (Laplace covariances of nearly duplicate points are)."""
    eye = torch.eye(cov.shape[0], dtype=cov.dtype)
    base = float(torch.diagonal(cov).mean().clamp_min(1e-12))
    for k in range(6):
        chol, info = torch.linalg.cholesky_ex(cov + eye * base * jitter * 10**k)
        if int(info) == 0:
            return chol
    raise RobustGaitError("the posterior covariance is not positive definite (Thompson sampling)")


def thompson_draws(mean: torch.Tensor, root: torch.Tensor, n_draws: int, generator: torch.Generator
                   ) -> torch.Tensor:
    """Joint draws from the posterior N(μ, Σ) over n points: f = μ + L z, z ~ N(0, I_n) from ``generator``,
    with L a square root of Σ (L Lᵀ = Σ, :func:`cholesky_root`).

    Shapes: mean (n,), root (n, n) → (n_draws, n). POLAR's ThompsonSampling.m draws ``mean + sigma * X``
    with ``sigma`` the posterior covariance Σ itself (post_update.m: ``sigma = inv(hessian)``), i.e. from
    N(μ, Σ²): too narrow where the variances are below 1, too wide where they are above. This uses L.
    """
    z = torch.randn(n_draws, mean.shape[0], generator=generator, dtype=root.dtype)
    return mean[None, :] + z @ root.T
