"""A person's answer as the page posts it, checked before anything is stored (docs/person.md).

The page posts ``{"iteration": k, "ranking": [[slot, …], …], "labels": {"slot": "good", …}}``: the shown gaits in
tiers, best first (a tier of several: "cannot tell" them apart), and optionally a label per gait. Every problem is
one line the page shows and the log records; :func:`robustgait.study.person.record_answer` then checks the answer
against the pending batch (stale or unknown iteration, a gait omitted or not shown, a second answer) and stores it
once. :func:`store_answer` does both, in that order, for the page."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from robustgait.study.person import AnswerError, answer_size, pending_iteration
from robustgait.study.ranking import LABELS
from robustgait.web.records import StudyRecords


@dataclass(frozen=True)
class PostedAnswer:
    """An answer that is well formed: its iteration (0-based), a rank per slot (None: not ranked) and a label per
    slot (None: none)."""

    iteration: int
    ranks: list[int | None]
    labels: list[str | None]


def _int(v: Any, what: str) -> int:
    if isinstance(v, bool) or not isinstance(v, int):
        raise AnswerError(f"{what}: expected an integer, got {v!r}")
    return v


def parse_answer(payload: Any, batch_size: int) -> PostedAnswer:
    """Check the posted JSON's shape and turn it into ranks and labels per slot; raise :class:`AnswerError` (400)
    naming the problem: a missing or unknown key, a slot outside the batch, a gait ranked twice, an empty tier, a
    label that is not bad/neutral/good."""
    if not isinstance(payload, dict):
        raise AnswerError("the answer must be a JSON object")
    unknown = set(payload) - {"iteration", "ranking", "labels"}
    if unknown:
        raise AnswerError(f"unknown key(s) {', '.join(sorted(unknown))} (expected iteration, ranking, labels)")
    if "iteration" not in payload or "ranking" not in payload:
        raise AnswerError("the answer needs 'iteration' and 'ranking'")
    k = _int(payload["iteration"], "iteration")
    ranking = payload["ranking"]
    if not isinstance(ranking, list) or not ranking:
        raise AnswerError("ranking: expected a non-empty list of tiers (lists of gaits), best first")
    ranks: list[int | None] = [None] * batch_size
    for t, tier in enumerate(ranking):
        if not isinstance(tier, list) or not tier:
            raise AnswerError(f"ranking: tier {t + 1} must be a non-empty list of gaits")
        for v in tier:
            s = _int(v, f"ranking: tier {t + 1}")
            if not 0 <= s < batch_size:
                raise AnswerError(f"ranking: gait {s + 1} is not in the batch of {batch_size}")
            if ranks[s] is not None:
                raise AnswerError(f"ranking: gait {s + 1} is ranked twice")
            ranks[s] = t
    labels: list[str | None] = [None] * batch_size
    raw = payload.get("labels") or {}
    if not isinstance(raw, dict):
        raise AnswerError("labels: expected an object {gait: bad|neutral|good}")
    for key, lab in raw.items():
        try:
            s = int(key)
        except ValueError:
            raise AnswerError(f"labels: {key!r} is not a gait number") from None
        if not 0 <= s < batch_size:
            raise AnswerError(f"labels: gait {s + 1} is not in the batch of {batch_size}")
        if lab is not None and lab not in LABELS:
            raise AnswerError(f"labels: gait {s + 1}: {lab!r} is not one of {', '.join(LABELS)}")
        labels[s] = lab
    return PostedAnswer(k, ranks, labels)


def store_answer(records: StudyRecords, payload: Any, shown: Callable[[], int | None]) -> PostedAnswer:
    """Check the posted JSON ``payload`` and store it as its iteration's answer, ``by`` the person; returns the
    answer stored. ``shown()``: the pending iteration the page shows (its videos rendered), None while none is;
    asked once the payload is parsed. Raises :class:`AnswerError`, nothing stored: 409 for an iteration the study
    does not have or the pending one not shown yet, 400 for a malformed answer (:func:`parse_answer`), and what
    :func:`robustgait.study.person.record_answer` refuses (a stale iteration, a second answer: 409; a gait omitted
    or not shown: 400)."""
    iterations = records.iterations()
    k = payload.get("iteration") if isinstance(payload, dict) else None
    if isinstance(k, int) and not isinstance(k, bool) and k not in iterations:
        raise AnswerError(f"iteration {k + 1} is unknown (the study has {len(iterations)} so far)", 409)
    size = answer_size(iterations.get(k, {})) if isinstance(k, int) else 0
    posted = parse_answer(payload, size)
    if posted.iteration == pending_iteration(iterations) and shown() != posted.iteration:
        raise AnswerError(f"iteration {posted.iteration + 1} is not shown yet", 409)
    records.record_answer(posted.iteration, {"ranks": posted.ranks, "labels": posted.labels, "by": "person"})
    return posted
