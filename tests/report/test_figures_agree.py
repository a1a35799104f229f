"""One name for the certificate's figure (docs/studies.md, "The certificate's figure"): ``study status --json``, the
study report and the person page agree on every gait's ``value``, ``estimate`` and ``verified`` — on a person study
whose records are written as a run writes them (the page and the report read records; nothing is simulated): a gait
verified in its evaluation, one estimated and verified after its trial, one estimated only, one refused."""

from __future__ import annotations

import html
import json
import re
from pathlib import Path

import pytest

from robustgait.cli import main
from robustgait.config import Config, PersonConfig, ReportConfig, StudyConfig
from robustgait.io.studyfile import load_config
from robustgait.report.study import write_study_report
from robustgait.study.person import FLOOR_ATTR, pending_record
from robustgait.study.ranking import requirements
from robustgait.study.run import completed_batches, create_study, open_store
from robustgait.web.server import PersonPage

COMFORT = {"speed": 0.2, "cadence": 86.0, "pelvis_acc_vertical_rms": 1.4, "pelvis_acc_lateral_rms": 1.3,
           "impact_force_ratio": 5.5, "cost_of_transport": 0.24}
FLOOR = 10.0


def result(status: str, value: float | None, estimate: float | None) -> dict:  # type: ignore[type-arg]
    return {"params": {}, "status": status, "reason": "" if status != "not_certified" else "unstable: …",
            "refusal": "unstable" if status == "not_certified" else None, "steps_taken": 50, "step_cap": 50,
            "fell": False, "fall_reason": None, "mean_speed": 0.2, "value": value, "estimate": estimate,
            "verified": value is not None, "comfort": COMFORT, "gait_file": None, "certificate_file": None,
            "seconds": {}}


# iteration 0 (answered, its recommendation stored) and iteration 1 (waiting for the person)
BATCHES = (
    (result("certified", 18.5, 21.25), result("estimated", None, 14.75), result("not_certified", None, None)),
    (result("certified", 12.125, 13.5), result("estimated", None, 9.5), result("certified", 16.0, 16.75)),
)
VERIFIED_AFTER = {1: {"status": "certified", "reason": "", "refusal": None, "value": 11.5, "estimate": 14.75,
                      "verified": True, "certificate_file": None}}  # trial 1's gait, verified after its trial


@pytest.fixture(scope="module")
def study(tmp_path_factory: pytest.TempPathFactory) -> Path:
    d = tmp_path_factory.mktemp("agree") / "study"
    create_study(d, "exo", Config(study=StudyConfig(metric="person", iterations=3, batch=3),
                                  person=PersonConfig(floor=FLOOR)))
    setup = load_config(d)
    space = setup.action_space()
    reqs = requirements(setup.config.study, space.names)
    store = open_store(d, setup, space)
    try:
        store.study.set_user_attr(FLOOR_ATTR, {"value": FLOOR, "source": "person.floor"})
        for k, batch in enumerate(BATCHES):
            proposals = [3 + 100 * k + 7 * s for s in range(len(batch))]
            store.set_iteration(k, {"proposals": proposals})
            for slot, index in enumerate(proposals):
                store.enqueue(k, slot, index)
            for res in batch:
                t = store.start()
                assert t is not None
                store.complete(t.number, {**res, "params": t.params}, 50.0 + (res["estimate"] or 0.0), {})
            done = completed_batches(store.records())[k]
            rec = dict(store.iterations()[k])
            if k == 0:
                rec.update(answer={"ranks": [0, None, None], "labels": None, "by": "test", "answered_at": 0.0},
                           comparisons=[], recommendation=done[0].params, recommended_trial=done[0].number)
            else:
                rec["pending"] = pending_record(done, FLOOR, reqs, "N s")
            store.set_iteration(k, rec)
        for number, verification in VERIFIED_AFTER.items():
            index = next(r.index for r in store.records() if r.number == number)
            store.set_verification(index, verification)
    finally:
        store.close()
    return d


def status_json(d: Path, capsys: pytest.CaptureFixture[str]) -> dict:  # type: ignore[type-arg]
    assert main(["study", "status", str(d), "--json"]) == 0
    return json.loads(capsys.readouterr().out)  # type: ignore[no-any-return]


@pytest.mark.slow  # the report's figures take seconds: plain pytest stays ≤ 60 s; CI runs it
def test_status_page_and_report_agree_on_every_figure(study: Path, capsys: pytest.CaptureFixture[str]) -> None:
    st = status_json(study, capsys)
    trials = {t["number"]: t for t in st["trials"]}
    assert st["figure_name"] == "J*" and st["unit"] == "N s" and all(t["unit"] == "N s" for t in trials.values())
    # the status: the verified figure as value, the exploration's as estimate; a gait verified after its trial shows
    # its verified value, and its status is the verification's
    assert (trials[0]["value"], trials[0]["estimate"], trials[0]["verified"]) == (18.5, 21.25, True)
    assert (trials[1]["value"], trials[1]["estimate"], trials[1]["verified"], trials[1]["status"]) == (
        11.5, 14.75, True, "certified")
    assert (trials[2]["value"], trials[2]["estimate"], trials[2]["verified"]) == (None, None, False)
    assert (trials[4]["value"], trials[4]["estimate"], trials[4]["verified"]) == (None, 9.5, False)
    assert not {"certificate_value", "verified_value"} & set(trials[0])

    # the page: the waiting batch's shown gaits and the recommendation carry the status's figures
    page = PersonPage(study)
    page.ready = 1
    try:
        state = page.state()
    finally:
        page.close()
    by_slot = {(t["iteration"], t["slot"]): t for t in trials.values()}
    shown = state["batch"] + [state["recommendation"]]
    assert len(state["batch"]) == 2 and state["recommendation"]["iteration"] == 0
    for g in shown:
        t = by_slot[(g["iteration"], g["slot"])]
        assert (g["value"], g["estimate"], g["verified"]) == (t["value"], t["estimate"], t["verified"])

    # the report: every trial's figure as the status gives it, the verified value or "≈ estimate (estimated)"
    index = write_study_report(study, ReportConfig(video=False))
    text = html.unescape(index.read_text())
    rows = {int(m.group(1)): m.group(2) for m in re.finditer(
        r"<tr><td>(\d+)</td><td>\d+</td><td>COMPLETE</td>(?:<td>[^<]*</td>){3}<td>([^<]*)</td>", text)}
    assert set(rows) == set(trials)
    for n, t in trials.items():
        cell = rows[n]
        if t["verified"]:
            assert cell == f"{t['value']:.4g} N s (verified)"
        elif t["estimate"] is not None:
            assert cell == f"≈ {t['estimate']:.4g} N s (estimated)"
        else:
            assert cell == "—"
    # the report's plots mark estimates as estimates
    assert (study / "report" / "history.png").stat().st_size > 10_000
