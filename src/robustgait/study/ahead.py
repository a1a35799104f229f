"""Evaluations ahead of a person's answer (docs/person.md).

While a person ranks iteration k, the study's workers evaluate the gaits the learner would propose for iteration
k + 1 if the person answered as the learner's preference model predicts (:func:`robustgait.study.person.
predicted_answer`). An evaluation depends only on the gait's parameters and the configuration
(:mod:`robustgait.study.evaluate`), so an evaluation made ahead *is* the one iteration k + 1 needs whenever the real
proposal holds its gait; one that is never proposed is never stored in the study. Nothing is stored until a trial
takes it: a study killed while it waits loses the speculation and nothing else.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

from robustgait.study.executors import Executor

Result = dict[str, Any]


class Ahead:
    """Speculative evaluations on the study's executor, over the candidates :meth:`plan` gives, in their order.

    :meth:`fill` submits the next unknown candidates to idle workers while fewer than ``batch`` of them are known, or
    running, to qualify (be shown to a person) — the rule an iteration's own candidates are evaluated by;
    :meth:`finish` keeps a finished evaluation; :meth:`take` hands it to the trial of its gait. Executor keys are
    −2, −3, … (the study's trials use their numbers, the floor's reference evaluation −1). ``verify_above``: each
    evaluation's certificate is verified when its estimate is at least this (the floor: the gaits a person may be
    shown)."""

    def __init__(self, executor: Executor, batch: int, params: Callable[[int], dict[str, float]],
                 qualifies: Callable[[int, Result], bool], verify_above: float | None = None):
        self.executor, self.batch, self.verify_above = executor, batch, verify_above
        self.params, self.qualifies = params, qualifies
        self.results: dict[int, Result] = {}  # grid index → its evaluation, as the study stores it
        self.running: dict[int, int] = {}  # executor key → grid index
        self.planned: list[int] = []
        self.known: dict[int, Result] = {}  # the study's own evaluations, by grid index
        self.submitted: set[int] = set()  # grid indices evaluated ahead for the current plan
        self.used = 0  # of them, how many a trial took
        self._next_key = -2

    def plan(self, candidates: Sequence[int], known: dict[int, Result]) -> None:
        """Evaluate ``candidates`` next (in their order), skipping the gaits whose evaluation is ``known``."""
        self.planned, self.known = list(candidates), known
        self.submitted, self.used = set(), 0

    def _result(self, index: int) -> Result | None:
        return self.known.get(index, self.results.get(index))

    def fill(self) -> int:
        """Submit planned candidates to idle workers; returns how many were submitted."""
        ready = sum(1 for i in self.planned if (r := self._result(i)) is not None and self.qualifies(i, r))
        running = set(self.running.values())
        submitted = 0
        for i in self.planned:
            if ready + len(running & set(self.planned)) >= self.batch or len(self.running) >= self.executor.workers:
                break
            if i in running or self._result(i) is not None:
                continue
            self.executor.submit(self._next_key, self.params(i), self.verify_above)
            self.running[self._next_key] = i
            running.add(i)
            self._next_key -= 1
            self.submitted.add(i)
            submitted += 1
        return submitted

    @property
    def busy(self) -> bool:
        return bool(self.running)

    def owns(self, key: int) -> bool:
        return key in self.running

    def index_of(self, key: int) -> int:
        return self.running[key]

    def key_of(self, index: int) -> int | None:
        """The executor key of the running evaluation of gait ``index`` (None: none runs)."""
        return next((k for k, i in self.running.items() if i == index), None)

    def finish(self, key: int, result: Result) -> int:
        """Keep the finished evaluation of ``key`` (as the study stores it); returns its grid index."""
        index = self.running.pop(key)
        self.results[index] = result
        return index

    def take(self, index: int) -> Result | None:
        """The evaluation made ahead of gait ``index`` for its trial (None: none was)."""
        result = self.results.pop(index, None)
        if result is not None and index in self.submitted:  # a result left from an earlier plan: not this one's
            self.used += 1
        return result
