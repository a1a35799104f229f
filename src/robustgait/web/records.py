"""The study's records as the page's threads read and write them: one database connection (a
:class:`~robustgait.study.storage.StudyStore`) shared by the server's threads and the study's runner, every access
behind one lock."""

from __future__ import annotations

import threading
from dataclasses import dataclass
from typing import Any

from robustgait.study.person import record_answer, stored_floor
from robustgait.study.run import completed_batches
from robustgait.study.storage import StudyStore, TrialRecord


@dataclass(frozen=True)
class StudySnapshot:
    """What the page shows is made of, read at one moment: the study's trials (``records``), its iterations' records
    by 0-based iteration (``iterations``: proposals, pending batch, answer, recommendation) and the robustness floor
    (``floor``: ``{"value": float, "source": str}``, None while not set)."""

    records: list[TrialRecord]
    iterations: dict[int, dict[str, Any]]
    floor: dict[str, Any] | None


class StudyRecords:
    """One study's store and the lock its users share (``store``, ``lock``: a caller holding ``lock`` may use
    ``store`` directly). Every method takes the lock for its own reads or write; none raises but the store's own
    errors, except as each says."""

    def __init__(self, store: StudyStore):
        self.store = store
        self.lock = threading.Lock()  # the page's threads share one database connection

    def snapshot(self) -> StudySnapshot:
        """The trials, the iterations and the floor, read under one hold of the lock."""
        with self.lock:
            records = self.store.records()
            iterations = self.store.iterations()
            floor = stored_floor(self.store)
        return StudySnapshot(records, iterations, floor)

    def iterations(self) -> dict[int, dict[str, Any]]:
        """Every iteration's record by 0-based iteration."""
        with self.lock:
            return self.store.iterations()

    def batch(self, k: int) -> tuple[dict[str, Any], list[TrialRecord]]:
        """Iteration k's record and its completed trials, read under one hold of the lock (``{}`` and ``[]`` for an
        iteration the study does not have)."""
        with self.lock:
            rec = self.store.iterations().get(k, {})
            batch = completed_batches(self.store.records()).get(k, [])
        return rec, batch

    def source(self, r: TrialRecord) -> TrialRecord:
        """The trial that evaluated ``r``: ``r`` itself, or the trial it reuses (``reused_from``); StopIteration
        when that trial is not in the store."""
        if r.reused_from is None:
            return r
        with self.lock:
            return next(t for t in self.store.records() if t.number == r.reused_from)

    def record_answer(self, k: int, answer: dict[str, Any]) -> None:
        """Store ``answer`` as iteration k's (:func:`robustgait.study.person.record_answer`: an
        :class:`~robustgait.study.person.AnswerError` for a stale iteration or a second answer, nothing written)."""
        with self.lock:
            record_answer(self.store, k, answer)

    def close(self) -> None:
        """Close the store's connection; the records are not used after."""
        with self.lock:
            self.store.close()
