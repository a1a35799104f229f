"""Studies (docs/studies.md): evaluation, config, Optuna storage contract, resume after kill -9, determinism
across worker counts, Ray retries, status/report/compare. Real components at small sizes: exo, a step cap
of 5, 10 certificate samples, 2 iterations × 3 gaits."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from robustgait import GaitParams, Robot, RobustGaitError, load_robot
from robustgait.config import (
    CertifyConfig,
    ComfortConfig,
    Config,
    GenerationConfig,
    LearnerConfig,
    OrbitConfig,
    PreferenceModelConfig,
    PushConfig,
    RunConfig,
    SimConfig,
    StudyConfig,
    to_dict,
)
from robustgait.io.robotfile import read_mjcf
from robustgait.io.studyfile import StudySetup, environment_changes, load_config, save_config
from robustgait.learn import ActionSpace
from robustgait.robots import FallCriteria
from robustgait.study.evaluate import evaluate
from robustgait.study.run import create_study
from robustgait.study.status import study_status
from robustgait.study.storage import StudyStore, default_url

REPO = Path(__file__).resolve().parents[2]
# a study's evaluations walk 5 steps (comfort measured on steps 2–4) and certify with 10 uniform samples; 2 iterations
# × 3 gaits
TINY = Config(study=StudyConfig(iterations=2, batch=3, seed=0), sim=SimConfig(step_cap=5),
              certify=CertifyConfig(method="uniform", n_samples=10), comfort=ComfortConfig(skip_steps=1, steps=3))
CLI_TINY = ["--robot", "exo", "--iterations", "2", "--batch", "3", "--method", "uniform", "--samples", "10", "--steps",
            "5", "--seed", "0", "--override", "comfort.skip_steps=1", "--override", "comfort.steps=3"]


def cli(*args: str, **kw) -> subprocess.CompletedProcess:  # type: ignore[no-untyped-def, type-arg]
    env = {**os.environ, "PYTHONPATH": str(REPO / "src")}
    return subprocess.run([sys.executable, "-m", "robustgait.cli", *args], env=env, capture_output=True, text=True,
                          **kw)


# ---- config and storage (fast) ---------------------------------------------------------------------------
def test_study_config_round_trip(tmp_path):
    study = replace(TINY.study, learner="eubo", learning=LearnerConfig(model=PreferenceModelConfig(
        lengthscale=(0.3, 0.2, 0.4, 0.5))))
    setup = StudySetup("exo", replace(TINY, study=study))
    save_config(tmp_path, setup)
    back = load_config(tmp_path)
    assert back == setup and isinstance(back.config.study.learning.model.lengthscale, tuple)
    raw = json.loads((tmp_path / "study.json").read_text())
    del raw["config"]["certify"]["alpha"]  # a field this file predates keeps its default
    raw["config"]["sim"]["step_cap"] = 7
    (tmp_path / "study.json").write_text(json.dumps(raw))
    assert load_config(tmp_path).config.sim == replace(TINY.sim, step_cap=7)
    raw["config"]["sim"]["step_cap"] = "many"
    (tmp_path / "study.json").write_text(json.dumps(raw))
    with pytest.raises(RobustGaitError, match=r"study.json: sim.step_cap: expected an integer, got a string"):
        load_config(tmp_path)
    raw["config"]["sim"]["step_cap"] = 0  # the config's own checks run too
    (tmp_path / "study.json").write_text(json.dumps(raw))
    with pytest.raises(RobustGaitError, match=r"study.json: sim.step_cap: must satisfy 1 ≤ x ≤ 1000 \(got 0\)"):
        load_config(tmp_path)


def test_study_json_records_the_library_versions_and_status_names_changes(tmp_path):
    """A study on another install may be proposed other gaits: study.json records the versions that decide its
    numbers and the status names those that changed (none for a study that predates the record)."""
    import numpy

    save_config(tmp_path, StudySetup("exo", TINY))
    raw = json.loads((tmp_path / "study.json").read_text())
    assert raw["environment"]["numpy"] == numpy.__version__ and set(raw["environment"]) >= {"botorch", "mujoco"}
    assert load_config(tmp_path).environment == raw["environment"] and environment_changes(raw["environment"]) == []
    raw["environment"]["numpy"] = "0.0.1"
    (tmp_path / "study.json").write_text(json.dumps(raw))
    assert environment_changes(load_config(tmp_path).environment) == [f"numpy 0.0.1 → {numpy.__version__}"]
    del raw["environment"]
    (tmp_path / "study.json").write_text(json.dumps(raw))
    assert load_config(tmp_path).environment is None and environment_changes(None) == []
    assert load_config(tmp_path) == StudySetup("exo", TINY)


def test_a_study_written_before_the_config_tree_still_loads(tmp_path):
    """format_version 1 (one StudyConfig holding the evaluation) → today's sections, same values."""
    old = {"format_version": 1, "config": {
        "robot": "exo", "metric": "stability", "learner": "eubo", "iterations": 4, "batch": 3, "seed": 2,
        "storage": None, "study_name": "robustgait",
        "learning": {"model": {"lengthscale": [0.4], "outputscale": 10.0, "hyperparameters": "fixed",
                               "jitter": 1e-6}, "max_candidates": 1000, "neighbourhood": 1, "max_redraws": 50,
                     "eubo_samples": 256},
        "evaluation": {"step_cap": 30, "certify": {"n_samples": 50, "method": "uniform", "seed": 5,
                                                   "sim": {"switching": "time", "n_threads": 0}},
                       "gaitgen": {"domains": "multicontact", "nodes": 17, "pelvis_roll": None}}}}
    (tmp_path / "study.json").write_text(json.dumps(old))
    setup = load_config(tmp_path)
    c = setup.config
    assert setup.robot == "exo" and c.study.metric == "stability" and c.study.iterations == 4
    assert c.sim.step_cap == 30 and c.sim.switching == "time" and c.certify.n_samples == 50 and c.certify.seed == 5
    assert c.generate.domains == "multicontact"
    # format 1 and 2 certified the base angular velocity in a ball, one step: so do they when resumed
    assert (c.certify.state, c.certify.set, c.certify.horizon, c.certify.disturbance) == ("omega", "ball", 1, "state")


def test_a_format_2_study_keeps_its_certificate_whatever_the_defaults(tmp_path):
    raw = {"format_version": 2, "robot": "exo", "config": {"certify": {"method": "uniform", "n_samples": 40}}}
    (tmp_path / "study.json").write_text(json.dumps(raw))
    c = load_config(tmp_path).config.certify
    assert (c.state, c.set, c.horizon, c.n_samples) == ("omega", "ball", 1, 40)


def test_a_study_with_the_first_push_steps_key_still_loads(tmp_path):
    """push_steps (format 3 as first written), later push.steps: a fixed horizon the recovery band retired — the study
    loads with the horizon of the push's statement."""
    raw = {"format_version": 3, "robot": "exo", "config": {"certify": {"push_steps": 2, "method": "uniform"}}}
    (tmp_path / "study.json").write_text(json.dumps(raw))
    c = load_config(tmp_path).config.certify
    assert c.push.horizon == PushConfig().horizon and c.method == "uniform"


def test_a_push_study_written_before_chunked_verification_keeps_whole_batches(tmp_path):
    push = {"steps": 3, "first_round": 50, "explore": 100, "explore_after_failure": 50}
    raw = {"format_version": 3, "robot": "exo", "config": {"certify": {"push": push}}}
    (tmp_path / "study.json").write_text(json.dumps(raw))
    assert load_config(tmp_path).config.certify.estimator.verify_chunk == 0  # as it was run
    assert Config().certify.estimator.verify_chunk == 25  # a push certificate's default now
    assert replace(Config().certify, disturbance="state").estimator.verify_chunk == 0
    chunked = {"certify": {"push": {**push, "verify_chunk": 5}}}
    (tmp_path / "study.json").write_text(json.dumps({**raw, "config": chunked}))
    assert load_config(tmp_path).config.certify.estimator.verify_chunk == 5


def test_a_push_study_with_a_state_choice_it_never_used_still_loads(tmp_path):
    """Before J* and a state choice were exclusive, `study run --metric push --state velocity` was accepted (the state
    ignored): such a study loads with the choice reset; a robustness study keeps the choice it certified."""
    certify = {"disturbance": "state", "state": "velocity", "set": "ellipsoid", "horizon": 2}
    for metric, state in (("push", "omega"), ("robustness", "velocity"), ("stability", "velocity")):
        raw = {"format_version": 3, "robot": "exo", "config": {"study": {"metric": metric}, "certify": certify}}
        (tmp_path / "study.json").write_text(json.dumps(raw))
        cfg = load_config(tmp_path).config
        assert cfg.certify.state == state and cfg.study_certify.space == ("push" if metric == "push" else "velocity")


def test_a_study_written_before_the_orbit_check_resumes_with_the_rules_it_ran_with(tmp_path):
    """A resume recomputes the learner's history from the stored results with the study's oracle (stored objective
    values and iteration records are written, never compared), then checks the proposals of an iteration already
    recorded against the learner's reproduction. A study created before certificates checked their orbit (its
    study.json has no uncertified_penalty and no orbit fields) therefore loads with the rule it ran with: a gait that
    walked the cap without a certificate tied with a certified r* = 0 — today's rule would add that comparison to its
    history, which can change the reproduced proposals and stop the resume."""
    from robustgait.study.run import completed_batches, history_before
    from robustgait.study.storage import TrialRecord

    save_config(tmp_path, StudySetup("exo", TINY))
    raw = json.loads((tmp_path / "study.json").read_text())
    del raw["config"]["certify"]["orbit"]
    del raw["config"]["study"]["uncertified_penalty"]
    (tmp_path / "study.json").write_text(json.dumps(raw))
    old = load_config(tmp_path).config
    assert old.study.uncertified_penalty == 0.0
    # one stored batch: certified with r* = 0, walked the cap without a certificate, fell
    results = [{"status": "certified", "steps_taken": 5, "step_cap": 5, "value": 0.0, "estimate": 0.0,
                "verified": True},
               {"status": "not_certified", "steps_taken": 5, "step_cap": 5, "value": None, "estimate": None,
                "verified": False},
               {"status": "fell", "steps_taken": 2, "step_cap": 5, "value": None, "estimate": None, "verified": False}]
    records = [TrialRecord(i, "COMPLETE", 0, i, 10 + i, {}, None, r, None, None, {}) for i, r in enumerate(results)]
    batches = completed_batches(records)
    assert history_before(1, batches, replace(old.study, batch=3)).comparisons == ((0, 2), (1, 2))  # as it ran
    now = history_before(1, batches, replace(old.study, batch=3, uncertified_penalty=0.5))
    assert now.comparisons == ((0, 1), (0, 2), (1, 2))  # what today's rule would have recomputed
    save_config(tmp_path, StudySetup("exo", TINY))  # a study created now keeps today's rules
    assert load_config(tmp_path).config.study.uncertified_penalty == 0.5


def test_a_study_with_the_fixed_point_fields_the_orbit_search_retired_still_loads(tmp_path):
    """A study written with the fixed-point search's fields (fp_*, stride_fallback) and a fixed push horizon
    (push.steps, push.recovery_band_steps) loads without them: its new gaits' orbits are found by the orbit search, its
    uncertified penalty is the one it ran with."""
    save_config(tmp_path, StudySetup("exo", TINY))
    raw = json.loads((tmp_path / "study.json").read_text())
    certify = raw["config"]["certify"]
    del certify["orbit"]
    certify.update({"fp_tol": 0.01, "fp_window": 20, "fp_metric": "section", "fp_min_steps": 10, "fp_max_steps": 100,
                    "fp_newton_iterations": 0, "fp_newton_tol": 1e-8, "fp_fd_step": 1e-6, "fp_fd_jump": 0.5,
                    "fp_rho_max": 1.0, "stride_fallback": True, "map": "step"})
    certify["push"].update({"steps": 3, "recovery_band_steps": 10})
    for k in ("horizon", "recovery_steps"):
        del certify["push"][k]
    (tmp_path / "study.json").write_text(json.dumps(raw))
    c = load_config(tmp_path).config
    assert c.certify.orbit == CertifyConfig().orbit and c.certify.map == "step" and c.study.uncertified_penalty == 0.5
    assert c.certify.push.horizon == PushConfig().horizon


def test_push_metric_certifies_pushes_and_robustness_states():
    c = Config(study=StudyConfig(metric="push"))
    assert c.study_certify.disturbance == "push" and c.study_certify.unit == "N s"
    assert Config().study_certify == Config().certify and Config().study.metric == "push"  # J*: the default
    r = Config(study=StudyConfig(metric="robustness"))
    assert r.study_certify.disturbance == "state" and r.study_certify.unit == "rad/s"
    with pytest.raises(RobustGaitError, match=r"Config.study.metric: push ranks gaits by J\*, which has no reduced "
                       r"state, set or horizon \(certify: state velocity"):
        Config(certify=CertifyConfig(disturbance="state", state="velocity"))


def test_studies_use_the_sequential_estimator_by_default():
    assert Config().certify.method == "sequential" and Config().certify.sequential.budget == 3000


def test_study_config_rejects_bad_values():
    with pytest.raises(RobustGaitError, match=r"StudyConfig\.metric: must be one of 'push', 'robustness', 'stability'"):
        StudyConfig(metric="speed")  # type: ignore[arg-type]
    with pytest.raises(RobustGaitError, match=r"batch: must satisfy 2 ≤ x ≤ 100 \(got 1\)"):
        StudyConfig(batch=1)
    with pytest.raises(RobustGaitError, match="iterations"):
        StudyConfig(iterations=1001)
    with pytest.raises(RobustGaitError, match="step_cap"):
        SimConfig(step_cap=0)
    with pytest.raises(RobustGaitError, match="workers"):
        RunConfig(workers=0)


@pytest.mark.slow  # seconds of its own: plain pytest stays ≤ 60 s; CI runs it
def test_storage_contract_round_trip(tmp_path):
    """enqueue (WAITING, recorded) → start (RUNNING) → complete (attributes, then COMPLETE); a RUNNING trial
    left by a dead process is failed and enqueued again with the same parameters and attributes."""
    space = ActionSpace.from_robot(load_robot("exo"))
    url = default_url(tmp_path)
    store = StudyStore(url, "s", space, create=True, user_attrs={"robustgait_config": {"x": 1}})
    store.enqueue(0, 0, 17, {"seeds": {"learner": 0, "certify": 0}})
    store.enqueue(0, 1, 839, {"seeds": {"learner": 0, "certify": 0}})
    a = store.start()
    assert a is not None and (a.iteration, a.slot, a.index) == (0, 0, 17) and a.params == space.value(17)
    result = {"status": "certified", "steps_taken": 5, "value": 0.25, "estimate": 0.3, "verified": True, "step_cap": 5,
              "reason": ""}
    store.complete(a.number, result, 5.25, {})
    b = store.start()
    assert b is not None and b.index == 839
    store.close()  # the process "dies" with trial b RUNNING

    store = StudyStore(url, "s", space)
    assert [r.state for r in store.records()] == ["COMPLETE", "RUNNING"]
    assert store.retry_interrupted() == [b.number]
    recs = store.records()
    assert [r.state for r in recs] == ["COMPLETE", "FAIL", "WAITING"]
    retry = recs[2]
    assert (retry.iteration, retry.slot, retry.index, retry.retry_of) == (0, 1, 839, b.number)
    assert retry.params == space.value(839) and retry.attrs["seeds"] == {"learner": 0, "certify": 0}
    assert recs[0].result == result and recs[0].value == 5.25 and recs[1].result is None
    store.set_iteration(0, {"proposals": [17, 839]})
    assert store.iterations() == {0: {"proposals": [17, 839]}}
    assert store.user_attrs()["robustgait_config"] == {"x": 1}
    store.close()
    # Optuna's own API reads it (what optuna-dashboard uses)
    import optuna

    s = optuna.load_study(study_name="s", storage=url)
    assert s.best_trial.params == space.value(17) and s.best_value == 5.25


def test_a_study_evaluated_before_comfort_figures_still_reads(tmp_path):
    """A trial whose stored evaluation has no comfort figures (robustgait before them): status gives None, the
    evaluation loads, the report's comfort section has nothing to show."""
    from robustgait.report.comfort import comfort_rows, measured_trials
    from robustgait.study.evaluate import Evaluation
    from robustgait.study.run import open_store

    d = tmp_path / "s"
    create_study(d, "exo", TINY)
    setup = load_config(d)
    store = open_store(d, setup, setup.action_space())
    store.enqueue(0, 0, 17)
    a = store.start()
    assert a is not None
    old = {"params": TINY.params.to_dict(), "status": "fell", "reason": "fell in step 3 (tilt)", "step_cap": 5,
           "steps_taken": 2, "fell": True, "fall_reason": "tilt", "mean_speed": 0.1, "value": None, "estimate": None,
           "verified": False, "generation": {}, "certificate": None, "seconds": {}}
    store.complete(a.number, old, 2.0, {})
    store.close()
    st = study_status(d)
    assert st["trials"][0]["comfort"] is None and st["trials"][0]["status"] == "fell"
    assert Evaluation.from_dict({**old, "gait": None}).comfort is None
    assert measured_trials(st) == [] and comfort_rows(st)[1] == []


def test_a_study_stored_with_older_names_reads_its_figure(tmp_path):
    """A study whose records name the certificate figure ``r_star`` or ``certificate_value`` (the trial's attributes,
    its stored evaluation, the floor's reference, a validation summary): every reader sees it as ``value`` (verified),
    ``estimate`` and ``verified``, with the same score; a certificate's own ``r_star`` is kept."""
    import optuna

    from robustgait.io.output import write_json
    from robustgait.study.evaluate import Evaluation
    from robustgait.study.person import stored_floor
    from robustgait.study.ranking import outcome_of, study_score
    from robustgait.study.run import open_store
    from robustgait.study.storage import current_evaluation, current_names
    from robustgait.study.validate import FORMAT_VERSION, load_summaries, summary_path

    d = tmp_path / "s"
    create_study(d, "exo", TINY)
    setup = load_config(d)
    space = setup.action_space()
    stored = {"params": TINY.params.to_dict(), "status": "certified", "reason": "", "step_cap": 5, "steps_taken": 5,
              "fell": False, "fall_reason": None, "mean_speed": 0.2, "r_star": 21.5, "generation": {},
              "certificate": {"status": "certified", "r_star": 21.5}, "comfort": None, "seconds": {}}
    store = open_store(d, setup, space)
    try:
        store.study.add_trial(optuna.trial.create_trial(
            params=space.value(17), distributions=store.distributions, value=26.5,
            user_attrs={"iteration": 0, "slot": 0, "grid_index": 17, "status": "certified", "steps_taken": 5,
                        "r_star": 21.5, "result": stored}))
        store.study.set_user_attr("floor", {"value": 16.125, "source": "person.floor_fraction", "fraction": 0.75,
                                            "reference": {"params": {}, "status": "certified", "r_star": 21.5,
                                                          "comfort": None}})
        [rec] = store.records()
        floor = stored_floor(store)
    finally:
        store.close()
    assert rec.result is not None and rec.result["value"] == rec.result["estimate"] == 21.5
    assert "r_star" not in rec.result
    assert rec.result["verified"] and rec.result["certificate"]["r_star"] == 21.5  # the certificate's field
    assert rec.attrs["value"] == 21.5 and "r_star" not in rec.attrs
    assert outcome_of(rec, False).figure == 21.5 and study_score(TINY.study, rec) == 5 + 21.5
    assert Evaluation.from_dict({**stored, "gait": None}).value == 21.5
    assert floor is not None and floor["reference"]["value"] == 21.5 and floor["value"] == 16.125
    st = study_status(d)
    assert st["trials"][0]["value"] == 21.5 and st["trials"][0]["verified"] and st["person"] is None
    assert current_names({"r_star": 1.0, "certificate_value": 2.0}) == {"value": 1.0}
    # a study that ranked on estimates: certificate_value was the estimate, verified_value the verified figure
    ranked = {"status": "certified", "certificate_value": 30.0, "estimate": 30.0, "verified_value": 24.0}
    assert current_evaluation(ranked) == {"status": "certified", "value": 24.0, "estimate": 30.0, "verified": True}
    estimated = {"status": "estimated", "certificate_value": 30.0, "estimate": 30.0, "verified_value": None}
    assert current_evaluation(estimated) == {"status": "estimated", "value": None, "estimate": 30.0, "verified": False}
    # a study validation summary written with the keys r_star, study_r_star, r_star_critical
    corr = {"x": "J*", "y": "push success", "n": 1, "rho": None, "p": None, "defined": False, "reason": "one gait"}
    summary_path(d, "push").parent.mkdir()
    write_json(summary_path(d, "push"), {
        "format_version": FORMAT_VERSION, "kind": "push",
        "gaits": [{"label": "g", "r_star": 21.0, "study_r_star": 21.5}], "skipped": [{"label": "h", "r_star": 0.0}],
        "correlations": {"r_star": corr, "r_star_critical": corr}})
    summary = load_summaries(d)["push"]
    assert summary["gaits"] == [{"label": "g", "value": 21.0, "study_value": 21.5}]
    assert summary["skipped"] == [{"label": "h", "value": 0.0}]
    assert list(summary["correlations"]) == ["value", "value_critical"]


def test_create_study_refuses_existing_and_bad_robot(tmp_path, capsys):
    (tmp_path / "full").mkdir()
    (tmp_path / "full" / "x.txt").write_text("x")
    with pytest.raises(RobustGaitError, match="not empty"):
        create_study(tmp_path / "full", "exo", TINY)
    with pytest.raises(RobustGaitError, match="not a shipped robot"):
        create_study(tmp_path / "new", "nope", TINY)
    from robustgait.cli import main

    assert main(["study", "status", str(tmp_path / "full")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("robustgait: error:") and "not a study directory" in err


def without_times(d):  # type: ignore[no-untyped-def]
    """A result without its wall-clock fields."""
    if isinstance(d, dict):
        return {k: without_times(v) for k, v in d.items()
                if k not in ("seconds", "solve_seconds", "build_seconds", "sim_steps_per_s", "worker")}
    if isinstance(d, list):
        return [without_times(v) for v in d]
    return d


def test_study_run_bad_options_leave_nothing_behind(tmp_path, capsys):
    from robustgait.cli import main

    for extra in (["--workers", "0"], ["--iterations", "0"], ["--batch", "1"], ["--samples", "0"],
                  ["--steps", "0"], ["--seed", "-1"], ["--robot", "nope"], ["--metric", "speed"]):
        d = tmp_path / "s"
        assert main(["study", "run", str(d), "--robot", "exo", *extra]) == 2
        err = capsys.readouterr().err
        assert "error:" in err and len(err.strip().splitlines()) == 1, err
        assert not d.exists()


def test_local_workers_each_get_every_core_unless_told():
    """A batch's last gait is certified alone: its worker must be able to use the cores the others left idle."""
    from robustgait.study.executors import LocalExecutor, WorkerSpec

    spec = WorkerSpec("exo", to_dict(Config()))
    assert LocalExecutor(spec, workers=2).spec.threads == (os.cpu_count() or 1)
    assert LocalExecutor(spec, workers=2, threads=1).spec.threads == 1


def test_multicontact_study_is_created_on_its_own_action_space(tmp_path):
    from robustgait.cli import main

    d = tmp_path / "mc"
    # --iterations 0 is refused, so create through the API: the CLI's --domains only sets generate.domains
    create_study(d, "exo", replace(TINY, generate=GenerationConfig(domains="multicontact")))
    assert load_config(d).config.generate.domains == "multicontact"
    st = study_status(d)
    assert st["trials_done"] == 0 and st["trials_planned"] == 6
    from robustgait.study.run import StudyRunner

    assert StudyRunner(d).space == ActionSpace.from_robot(load_robot("exo"), "multicontact")
    assert main(["study", "run", str(tmp_path / "bad"), "--robot", "exo", "--domains", "hopping"]) == 2


@pytest.mark.slow
def test_multicontact_study_runs(tmp_path):
    """One batch of two multi-contact gaits, generated, walked and certified on one worker (one build of the 2-domain
    problem, the slowest part)."""
    d = tmp_path / "mc"
    res = cli("study", "run", str(d), "--robot", "exo", "--domains", "multicontact", "--iterations", "1", "--batch",
              "2", "--method", "uniform", "--samples", "10", "--steps", "5", "--workers", "1", "--quiet")
    assert res.returncode == 0, res.stderr
    st = json.loads(cli("study", "status", str(d), "--json").stdout)
    assert st["trials_done"] == 2
    for t in st["trials"]:
        assert set(t["params"]) >= {"rolling_fraction"} and 0.8 <= t["params"]["step_duration"] <= 1.1
        assert t["status"] in ("certified", "not_certified", "fell", "generation_failed")
    assert any(t["status"] != "generation_failed" for t in st["trials"]), st["trials"]


# ---- evaluation -------------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def exo_generator():
    from robustgait.gaitgen import GaitGenerator

    robot = load_robot("exo")
    return robot, GaitGenerator(robot, TINY.generate)


@pytest.mark.slow
def test_evaluate_never_raises_and_records_stages(exo_generator):
    robot, gen = exo_generator
    good = evaluate(robot, GaitParams(), TINY, generator=gen)
    assert good.status == "certified" and good.steps_taken == 5 and not good.fell and good.value is not None
    assert good.verified and 0 < good.value <= good.estimate
    assert good.comfort is not None and good.comfort["first_step"] == 2 and good.comfort["steps"] == 3
    assert good.summary()["comfort"] == good.comfort
    assert good.certificate is not None and good.certificate["value"] == good.value  # a push certificate
    assert good.certificate["figure"] == "J*" and good.summary()["verified"]
    assert set(good.seconds) >= {"generate", "walk", "certify", "total"} and good.gait is not None
    assert "build" not in good.seconds  # the generator was given
    bad = evaluate(robot, GaitParams(step_width=0.1), TINY, generator=gen)  # the feet would collide
    assert bad.status == "generation_failed" and "Infeasible_Parameters" in bad.reason and bad.gait is None
    assert bad.steps_taken == 0 and bad.value is None and bad.estimate is None and not bad.verified
    # a fall: the same robot with a fall criterion its pelvis cannot meet (base above 0.99 m)
    strict_spec = replace(robot.spec, fall=FallCriteria(min_base_height=0.99, max_tilt=0.8))
    strict = Robot(strict_spec, read_mjcf(strict_spec))
    falls = evaluate(strict, GaitParams(), TINY, generator=gen)
    assert falls.status == "fell" and falls.fell and falls.fall_reason == "base_low" and falls.value is None
    assert falls.reason == f"fell in step {falls.steps_taken + 1} (base_low)" and "certify" not in falls.seconds
    # walks the cap but has no certificate: an orbit search that cannot settle
    never = OrbitConfig(max_steps=32, floor=1e-12, drift=1e-9)
    no_fp = replace(TINY, certify=replace(TINY.certify, orbit=never))
    nc = evaluate(robot, GaitParams(), no_fp, generator=gen)
    assert nc.status == "not_certified" and nc.steps_taken == 5 and nc.value is None and nc.refusal == "unsettled"
    assert nc.reason.startswith("unsettled: ")
    # an evaluation is a function of the parameters and the config alone (what resume and reuse rely on)
    again = evaluate(robot, GaitParams(), TINY, generator=gen)
    assert without_times(again.to_dict()) == without_times(good.to_dict())


# ---- whole studies (slow) --------------------------------------------------------------------------------
def comparable(directory: Path, finished_only: bool = False) -> dict:  # type: ignore[type-arg]
    """What must not depend on crashes or worker counts: per (iteration, slot) the gait and its outcome,
    per iteration the proposals, comparisons (as slots) and recommendation, and the best gait (``finished_only``: of
    the iterations finished so far, without the best: a study that was stopped)."""
    st = study_status(directory)
    done = [t for t in st["trials"] if t["state"] == "COMPLETE"]
    by_number = {t["number"]: t for t in done}
    slot = {t["number"]: (t["iteration"], t["slot"]) for t in done}
    keys = ("params", "status", "reason", "steps_taken", "fell", "value", "estimate", "verified", "score", "x_star")
    return {
        "trials": sorted(((t["iteration"], t["slot"]), {k: t[k] for k in keys}) for t in done),
        "iterations": [(it["proposals"], sorted((slot[w], slot[lo]) for w, lo in it["comparisons"]),
                        it["best"]["grid_index"]) for it in st["iterations"] if it["done"] or not finished_only],
        "reused": sorted((slot[t["number"]], slot[t["reused_from"]]) for t in done if t["reused_from"] is not None
                         and t["reused_from"] in by_number),
        "best": None if finished_only else (st["best"]["params"], st["best"]["value"], st["best"]["estimate"],
                                            st["best"]["steps_taken"]),
    }


@pytest.mark.slow
def test_status_reports_the_machine_use_of_a_run(tiny_study):
    """Each evaluation records its worker's CPU time; `study status` divides their sum by the busy wall time and the
    cores. An evaluation's CPU time is measured inside its trial's interval, so the share cannot exceed 1; how close
    to 1 it gets depends on what else the machine runs (another test process here), which this test does not
    assert."""
    st = study_status(tiny_study)
    use = st["utilisation"]
    assert use is not None and use["cores"] == (os.cpu_count() or 1)
    done = [t for t in st["trials"] if t["state"] == "COMPLETE" and t["reused_from"] is None]
    assert done and all(t["seconds"] for t in done)
    # busy time covers the longest evaluation and at most the evaluations one after another
    assert max(t["seconds"]["total"] for t in done) <= use["busy_seconds"] + 1.0
    assert 0.0 < use["cpu_seconds"] and 0.0 < use["share"] <= 1.0 + 1e-6
    out = cli("study", "status", str(tiny_study))
    assert out.returncode == 0 and "machine use: " in out.stdout


@pytest.mark.slow
def test_kill_9_then_resume_equals_an_uninterrupted_run(tmp_path, interrupted_study, tiny_study):
    """kill -9 of `study run` in its second iteration (conftest's ``interrupted_study``: on Ray, 2 actors);
    `study resume` (1 worker) finishes it: every trial exactly once, and the same gaits, outcomes, comparisons and best
    as the uninterrupted 2-worker reference."""
    st = study_status(interrupted_study["killed"])
    assert st["state"] == "stopped" and 1 <= st["trials_done"] < st["trials_planned"]
    interrupted = {t["number"] for t in st["trials"] if t["state"] == "RUNNING"}
    resume = interrupted_study["facts"]["resume"]
    assert resume["returncode"] == 0, resume["stderr"]
    d = interrupted_study["study"]
    st = study_status(d)
    assert st["state"] == "complete" and st["trials_done"] == 6
    done = [(t["iteration"], t["slot"]) for t in st["trials"] if t["state"] == "COMPLETE"]
    assert sorted(done) == [(k, s) for k in range(2) for s in range(3)]  # each exactly once
    failed = [t for t in st["trials"] if t["state"] == "FAIL"]
    retried = {t["retry_of"] for t in st["trials"] if t["retry_of"] is not None}
    assert {t["number"] for t in failed} == retried == interrupted  # every interrupted trial was re-run
    assert comparable(d) == comparable(tiny_study)
    d = shutil.copytree(d, tmp_path / "study")  # a finished study: nothing to do, nothing changes
    again = cli("study", "resume", str(d), "--quiet")
    assert again.returncode == 0 and comparable(d) == comparable(tiny_study)


@pytest.mark.slow  # rendering: keeps plain pytest ≤ 60 s; CI runs it
def test_report_video_is_what_the_configuration_says(tmp_path, exo, exo_gait):
    """The report's video of the best gait (render_best_video, the defaults of ReportConfig): video_steps steps from
    the gait's initial state, a frame every 1/video_fps s of them, video_width × video_height, H.264 yuv420p with its
    index first — what the page's <video> plays as it loads."""
    from robustgait.config import ReportConfig
    from robustgait.report.study import render_best_video
    from robustgait.sim import walk
    from tests.conftest import EXO_GAIT
    from tests.sim.test_engine import mp4_facts

    cfg = ReportConfig()
    status = {"robot": "exo", "best": {"gait_file": EXO_GAIT.name}}
    try:
        out = render_best_video(EXO_GAIT.parent, status, tmp_path / "best.mp4")
    except RobustGaitError as exc:  # no EGL/OSMesa on this machine: the message says what to do
        assert "MUJOCO_GL" in str(exc)
        return
    n = len(walk(exo, exo_gait, steps=cfg.video_steps, keep_trajectory=True).trajectory)
    frames = -(-n // round(1 / (cfg.video_fps * exo.dt)))
    assert frames == pytest.approx(cfg.video_steps * exo_gait.params.step_duration * cfg.video_fps, abs=1.5)
    assert mp4_facts(out) == {"codec": "h264", "pix_fmt": "yuv420p", "size": (cfg.video_width, cfg.video_height),
                              "fps": float(cfg.video_fps), "frames": frames, "index_first": True}
    small = ReportConfig(video_steps=1, video_fps=10, video_width=96, video_height=64, video_shadows=True)
    assert mp4_facts(render_best_video(EXO_GAIT.parent, status, tmp_path / "b.mp4", 2, small))["frames"] == \
        pytest.approx(2 * exo_gait.params.step_duration * 10, abs=1.5)  # steps given: the configuration's overridden


@pytest.mark.slow
def test_status_report_and_compare(tmp_path, reported_study):
    """The tiny study's status, its report (conftest's ``reported_study``: written by ``study report --no-video``) and
    ``study compare`` of the study with itself."""
    study = tmp_path / "study"  # a copy of the shared one: nothing here may write into it
    shutil.copytree(reported_study["study"], study)
    res = cli("study", "status", str(study), "--json")
    st = json.loads(res.stdout)
    assert st["trials_done"] == st["trials_planned"] == 6 and st["state"] == "complete"
    assert set(st["best"]) >= {"params", "value", "estimate", "verified", "steps_taken", "gait_file"}
    assert len(st["trials"]) == 6
    assert all({"params", "value", "estimate", "verified", "unit", "steps_taken", "status"} <= set(t)
               for t in st["trials"])
    walked = [t for t in st["trials"] if t["status"] in ("certified", "not_certified")]
    assert walked and all(t["comfort"]["steps"] == 3 and t["comfort"]["speed"] > 0 for t in walked)
    assert st["best"]["comfort"] is not None and st["best"]["comfort"]["cost_of_transport"] > 0
    best = st["best"]
    assert best["steps_taken"] == 5 and (study / best["gait_file"]).is_file()
    observed = max(t["score"] for t in st["trials"])
    assert best["score"] <= observed
    text = cli("study", "status", str(study))
    assert text.returncode == 0 and "best gait" in text.stdout
    assert st["environment_changes"] == [] and "other library versions" not in text.stdout
    moved = tmp_path / "moved"  # the same study opened on another install: the status says which versions differ
    shutil.copytree(study, moved)
    raw = json.loads((moved / "study.json").read_text())
    raw["environment"]["botorch"] = "0.0.1"
    (moved / "study.json").write_text(json.dumps(raw))
    text = cli("study", "status", str(moved))
    assert text.returncode == 0 and "created with other library versions (botorch 0.0.1 → " in text.stdout
    again = cli("study", "run", str(study), *CLI_TINY)
    assert again.returncode == 2 and "study resume" in again.stderr

    rep = reported_study["report"]
    assert rep["returncode"] == 0, rep["stderr"]
    assert rep["stdout"].splitlines()[0].endswith("/report/index.html")  # made elsewhere: the copy's page
    html = study / "report" / "index.html"
    page = html.read_text()
    assert page.count("data:image/png;base64,") >= 3 and "<img src=\"report/" not in page
    assert "What the passenger feels" in page and "cost of transport" in page
    for png in ("history.png", "explored.png", "posterior.png", "comfort.png"):
        assert (html.parent / png).stat().st_size > 10_000

    cmp = cli("study", "compare", str(study), str(study), "--seeds", "2", "--samples", "10",
              "--json")
    out = json.loads(cmp.stdout)
    a, b = out["studies"]
    assert out["seeds"] == [1000, 1001] and a["values"] == b["values"] and out["winner"] is None
    assert a["steps_taken"] == 5 and len(a["certificates"]) == 2
    # the text names the estimator in its own words: the reference study certifies with the uniform estimator
    assert out["method"] == "uniform"
    txt = cli("study", "compare", str(study), str(study), "--seeds", "1", "--samples", "10")
    assert txt.returncode == 0 and "(uniform, N = 10)" in txt.stdout.splitlines()[0]


def stored_and_refitted_posterior(directory: Path) -> tuple[int, np.ndarray, np.ndarray]:
    """(k, the posterior mean the study stored after iteration k, the model refitted to the same history)."""
    from robustgait.report.study import _grid_posterior
    from robustgait.study.ranking import history_before, requirements
    from robustgait.study.run import completed_batches, open_store

    setup = load_config(directory)
    cfg, space = setup.config.study, setup.action_space()
    store = open_store(directory, setup, space)
    try:
        stored, batches, iterations = store.posterior(), completed_batches(store.records()), store.iterations()
    finally:
        store.close()
    assert stored is not None and stored[1].shape == (space.size,)
    history = history_before(stored[0] + 1, batches, cfg, iterations, requirements(cfg, space.names))
    return stored[0], stored[1], _grid_posterior(space, cfg, history, stored[0], None)


@pytest.mark.slow
def test_the_report_draws_the_posterior_the_study_stored_without_torch(tiny_study, reported_study):
    """The study stores the learner's posterior over the grid when it closes an iteration (the tiny study's gaits tie:
    the prior's zeros; a map with comparisons: tests/study/test_person_batches.py), and the report draws it without
    importing torch (conftest's ``reported_study``: ``study report`` in a fresh interpreter)."""
    k, stored, refit = stored_and_refitted_posterior(tiny_study)
    assert k == load_config(tiny_study).config.study.iterations - 1
    np.testing.assert_allclose(stored, refit, rtol=1e-6, atol=1e-12)
    res = reported_study["report"]
    assert res["returncode"] == 0, res["stderr"]
    assert res["stdout"].strip().splitlines()[-1] == "False"
    assert (reported_study["study"] / "report" / "posterior.png").stat().st_size > 10_000


@pytest.mark.slow
def test_ray_worker_killed_mid_task_is_retried(interrupted_study, tiny_study):
    """A Ray actor killed while it evaluates a gait (conftest's ``interrupted_study``): Ray restarts it and runs the
    task again — the first iteration completes on Ray with no failed trial, none of its gaits from the killed actor
    and one from the actor in its place, each the reference's; the study resumed on Ray completes with the reference
    results (tests/study/test_study.py's kill -9 test checks the resume)."""
    from robustgait.study.run import open_store

    facts = interrupted_study["facts"]
    assert len(facts["actors"]) == 2 and facts["killed_actor"] in facts["actors"]
    assert facts["restarted"] and not set(facts["restarted"]) & set(facts["actors"])  # the actor was restarted
    killed = interrupted_study["killed"]
    setup = load_config(killed)
    store = open_store(killed, setup, setup.action_space())
    try:
        records = store.records()
    finally:
        store.close()
    assert not [r for r in records if r.state == "FAIL"]  # Ray ran the task again: the study saw no failure
    first = [r for r in records if r.state == "COMPLETE" and r.iteration == 0]
    assert sorted(r.slot for r in first) == [0, 1, 2]
    pids = {(r.result or {})["worker"]["pid"] for r in records if r.state == "COMPLETE"}
    assert facts["killed_actor"] not in pids and pids & set(facts["restarted"])
    ref = comparable(tiny_study)
    ray = comparable(killed, finished_only=True)
    assert ray["trials"] and all(t in ref["trials"] for t in ray["trials"])
    assert ray["iterations"] == ref["iterations"][:1]
    st = study_status(interrupted_study["study"])
    assert st["state"] == "complete" and st["trials_done"] == 6
    assert comparable(interrupted_study["study"]) == ref


def test_the_progress_bar_and_status_say_a_refused_gait_is_refused():
    """A gait that walked the cap without a certificate is 'refused' with its status, not a zero; study status counts
    every outcome."""
    from robustgait.study.status import outcome_counts
    from robustgait.study.storage import TrialRecord
    from robustgait.study.trials import outcome_line

    results = [{"status": "certified", "value": 21.5, "estimate": 25.0, "verified": True, "steps_taken": 50},
               {"status": "not_certified", "value": None, "steps_taken": 50, "refusal": "unsettled",
                "reason": "unsettled: its band keeps moving …"},
               {"status": "not_certified", "value": None, "steps_taken": 50, "refusal": "unstable",
                "reason": "unstable: the walk settled …"},
               {"status": "fell", "value": None, "steps_taken": 12},
               {"status": "generation_failed", "value": None, "steps_taken": 0}]
    lines = [outcome_line(r, "J*") for r in results]
    assert lines == ["J* 21.500, steps 50", "refused (unsettled), steps 50", "refused (unstable), steps 50",
                     "fell in step 13", "generation failed"]
    again = {**results[0], "retried": {"joint_margin": 0.1, "status": "fell", "limit_joint": "hip_roll"}}
    assert outcome_line(again, "J*") == "J* 21.500, steps 50 (generated again with joint margin 0.1 rad)"
    records = [TrialRecord(i, "COMPLETE", 0, i, i, {}, None, r, None, None, {}) for i, r in enumerate(results)]
    records.append(TrialRecord(9, "RUNNING", 0, 9, 9, {}, None, None, None, None, {}))
    assert outcome_counts(records) == {"certified": 1, "fell": 1, "generation_failed": 1, "refused: unsettled": 1,
                                       "refused: unstable": 1}
