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
* ``person``, ``simulated-person`` — a person ranks the batch (:func:`person_scores`); the score of a trial, which
  also ranks the gaits a person is not shown, is the certificate's (as ``push``/``robustness``).

Requirements (``study.require``): a gait that fails one ranks below every gait that meets them all — its score is
lowered by :data:`REQUIREMENT_PENALTY`, more than any score can be (scores are below cap + certificate, both at most
10⁶ by their limits), so failing gaits keep their order among themselves.
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
    of the walk, the certificate's figure the study ranks by (``figure``: r* for the robustness metric, J* for the push
    metric; 0 when the gait was not certified), and whether it was certified (a gait that fell is never certified; only
    a walker's flag counts)."""

    steps_taken: int
    step_cap: int
    figure: float = 0.0
    certified: bool = True
    meets: bool = True  # the study's requirements (study.require) hold

    @property
    def walked_cap(self) -> bool:
        return self.steps_taken >= self.step_cap


REQUIREMENT_PENALTY = 1e7


def score(metric: Metric | str, outcome: Outcome, penalty: float = UNCERTIFIED_PENALTY) -> float:
    """The oracle's scalar: robustness (push, and the person metrics) = cap + r* (J*) if the gait walked the cap and was
    certified, cap − ``penalty`` if it walked the cap without a certificate, else steps; stability = steps; minus
    :data:`REQUIREMENT_PENALTY` for a gait that fails a requirement."""
    if metric in ("robustness", "push", "person", "simulated-person"):
        if not outcome.walked_cap:
            base = float(outcome.steps_taken)
        else:
            base = (float(outcome.step_cap + outcome.figure) if outcome.certified
                    else float(outcome.step_cap) - penalty)
    elif metric == "stability":
        base = float(outcome.steps_taken)
    else:
        raise RobustGaitError(f"unknown metric {metric!r}")
    return base if outcome.meets else base - REQUIREMENT_PENALTY


def person_scores(ranks: Sequence[int | None], fallback: Sequence[float]) -> list[float]:
    """Scores of a batch ranked by a person, for :func:`batch_comparisons`: ``ranks[i]`` is the rank of slot i among
    the shown gaits (0 the best; equal ranks: "cannot tell"), None for a gait not shown (below the floor or failing a
    requirement), which ranks below every shown one and among those by its ``fallback`` score (the certificate's,
    :func:`score`). Shown: max(fallback) + 1 + (worst rank − rank)."""
    if len(ranks) != len(fallback):
        raise RobustGaitError(f"{len(ranks)} ranks for a batch of {len(fallback)}")
    shown = [r for r in ranks if r is not None]
    top = max(fallback, default=0.0) + 1.0
    worst = max(shown, default=0)
    return [float(f) if r is None else top + (worst - r) for r, f in zip(ranks, fallback, strict=True)]


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
