"""Preference oracles (docs/design.md §7): who wins between two evaluated gaits, decided from simulation.

An oracle maps an :class:`Outcome` to a score; of two gaits the one with the higher score is preferred,
and equal scores give no comparison. The scores are a faithful scalarization of the rules, chosen so
that a study's objective value (what Optuna's tools plot) orders trials exactly as the oracle does:

* ``robustness`` — a gait that walks the step cap beats one that falls; among walkers a certified gait beats one
  without a certificate (its orbit did not settle, is unstable, …) and the higher r* wins; among fallers the one
  with more steps: score = cap + r* for a certified walker, cap − ½ (``study.uncertified_penalty``) for a walker
  without a certificate, steps for a faller (steps ≤ cap − 1 < cap − ½ < cap ≤ cap + r*). A failed generation is a
  faller with 0 steps.
* ``push`` — as ``robustness`` with the push certificate J* [N s] (``certify --disturbance push``) for r*.
* ``stability`` — the paper's baseline: steps only, score = steps taken (r* is ignored, so all the
  gaits that walk the cap tie).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from robustgait.config import Metric
from robustgait.config.study import UNCERTIFIED_PENALTY
from robustgait.errors import RobustGaitError


@dataclass(frozen=True)
class Outcome:
    """What an oracle sees of one evaluated gait: steps completed (0 if generation failed), the step cap
    of the walk, r* (J* for the push metric; 0 when the gait was not certified), and whether it was certified (a
    gait that fell is never certified; only a walker's flag counts)."""

    steps_taken: int
    step_cap: int
    r_star: float = 0.0
    certified: bool = True

    @property
    def walked_cap(self) -> bool:
        return self.steps_taken >= self.step_cap


def score(metric: Metric | str, outcome: Outcome, penalty: float = UNCERTIFIED_PENALTY) -> float:
    """The oracle's scalar: robustness (push) = cap + r* (J*) if the gait walked the cap and was certified, cap −
    ``penalty`` if it walked the cap without a certificate, else steps; stability = steps."""
    if metric in ("robustness", "push"):
        if not outcome.walked_cap:
            return float(outcome.steps_taken)
        return float(outcome.step_cap + outcome.r_star) if outcome.certified else float(outcome.step_cap) - penalty
    if metric == "stability":
        return float(outcome.steps_taken)
    raise RobustGaitError(f"unknown metric {metric!r}")


def prefer(metric: Metric | str, a: Outcome, b: Outcome) -> int:
    """+1 if ``a`` is preferred, −1 if ``b`` is, 0 if the oracle gives no comparison (equal)."""
    sa, sb = score(metric, a), score(metric, b)
    return (sa > sb) - (sa < sb)


def batch_comparisons(scores: Sequence[float]) -> list[tuple[int, int]]:
    """All C(n, 2) pairwise comparisons of a ranked batch as (winner, loser) positions in the batch; ties
    give none. Ordered by (i, j), i < j, so the list is a function of the scores alone."""
    out = []
    for i in range(len(scores)):
        for j in range(i + 1, len(scores)):
            if scores[i] > scores[j]:
                out.append((i, j))
            elif scores[j] > scores[i]:
                out.append((j, i))
    return out
