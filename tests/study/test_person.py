"""A person's preferences in a study (docs/person.md): simulated persons, the person's ranking as comparisons, the
robustness floor, requirements on recorded figures, labels across batches, the Pareto front — fast, on records."""

from __future__ import annotations

import math
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from robustgait.config import Config, PersonConfig, SimulatedPersonConfig, StudyConfig, with_overrides
from robustgait.errors import RobustGaitError
from robustgait.learn import History
from robustgait.learn.oracle import REQUIREMENT_PENALTY, Outcome, batch_comparisons, person_scores, score
from robustgait.learn.person import SimulatedPerson
from robustgait.study.ahead import Ahead
from robustgait.study.executors import Executor
from robustgait.study.front import non_dominated
from robustgait.study.pareto import pareto
from robustgait.study.person import (
    answer_size,
    automatic_answer,
    floor_record,
    predicted_answer,
    recommendation,
    simulated_answer,
)
from robustgait.study.ranking import Requirement, figure_names, label_comparisons, requirements, shown
from robustgait.study.run import create_study
from robustgait.study.storage import TrialRecord

REPO = Path(__file__).resolve().parents[2]
PARAMS = ("step_length", "step_duration", "step_width", "step_height")


def comfort(speed: float, acc: float = 1.0, impact: float = 5.0) -> dict:  # type: ignore[type-arg]
    return {"speed": speed, "pelvis_acc_vertical_rms": acc / 2, "pelvis_acc_lateral_rms": acc / 2,
            "impact_force_ratio": impact}


def record(slot: int, value: float, status: str = "certified", speed: float = 0.2, length: float = 0.16,
           iteration: int = 0) -> TrialRecord:
    result = {"status": status, "steps_taken": 50 if status != "fell" else 10, "step_cap": 50,
              "value": value if status == "certified" else None, "estimate": value, "verified": status == "certified",
              "mean_speed": speed, "comfort": comfort(speed) if status != "fell" else None,
              "reason": ""}
    params = {"step_length": length, "step_duration": 0.8, "step_width": 0.24, "step_height": 0.06}
    return TrialRecord(slot, "COMPLETE", iteration, slot, slot, params, None, result, None, None, {})


# ---- simulated persons ------------------------------------------------------------------------------------
def test_a_simulated_person_is_drawn_from_its_seed_within_the_ranges():
    cfg = SimulatedPersonConfig(seed=4)
    a, b = SimulatedPerson.from_config(cfg), SimulatedPerson.from_config(cfg)
    assert a == b
    others = {SimulatedPerson.from_config(SimulatedPersonConfig(seed=s)).preferred_speed for s in range(20)}
    assert len(others) == 20 and all(0.18 <= v <= 0.30 for v in others)
    assert 0.5 <= a.speed_weight <= 2.0 and 0.5 <= a.acceleration_weight <= 2.0 and 0.0 <= a.impact_weight <= 1.0


def test_simulated_utility_prefers_its_speed_and_less_acceleration_and_impact():
    p = SimulatedPerson.from_config(SimulatedPersonConfig(seed=1))
    v = p.preferred_speed
    assert p.utility(comfort(v)) > p.utility(comfort(v + 0.05)) > p.utility(comfort(v + 0.1))
    assert p.utility(comfort(v, acc=1.0)) > p.utility(comfort(v, acc=2.0))
    assert p.utility(comfort(v, impact=3.0)) >= p.utility(comfort(v, impact=6.0))
    expected = -p.speed_weight * 0 - p.acceleration_weight * 1.0 - p.impact_weight * 5.0 / 5.0
    assert p.utility(comfort(v)) == pytest.approx(expected)
    assert p.utility(None) == -math.inf


def test_simulated_answers_follow_bradley_terry_and_say_cannot_tell():
    """Over many questions P(a ranked above b) = σ(Δu/noise); with cannot_tell the close pairs tie at that rate."""
    p = SimulatedPerson.from_config(SimulatedPersonConfig(seed=0, noise=0.1, cannot_tell=0.0))
    du = 0.1
    wins = np.mean([p.rank([du, 0.0], (k,))[0] == 0 for k in range(4000)])
    assert wins == pytest.approx(1 / (1 + math.exp(-du / 0.1)), abs=0.025)  # σ(1) = 0.731
    assert p.rank([5.0, 0.0, -5.0], (1,)) == [0, 1, 2]  # far apart: the utility's order, no tie
    q = SimulatedPerson.from_config(SimulatedPersonConfig(seed=0, noise=0.1, cannot_tell=0.3))
    ties = np.mean([len(set(q.rank([0.0, 0.0], (k,)))) == 1 for k in range(4000)])
    assert ties == pytest.approx(0.3, abs=0.025)
    assert q.rank([0.2, 0.1], (3,)) == q.rank([0.2, 0.1], (3,))  # the same question, the same answer


def test_simulated_answer_ranks_only_the_shown_gaits():
    cfg = Config(person=PersonConfig(simulated=SimulatedPersonConfig(seed=2, noise=1e-3, cannot_tell=0.0)))
    v = SimulatedPerson.from_config(cfg.person.simulated).preferred_speed
    batch = [record(0, 20, speed=v + 0.1), record(1, 20, speed=v), record(2, 5, speed=v)]
    a = simulated_answer(cfg, batch, [True, True, False], 0)
    assert a["ranks"] == [1, 0, None] and a["by"] == "simulated-person" and len(a["utilities"]) == 3


# ---- a person's answer as comparisons -------------------------------------------------------------------
def test_person_scores_put_every_shown_gait_above_the_hidden_ones():
    fallback = [60.0, 70.0, 65.0, 10.0]  # cap 50 + J*, or steps of a faller
    s = person_scores([1, None, 0, None], fallback)
    assert s[2] > s[0] > s[1] > s[3]  # shown by rank, then hidden by the certificate's oracle
    assert sorted(batch_comparisons(s)) == [(0, 1), (0, 3), (1, 3), (2, 0), (2, 1), (2, 3)]
    tie = person_scores([0, 0, None], [55.0, 60.0, 70.0])
    assert tie[0] == tie[1] > tie[2] and (0, 1) not in batch_comparisons(tie)  # cannot tell: no comparison
    assert person_scores([None] * 3, [3.0, 2.0, 1.0]) == [3.0, 2.0, 1.0]  # nothing shown: the oracle's order
    with pytest.raises(RobustGaitError):
        person_scores([0], [1.0, 2.0])


def test_labels_compare_gaits_across_batches():
    answers = {0: {"answer": {"labels": ["good", None, "bad"]}}, 1: {"answer": {"labels": ["neutral", "bad", None]}},
               2: {"answer": {"labels": ["good"]}}}
    comps = label_comparisons({}, answers, 2)  # iterations 0 and 1 only
    assert set(comps) == {((0, 0), (1, 0)), ((0, 0), (1, 1)), ((1, 0), (0, 2))}  # never within one batch
    h = History.from_batches([[(10, 1.0), (11, 0.0), (12, 2.0)], [(20, 0.0), (21, 1.0), (22, 2.0)]], comps)
    assert (0, 3) in h.comparisons and (3, 2) in h.comparisons


def test_the_floor_is_a_fraction_of_the_default_gait_or_set():
    ref = {"params": {"step_length": 0.15}, "status": "certified", "value": 18.0, "estimate": 19.0, "verified": True,
           "comfort": None}
    rec = floor_record(Config(), ref)
    assert rec["value"] == pytest.approx(0.75 * 18.0) and rec["source"] == "person.floor_fraction"
    assert rec["reference"]["value"] == 18.0 and rec["reference"]["estimate"] == 19.0 and rec["reference"]["verified"]
    assert floor_record(Config(person=PersonConfig(floor=12.5)), None) == {"value": 12.5, "source": "person.floor"}
    fell = floor_record(Config(), {**ref, "status": "fell", "value": None, "estimate": None, "verified": False,
                                   "reason": "fell in step 3"})
    assert fell["value"] == 0.0 and "not certified" in fell["note"]
    assert automatic_answer(3, "why")["ranks"] == [None, None, None]


def test_only_certified_gaits_at_or_above_the_floor_meeting_the_requirements_are_shown():
    reqs = [Requirement.parse("speed>=0.2", figure_names(PARAMS))]
    assert shown(record(0, 14.0), 13.5, reqs)
    assert not shown(record(0, 13.0), 13.5, reqs)  # below the floor
    assert not shown(record(0, 14.0, status="not_certified"), 0.0, [])
    assert not shown(record(0, 14.0, speed=0.15), 13.5, reqs)  # fails the requirement


def test_the_recommendation_is_never_refused_or_below_the_floor():
    """The page's current recommendation: the learner's newest pick when a person may be shown it, else the newest
    earlier pick that may — never a gait the certificate refused or one below the floor (a 15.9 N s pick under a
    17.1 N s floor, from a batch the person was never shown), with a note on the picks passed over."""
    by_number = {0: record(0, 18.0), 1: record(1, 15.9), 2: record(2, 16.0, status="not_certified")}
    its = {0: {"recommendation": 3, "recommended_trial": 0}, 1: {"recommendation": 4, "recommended_trial": 1},
           2: {"recommendation": 5, "recommended_trial": 2}}
    pick, note = recommendation(its, by_number, 17.1, [])
    assert pick is not None and pick.number == 0
    assert "after iteration 3, 2 may not be shown" in note and "its pick after iteration 1" in note
    pick, note = recommendation({0: its[0]}, by_number, 17.1, [])
    assert pick is not None and pick.number == 0 and note == ""
    pick, note = recommendation({1: its[1], 2: its[2]}, by_number, 17.1, [])
    assert pick is None and "no pick of the learner is certified at or above the floor yet" in note
    assert recommendation({}, by_number, 17.1, []) == (None, "")


# ---- requirements ----------------------------------------------------------------------------------------
def test_requirements_rank_failing_gaits_below_all_others_keeping_their_order():
    names = figure_names(PARAMS)
    q = [Requirement.parse(" speed >= 0.2", names), Requirement.parse("step_length<0.2", names)]
    ok, slow, long_ = record(0, 20.0), record(1, 30.0, speed=0.15), record(2, 25.0, length=0.22)
    assert [all(x.holds(r.params, r.result or {}) for x in q) for r in (ok, slow, long_)] == [True, False, False]
    fell = record(3, 0.0, status="fell")  # no comfort figures: a requirement on one is not met
    assert not q[0].holds(fell.params, fell.result or {})
    s_ok = score("push", Outcome(50, 50, 20.0, meets=True))
    s_slow = score("push", Outcome(50, 50, 30.0, meets=False))
    s_long = score("push", Outcome(50, 50, 25.0, meets=False))
    assert s_ok > s_slow > s_long and s_slow == 80.0 - REQUIREMENT_PENALTY
    assert score("stability", Outcome(40, 50, meets=False)) < score("stability", Outcome(3, 50))
    for bad in ("speed=>0.2", "speed>=fast", "speed", ">=0.2"):
        with pytest.raises(RobustGaitError, match="FIGURE OP NUMBER"):
            with_overrides(Config(), {"study": {"require": [bad]}})
    with pytest.raises(RobustGaitError, match="no figure 'sped' is recorded"):
        requirements(StudyConfig(require=("sped>=0.2",)), PARAMS)


def test_a_requirement_on_the_certificate_accepts_its_other_names():
    """``value`` is the study's verified certificate figure; ``j_star``, ``r_star`` and ``certificate_value`` (the name
    studies wrote before) name it too (requirement strings stored in a study's config keep the name they were written
    with)."""
    texts = ("value>=22", "certificate_value>=22", "r_star>=22", "j_star >= 22")
    reqs = requirements(StudyConfig(require=texts), PARAMS)
    assert [q.figure for q in reqs] == ["value"] * 4 and [q.text for q in reqs] == list(texts)
    low, high, estimated = record(0, 20.0), record(1, 25.0), record(2, 25.0, status="estimated")
    assert [[q.holds(r.params, r.result or {}) for q in reqs] for r in (low, high, estimated)] == [
        [False] * 4, [True] * 4, [False] * 4]  # an estimate meets no requirement on the verified figure
    assert "value" in figure_names(PARAMS) and "r_star" not in figure_names(PARAMS)


def test_a_requirement_on_an_unrecorded_figure_is_refused_before_the_study_exists(tmp_path):
    with pytest.raises(RobustGaitError, match="no figure 'comfort' is recorded"):
        create_study(tmp_path / "s", "exo", Config(study=StudyConfig(require=("comfort>1",))))
    assert not (tmp_path / "s").exists()


@pytest.mark.slow  # seconds of its own: plain pytest stays ≤ 60 s; CI runs it
def test_require_on_the_command_line(tmp_path):
    env = {**os.environ, "PYTHONPATH": str(REPO / "src")}
    res = subprocess.run([sys.executable, "-m", "robustgait.cli", "study", "run", str(tmp_path / "s"), "--robot", "exo",
                          "--require", "speed=>0.2"], env=env, capture_output=True, text=True, timeout=60)
    assert res.returncode == 2 and res.stderr.strip().splitlines() == [
        "robustgait: error: argument --require: 'speed=>0.2' is not FIGURE OP NUMBER with OP one of >= <= > < (e.g. "
        "speed>=0.2)"]
    from robustgait.cli import build_parser
    from robustgait.cli.options import config_from

    args = build_parser().parse_args(["study", "run", "d", "--robot", "exo", "--require",
                                      "speed>=0.2, impact_force_ratio<=6", "--floor", "12", "--person-seed", "3",
                                      "--metric", "simulated-person"])
    cfg = config_from(args)
    assert cfg.study.require == ("speed>=0.2", "impact_force_ratio<=6") and cfg.person.floor == 12.0
    assert cfg.person.simulated.seed == 3 and cfg.study.asks_a_person


# ---- the Pareto front --------------------------------------------------------------------------------------
def test_non_dominated_rows():
    x = np.array([[3, 1, -1], [2, 2, -1], [1, 1, -2], [3, 1, -1.5], [2, 2, -1]], dtype=float)
    assert non_dominated(x).tolist() == [True, True, False, False, True]  # equal rows both stay


def test_pareto_over_certificate_speed_and_a_comfort_figure():
    def trial(n: int, r: float, v: float, acc: float, status: str = "certified", index: int | None = None) -> dict:  # type: ignore[type-arg]
        return {"number": n, "state": "COMPLETE", "status": status, "grid_index": n if index is None else index,
                "params": {"step_length": 0.1 + n / 100}, "value": r if status == "certified" else None,
                "estimate": r, "verified": status == "certified", "gait_file": None,
                "comfort": {"speed": v, "pelvis_acc_vertical_rms": acc}}

    st = {"unit": "N s", "certificate": "push", "trials": [
        trial(0, 20, 0.15, 1.4), trial(1, 18, 0.25, 1.5), trial(2, 17, 0.20, 1.6), trial(3, 16, 0.14, 1.0),
        trial(4, 25, 0.30, 0.5, status="fell"), trial(5, 20, 0.15, 1.4, index=0)]}
    out = pareto(st, "pelvis_acc_vertical_rms")
    assert [r["trial"] for r in out["gaits"]] == [0, 1, 2, 3]  # certified, each gait once
    assert [r["trial"] for r in out["front"]] == [0, 1, 3]  # 2 is beaten by 1 on all three
    with pytest.raises(RobustGaitError, match="not a comfort cost"):
        pareto(st, "speed")


# ---- over-drawn batches, evaluations ahead ----------------------------------------------------------------
def test_the_predicted_answer_ranks_shown_gaits_by_utility_then_certificate():
    a = predicted_answer([0.2, 0.9, -0.1, 0.5], [10.0, 20.0, 30.0, 40.0], [True, True, False, True])
    assert a["ranks"] == [2, 0, None, 1] and a["by"] == "predicted"
    prior = predicted_answer([0.0, 0.0, 0.0], [10.0, 30.0, 20.0], [True, True, True])  # the prior: the certificate
    assert prior["ranks"] == [2, 0, 1]


def test_an_answer_ranks_the_evaluated_candidates_of_its_iteration():
    assert answer_size({"proposals": [1, 2, 3, 4, 5], "pending": {"size": 4, "shown": [0, 1, 3]}}) == 4
    assert answer_size({"proposals": [1, 2, 3]}) == 3  # a study written before over-drawn batches


class Recording(Executor):
    """An executor that records what it is given (the tests of :class:`Ahead`'s rule; nothing is evaluated)."""

    def __init__(self, workers: int):
        self.workers, self.submitted = workers, []  # type: ignore[var-annotated]

    def submit(self, key: int, params: dict[str, float], verify_above: float | None = None) -> None:
        self.submitted.append((key, params["i"]))

    @property
    def pending(self) -> int:
        return 0


def test_ahead_fills_idle_workers_in_order_until_a_batch_may_be_shown():
    ex = Recording(workers=2)
    good = {0: True, 1: False, 2: True, 3: True, 4: True, 5: True}
    ahead = Ahead(ex, 3, lambda i: {"i": float(i)}, lambda i, r: r["ok"])
    ahead.plan([5, 0, 1, 2, 3, 4], known={5: {"ok": True}})  # 5 is the study's own evaluation already
    assert ahead.fill() == 2 and ex.submitted == [(-2, 0.0), (-3, 1.0)]  # two workers: two at a time
    assert ahead.fill() == 0
    assert ahead.finish(-3, {"ok": good[1]}) == 1 and ahead.fill() == 1 and ex.submitted[-1] == (-4, 2.0)
    ahead.finish(-2, {"ok": good[0]})
    assert ahead.fill() == 0  # 5 and 0 may be shown, 2 runs: three would fill the batch
    ahead.finish(-4, {"ok": good[2]})
    assert ahead.fill() == 0 and ahead.submitted == {0, 1, 2}
    assert ahead.key_of(3) is None and ahead.take(0) == {"ok": True} and ahead.take(0) is None and ahead.used == 1
    ahead.plan([3, 4], known={})  # a new plan counts its own evaluations: one left from the last is not its
    assert ahead.take(2) == {"ok": True} and (ahead.submitted, ahead.used) == (set(), 0)
