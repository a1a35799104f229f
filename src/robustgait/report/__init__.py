"""Figures and reports from certificates, walks and validations."""

from robustgait.report.figures import outcome_masks, plot_barrier_trace, plot_certificate
from robustgait.report.validation import plot_validation

__all__ = ["outcome_masks", "plot_barrier_trace", "plot_certificate", "plot_validation"]
