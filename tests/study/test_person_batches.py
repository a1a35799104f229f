"""A person study's batches (docs/person.md): candidates over-drawn so that each batch shown is full, evaluations made
ahead while the person answers — on a tiny exo study run by the real runner and workers, answered by a person who
takes their time (:class:`Patient`, the runner's :class:`~robustgait.study.policies.Asker`); and a study written before
over-drawn batches keeps its rule."""

from __future__ import annotations

import json
import time
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from robustgait.cli.study import print_summary
from robustgait.config import (
    CertifyConfig,
    ComfortConfig,
    Config,
    GaitParams,
    PersonConfig,
    RunConfig,
    SimConfig,
    StudyConfig,
)
from robustgait.io.robotfile import load_robot
from robustgait.io.studyfile import load_config
from robustgait.study.evaluate import evaluate
from robustgait.study.person import record_answer
from robustgait.study.run import create_study, open_store, run_study
from robustgait.study.status import study_status
from tests.study.test_study import stored_and_refitted_posterior

BATCH, OVERDRAW, FIRST = 3, 3, 2
# evaluations walk 5 steps and certify with 10 uniform samples; a gait is shown only if its step is 0.14 m or longer
TINY = Config(study=StudyConfig(iterations=2, batch=BATCH, first_batch=FIRST, seed=0, metric="person",
                                require=("step_length>=0.14",)),
              sim=SimConfig(step_cap=5), certify=CertifyConfig(method="uniform", n_samples=10),
              comfort=ComfortConfig(skip_steps=1, steps=3), person=PersonConfig(floor=0.0, overdraw=OVERDRAW))


class Patient:
    """A person who answers each batch ``seconds`` after it is shown, ranking the shown gaits in slot order — and,
    before the last batch, not before a gait evaluated ahead of the answer was made ready to show (the event the study
    evaluates ahead for, whatever the machine's speed; ``patience`` s at most)."""

    def __init__(self, directory: Path, seconds: float, last: int, patience: float = 120.0):
        self.directory, self.seconds, self.last, self.patience = directory, seconds, last, patience
        self.shown_at: dict[int, float] = {}
        self.rendered_ahead: list[int] = []
        self.ahead_at: dict[int, int] = {}  # iteration → how many were rendered ahead when it was shown

    def show(self, k: int) -> None:
        self.shown_at[k] = time.monotonic()
        self.ahead_at[k] = len(self.rendered_ahead)

    def render_ahead(self, index: int, result: dict[str, Any]) -> None:
        self.rendered_ahead.append(index)  # this person watches no videos: nothing to render

    def answered(self, k: int, timeout: float) -> bool:
        time.sleep(timeout)
        waited = time.monotonic() - self.shown_at[k]
        ahead = k == self.last or len(self.rendered_ahead) > self.ahead_at[k]
        if waited < self.seconds or (not ahead and waited < self.patience):
            return False
        setup = load_config(self.directory)
        store = open_store(self.directory, setup, setup.action_space())
        try:
            pending = store.iterations()[k]["pending"]
            ranks: list[int | None] = [None] * pending["size"]
            for rank, slot in enumerate(pending["shown"]):
                ranks[slot] = rank
            record_answer(store, k, {"ranks": ranks, "labels": [None] * pending["size"], "by": "test"})
        finally:
            store.close()
        return True


@pytest.mark.slow
def test_batches_are_full_and_evaluations_ahead_are_the_evaluations(tmp_path, capsys):
    d = create_study(tmp_path / "s", "exo", TINY)
    person = Patient(d, seconds=12.0, last=TINY.study.iterations - 1)
    run_study(d, progress=False, asker=person)
    st = study_status(d)
    assert st["state"] == "complete"
    trials = [t for t in st["trials"] if t["state"] == "COMPLETE"]
    over = []
    assert st["trials_planned"] == FIRST + (TINY.study.iterations - 1) * BATCH
    for it in st["iterations"]:
        size = FIRST if it["iteration"] == 0 else BATCH  # the person's first question asks for fewer gaits
        mine = sorted((t for t in trials if t["iteration"] == it["iteration"]), key=lambda t: t["slot"])
        n = len(mine)
        over.append(n > size)
        assert [t["slot"] for t in mine] == list(range(n)) and size <= n <= size + OVERDRAW
        assert [t["grid_index"] for t in mine] == it["proposals"][:n]  # evaluated in the learner's order
        may_show = [t["params"]["step_length"] >= 0.14 and t["status"] == "certified" for t in mine]
        assert sum(may_show) <= size and (sum(may_show) == size or n == size + OVERDRAW)
        answer = next(a for a in st["person"]["answers"] if a["iteration"] == it["iteration"])
        assert len(answer["ranks"]) == n and [r is not None for r in answer["ranks"]] == may_show
    assert any(over), over  # some batch needed its over-drawn candidates
    ahead = [t for t in trials if t["evaluated_ahead"]]
    assert st["person"]["ahead"]["evaluated"] >= st["person"]["ahead"]["used"] == len(ahead) > 0
    space = load_config(d).action_space()  # videos are made ahead only of gaits that may be shown
    assert person.rendered_ahead and all(space.value(i)["step_length"] >= 0.14 for i in person.rendered_ahead)
    assert 0.0 < st["utilisation"]["share"] <= 1.05  # an evaluation made ahead counts when its worker ran it
    print_summary(d)
    out = capsys.readouterr().out
    assert "over-drawn candidates" in out and "evaluated ahead of an answer" in out
    setup = load_config(d)
    t = ahead[0]
    fresh = evaluate(load_robot(setup.robot), GaitParams(**t["params"]), setup.config)  # ahead: the evaluation
    assert (fresh.status, fresh.steps_taken, fresh.value, fresh.estimate) == (t["status"], t["steps_taken"],
                                                                              t["value"], t["estimate"])


@pytest.mark.slow
def test_the_floor_is_the_first_gait_of_a_first_batch_proposed_around_the_default_gait(tmp_path):
    """No floor given: the first batch's first gait is the grid point nearest the default gait, and its verified
    certificate sets the floor (``floor_fraction`` of it); the batch is proposed in the ball around the default gait
    that the region's formula gives (its radius does not depend on the figure) and holds ``first_batch`` gaits that
    may be shown, evaluated on the workers side by side."""
    from robustgait.config import PushConfig, SequentialConfig
    from robustgait.learn.floor import predicted_to_clear

    cfg = Config(study=StudyConfig(iterations=1, batch=3, first_batch=2, seed=0, metric="simulated-person"),
                 sim=SimConfig(step_cap=5), comfort=ComfortConfig(skip_steps=1, steps=3),
                 certify=CertifyConfig(sequential=SequentialConfig(epsilon=0.2, first_round=10, explore=10,
                                                                  explore_after_failure=10),
                                       push=PushConfig(horizon=3, explore_horizon=3)))
    d = create_study(tmp_path / "s", "exo", cfg)
    run_study(d, progress=False, run=RunConfig(workers=2))
    st = study_status(d)
    space = load_config(d).action_space()
    mine = sorted((t for t in st["trials"] if t["state"] == "COMPLETE" and t["iteration"] == 0),
                  key=lambda t: t["slot"])
    reference = mine[0]
    assert reference["grid_index"] == space.nearest(cfg.params.to_dict())
    assert reference["status"] == "certified" and reference["value"] > 0
    floor = st["person"]["floor"]
    assert floor["reference"]["params"] == reference["params"]
    assert floor["value"] == pytest.approx(0.75 * reference["value"])
    assert st["state"] == "complete" and st["trials_planned"] == 2
    ball = predicted_to_clear(space, [(cfg.params.to_dict(), 1.0)], 0.75, 0.2, 0.1)
    proposals = st["iterations"][0]["proposals"]
    assert ball[proposals[:cfg.study.batch_size(0) + cfg.person.overdraw]].all() and ball.sum() < space.size
    shown = [t for t in mine if t["status"] == "certified" and t["value"] is not None
             and t["value"] >= floor["value"]]
    assert reference in shown and (len(shown) == 2 or len(mine) >= 2 + cfg.person.overdraw), mine
    # the posterior the study stored for the report's map: the model refitted to the person's answer
    k, stored, refit = stored_and_refitted_posterior(d)
    assert k == 0 and float(np.ptp(refit)) > 0  # two gaits ranked: a map, not the prior's zeros
    np.testing.assert_allclose(stored, refit, rtol=1e-6, atol=1e-9 * float(np.abs(refit).max()))


def test_a_study_written_before_over_drawn_batches_evaluates_its_batch_alone(tmp_path):
    d = create_study(tmp_path / "s", "exo", TINY)
    assert load_config(d).config.person.overdraw == OVERDRAW and load_config(d).config.person.ahead
    path = d / "study.json"
    raw = json.loads(path.read_text())
    raw["config"]["person"] = {k: v for k, v in raw["config"]["person"].items() if k not in ("overdraw", "ahead")}
    path.write_text(json.dumps(raw))
    person = load_config(d).config.person
    assert person.overdraw == 0 and not person.ahead


def test_a_study_written_before_the_reference_in_the_batch_evaluates_the_default_gait_beside_it(tmp_path):
    """The floor's reference of a study created before it joined the first batch stays the default gait, evaluated on
    its own: no reference index, and the first batch's proposals reproduce as they were made."""
    from robustgait.study.person import Floor

    d = create_study(tmp_path / "s", "exo", TINY)
    setup = load_config(d)
    assert setup.config.person.reference_in_batch and Floor(replace(setup.config, person=replace(
        setup.config.person, floor=None)), setup.action_space()).index is not None
    path = d / "study.json"
    raw = json.loads(path.read_text())
    del raw["config"]["person"]["reference_in_batch"]
    path.write_text(json.dumps(raw))
    old = load_config(d).config
    assert not old.person.reference_in_batch
    assert Floor(replace(old, person=replace(old.person, floor=None)), setup.action_space()).index is None
    not_person = replace(old, study=replace(old.study, metric="push"), person=replace(old.person, floor=None,
                                                                                       reference_in_batch=True))
    assert Floor(not_person, setup.action_space()).index is None  # only a study that asks a person has one
