"""Figures and reports from certificates and walks."""

from robustgait.report.figures import outcome_masks, plot_barrier_trace, plot_certificate

__all__ = ["outcome_masks", "plot_barrier_trace", "plot_certificate"]
