"""Figures and reports from certificates, walks and studies."""

from robustgait.report.figures import outcome_masks, plot_barrier_trace, plot_certificate
from robustgait.report.study import write_study_report

__all__ = ["outcome_masks", "plot_barrier_trace", "plot_certificate", "write_study_report"]
