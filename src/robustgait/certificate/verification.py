"""How large a sequential certificate's verification batches are, and what a passed batch certifies
(``docs/certificate.md``, "The sequential estimator"): β is spent over the verification attempts a = 1, 2, …, and
attempt a's batch is the least n with (1 − ε)^n ≤ β_a."""

from __future__ import annotations

import math

from robustgait.config import CertifyConfig
from robustgait.errors import RobustGaitError


def verification_beta(beta: float, attempt: int, first_share: float = 0.5) -> float:
    """β_a: the part of β spent on verification attempt a ≥ 1 of the sequential estimator, β_1 = s β and
    β_a = (1 − s) β / 2^(a−1) for a ≥ 2, s = ``first_share`` ∈ (0, 1) (Σ_a β_a = β; s = ½ gives β / 2^a).
    Raises ValueError for a < 1."""
    if attempt < 1:
        raise ValueError(f"verification attempts count from 1, got {attempt}")
    if attempt == 1:
        return beta * first_share
    return beta * (1.0 - first_share) * 0.5 ** (attempt - 1)


def verification_size(epsilon: float, beta: float, attempt: int, first_share: float = 0.5) -> int:
    """n_a = ⌈ln β_a / ln(1 − ε)⌉: the least batch with (1 − ε)^{n_a} ≤ β_a (:func:`verification_beta`)."""
    n = math.log(verification_beta(beta, attempt, first_share)) / math.log1p(-epsilon)
    return max(1, math.ceil(n - 1e-9))  # the slack absorbs rounding when n is an integer


def verification_bound(n: int, beta: float, attempt: int, first_share: float = 0.5) -> float:
    """ε_a = 1 − β_a^{1/n}: the bound certified by n fresh uniform samples that all satisfy (attempt a; β_a of
    :func:`verification_beta` with ``first_share``). Raises RobustGaitError for n < 1."""
    if n < 1:
        raise RobustGaitError(f"a verification batch has at least one sample, got {n}")
    return float(-math.expm1(math.log(verification_beta(beta, attempt, first_share)) / n))


def attempt_beta(config: CertifyConfig, attempt: int) -> float:
    """β_a of ``config``'s verification attempt a (:func:`verification_beta` with its estimator's ``first_share``)."""
    return verification_beta(config.beta, attempt, config.estimator.first_share)


def attempt_size(config: CertifyConfig, attempt: int) -> int:
    """n_a of ``config``'s verification attempt a (:func:`verification_size` with its estimator's ``epsilon`` and
    ``first_share``)."""
    est = config.estimator
    return verification_size(est.epsilon, config.beta, attempt, est.first_share)


def check_budget(config: CertifyConfig, where: str = "certify") -> None:
    """Refuse a sequential certificate whose ``sequential.budget`` cannot hold its first round and one verification
    batch (:func:`attempt_size`): it could never issue a statement. One line naming ``where``.sequential.budget and
    the figures; nothing for the uniform estimator (its sample count is ``n_samples``)."""
    if config.method != "sequential":
        return
    est = config.estimator
    need = est.first_round + attempt_size(config, 1)
    if est.budget < need:
        raise RobustGaitError(f"{where}.sequential.budget: {est.budget} samples cannot hold the first round "
                              f"({est.first_round}) and one verification batch ({need - est.first_round} for "
                              f"epsilon = {est.epsilon:g}, beta = {config.beta:g})")
