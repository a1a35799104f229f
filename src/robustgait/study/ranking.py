"""How a study ranks a batch (docs/studies.md, docs/person.md): the oracle's scores, lowered for a gait that fails one
of the study's requirements (``study.require``), or a person's answer, in which only the gaits certified at or above
the robustness floor and meeting the requirements were shown — the others rank below every shown gait, among
themselves by the certificate's oracle — and, across batches, the person's ordinal labels (good ≻ neutral ≻ bad).

Everything here reads stored records only: the learner's history is reproduced from the database on resume."""

from __future__ import annotations

import operator
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from robustgait.config import StudyConfig, parse_requirement
from robustgait.config.study import FIGURE_ALIASES
from robustgait.errors import RobustGaitError
from robustgait.learn.history import History
from robustgait.learn.oracle import Outcome, person_scores, score
from robustgait.sim.comfort import FIGURES
from robustgait.study.outcome import RANKED, EvaluationStatus, ranked_figure, status_of
from robustgait.study.storage import TrialRecord

LABELS = ("bad", "neutral", "good")  # a person's ordinal labels, worst first (ROIAL's)
OUTCOME_FIGURES = ("value", "steps_taken", "mean_speed")  # value: the certificate's verified figure
_OPS: dict[str, Callable[[float, float], bool]] = {">=": operator.ge, "<=": operator.le, ">": operator.gt,
                                                   "<": operator.lt}


def figure_names(param_names: Sequence[str]) -> tuple[str, ...]:
    """What a requirement may name: the comfort figures, the outcome's and the gait parameters
    (:meth:`Requirement.parse` also takes the names of :data:`FIGURE_ALIASES`)."""
    return (*FIGURES, *OUTCOME_FIGURES, *param_names)


@dataclass(frozen=True)
class Requirement:
    """``figure op value`` (``speed >= 0.2``); ``figure`` is the recorded figure's name (an alias of
    :data:`~robustgait.config.study.FIGURE_ALIASES` resolved: ``j_star >= 10`` checks the certificate's ``value``)."""

    text: str
    figure: str
    op: str
    value: float

    @classmethod
    def parse(cls, text: str, names: Sequence[str]) -> Requirement:
        figure, op, value = parse_requirement(text)
        if figure not in names:
            figure = FIGURE_ALIASES.get(figure, figure)
        if figure not in names:
            raise RobustGaitError(f"study.require: {text!r}: no figure {figure!r} is recorded (one of "
                                  f"{', '.join(names)})")
        return cls(text.strip(), figure, op, value)

    def holds(self, params: Mapping[str, float], result: Mapping[str, Any]) -> bool:
        """Whether the evaluated gait meets it; a figure that was not measured (a gait that fell) does not."""
        v = figure_value(self.figure, params, result)
        return v is not None and _OPS[self.op](v, self.value)


def requirements(config: StudyConfig, param_names: Sequence[str]) -> list[Requirement]:
    """The study's requirements, each checked against the recorded figures (a one-line error for an unknown one)."""
    names = figure_names(param_names)
    return [Requirement.parse(t, names) for t in config.require]


def figure_value(name: str, params: Mapping[str, float], result: Mapping[str, Any]) -> float | None:
    """A recorded figure of an evaluated gait: a comfort figure; ``value`` (the certificate's verified figure: a study
    with a requirement on it verifies every gait), ``steps_taken``, ``mean_speed``; a gait parameter. None when it was
    not measured."""
    if name in params:
        return float(params[name])
    if name in OUTCOME_FIGURES:
        v = result.get(name)
    else:
        v = (result.get("comfort") or {}).get(name)
    return None if v is None else float(v)


def meets(r: TrialRecord, reqs: Sequence[Requirement]) -> bool:
    """Whether a stored evaluation meets every requirement."""
    return all(q.holds(r.params, r.result or {}) for q in reqs)


def outcome_of(r: TrialRecord, ranks_verified: bool, reqs: Sequence[Requirement] = ()) -> Outcome:
    """The oracle's view of a stored evaluation: its figure the one the study ranks by
    (:func:`~robustgait.study.outcome.ranked_figure`); certified: its ``status`` is one with a certificate figure,
    verified or estimated (:data:`~robustgait.study.outcome.RANKED`); meets: the requirements."""
    res = r.result or {}
    return Outcome(int(res["steps_taken"]), int(res["step_cap"]), ranked_figure(res, ranks_verified),
                   status_of(res) in RANKED, meets(r, reqs))


def study_score(config: StudyConfig, r: TrialRecord, reqs: Sequence[Requirement] = ()) -> float:
    """The study's oracle score of a stored evaluation — recomputed from it whenever a study is resumed (the history
    the learner reproduces), with the study's own ``uncertified_penalty``."""
    return score(config.metric, outcome_of(r, config.verifies_all, reqs), config.uncertified_penalty)


def shown(r: TrialRecord, floor: float, reqs: Sequence[Requirement]) -> bool:
    """Whether a person may be shown this gait: certified, its verified certificate at or above the floor,
    requirements met."""
    res = r.result or {}
    v = res.get("value")
    return status_of(res) == EvaluationStatus.CERTIFIED and v is not None and v >= floor and meets(r, reqs)


def batch_scores(config: StudyConfig, batch: Sequence[TrialRecord], record: Mapping[str, Any],
                 reqs: Sequence[Requirement]) -> list[float]:
    """The scores that rank a batch: the oracle's (:func:`~robustgait.learn.oracle.score`), or for a person study the
    stored answer's (:func:`~robustgait.learn.oracle.person_scores`: shown gaits by their rank, above the others)."""
    fallback = [study_score(config, r, reqs) for r in batch]
    if not config.asks_a_person:
        return fallback
    answer = record.get("answer")
    if answer is None:
        raise RobustGaitError(f"iteration {batch[0].iteration if batch else '?'} has no answer yet")
    return person_scores(answer["ranks"], fallback)


def label_comparisons(batches: Mapping[int, Sequence[TrialRecord]], iterations: Mapping[int, Mapping[str, Any]],
                      k: int) -> list[tuple[tuple[int, int], tuple[int, int]]]:
    """Comparisons from a person's ordinal labels of iterations < k: a gait labelled better than another of an earlier
    or later batch is preferred to it (within a batch the ranking decides). As (iteration, slot) pairs."""
    labelled = [((i, s), LABELS.index(lab)) for i in range(k)
                for s, lab in enumerate((iterations.get(i, {}).get("answer") or {}).get("labels") or [])
                if lab is not None]
    return [(a, b) for a, la in labelled for b, lb in labelled if a[0] != b[0] and la > lb]


def history_before(k: int, batches: Mapping[int, Sequence[TrialRecord]], config: StudyConfig,
                   iterations: Mapping[int, Mapping[str, Any]] | None = None,
                   reqs: Sequence[Requirement] = ()) -> History:
    """The learner's history: iterations 0..k−1 (each must be complete), ranked by the study's oracle (a person study:
    by the stored answers, with the comparisons of their labels). A person study's iteration i holds
    ``config.batch_size(i)`` evaluated candidates or more (``person.overdraw``): every one of them is ranked."""
    iterations = iterations or {}
    ranked = []
    for i in range(k):
        batch, size = batches.get(i, []), config.batch_size(i)
        if len(batch) < size or (len(batch) > size and not config.asks_a_person):
            raise RobustGaitError(f"iteration {i} has {len(batch)} of {size} trials complete")
        scores = batch_scores(config, batch, iterations.get(i, {}), reqs)
        ranked.append([(r.index, s) for r, s in zip(batch, scores, strict=True)])
    extra = label_comparisons(batches, iterations, k) if config.asks_a_person else []
    return History.from_batches(ranked, extra)
