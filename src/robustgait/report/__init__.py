"""Figures and reports from certificates, walks, validations and studies."""

from robustgait.report.figures import outcome_masks, plot_barrier_trace, plot_certificate
from robustgait.report.study import write_study_report
from robustgait.report.validation import plot_validation

__all__ = ["outcome_masks", "plot_barrier_trace", "plot_certificate", "plot_validation", "write_study_report"]
