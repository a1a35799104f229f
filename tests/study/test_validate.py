"""``robustgait study validate``: every unique gait of a study under the same disturbances, the
Spearman correlations, stored and reused per gait, the scatter in the study report.

Fast tests use a small study on exo written through the study's own storage and file writers (Optuna for
real) with gaits that need no solve: the stored exo gait (certified), its mirror image (certified), the exo
gait again at another grid point whose certificate failed (a fixed-point search cut to 2 steps: a real
``not_certified`` outcome), a grid point whose generation failed, and a repeated proposal. The slow test
runs ``study run`` end to end first."""

from __future__ import annotations

import json
import math
import shutil
import time
from dataclasses import replace

import numpy as np
import pytest
from tqdm import tqdm

from robustgait import RobustGaitError, load_gait, load_robot
from robustgait.certificate.certify import certify_gait
from robustgait.cli import main
from robustgait.config import GaitParams, OrbitConfig, StudyConfig, ValidateConfig, to_dict
from robustgait.sim import walk
from robustgait.study.evaluate import Evaluation
from robustgait.study.run import StudyRunner, create_study, open_store
from robustgait.study.status import study_status
from robustgait.study.validate import RUNS_DIR, VALIDATION_DIR, config_key, validate_study
from robustgait.validate import spearman
from tests.conftest import EXO_GAIT, EXO_MC_GAIT
from tests.study.test_study import TINY

SMALL = ValidateConfig(trials=8, steps_after=3)
CAP = TINY.sim.step_cap


def _evaluation(robot, gait, params, certify):  # type: ignore[no-untyped-def]
    """What ``evaluate`` returns for a gait that was given instead of generated: walk the cap, certify."""
    w = walk(robot, gait, TINY.sim)
    gc = certify_gait(robot, gait, certify, TINY.sim)
    ok = gc.ok and w.steps_taken == CAP
    return Evaluation(params=params, status="certified" if ok else "not_certified",
                      reason="" if ok else f"{gc.status}: {gc.reason}", step_cap=CAP,
                      steps_taken=w.steps_taken, fell=w.fell, value=float(gc.value) if ok else None,
                      estimate=gc.estimate if ok else None,
                      certificate=gc.to_dict(samples=True) if ok else None, gait=gait)


@pytest.fixture(scope="module")
def small_study(tmp_path_factory):
    d = tmp_path_factory.mktemp("sv") / "study"
    create_study(d, "exo", replace(TINY, study=StudyConfig(iterations=1, batch=6)))
    robot = load_robot("exo")
    exo = load_gait(EXO_GAIT, robot)
    no_fp = replace(TINY.certify, orbit=OrbitConfig(max_steps=32, floor=1e-12, drift=1e-9))
    runner = StudyRunner(d)
    store = open_store(d, runner.setup, runner.space)
    bar = tqdm(disable=True)
    try:
        mc = load_gait(EXO_MC_GAIT, robot)  # a multi-contact gait whose certificate failed: from its heel strike
        plan = [(10, exo, TINY.certify), (20, exo.mirrored(robot), TINY.certify), (40, exo, no_fp),
                (30, None, None), (10, "again", None), (50, mc, no_fp)]
        for slot, (index, gait, certify) in enumerate(plan):
            store.enqueue(0, slot, index)
            trial = store.start()
            assert trial is not None
            params = GaitParams(**trial.params)
            if gait == "again":
                first = next(r for r in store.records() if r.index == index and r.state == "COMPLETE")
                runner._complete(store, trial, first.result or {}, bar, reused_from=first.number)
                continue
            ev = (Evaluation(params=params, status="generation_failed", reason="Infeasible_Parameters: test",
                             step_cap=CAP) if gait is None else _evaluation(robot, gait, params, certify))
            runner._complete(store, trial, runner._write_files(trial.index, ev.to_dict()), bar)
    finally:
        store.close()
    return d


@pytest.fixture(scope="module")
def first_run(small_study):
    t0 = time.perf_counter()
    out = validate_study(small_study, SMALL, progress=False)["push"]
    return out, time.perf_counter() - t0


def test_spearman_defined_and_undefined():
    from scipy.stats import spearmanr

    x, y = np.array([0.1, 0.4, 0.3, 0.9, 0.5]), np.array([0.2, 0.5, 0.1, 0.8, 0.6])
    c = spearman(x, y, "r*", "push success")
    ref = spearmanr(x, y)
    assert c.defined and c.n == 5 and c.rho == pytest.approx(ref.statistic) and c.p == pytest.approx(ref.pvalue)
    assert c.rho == pytest.approx(0.9)  # ranks (1 3 2 5 4) vs (2 3 1 5 4): 1 − 6·2/(5·24)
    for a, b, why in (([0.1, 0.2], [0.3, 0.4], "fewer than 3 gaits (n = 2)"),
                      ([0.1, 0.2, 0.3], [0.5, 0.5, 0.5], "push success is the same for every gait (0.5)"),
                      ([50, 50, 50], [0.1, 0.2, 0.3], "r* is the same for every gait (50)")):
        u = spearman(np.array(a, float), np.array(b, float), "r*", "push success")
        assert not u.defined and u.rho is None and u.p is None and u.reason == why
        json.dumps(u.to_dict(), allow_nan=False)  # never NaN


@pytest.mark.xdist_group("small_study")  # one worker computes the shared module fixture
@pytest.mark.slow  # keeps plain pytest within 60 s; CI runs it
def test_every_unique_gait_meets_the_same_disturbances(small_study, first_run):
    out, _ = first_run
    rows = {r["grid_index"]: r for r in out["gaits"]}
    assert sorted(rows) == [10, 20, 40, 50] and out["n_validated"] == 4 and out["study"]["unique_gaits"] == 5
    assert rows[10]["trials"] == [0, 4]  # proposed twice, validated once
    skipped = {s["grid_index"]: s for s in out["skipped"]}
    assert sorted(skipped) == [30] and out["skipped_counts"] == {"generation_failed": 1}
    assert "no gait file" in skipped[30]["why"]
    assert rows[50]["start"] == "initial_state" and rows[50]["status"] == "not_certified"
    assert rows[10]["start"] == rows[20]["start"] == "fixed_point" and rows[40]["start"] == "initial_state"
    assert rows[40]["status"] == "not_certified" and rows[40]["value"] == 0.0
    assert rows[40]["certificate_check"] is None
    assert rows[10]["value"] > 0 and rows[10]["certificate"]["value"] == rows[10]["value"]
    assert rows[10]["study_value"] == rows[10]["value"]
    for r in rows.values():
        s = r["success"]
        assert s["n"] == SMALL.trials and s["low"] <= s["rate"] <= s["high"] and 0 <= s["k"] <= s["n"]
    # same seed → the same draws for every gait, whatever its start, stance or step
    runs = sorted((small_study / VALIDATION_DIR / RUNS_DIR).glob("push-*/*.json"))
    assert len(runs) == 4 and len({p.parent for p in runs}) == 1
    details = [json.loads(p.read_text())["result"]["trials_detail"] for p in runs]
    for d in details[1:]:
        assert d["size"] == details[0]["size"] and d["params"] == details[0]["params"]
    assert details[0]["x_first"] != details[1]["x_first"]  # ... but different gaits, different walks
    other = validate_study(small_study, replace(SMALL, seed=1), progress=False)["push"]
    assert other["config_key"] != out["config_key"]
    seed1 = json.loads(next((small_study / VALIDATION_DIR / RUNS_DIR).glob(f"push-{other['config_key']}/*.json"))
                       .read_text())["result"]["trials_detail"]
    assert seed1["size"] != details[0]["size"]
    validate_study(small_study, SMALL, progress=False)  # push.json back to seed 0 (stored: nothing runs)


@pytest.mark.xdist_group("small_study")  # one worker computes the shared module fixture
@pytest.mark.slow  # the study it reads takes seconds to build: plain pytest stays ≤ 60 s
def test_correlations_have_n_and_p_or_a_reason(small_study, first_run):
    out, _ = first_run
    stored = json.loads((small_study / VALIDATION_DIR / "push.json").read_text())
    assert stored["correlations"] == out["correlations"] and stored["config"]["trials"] == SMALL.trials
    steps = out["correlations"]["steps_taken"]
    # every validated gait walked the cap (a certificate needs it): undefined, and said why
    assert steps == {"x": "steps taken", "y": "push success", "n": 4, "rho": None, "p": None, "defined": False,
                     "reason": "steps taken is the same for every gait (5): every validated gait walked the step cap"}
    assert set(out["correlations"]) == {"value", "value_critical", "steps_taken"}
    r = out["correlations"]["value"]
    assert r["n"] == 4 and set(r) == {"x", "y", "n", "rho", "p", "defined", "reason"}
    rates = [g["success"]["rate"] for g in out["gaits"]]
    if r["defined"]:
        assert -1 <= r["rho"] <= 1 and 0 <= r["p"] <= 1 and r["reason"] == ""
    else:
        assert len(set(rates)) == 1 and r["reason"].startswith("push success is the same")
    assert stored["sim"] == {**to_dict(TINY.sim), "n_threads": 0}  # the study's simulation


@pytest.mark.xdist_group("small_study")  # one worker computes the shared module fixture
@pytest.mark.slow  # the study it reads takes seconds to build: plain pytest stays ≤ 60 s
def test_rerun_reuses_stored_results(small_study, first_run):
    out, seconds = first_run
    t0 = time.perf_counter()
    again = validate_study(small_study, SMALL, progress=False)["push"]
    took = time.perf_counter() - t0
    assert again["n_from_earlier_runs"] == 4 and all(r["from_earlier_run"] for r in again["gaits"])
    strip = ("from_earlier_run", "seconds")
    assert [{k: v for k, v in r.items() if k not in strip} for r in again["gaits"]] == \
        [{k: v for k, v in r.items() if k not in strip} for r in out["gaits"]]
    assert again["correlations"] == out["correlations"]
    assert took < seconds


def test_config_key_ignores_threads_and_workers_only():
    c, s = TINY.certify, TINY.sim
    key = config_key(SMALL, c, s, "push")
    assert key == config_key(SMALL, c, replace(s, n_threads=3), "push") == config_key(replace(SMALL, workers=2), c, s,
                                                                                      "push")
    assert key != config_key(SMALL, c, s, "mass")
    assert key != config_key(replace(SMALL, steps_after=4), c, s, "push")
    assert key != config_key(SMALL, replace(c, seed=1), s, "push")
    assert key != config_key(SMALL, c, replace(s, step_cap=6), "push")


@pytest.mark.slow  # the study it reads takes seconds to build: plain pytest stays ≤ 60 s
def test_cli_errors_exit_2_with_one_line(tmp_path, capsys, small_study):
    (tmp_path / "plain").mkdir()
    empty = tmp_path / "empty"
    create_study(empty, "exo", replace(TINY, study=StudyConfig(iterations=1, batch=2)))
    for args, msg in ((["study", "validate", str(tmp_path / "plain")], "not a study directory"),
                      (["study", "validate", str(tmp_path / "missing")], "not a study directory"),
                      (["study", "validate", str(empty)], "no completed trial"),
                      (["study", "validate", str(small_study), "--trials", "0"], "--trials"),
                      (["study", "validate", str(small_study), "--steps-after", "-1"], "--steps-after"),
                      (["study", "validate", str(small_study), "--workers", "1000"], "--workers"),
                      (["study", "validate", str(small_study), "--disturbance", "quake"], "--disturbance")):
        assert main(args) == 2, args
        err = capsys.readouterr().err
        assert err.startswith("robustgait: error:") and msg in err and len(err.strip().splitlines()) == 1, err
    assert not (tmp_path / "plain" / VALIDATION_DIR).exists()
    with pytest.raises(RobustGaitError, match="trials"):
        validate_study(small_study, replace(SMALL, trials=20_000), progress=False)


@pytest.mark.xdist_group("small_study")  # one worker computes the shared module fixture
@pytest.mark.slow  # the study it reads takes seconds to build: plain pytest stays ≤ 60 s
def test_cli_text_and_json(small_study, first_run, capsys):
    assert main(["study", "validate", str(small_study), "--trials", "8", "--steps-after", "3", "--quiet"]) == 0
    text = capsys.readouterr().out
    assert "4 of 5 unique gaits validated (4 from an earlier run); skipped: 1 generation failed" in text
    assert "steps taken vs push success: Spearman ρ undefined (steps taken is the same" in text
    assert main(["study", "validate", str(small_study), "--trials", "8", "--steps-after", "3", "--json",
                 "--quiet"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["push"]["correlations"] == first_run[0]["correlations"]


@pytest.mark.xdist_group("small_study")  # one worker computes the shared module fixture
@pytest.mark.slow  # keeps plain pytest within 60 s; CI runs it
def test_another_state_certifies_every_gait_again(small_study, first_run, capsys):
    """--state: every certified gait gets a certificate of that state (the study's other options), is checked in
    its coordinates, and its r* is the one correlated; the study's own results stay stored under their key."""
    assert main(["study", "validate", str(small_study), "--trials", "8", "--steps-after", "3", "--state",
                 "centroidal", "--json", "--quiet"]) == 0
    out = json.loads(capsys.readouterr().out)["push"]
    assert out["certify"]["state"] == "centroidal" and out["config_key"] != first_run[0]["config_key"]
    rows = {r["grid_index"]: r for r in out["gaits"]}
    study_rows = {r["grid_index"]: r for r in first_run[0]["gaits"]}
    for i in (10, 20):
        cert = rows[i]["certificate"]
        assert cert["space"] == "centroidal" and cert["source"] == "computed" and len(cert["x_star"]) == 6
        assert rows[i]["value"] == cert["value"]
        assert rows[i]["study_value"] == study_rows[i]["value"]
        assert cert["energy"] == pytest.approx(cert["value"] ** 2 / 2)
    assert rows[40]["start"] == "initial_state" and rows[40]["value"] == 0.0
    # the same pushes as the study's own validation (the draws depend on the seed only)
    mine = json.loads(next((small_study / VALIDATION_DIR / RUNS_DIR).glob(f"push-{out['config_key']}/*.json"))
                      .read_text())["result"]["trials_detail"]
    theirs = json.loads(next((small_study / VALIDATION_DIR / RUNS_DIR).glob(
        f"push-{first_run[0]['config_key']}/*.json")).read_text())["result"]["trials_detail"]
    assert mine["size"] == theirs["size"] and len(mine["x_first"][0] or [0] * 6) == 6
    validate_study(small_study, SMALL, progress=False)  # push.json back to the study's certificates (stored)


@pytest.mark.xdist_group("small_study")  # one worker computes the shared module fixture
@pytest.mark.slow  # rendering / a second map: keeps plain pytest ≤ 60 s; CI runs it
def test_report_with_and_without_validation(small_study, first_run, tmp_path):
    from robustgait.config import ReportConfig
    from robustgait.report.study import write_study_report

    page = write_study_report(small_study, ReportConfig(video=False)).read_text()
    assert "Validation: push" in page and "Spearman ρ" in page and "skipped: no gait file" in page
    png = small_study / "report" / "validation_push.png"
    assert png.stat().st_size > 10_000
    bare = tmp_path / "bare"
    shutil.copytree(small_study, bare, ignore=shutil.ignore_patterns(VALIDATION_DIR, "report", ".lock"))
    # the copy's database path is its own (sqlite URL from the directory)
    page = write_study_report(bare, ReportConfig(video=False)).read_text()
    assert "Validation:" not in page and (bare / "report" / "history.png").is_file()


@pytest.mark.xdist_group("small_study")  # one worker computes the shared module fixture
@pytest.mark.slow  # seconds of its own: plain pytest stays ≤ 60 s; CI runs it
def test_a_changed_gait_file_is_validated_again(small_study, first_run):
    """The stored results are keyed by the files too (last in this module: it leaves one gait stored twice)."""
    g = next(r for r in first_run[0]["gaits"] if r["grid_index"] == 20)
    path = small_study / g["gait_file"]
    path.write_text(path.read_text() + "\n")  # other bytes, the same gait
    again = validate_study(small_study, SMALL, progress=False)["push"]
    assert again["n_from_earlier_runs"] == 3
    assert not next(r for r in again["gaits"] if r["grid_index"] == 20)["from_earlier_run"]


@pytest.mark.slow
def test_study_validate_on_a_study_run_end_to_end(reported_study):
    """A study made by ``study run`` (conftest's ``tiny_study``: 2 × 3 gaits, generated, walked and certified), then
    ``study validate`` with 2 worker processes; again with 1 process after removing the stored results of half the
    gaits: identical, those validated again (the rollout's thread count does not change results) and those read back;
    the report shows the scatter (conftest's ``reported_study``)."""
    d = reported_study["study"]
    two, one = reported_study["validate"]
    assert two["returncode"] == 0, two["stderr"]
    a = json.loads(two["stdout"])["push"]
    st = study_status(d)
    assert a["n_validated"] + len(a["skipped"]) == st["unique_gaits"] and a["n_validated"] >= 1
    for key, c in a["correlations"].items():
        # J* against the success rate of every validated gait; value_critical against s₅₀ of the gaits
        # with a fit
        fitted = [g for g in a["gaits"] if key != "value_critical" or g["critical"]["s50"] is not None]
        assert c["n"] == len(fitted) and (key == "value_critical" or c["n"] == a["n_validated"])
        if c["defined"]:
            assert -1 <= c["rho"] <= 1 and 0 <= c["p"] <= 1
            x = [g["value" if c["x"] in ("r*", "J*") else "steps_taken"] for g in fitted]
            from scipy.stats import spearmanr

            y = [g["critical"]["s50"] if key == "value_critical" else g["success"]["rate"] for g in fitted]
            ref = spearmanr(x, y)
            assert math.isclose(c["rho"], ref.statistic) and math.isclose(c["p"], ref.pvalue)
        else:
            assert c["rho"] is None and c["reason"]
    assert one["returncode"] == 0, one["stderr"]
    b = json.loads(one["stdout"])["push"]
    removed = reported_study["removed"]
    assert 1 <= len(removed) < a["n_validated"] and b["n_from_earlier_runs"] == a["n_validated"] - len(removed)
    assert sorted(r["label"] for r in b["gaits"] if not r["from_earlier_run"]) == sorted(removed)
    strip = ("from_earlier_run", "seconds")
    assert [{k: v for k, v in r.items() if k not in strip} for r in a["gaits"]] == \
        [{k: v for k, v in r.items() if k not in strip} for r in b["gaits"]]
    rep = reported_study["report"]
    assert rep["returncode"] == 0, rep["stderr"]
    assert rep["stdout"].splitlines()[0].endswith("/report/index.html")  # made elsewhere (renamed into place)
    page = (d / "report" / "index.html").read_text()
    assert "Validation: push" in page and (d / "report" / "validation_push.png").stat().st_size > 10_000
