"""A study evaluation whose gait fell at a joint limit is generated again with room there
(robustgait.study.evaluate.retry_after_fall), as gait generate's walk check does."""

from __future__ import annotations

import pytest

from robustgait.certificate.orbit import Status
from robustgait.config import Config
from robustgait.study.evaluate import Evaluation, fell_undisturbed, refusal_of, retry_after_fall
from robustgait.study.outcome import EvaluationStatus
from robustgait.study.storage import current_evaluation


def evaluation(status: str, reason: str = "", steps: int = 50, gait: object = None) -> Evaluation:
    """An evaluation as a study makes it: a refused one's refusal is the certificate's status its reason opens with."""
    head = reason.split(":", 1)[0]
    refusal = Status(head) if status == "not_certified" and head in {s.value for s in Status} else None
    return Evaluation(params=Config().params, status=EvaluationStatus(status), reason=reason, step_cap=50,
                      steps_taken=steps, gait=gait, refusal=refusal)  # type: ignore[arg-type]


def test_a_refusal_travels_as_the_certificates_status() -> None:
    """A refused gait's evaluation carries the certificate's Status (not a reason parsed back), stored as its value and
    read again; a record stored before refusals were kept names it as its reason's first word; other outcomes have
    none."""
    ev = evaluation("not_certified", "unstable: the walk settled, but …")
    assert ev.refusal is Status.UNSTABLE
    stored = ev.summary()
    assert stored["refusal"] == "unstable" and stored["status"] == "not_certified"
    again = Evaluation.from_dict({**stored, "gait": None})
    assert again.refusal is Status.UNSTABLE and again.status is EvaluationStatus.NOT_CERTIFIED
    # an unrelated reason is not read as a status once the refusal is stored
    assert refusal_of({**stored, "reason": "fell: …"}) is Status.UNSTABLE
    old = {k: v for k, v in stored.items() if k != "refusal"}
    assert refusal_of(old) is None  # the reason is not parsed where a status is read
    assert refusal_of(current_evaluation(old)) is Status.UNSTABLE  # an older study's record, upgraded once on reading
    assert Evaluation.from_dict({**old, "gait": None}).refusal is Status.UNSTABLE
    assert refusal_of({"status": "certified", "reason": ""}) is None
    assert refusal_of({"status": "not_certified", "reason": "not certified yet"}) is None


def test_an_undisturbed_fall_is_found_in_the_walk_or_the_orbit_search(exo_gait) -> None:  # type: ignore[no-untyped-def]
    cfg = Config()
    o = cfg.study_certify.orbit
    assert fell_undisturbed(evaluation("fell", "fell in step 31 (tilt)", 30, exo_gait), cfg) == 31
    assert fell_undisturbed(evaluation("not_certified", "fell: the gait fell in step 64", 50, exo_gait),
                            cfg) == o.max_steps + o.hold_steps
    for status, reason in (("certified", ""), ("not_certified", "unsettled: ..."), ("not_certified", "unstable: .."),
                           ("generation_failed", "Infeasible_Problem_Detected: ...")):
        assert fell_undisturbed(evaluation(status, reason, 50, exo_gait), cfg) is None
    assert fell_undisturbed(evaluation("fell", "fell in step 3", 2, None), cfg) is None  # no gait to walk


def test_a_gait_that_walks_or_fell_for_another_cause_is_not_retried(exo, exo_gait) -> None:  # type: ignore[no-untyped-def]
    cfg = Config()
    walks = evaluation("fell", "fell in step 4 (tilt)", 3, exo_gait)  # exo's gait walks: no fall to diagnose
    assert retry_after_fall(exo, cfg.params, cfg, walks) is walks


@pytest.mark.slow
def test_a_fall_at_a_joint_limit_is_evaluated_again_with_the_margin(exo, exo_gait, monkeypatch):  # type: ignore[no-untyped-def]
    """exo's gaits walk, so the diagnosis of the first evaluation's fall is replaced by a joint at its limit; the
    evaluation returned is the margin gait's, certified, and says why it was made."""
    from robustgait.gaitgen import walkcheck

    monkeypatch.setattr(walkcheck, "diagnose_fall", lambda robot, gait, config, steps, check=None: (
        "left_knee reached the upper end of its range in step 26", "left_knee", []))
    cfg = Config(gait=exo.default_params)
    first = evaluation("fell", "fell in step 31 (tilt)", 30, exo_gait)
    first.seconds = {"total": 10.0}
    out = retry_after_fall(exo, cfg.params, cfg, first)
    assert out is not first and out.retried is not None
    assert out.retried["joint_margin"] == pytest.approx(0.1) and out.retried["limit_joint"] == "left_knee"
    assert out.retried["status"] == "fell" and out.retried["reason"] == "fell in step 31 (tilt)"
    assert out.status in ("certified", "estimated") and out.gait is not None  # ranked: verified or estimated
    assert out.gait.solver["joint_margin"] == pytest.approx(0.1)
    assert out.seconds["first"] == 10.0 and out.seconds["retry"] > 0
    assert out.seconds["total"] == pytest.approx(sum(out.seconds[k] for k in ("generate", "walk", "certify", "first",
                                                                                "retry")))
    assert Evaluation.from_dict(out.to_dict()).retried == out.retried
