"""A study's database: an Optuna study in an RDB storage (docs/design.md §7) — a SQLite file in the study
directory by default, any SQLAlchemy URL otherwise — so Optuna's tools (``optuna-dashboard``, plots) open
our studies.

One Optuna trial per proposed gait. Its lifecycle is the storage contract (docs/studies.md):

1. ``enqueue`` — WAITING, with its parameters and user attributes (iteration, slot, grid index, seeds):
   recorded, in one transaction, before it is dispatched.
2. ``start`` — ``Study.ask`` moves the oldest WAITING trial to RUNNING (atomic in the database).
3. ``complete`` — the evaluation's attributes are written, then ``Study.tell(COMPLETE, value)``. The
   COMPLETE state is the single commit point: a trial that is not COMPLETE counts as not evaluated, and
   whatever attributes it holds are ignored.
4. After a crash, ``retry_interrupted`` marks the RUNNING trials FAIL and enqueues each again with the same
   parameters and attributes (``retry_of`` = the failed trial's number).

Per-iteration records (proposals, learner seed, comparisons, recommendation) are study user attributes
``iteration_NNN``: comparisons exist only once a whole batch is in, after its trials are complete; the learner's
posterior mean over the grid after the last closed iteration is ``posterior_mean``. The verified
certificate of a gait whose trial holds an estimate is the study user attribute ``verified_NNNNNN`` (its grid index):
a completed trial is never written again.
"""

from __future__ import annotations

import logging
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from robustgait.certificate.orbit import Status as OrbitStatus
from robustgait.errors import RobustGaitError
from robustgait.learn.space import ActionSpace
from robustgait.study.outcome import RANKED, EvaluationStatus, status_of

DB_FILE = "study.db"
VERIFIED_PREFIX = "verified_"
POSTERIOR_KEY = "posterior_mean"  # the learner's posterior mean over the grid after the last closed iteration

STORED_NAMES = {"r_star": "value", "certificate_value": "value", "study_r_star": "study_value",
                "study_certificate_value": "study_value", "r_star_critical": "value_critical",
                "certificate_value_critical": "value_critical"}
"""Keys a stored study record may hold → the names this package reads them by: the certificate's figure (J* [N s] of a
push certificate, r* of a state certificate) is ``value``, a study's own record of it ``study_value``."""
OLD_FIGURE_KEYS = ("certificate_value", "r_star", "verified_value")
"""The keys an evaluation's figure was stored under before it had one name (:func:`current_evaluation`)."""


def current_names(record: Mapping[str, Any]) -> dict[str, Any]:
    """``record`` (a trial's attributes, a row or the correlations of a study validation summary) with its top-level
    keys named as this package reads them (:data:`STORED_NAMES`); a key already under its current name wins. Nested
    records keep their keys. An evaluation's record: :func:`current_evaluation`."""
    out: dict[str, Any] = {}
    for key, value in record.items():
        name = STORED_NAMES.get(key)
        if name is None:
            out[key] = value
        elif name not in record and name not in out:
            out[name] = value
    return out


def current_evaluation(record: Mapping[str, Any]) -> dict[str, Any]:
    """An evaluation's stored record (:meth:`~robustgait.study.evaluate.Evaluation.summary`, a verification's record, a
    person study's reference) with its figure as ``value`` (the verified figure, None unless verified), ``estimate``
    (the exploration's, None without one) and ``verified``. A record written before the figure had one name held
    ``certificate_value`` (or ``r_star``: the figure the study ranked by — the estimate of an ``estimated`` gait) and
    ``verified_value`` (absent before estimates, when every ``certified`` figure was verified). A refused gait's record
    written before refusals were stored named the certificate's status only as its reason's first word: its
    ``refusal`` is read from there, once, here."""
    out = dict(record)
    if status_of(record) == EvaluationStatus.NOT_CERTIFIED and "refusal" not in record:
        head = str(record.get("reason") or "").split(":", 1)[0]
        out["refusal"] = head if head in {s.value for s in OrbitStatus} else None
    if "verified" in record or not any(k in record for k in OLD_FIGURE_KEYS):
        return out
    out = {k: v for k, v in out.items() if k not in OLD_FIGURE_KEYS}
    ranked = record.get("certificate_value", record.get("r_star"))
    status = status_of(record)
    value = (record["verified_value"] if "verified_value" in record
             else ranked if status == EvaluationStatus.CERTIFIED else None)
    estimate = record.get("estimate")
    if estimate is None and status in RANKED:
        estimate = ranked
    out.update(value=None if value is None else float(value), estimate=None if estimate is None else float(estimate),
               verified=value is not None)
    return out


def default_url(directory: Path) -> str:
    return f"sqlite:///{(directory / DB_FILE).resolve()}"


@dataclass(frozen=True)
class TrialRecord:
    """One trial as stored: Optuna's number and state, our attributes, and the evaluation summary
    (``result``, None unless COMPLETE)."""

    number: int
    state: str
    iteration: int
    slot: int
    index: int
    params: dict[str, float]
    value: float | None
    result: dict[str, Any] | None
    reused_from: int | None
    retry_of: int | None
    attrs: dict[str, Any]
    started: float | None = None  # POSIX time the trial started and completed (Optuna's record)
    completed: float | None = None


class StudyStore:
    """Our view of the Optuna study (see the module docstring)."""

    def __init__(self, url: str, name: str, space: ActionSpace, *, create: bool = False,
                 user_attrs: dict[str, Any] | None = None):
        import optuna
        from optuna.distributions import BaseDistribution, FloatDistribution

        optuna.logging.set_verbosity(logging.WARNING)
        self.url, self.name, self.space = url, name, space
        kwargs = {"connect_args": {"timeout": 60}} if url.startswith("sqlite") else {}
        try:
            self.storage = optuna.storages.RDBStorage(url, engine_kwargs=kwargs)
            if create:
                self.study = optuna.create_study(storage=self.storage, study_name=name, direction="maximize")
                for key, value in (user_attrs or {}).items():
                    self.study.set_user_attr(key, value)
            else:
                self.study = optuna.load_study(study_name=name, storage=self.storage)
        except optuna.exceptions.DuplicatedStudyError:
            raise RobustGaitError(f"{url}: a study named '{name}' already exists in this database") from None
        except KeyError:
            raise RobustGaitError(f"{url}: no study named '{name}' in this database") from None
        except Exception as exc:  # SQLAlchemy's errors (bad URL, unreachable server) have many types
            if isinstance(exc, RobustGaitError):
                raise
            raise RobustGaitError(f"{url}: cannot open the study database ({type(exc).__name__}: "
                                  f"{' '.join(str(exc).split())[:200]})") from None
        self._running: dict[int, Any] = {}  # trial number → optuna Trial, between start and complete
        self.distributions: dict[str, BaseDistribution] = {
            n: FloatDistribution(v[0], v[-1]) for n, v in zip(space.names, space.values, strict=True)}

    # ---- trials -----------------------------------------------------------------------------------------
    def enqueue(self, iteration: int, slot: int, index: int, attrs: dict[str, Any] | None = None) -> None:
        """Record a proposal (WAITING) in one transaction."""
        self.study.enqueue_trial(self.space.value(index), user_attrs={
            "iteration": iteration, "slot": slot, "grid_index": index, **(attrs or {})})

    def start(self) -> TrialRecord | None:
        """Move the oldest WAITING trial to RUNNING and return it (None if none is waiting)."""
        from optuna.trial import TrialState

        if not self.study.get_trials(deepcopy=False, states=(TrialState.WAITING,)):
            return None
        trial = self.study.ask(fixed_distributions=self.distributions)
        self._running[trial.number] = trial
        attrs = trial.user_attrs
        return TrialRecord(trial.number, "RUNNING", attrs["iteration"], attrs["slot"], attrs["grid_index"],
                           dict(trial.params), None, None, None, attrs.get("retry_of"), attrs)

    def complete(self, number: int, result: dict[str, Any], value: float, extra: dict[str, Any]) -> None:
        """Write the result's attributes, then COMPLETE with ``value`` (the commit point)."""
        from optuna.trial import TrialState

        trial = self._running.pop(number)
        for key in ("status", "steps_taken", "value", "estimate"):
            trial.set_user_attr(key, result[key])
        for key, v in extra.items():
            trial.set_user_attr(key, v)
        trial.set_user_attr("result", result)
        self.study.tell(trial, values=[value], state=TrialState.COMPLETE)

    def retry_interrupted(self) -> list[int]:
        """RUNNING trials (their process died): FAIL each and enqueue it again with the same parameters and
        attributes. Returns the failed trial numbers. Call only while holding the study lock."""
        from optuna.trial import TrialState

        failed = []
        for t in self.study.get_trials(deepcopy=False, states=(TrialState.RUNNING,)):
            self.study.tell(t.number, state=TrialState.FAIL)
            keep = {k: v for k, v in t.user_attrs.items() if k in ("iteration", "slot", "grid_index", "seeds")}
            self.enqueue(keep.pop("iteration"), keep.pop("slot"), keep.pop("grid_index"),
                         {**keep, "retry_of": t.number})
            failed.append(t.number)
        return failed

    def records(self) -> list[TrialRecord]:
        out = []
        for t in self.study.get_trials(deepcopy=False):
            a = current_names(t.user_attrs)
            if "iteration" not in a:
                continue  # not one of ours
            if isinstance(a.get("result"), Mapping):
                a["result"] = current_evaluation(a["result"])
            params = dict(t.params) or dict(t.system_attrs.get("fixed_params", {}))
            out.append(TrialRecord(t.number, t.state.name, a["iteration"], a["slot"], a["grid_index"], params,
                                   t.value if t.state.name == "COMPLETE" else None,
                                   a.get("result") if t.state.name == "COMPLETE" else None,
                                   a.get("reused_from"), a.get("retry_of"), a,
                                   t.datetime_start.timestamp() if t.datetime_start else None,
                                   t.datetime_complete.timestamp() if t.datetime_complete else None))
        return out

    # ---- study-level records -----------------------------------------------------------------------------
    def set_iteration(self, k: int, record: dict[str, Any]) -> None:
        self.study.set_user_attr(f"iteration_{k:03d}", record)

    def set_verification(self, index: int, record: dict[str, Any]) -> None:
        """The verified certificate of grid point ``index``'s gait, made after its trial completed (a study that
        ranks on estimates verifies what it shows or recommends)."""
        self.study.set_user_attr(f"{VERIFIED_PREFIX}{index:06d}", record)

    def verifications(self) -> dict[int, dict[str, Any]]:
        """Grid index → its verification record (:meth:`set_verification`, read by :func:`current_evaluation`)."""
        return {int(key[len(VERIFIED_PREFIX):]): current_evaluation(v) for key, v in self.study.user_attrs.items()
                if key.startswith(VERIFIED_PREFIX)}

    def set_posterior(self, k: int, mean: NDArray[np.float64]) -> None:
        """The learner's posterior mean utility (space.size,) over the whole grid after iteration ``k`` (the report's
        map, drawn without refitting the model); replaces the previous iteration's."""
        self.study.set_user_attr(POSTERIOR_KEY, {"iteration": k, "mean": [float(f"{v:.7g}") for v in mean.tolist()]})

    def posterior(self) -> tuple[int, NDArray[np.float64]] | None:
        """(k, mean (space.size,)) of :meth:`set_posterior`; None when none is stored (a study run before it was
        stored, or a grid larger than ``config.study.POSTERIOR_STORE_LIMIT``)."""
        rec = self.study.user_attrs.get(POSTERIOR_KEY)
        if not isinstance(rec, Mapping) or len(rec.get("mean", ())) != self.space.size:
            return None
        return int(rec["iteration"]), np.asarray(rec["mean"], dtype=float)

    def iterations(self) -> dict[int, dict[str, Any]]:
        return {int(key.split("_")[1]): v for key, v in self.study.user_attrs.items() if key.startswith("iteration_")}

    def user_attrs(self) -> dict[str, Any]:
        return dict(self.study.user_attrs)

    def close(self) -> None:
        self.storage.remove_session()
        self.storage.engine.dispose()


def completed_batches(records: list[TrialRecord]) -> dict[int, list[TrialRecord]]:
    """COMPLETE trials per iteration, ordered by slot; an (iteration, slot) completed twice is an error."""
    out: dict[int, dict[int, TrialRecord]] = {}
    for r in records:
        if r.state == "COMPLETE":
            slots = out.setdefault(r.iteration, {})
            if r.slot in slots:
                raise RobustGaitError(f"iteration {r.iteration} slot {r.slot} was completed twice "
                                      f"(trials {slots[r.slot].number} and {r.number})")
            slots[r.slot] = r
    return {k: [v[s] for s in sorted(v)] for k, v in out.items()}
