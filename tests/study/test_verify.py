"""A study that ranks on estimates and verifies what it shows (docs/studies.md, ``study.verify``): the evaluations hold
the exploration's estimate, each iteration's best and the recommendation get the verified certificate on the study's
workers, a study killed before they finished verifies them when resumed, and the commands that show gaits (status,
pareto) mark or verify them. Real components at small sizes: exo, a step cap of 5, push certificates with small
exploration rounds."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from robustgait.config import (
    CertifyConfig,
    ComfortConfig,
    Config,
    PushConfig,
    SequentialConfig,
    SimConfig,
    StudyConfig,
)
from robustgait.io.studyfile import load_config
from robustgait.study.run import create_study, open_store, run_study
from robustgait.study.status import figure_text, study_status
from robustgait.study.verify import Verifier

# exo, 2 × 2 gaits walked 5 steps; J* with small rounds, ε 0.2 (verification batches of 14) and 3 steps after a push
SMALL = Config(study=StudyConfig(iterations=2, batch=2, seed=0), sim=SimConfig(step_cap=5),
               certify=CertifyConfig(sequential=SequentialConfig(epsilon=0.2, first_round=10, explore=10,
                                                                explore_after_failure=10),
                                     push=PushConfig(horizon=3, explore_horizon=3)),
               comfort=ComfortConfig(skip_steps=1, steps=3))


def test_an_old_study_file_verifies_every_gait(tmp_path: Path) -> None:
    """A study written before estimates keeps ranking on verified values, its exploration the statement's."""
    d = create_study(tmp_path / "s", "exo", SMALL)
    assert load_config(d).config.study.verify == "shown"
    path = d / "study.json"
    raw = json.loads(path.read_text())
    raw["config"]["study"].pop("verify")
    for key in ("pass_probability", "explore_horizon", "explore_recovery_radius", "explore_recovery_steps"):
        raw["config"]["certify"]["push"].pop(key)
    # then the push certificate had its own round sizes in its push table
    raw["config"]["certify"]["push"].update(first_round=50, explore=100, explore_after_failure=50, verify_chunk=25)
    raw["config"]["certify"]["sequential"].update(first_round=200, explore=600, explore_after_failure=200,
                                                  verify_chunk=0, first_share=0.5)
    path.write_text(json.dumps(raw))
    cfg = load_config(d).config
    assert cfg.study.verify == "all" and cfg.study.verifies_all
    p, e = cfg.certify.push, cfg.study_certify.estimator
    assert (e.first_share, p.explore_horizon, p.explore_recovery_steps) == (0.5, 3, 2)
    assert (e.first_round, e.explore, e.explore_after_failure, e.verify_chunk) == (50, 100, 50, 25)
    # a study written with the constant margin of before reads, its verification disk now placed by the fall curve
    raw["config"]["certify"]["push"]["verify_margin"] = 0.8
    path.write_text(json.dumps(raw))
    assert load_config(d).config.certify.push.pass_probability == PushConfig().pass_probability


def test_a_requirement_on_the_certificate_verifies_every_gait() -> None:
    assert not SMALL.study.verifies_all
    assert StudyConfig(require=("j_star>=10",)).verifies_all and StudyConfig(verify="all").verifies_all
    assert not StudyConfig(require=("speed>=0.2",)).verifies_all


@pytest.mark.slow
def test_estimates_ranked_and_what_is_shown_verified_also_after_a_kill(tmp_path: Path,
                                                                       monkeypatch: pytest.MonkeyPatch) -> None:
    d = create_study(tmp_path / "s", "exo", SMALL)
    # a run whose verifications never happen (as a study killed before they finished)
    monkeypatch.setattr(Verifier, "submit", lambda self, store, indices: None)
    run_study(d, progress=False)
    st = study_status(d)
    assert st["state"] == "complete" and st["verify"] == "shown"
    trials = [t for t in st["trials"] if t["state"] == "COMPLETE"]
    estimated = [t for t in trials if t["status"] == "estimated"]
    assert estimated and all(not t["verified"] and t["value"] is None and t["estimate"] > 0 for t in estimated)
    assert all((d / t["certificate_file"]).name == "estimate.json" for t in estimated)
    best = st["best"]
    assert best is not None and not best["verified"] and "(estimated)" in figure_text(best, st["unit"])
    monkeypatch.undo()
    run_study(d, progress=False)  # resumed: the study is complete, its verifications are made now
    st = study_status(d)
    store = open_store(d, load_config(d), load_config(d).action_space())
    try:
        verified = store.verifications()
    finally:
        store.close()
    wanted = {st["best"]["grid_index"], *(it["batch_best"]["grid_index"] for it in st["iterations"])}
    assert wanted <= set(verified)
    from robustgait.study.pareto import study_pareto

    front = study_pareto(d, load_config(d).config.report.pareto_figure, verify=False)["front"]
    assert front and all(g["verified"] for g in front)  # the run verified the trade-off front the report shows
    best = st["best"]
    assert best["verified"] and best["status"] in ("certified", "not_certified")
    if best["status"] == "certified":
        assert best["value"] <= best["estimate"] + 1e-9  # drawn in a margin of the estimate
        assert (d / best["certificate_file"]).name == "certificate.json"
        cert = json.loads((d / best["certificate_file"]).read_text())
        assert cert["verified"] and cert["estimate"] == best["estimate"]
        # the verification replayed the estimate's exploration (estimate.json) instead of walking it again
        estimate = json.loads((d / best["certificate_file"]).with_name("estimate.json").read_text())
        n = estimate["n_samples"]
        assert cert["replayed_samples"] == n and cert["samples"][:n] == estimate["samples"] and cert["replayed_orbit"]
        assert cert["orbit"] == estimate["orbit"] and cert["orbit_state"] == estimate["orbit_state"]
        assert "(verified)" in figure_text(best, st["unit"])
    # the ranking is the estimates': the trials' scores did not change with the verifications
    assert [t["score"] for t in st["trials"]] == [t["score"] for t in study_status(d)["trials"]]
