"""Does the certificate (J* or r*) predict robustness? Disturbed walks of a gait — pushes, model mismatch, rough
ground, slopes, noise, latency — and the certificate's promise tested (``robustgait validate``,
``docs/validation.md``)."""

from robustgait.validate.disturbances import KINDS, SIZE_LABELS, Draws, draw
from robustgait.validate.run import (
    CertificateRef,
    KindResult,
    ValidationResult,
    Validator,
    simulate_trials,
    validate_gait,
)
from robustgait.validate.stats import (
    Correlation,
    LogisticFit,
    Rate,
    binned_rates,
    logistic_fit,
    spearman,
    wilson_interval,
)

__all__ = ["KINDS", "SIZE_LABELS", "CertificateRef", "Correlation", "Draws", "KindResult", "LogisticFit", "Rate",
           "ValidationResult", "Validator", "binned_rates", "draw", "logistic_fit", "simulate_trials",
           "spearman", "validate_gait", "wilson_interval"]
