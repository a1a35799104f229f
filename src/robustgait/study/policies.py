"""What a study that asks a person adds to the loop (docs/person.md), as policies the loop calls
(:class:`robustgait.study.run.StudyRunner` keeps the loop itself):

* :class:`FloorPolicy` — the robustness floor: its reference evaluation, which gaits may be shown, where proposals are
  made (the region predicted to clear it), and which evaluations verify their certificate;
* :class:`Overdraw` — how many candidates an iteration proposes, and more when too few of them may be shown;
* :class:`AheadPolicy` — the next iteration's evaluations while the person answers.

An automatic study (ranked by a certificate or a simulated person) has a floor of 0, no over-draw and nothing ahead:
each policy then answers as if it were absent.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np
from numpy.typing import NDArray

from robustgait.io.studyfile import StudySetup
from robustgait.learn.floor import predicted_to_clear
from robustgait.learn.space import ActionSpace
from robustgait.study.ahead import Ahead
from robustgait.study.executors import Executor
from robustgait.study.outcome import known_figure, verified_value
from robustgait.study.person import FLOOR_ATTR, Floor, predicted_answer
from robustgait.study.ranking import Requirement, history_before, shown, study_score
from robustgait.study.storage import StudyStore, TrialRecord, completed_batches, current_evaluation

if TYPE_CHECKING:
    from robustgait.learn.learners import Learner

REFERENCE_KEY = -1  # the executor key of a person study's reference evaluation (the default gait, for its floor)

Result = dict[str, Any]


class Asker(Protocol):
    """How a person study asks (:class:`robustgait.web.server.PersonPage` serves the page that stores the answers)."""

    def show(self, k: int) -> None:
        """Show iteration k's pending batch to the person (its videos rendered)."""

    def answered(self, k: int, timeout: float) -> bool:
        """Whether iteration k's answer is stored, waiting up to ``timeout`` s for one."""
        ...

    def render_ahead(self, index: int, result: dict[str, Any]) -> None:
        """Prepare what showing grid point ``index`` needs (its video): it was evaluated ahead of an answer
        (``result``, as stored) and may be shown in the next batch."""


@dataclass
class StudyContext:
    """What the policies read of a running study: its directory and setup, the action space, the requirements, and
    the executor and learner (callables: each is made on first use)."""

    directory: Path
    setup: StudySetup
    space: ActionSpace
    reqs: list[Requirement]
    executor: Callable[[], Executor]
    learner: Callable[[], Learner]
    asker: Asker | None

    @property
    def asks_a_person(self) -> bool:
        return self.setup.config.study.asks_a_person


class FloorPolicy:
    """A study's robustness floor in its loop (:class:`~robustgait.study.person.Floor` holds its value): 0 for a study
    that does not ask a person."""

    def __init__(self, ctx: StudyContext):
        self.ctx = ctx
        self.floor = Floor(ctx.setup.config, ctx.space)

    @property
    def value(self) -> float:
        return self.floor.value

    @property
    def pending(self) -> bool:
        return self.floor.pending

    @property
    def index(self) -> int | None:
        """The grid index of the reference in the first batch, or None."""
        return self.floor.index

    def start(self, store: StudyStore) -> None:
        """Stored once (:meth:`Floor.start`); not configured, its reference is the first batch's first gait, or for a
        study created before, the default gait evaluated on the workers beside the first batch's candidates under
        :data:`REFERENCE_KEY` (:meth:`set` when it ends)."""
        if self.ctx.asks_a_person and self.floor.start(store):
            self.ctx.executor().submit(REFERENCE_KEY, self.ctx.setup.config.params.to_dict(), verify_above=0.0)

    def is_reference(self, trial: TrialRecord) -> bool:
        return self.floor.is_reference(trial)

    def set(self, store: StudyStore, result: Result) -> str:
        """The reference evaluation ended: store the floor, render the videos of the first batch's gaits that may now
        be shown, and return what to say of it (one line)."""
        self.floor.set(store, result)
        if self.ctx.asker is not None:
            for r in store.records():
                if r.state == "COMPLETE" and r.iteration == 0 and r.result is not None \
                        and self.qualifies(r.index, r.result):
                    self.ctx.asker.render_ahead(r.index, r.result)
        config = self.ctx.setup.config
        if self.value > 0:
            return (f"floor {self.value:.4g} {config.study_certify.unit} ({config.person.floor_fraction:g} × the "
                    "reference gait's)")
        return "floor 0: the reference gait was not certified"

    def qualifies(self, index: int, result: Result, any_floor: bool = False) -> bool:
        """Whether a person may be shown the evaluated gait ``index`` (:func:`~robustgait.study.ranking.shown`; with
        ``any_floor``, under a floor of 0)."""
        record = TrialRecord(-1, "COMPLETE", -1, -1, index, self.ctx.space.value(index), None, result, None, None, {})
        return shown(record, 0.0 if any_floor else self.value, self.ctx.reqs)

    def verify_above(self) -> float | None:
        """Evaluations verify their certificate when its estimate is at least this (a person study's floor: the gaits
        it may show; every estimate while the floor is not known yet), else only when the study verifies every gait
        (None)."""
        if not self.ctx.asks_a_person:
            return None
        return 0.0 if self.pending else self.value

    def region(self, store: StudyStore, k: int, within: bool = False) -> NDArray[np.bool_] | None:
        """A person study's proposals for iteration k are made among the grid points predicted to clear its floor
        (:func:`~robustgait.learn.floor.predicted_to_clear`, ``person.region``): from the floor's reference evaluation
        and the evaluations of iterations before k (``within``: of k too). None: not a person study, or no floor
        (0) to clear.

        With the reference alone (the first iteration's proposals, made while the reference is still evaluated) the
        region does not depend on the reference's value when the floor is ``floor_fraction`` of it
        (:mod:`robustgait.learn.floor`): it is computed with the value 1 and the floor ``floor_fraction``, so that the
        proposals are the same whether the floor is known yet or not."""
        config, space = self.ctx.setup.config, self.ctx.space
        person = config.person
        if not self.ctx.asks_a_person or not person.region:
            return None
        verifications = store.verifications()
        observed = [(r.params, known_figure(r.result, verifications.get(r.index)) or 0.0) for r in store.records()
                    if r.state == "COMPLETE" and r.result is not None
                    and (r.iteration < k or (within and r.iteration == k))]
        if not observed and person.floor is None:
            default = config.params.to_dict()
            return predicted_to_clear(space, [(default, 1.0)], person.floor_fraction, person.region_lengthscale,
                                      person.region_prior)
        if self.value <= 0.0 or self.pending:
            return None
        reference = (store.user_attrs().get(FLOOR_ATTR) or {}).get("reference")
        if reference and reference.get("params") and self.index is None:  # in the batch: among the records
            value = verified_value(current_evaluation(reference))
            observed.insert(0, ({**config.params.to_dict(), **reference["params"]}, value or 0.0))
        return predicted_to_clear(space, observed, self.value, person.region_lengthscale, person.region_prior)


class Overdraw:
    """A person study draws more candidates than its batch (``person.overdraw``), so that enough of those evaluated
    may be shown; an automatic study proposes its batch."""

    def __init__(self, ctx: StudyContext, floor: FloorPolicy):
        self.ctx, self.floor = ctx, floor

    def candidates(self, k: int) -> int:
        """Candidates iteration k proposes: its batch, and for a study that asks a person its over-draw."""
        config = self.ctx.setup.config
        return config.study.batch_size(k) + (config.person.overdraw if self.ctx.asks_a_person else 0)

    def more(self, store: StudyStore, k: int, proposals: list[int], ready: int) -> list[int]:
        """Iteration k has evaluated every candidate and fewer than ``person.min_shown`` of them (``ready``) may be
        shown: the learner proposes ``person.overdraw`` more (new ones, within the region predicted to clear the floor
        given this iteration's evaluations too), recorded in the iteration's proposals before they are dispatched.
        ``proposals`` unchanged when enough may be shown, or when the action space holds no other gait."""
        config, space = self.ctx.setup.config, self.ctx.space
        need = min(config.person.min_shown, config.study.batch_size(k))
        if ready >= need or len(proposals) >= space.size:
            return proposals
        batches, iterations = completed_batches(store.records()), store.iterations()
        history = history_before(k, batches, config.study, iterations, self.ctx.reqs)
        size = min(space.size, len(proposals) + max(1, config.person.overdraw))
        region = self.floor.region(store, k, within=True)
        if region is not None:
            region[proposals] = False  # evaluated already: the new candidates come from the rest of the region
        taken = set(proposals)
        more = [i for i in self.ctx.learner().propose(history, k, size, region) if i not in taken]
        out = proposals + more[:size - len(proposals)]
        store.set_iteration(k, {**iterations.get(k, {}), "proposals": out})
        return out


class AheadPolicy:
    """Evaluations ahead of a person's answer (:class:`~robustgait.study.ahead.Ahead`, ``person.ahead``): planned when
    iteration k is shown, from the answer the learner's model predicts; none before the first plan."""

    def __init__(self, ctx: StudyContext, floor: FloorPolicy, overdraw: Overdraw):
        self.ctx, self.floor, self.overdraw = ctx, floor, overdraw
        self.ahead: Ahead | None = None

    def wanted(self, k: int) -> bool:
        """Whether the study evaluates ahead while iteration k is asked (``person.ahead``, a next iteration)."""
        return self.ctx.setup.config.person.ahead and k + 1 < self.ctx.setup.config.study.iterations

    @property
    def busy(self) -> bool:
        return self.ahead is not None and self.ahead.busy

    def owns(self, key: int) -> bool:
        return self.ahead is not None and self.ahead.owns(key)

    def plan(self, store: StudyStore, k: int, batch: list[TrialRecord], show: list[bool]) -> None:
        """Start evaluating iteration k + 1's candidates as the learner would propose them if the person answered as
        its model predicts (:func:`~robustgait.study.person.predicted_answer`); recorded in iteration k's record."""
        cfg, reqs, learner = self.ctx.setup.config.study, self.ctx.reqs, self.ctx.learner()
        records = store.records()
        batches, iterations = completed_batches(records), store.iterations()
        history = history_before(k, batches, cfg, iterations, reqs)
        utilities = learner.predicted_utility(history, [r.index for r in batch], k)
        fallback = [study_score(cfg, r, reqs) for r in batch]
        guess = {**iterations[k], "answer": predicted_answer(list(utilities), fallback, show)}
        t0 = time.perf_counter()
        candidates = learner.propose(history_before(k + 1, batches, cfg, {**iterations, k: guess}, reqs),
                                     k + 1, self.overdraw.candidates(k + 1), self.floor.region(store, k + 1))
        if self.ahead is None:
            self.ahead = Ahead(self.ctx.executor(), cfg.batch, self.ctx.space.value, self.floor.qualifies,
                               self.floor.verify_above())
        known = {r.index: r.result for r in records if r.state == "COMPLETE" and r.result is not None}
        self.ahead.plan(candidates, known)
        self.ahead.fill()
        rec = dict(store.iterations()[k])
        rec["ahead"] = {"candidates": candidates, "propose_seconds": time.perf_counter() - t0}
        store.set_iteration(k, rec)

    def finish(self, key: int, written: Result) -> int:
        """Keep the evaluation made ahead under executor ``key`` (as the study stores it, its files written:
        ``written``); its grid index."""
        assert self.ahead is not None
        return self.ahead.finish(key, written)

    def index_of(self, key: int) -> int:
        assert self.ahead is not None
        return self.ahead.index_of(key)

    def take(self, index: int) -> Result | None:
        """The evaluation made ahead of grid point ``index``, for its trial (None: none finished)."""
        return self.ahead.take(index) if self.ahead is not None else None

    def key_of(self, index: int) -> int | None:
        """The executor key of the running evaluation ahead of grid point ``index``, or None."""
        return self.ahead.key_of(index) if self.ahead is not None else None

    def fill(self) -> None:
        if self.ahead is not None:
            self.ahead.fill()

    def record_use(self, store: StudyStore, k: int) -> None:
        """What the evaluations ahead of iteration k gave, in iteration k − 1's record (evaluated, used)."""
        before = store.iterations().get(k - 1, {})
        if self.ahead is not None and "ahead" in before:
            store.set_iteration(k - 1, {**before, "ahead": {**before["ahead"], "evaluated": len(self.ahead.submitted),
                                                            "used": self.ahead.used}})
