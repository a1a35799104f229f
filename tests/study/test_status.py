"""The study's machine use (``study status``): CPU seconds of the evaluations over the busy wall time and cores."""

from __future__ import annotations

import pytest

from robustgait.study.status import utilisation
from robustgait.study.storage import TrialRecord


def record(number: int, start: float, stop: float, cpu: float | None, *, cores: int = 2,
           reused_from: int | None = None, state: str = "COMPLETE") -> TrialRecord:
    result = {"worker": {"cores": cores}} | ({} if cpu is None else {"cpu_seconds": cpu})
    return TrialRecord(number, state, 0, number, number, {}, 1.0, result, reused_from, None, {}, start, stop)


def test_busy_time_is_the_union_of_the_evaluations() -> None:
    # two evaluations overlap for 5 s, a third runs alone after a 5 s pause (the learner, or a stop)
    recs = [record(0, 0.0, 10.0, 20.0), record(1, 5.0, 15.0, 10.0), record(2, 20.0, 30.0, 10.0)]
    use = utilisation(recs)
    assert use is not None
    assert use["busy_seconds"] == pytest.approx(25.0)
    assert use["cpu_seconds"] == pytest.approx(40.0)
    assert use["cores"] == 2
    assert use["share"] == pytest.approx(40.0 / (25.0 * 2))


def test_reused_failed_and_unrecorded_evaluations_do_not_count() -> None:
    recs = [record(0, 0.0, 10.0, 20.0), record(1, 10.0, 10.5, 20.0, reused_from=0),
            record(2, 0.0, 50.0, 5.0, state="FAIL"), record(3, 0.0, 40.0, None)]
    use = utilisation(recs)
    assert use is not None
    assert (use["busy_seconds"], use["cpu_seconds"], use["share"]) == pytest.approx((10.0, 20.0, 1.0))
    assert utilisation([record(3, 0.0, 40.0, None)]) is None
    assert utilisation([]) is None


def test_an_evaluation_made_ahead_counts_when_its_worker_ran_it() -> None:
    """A trial that took an evaluation made ahead of it completes at once: its worker's interval is the busy time."""
    ahead = record(1, 40.0, 40.1, 20.0)
    ahead.result["worker"]["wall"] = [20.0, 30.0]  # type: ignore[index]
    use = utilisation([record(0, 0.0, 10.0, 20.0), ahead])
    assert use is not None
    assert (use["busy_seconds"], use["share"]) == pytest.approx((20.0, 1.0))
