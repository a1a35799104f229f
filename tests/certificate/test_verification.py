"""Tests for robustgait.certificate.verification: the verification batches spend β over the attempts, their sizes
and bounds agree, and a budget that cannot hold one batch is refused before any sample (API and command line)."""

from __future__ import annotations

import numpy as np
import pytest

from robustgait.certificate.estimators import certify_map_sequential
from robustgait.certificate.verification import (
    attempt_beta,
    attempt_size,
    check_budget,
    verification_beta,
    verification_bound,
    verification_size,
)
from robustgait.cli import main
from robustgait.config import CertifyConfig, SequentialConfig
from robustgait.errors import RobustGaitError


def test_verification_sizes_spend_beta() -> None:
    assert sum(verification_beta(0.05, a) for a in range(1, 60)) == pytest.approx(0.05)
    for eps, beta in ((0.02, 0.05), (0.1, 0.05), (0.05, 0.01)):
        for a in (1, 2, 5):
            n = verification_size(eps, beta, a)
            assert (1 - eps) ** n <= verification_beta(beta, a) < (1 - eps) ** (n - 1)
            assert verification_bound(n, beta, a) <= eps
            assert (1 - verification_bound(n, beta, a)) ** n == pytest.approx(verification_beta(beta, a))
    assert verification_size(0.02, 0.05, 1) == 183  # ln(0.025) / ln(0.98) = 182.6
    with pytest.raises(ValueError, match="count from 1"):
        verification_size(0.02, 0.05, 0)


def test_a_first_share_spends_beta_and_shrinks_the_first_batch() -> None:
    """β_1 = s β and β_a = (1 − s) β / 2^(a−1) after: Σ β_a = β for any share; s = 0.9 draws 154 pushes first (ε 2 %,
    β 5 %) where s = 0.5 draws 183, and a second batch of 297."""
    for share in (0.5, 0.7, 0.9):
        assert sum(verification_beta(0.05, a, share) for a in range(1, 60)) == pytest.approx(0.05)
        assert verification_beta(0.05, 1, share) == pytest.approx(0.05 * share)
    assert [verification_size(0.02, 0.05, a, 0.9) for a in (1, 2)] == [154, 297]
    assert verification_size(0.02, 0.05, 1, 0.5) == 183
    n = verification_size(0.02, 0.05, 1, 0.9)
    assert verification_bound(n, 0.05, 1, 0.9) <= 0.02


def test_a_certificate_s_attempts_use_its_estimator() -> None:
    """attempt_beta / attempt_size read ε and the first share from the certificate's resolved estimator: a push
    certificate's first share 0.9 (154 pushes), a state certificate's 0.5 (183 states)."""
    push, state = CertifyConfig(), CertifyConfig(disturbance="state")
    assert attempt_size(push, 1) == 154 and attempt_beta(push, 1) == pytest.approx(0.045)
    assert attempt_size(state, 1) == 183 and attempt_beta(state, 2) == pytest.approx(0.0125)


def test_budget_must_hold_a_verification(capsys: pytest.CaptureFixture[str]) -> None:
    """A budget below the first round and one batch is refused in one line naming the field and the figures: by the
    check, by the estimator before any sample, and by the command line (exit 2) before any work."""
    cfg = CertifyConfig(disturbance="state", sequential=SequentialConfig(budget=300))  # the config itself is data
    message = (r"certify.sequential.budget: 300 samples cannot hold the first round \(200\) and one verification "
               r"batch \(183 for epsilon = 0.02, beta = 0.05\)")
    with pytest.raises(RobustGaitError, match=message):
        check_budget(cfg)
    calls = []

    def never(x: np.ndarray) -> np.ndarray:
        calls.append(x)
        return x

    with pytest.raises(RobustGaitError, match=message):
        certify_map_sequential(never, np.zeros(3), cfg)
    assert calls == []
    check_budget(CertifyConfig(method="uniform", sequential=SequentialConfig(budget=300)))  # not the uniform's
    assert main(["certify", "no-such-gait.json", "--robot", "exo", "--override", "certify.sequential.budget=100"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1
    assert "--override certify.sequential.budget=100: 100 samples cannot hold the first round (50)" in err[0]
