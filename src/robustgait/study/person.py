"""A person as a study's oracle (docs/person.md): the robustness floor, the batch a person is asked to rank, and the
answer stored in the study the moment it is given.

* **The floor** (``person.floor``, in the certificate's unit; not set: ``person.floor_fraction`` × the certificate of
  the grid gait nearest the robot's default gait, the first batch's first gait: :class:`Floor`): a person is shown
  only gaits certified at or above it that meet the study's requirements (:func:`robustgait.study.ranking.shown`); a
  proposal below it is ranked below every shown gait without asking. Stored as the study attribute ``floor``.
* **A pending batch**: iteration k's record (``iteration_NNN``) gets ``pending`` — the shown slots and why the others
  are hidden — before the person is asked; the answer is ``answer``: a rank per slot (0 the best, equal ranks "cannot
  tell", None for a hidden gait), optionally a label per slot (bad / neutral / good), who answered and when.
  :func:`record_answer` writes it in one transaction (Optuna's study attribute) and refuses a second answer, so
  nothing is stored twice; a study killed while it waits comes back at the same pending batch with nothing lost.
"""

from __future__ import annotations

import math
import threading
import time
from collections.abc import Sequence
from typing import Any

from robustgait.config import Config
from robustgait.errors import RobustGaitError
from robustgait.learn.person import SimulatedPerson
from robustgait.learn.space import ActionSpace
from robustgait.study.outcome import EvaluationStatus, status_of, verified_value
from robustgait.study.ranking import LABELS, Requirement, shown
from robustgait.study.storage import StudyStore, TrialRecord, current_evaluation

FLOOR_ATTR = "floor"
_ANSWER_LOCK = threading.Lock()  # one answer at a time in this process (the page's server threads, the runner)


class AnswerError(RobustGaitError):
    """An answer that cannot be stored: ``status`` is the HTTP status the page gets (400 malformed, 409 stale or
    already answered)."""

    def __init__(self, message: str, status: int = 400):
        super().__init__(message)
        self.status = status


def floor_record(config: Config, reference: dict[str, Any] | None) -> dict[str, Any]:
    """The study's floor: ``person.floor`` if set, else ``floor_fraction`` × the reference evaluation's verified
    certificate (:class:`Floor`; 0 if it was not certified: every certified gait is then shown — said in ``note``)."""
    p = config.person
    if p.floor is not None:
        return {"value": float(p.floor), "source": "person.floor"}
    if reference is None:
        raise RobustGaitError("the floor needs its reference gait's evaluation")
    verified = verified_value(reference)
    value = verified or 0.0
    rec = {"value": p.floor_fraction * value, "source": "person.floor_fraction", "fraction": p.floor_fraction,
           "reference": {"params": reference.get("params"), "status": reference.get("status"),
                         "value": verified, "estimate": reference.get("estimate"), "verified": verified is not None,
                         "comfort": reference.get("comfort")}}
    if status_of(reference) != EvaluationStatus.CERTIFIED:
        rec["note"] = (f"the reference gait was not certified ({reference.get('status')}: {reference.get('reason')}): "
                       "floor 0, every certified gait is shown")
    return rec


class Floor:
    """A person study's floor as its run knows it (:func:`floor_record`): :attr:`value` is 0 (no floor to clear), the
    floor in the certificate's unit, or ∞ while the reference evaluation that sets it runs (:attr:`pending`: no gait
    may be shown yet, every candidate verifies its certificate).

    Without ``person.floor`` the reference is the first gait of the first batch, the grid point nearest the robot's
    default gait (``person.reference_in_batch``: :attr:`index`), or else the default gait itself, evaluated on its own
    beside the first batch (a study created before; :meth:`start` says so)."""

    def __init__(self, config: Config, space: ActionSpace):
        self.config = config
        person = config.person
        self.value = 0.0
        in_batch = config.study.asks_a_person and person.floor is None and person.reference_in_batch
        self.index = space.nearest(config.params.to_dict()) if in_batch else None

    @property
    def pending(self) -> bool:
        return math.isinf(self.value)

    def start(self, store: StudyStore) -> bool:
        """Take the stored floor, or the configured one (stored), or else mark it pending; a reference in the batch
        that completed before a killed run could store its floor sets it now. True: the default gait must be
        evaluated on its own for it (:meth:`set` with its result)."""
        rec = store.user_attrs().get(FLOOR_ATTR)
        if rec is None and self.config.person.floor is not None:
            rec = floor_record(self.config, None)
            store.study.set_user_attr(FLOOR_ATTR, rec)
        if rec is not None:
            self.value = float(rec["value"])
            return False
        self.value = math.inf
        if self.index is None:
            return True
        first = next((r for r in store.records() if r.state == "COMPLETE" and r.iteration == 0 and r.slot == 0), None)
        if first is not None and first.result is not None:
            self.set(store, {**first.result, "params": first.params})
        return False

    def is_reference(self, trial: TrialRecord) -> bool:
        """Whether ``trial`` is the reference in the batch whose result sets the pending floor."""
        return self.pending and self.index is not None and (trial.iteration, trial.slot) == (0, 0)

    def set(self, store: StudyStore, result: dict[str, Any]) -> None:
        """Store the floor from the reference's evaluation ``result`` (its verified certificate)."""
        reference = {k: v for k, v in result.items() if k not in ("gait", "certificate")}
        rec = floor_record(self.config, reference)
        store.study.set_user_attr(FLOOR_ATTR, rec)
        self.value = float(rec["value"])


def stored_floor(store: StudyStore) -> dict[str, Any] | None:
    """The study's floor as stored (the study attribute ``floor``, :func:`floor_record`; None while not set), its
    reference evaluation read by :func:`~robustgait.study.storage.current_evaluation`."""
    rec = store.user_attrs().get(FLOOR_ATTR)
    if not isinstance(rec, dict) or not isinstance(rec.get("reference"), dict):
        return rec
    return {**rec, "reference": current_evaluation(rec["reference"])}


def hidden_reason(r: TrialRecord, floor: float, reqs: Sequence[Requirement], unit: str) -> str | None:
    """Why a gait is not shown (None: it is)."""
    if shown(r, floor, reqs):
        return None
    res = r.result or {}
    status = status_of(res)
    if status == EvaluationStatus.ESTIMATED:
        return f"estimated {float(res['estimate']):.3g} {unit}, below the floor {floor:.3g} {unit}"
    if status != EvaluationStatus.CERTIFIED:
        return f"{res.get('status')}: {res.get('reason') or ''}".strip(": ")
    value = verified_value(res) or 0.0
    if value < floor:
        return f"certified {value:.3g} {unit}, below the floor {floor:.3g} {unit}"
    failed = [q.text for q in reqs if not q.holds(r.params, res)]
    return "fails " + ", ".join(failed)


def pending_record(batch: Sequence[TrialRecord], floor: float, reqs: Sequence[Requirement],
                   unit: str) -> dict[str, Any]:
    """What iteration k asks: the number of its evaluated candidates (slots 0 … size − 1), the shown slots, and per
    hidden slot why."""
    reasons = {r.slot: hidden_reason(r, floor, reqs, unit) for r in batch}
    return {"size": len(batch), "shown": [s for s, why in reasons.items() if why is None],
            "hidden": {str(s): why for s, why in reasons.items() if why is not None}, "asked_at": time.time()}


def automatic_answer(n: int, why: str) -> dict[str, Any]:
    """The answer of a batch with no gait to show: nothing asked, every gait ranked by the certificate's oracle."""
    return {"ranks": [None] * n, "labels": [None] * n, "by": "floor", "note": why, "answered_at": time.time()}


def simulated_answer(config: Config, batch: Sequence[TrialRecord], show: Sequence[bool], k: int) -> dict[str, Any]:
    """A simulated person's answer (:class:`~robustgait.learn.person.SimulatedPerson`, ``person.simulated``): its ranks
    of the shown gaits, drawn with (person seed, iteration), and its utility of every gait (for the benchmarks)."""
    person = SimulatedPerson.from_config(config.person.simulated)
    utilities = [person.utility((r.result or {}).get("comfort")) for r in batch]
    slots = [i for i, s in enumerate(show) if s]
    ranks: list[int | None] = [None] * len(batch)
    for slot, rank in zip(slots, person.rank([utilities[i] for i in slots], (k,)), strict=True):
        ranks[slot] = rank
    return {"ranks": ranks, "labels": [None] * len(batch), "by": "simulated-person",
            "person": {"seed": config.person.simulated.seed, "preferred_speed": person.preferred_speed,
                       "weights": [person.speed_weight, person.acceleration_weight, person.impact_weight]},
            "utilities": [u if math.isfinite(u) else None for u in utilities], "answered_at": time.time()}


def check_answer(pending: dict[str, Any], n: int, ranks: Sequence[int | None], labels: Sequence[str | None]) -> None:
    """An answer fits its pending batch: a rank for every shown slot and none for a hidden one, ranks 0, 1, … without
    gaps (equal: cannot tell), labels of shown slots only, each one of :data:`LABELS`."""
    shown_slots = set(pending["shown"])
    if len(ranks) != n or len(labels) != n:
        raise AnswerError(f"the batch has {n} gaits: {len(ranks)} ranks and {len(labels)} labels given")
    for s in range(n):
        if (ranks[s] is None) == (s in shown_slots):
            raise AnswerError(f"gait {s + 1} is {'shown and not ranked' if s in shown_slots else 'not shown'}")
        if labels[s] is not None and (s not in shown_slots or labels[s] not in LABELS):
            raise AnswerError(f"gait {s + 1}: label {labels[s]!r} (one of {', '.join(LABELS)}, for a shown gait)")
    used = sorted({int(r) for r in ranks if r is not None})
    if used != list(range(len(used))):
        raise AnswerError(f"ranks must be 0, 1, … without gaps (equal ranks: cannot tell), got {used}")


def record_answer(store: StudyStore, k: int, answer: dict[str, Any]) -> dict[str, Any]:
    """Store ``answer`` (ranks, labels, by, …) as iteration k's, once: a stale iteration (not the pending one) or a
    second answer is refused (409) and nothing is written. Returns the iteration's record."""
    with _ANSWER_LOCK:
        iterations = store.iterations()
        rec = dict(iterations.get(k, {}))
        pending = rec.get("pending")
        if "answer" in rec:
            raise AnswerError(f"iteration {k + 1} was answered already (at "
                              f"{time.strftime('%H:%M:%S', time.localtime(rec['answer']['answered_at']))})", 409)
        if pending is None:
            waiting = pending_iteration(iterations)
            raise AnswerError(f"iteration {k + 1} does not wait for an answer"
                              + (f" (iteration {waiting + 1} does)" if waiting is not None else ""), 409)
        batch_size = answer_size(rec)
        check_answer(pending, batch_size, answer["ranks"], answer["labels"])
        rec["answer"] = {**answer, "answered_at": time.time()}
        store.set_iteration(k, rec)
        return rec


def answer_size(record: dict[str, Any]) -> int:
    """How many slots an answer to this iteration ranks: its evaluated candidates (a study written before over-drawn
    batches: its proposals)."""
    pending = record.get("pending") or {}
    return int(pending["size"]) if "size" in pending else len(record.get("proposals") or [])


def predicted_answer(utilities: Sequence[float], fallback: Sequence[float], show: Sequence[bool]) -> dict[str, Any]:
    """The answer a preference model predicts for a batch: the shown gaits ranked by their predicted utility, best
    first (equal utilities, as under the prior: by the certificate's oracle ``fallback``), the hidden ones unranked.
    Never stored: it is what :mod:`robustgait.study.ahead` evaluates the next proposals for."""
    order = sorted((i for i, s in enumerate(show) if s),
                   key=lambda i: (-round(float(utilities[i]), 9), -fallback[i], i))
    ranks: list[int | None] = [None] * len(show)
    for rank, i in enumerate(order):
        ranks[i] = rank
    return {"ranks": ranks, "labels": [None] * len(show), "by": "predicted"}


def pending_iteration(iterations: dict[int, dict[str, Any]]) -> int | None:
    """The iteration that waits for a person's answer (None: none)."""
    waiting = [k for k, rec in iterations.items() if "pending" in rec and "answer" not in rec]
    return min(waiting) if waiting else None


def recommendation(iterations: dict[int, dict[str, Any]], by_number: dict[int, TrialRecord], floor: float,
                   reqs: Sequence[Requirement]) -> tuple[TrialRecord | None, str]:
    """The gait a person study recommends now: the learner's pick after the newest finished iteration when a person
    may be shown it (:func:`~robustgait.study.ranking.shown`: certified, at or above the floor, requirements met), else
    the newest earlier pick that may — never a gait refused or below the floor, and never one of a batch the person
    was not shown for that reason. Returns it (None: no pick qualifies yet) and a note on the picks passed over."""
    finished = [k for k in sorted(iterations) if "recommendation" in iterations[k]]
    skipped: list[str] = []
    for k in reversed(finished):
        number = iterations[k].get("recommended_trial")
        r = by_number.get(number) if number is not None else None
        if r is not None and shown(r, floor, reqs):
            note = (f"the learner's picks after iteration {', '.join(skipped)} may not be shown (refused or below "
                    f"the floor): its pick after iteration {k + 1}") if skipped else ""
            return r, note
        skipped.append(str(k + 1))
    return None, ("no pick of the learner is certified at or above the floor yet" if finished else "")


def shown_flags(batch: Sequence[TrialRecord], floor: float, reqs: Sequence[Requirement]) -> list[bool]:
    return [shown(r, floor, reqs) for r in batch]
