"""Tests for robustgait.study.policies: what a person study adds to the loop, and that an automatic study's policies
answer as if absent — on real study directories (a real Optuna store), no evaluation run."""

from __future__ import annotations

import math
from pathlib import Path

from robustgait.config import CertifyConfig, Config, PersonConfig, SimConfig, StudyConfig
from robustgait.io.robotfile import load_robot
from robustgait.io.studyfile import load_config
from robustgait.learn.space import ActionSpace
from robustgait.robots import Robot
from robustgait.study.executors import Executor
from robustgait.study.outcome import EvaluationStatus
from robustgait.study.policies import AheadPolicy, FloorPolicy, Overdraw, StudyContext
from robustgait.study.ranking import requirements
from robustgait.study.run import create_study, open_store
from robustgait.study.storage import StudyStore

SMALL = dict(sim=SimConfig(step_cap=5), certify=CertifyConfig(method="uniform", n_samples=10))


def no_executor() -> Executor:
    raise AssertionError("the policy submitted an evaluation")


def no_learner():  # type: ignore[no-untyped-def]
    raise AssertionError("the policy asked the learner")


def context(tmp_path: Path, config: Config) -> tuple[StudyContext, StudyStore]:
    d = create_study(tmp_path / "s", "exo", config)
    setup = load_config(d)
    robot: Robot = load_robot(setup.robot)
    space: ActionSpace = setup.action_space(robot)
    ctx = StudyContext(d, setup, space, requirements(setup.config.study, space.names), no_executor, no_learner, None)
    return ctx, open_store(d, setup, space)


def test_an_automatic_study_s_policies_are_absent(tmp_path: Path) -> None:
    """No floor (0, never pending, nothing submitted), every gait's own rule for verification (None), no region,
    the batch and no over-draw, nothing ahead."""
    ctx, store = context(tmp_path, Config(study=StudyConfig(iterations=2, batch=3, first_batch=2), **SMALL))
    floor = FloorPolicy(ctx)
    floor.start(store)
    overdraw = Overdraw(ctx, floor)
    ahead = AheadPolicy(ctx, floor, overdraw)
    assert floor.value == 0.0 and not floor.pending and floor.verify_above() is None
    assert floor.region(store, 1) is None
    assert [overdraw.candidates(k) for k in (0, 1)] == [ctx.setup.config.study.batch_size(k) for k in (0, 1)] == [3, 3]
    assert not ahead.busy and not ahead.owns(-2) and ahead.take(0) is None and ahead.key_of(0) is None
    assert not ahead.wanted(1)
    store.close()


def test_a_person_study_s_floor_over_draw_and_what_it_may_show(tmp_path: Path) -> None:
    """A configured floor is stored at the start and verifies the estimates at or above it; a candidate is shown
    only when certified at or above it; the batch is over-drawn by ``person.overdraw``; the region is where the
    floor is predicted to be cleared (a strict part of the grid around the default gait)."""
    cfg = Config(study=StudyConfig(iterations=2, batch=3, first_batch=2, metric="person"),
                 person=PersonConfig(floor=1.5, overdraw=2), **SMALL)
    ctx, store = context(tmp_path, cfg)
    floor = FloorPolicy(ctx)
    floor.start(store)
    assert floor.value == 1.5 and not floor.pending and floor.verify_above() == 1.5
    assert store.user_attrs()["floor"] == {"value": 1.5, "source": "person.floor"}
    certified = {"status": EvaluationStatus.CERTIFIED.value, "value": 2.0, "estimate": 2.4, "verified": True}
    assert floor.qualifies(0, certified)
    assert not floor.qualifies(0, {**certified, "value": 1.0})
    assert floor.qualifies(0, {**certified, "value": 1.0}, any_floor=True)
    assert not floor.qualifies(0, {"status": EvaluationStatus.ESTIMATED.value, "value": None, "estimate": 9.0})
    assert [Overdraw(ctx, floor).candidates(k) for k in (0, 1)] == [4, 5]
    store.close()


def test_an_unset_floor_is_pending_until_its_reference_and_its_first_region_does_not_wait(tmp_path: Path) -> None:
    """Without ``person.floor`` the floor is pending (∞: nothing shown, every estimate verified) until the reference
    in the first batch sets it; the first iteration's region is computed from the default gait alone, so it is
    the same before and after the floor is known."""
    cfg = Config(study=StudyConfig(iterations=2, batch=3, first_batch=2, metric="person"),
                 person=PersonConfig(overdraw=2), **SMALL)
    ctx, store = context(tmp_path, cfg)
    floor = FloorPolicy(ctx)
    floor.start(store)
    assert floor.pending and math.isinf(floor.value) and floor.verify_above() == 0.0
    assert floor.index == ctx.space.nearest(cfg.params.to_dict())
    region = floor.region(store, 0)
    assert region is not None and 0 < region.sum() < ctx.space.size and region[floor.index]
    store.close()
