"""How the report marks what it plots and prints: a gait's certificate figure as verified or as an estimate
(:mod:`robustgait.study.outcome`), each evaluation outcome's colour and marker, a label with its unit."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

from matplotlib.axes import Axes

from robustgait.study.outcome import EvaluationStatus, known_figure

OUTCOME_COLORS = {EvaluationStatus.CERTIFIED.value: "tab:green", EvaluationStatus.ESTIMATED.value: "tab:cyan",
                  EvaluationStatus.NOT_CERTIFIED.value: "tab:olive", EvaluationStatus.FELL.value: "tab:red",
                  EvaluationStatus.GENERATION_FAILED.value: "0.3"}
OUTCOME_MARKERS = {EvaluationStatus.CERTIFIED.value: "o", EvaluationStatus.ESTIMATED.value: "^",
                   EvaluationStatus.NOT_CERTIFIED.value: "s", EvaluationStatus.FELL.value: "x",
                   EvaluationStatus.GENERATION_FAILED.value: "+"}
OUTCOME_LABELS = {EvaluationStatus.CERTIFIED.value: "certified (verified)",
                  EvaluationStatus.ESTIMATED.value: "estimated (not verified)",
                  EvaluationStatus.NOT_CERTIFIED.value: "refused (0)", EvaluationStatus.FELL.value: "fell (0)",
                  EvaluationStatus.GENERATION_FAILED.value: "generation failed (0)"}


def labelled(text: str, unit: str) -> str:
    """``text [unit]``, or ``text`` alone for a dimensionless figure (an empty unit)."""
    return f"{text} [{unit}]" if unit else text


def plotted_figure(entry: Mapping[str, Any]) -> float:
    """The certificate figure a plot puts a gait at: the verified value, else its estimate, else 0 (no certificate:
    :func:`~robustgait.study.outcome.known_figure`)."""
    v = known_figure(entry)
    return 0.0 if v is None else v


def plot_marked(ax: Axes, xs: Sequence[float], entries: Sequence[Mapping[str, Any] | None], *, label: str,
                color: str, ls: str = "-") -> None:
    """A line through ``entries``' certificate figures (:func:`plotted_figure`) at ``xs`` (None entries skipped), each
    point marked as what it is: a filled dot where verified, a hollow triangle where only estimated (its own legend
    entry)."""
    pts = [(x, e) for x, e in zip(xs, entries, strict=True) if e is not None]
    if not pts:
        return
    ax.plot([x for x, _ in pts], [plotted_figure(e) for _, e in pts], ls, color=color, lw=1.5, label=label)
    verified = [(x, plotted_figure(e)) for x, e in pts if e.get("verified")]
    estimated = [(x, plotted_figure(e)) for x, e in pts if not e.get("verified") and known_figure(e) is not None]
    if verified:
        ax.plot(*zip(*verified, strict=True), "o", color=color, ms=6)
    if estimated:
        ax.plot(*zip(*estimated, strict=True), "^", color=color, mfc="white", ms=7,
                label=f"{label}: estimate, not verified")
