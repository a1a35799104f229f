"""A person's answer as the page posts it, checked before anything is stored (docs/person.md).

The page posts ``{"iteration": k, "ranking": [[slot, …], …], "labels": {"slot": "good", …}}``: the shown gaits in
tiers, best first (a tier of several: "cannot tell" them apart), and optionally a label per gait. Every problem is
one line the page shows and the log records; :func:`robustgait.study.person.record_answer` then checks the answer
against the pending batch (stale or unknown iteration, a gait omitted or not shown, a second answer) and stores it
once."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from robustgait.study.person import AnswerError
from robustgait.study.ranking import LABELS


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
