"""The walk check of gait generate (robustgait.gaitgen.walkcheck): how long it walks, what it blames a fall on, and
when it solves again with room at the joint limits."""

from __future__ import annotations

import copy
from dataclasses import replace

import numpy as np
import pytest

from robustgait.config import Config
from robustgait.gaitgen.walkcheck import (
    LIMIT_ROOM,
    WalkCheck,
    advice,
    joint_at_limit,
    planned_envelope,
    probable_cause,
    retry_margin,
    sole_tipping,
    tipping_text,
    walk_check,
    walk_plan,
)
from robustgait.sim import walk


@pytest.fixture(scope="module")
def exo_record(exo, exo_gait):  # type: ignore[no-untyped-def]
    """Three steps of exo's gait with every physics step kept."""
    return walk(exo, exo_gait, steps=3, keep_trajectory=True)


def test_a_joint_near_its_range_end_is_found_first_and_named(exo, exo_gait, exo_record):  # type: ignore[no-untyped-def]
    tr = exo_record.trajectory
    plan = planned_envelope(exo, exo_gait)
    # exo's knees are planned straight, on their stops: that is not a joint running out of room
    knee, end, _ = joint_at_limit(exo, tr)  # type: ignore[misc]
    k = exo.spec.joints.index(knee)
    assert "knee" in knee and end == "lower" and plan[k, 0] - exo.joint_range[k, 0] < LIMIT_ROOM
    assert joint_at_limit(exo, tr, plan) is None
    # a joint the plan keeps 3 LIMIT_ROOM from its upper end, driven to it in one row of the second step
    q = tr[:, 1 + exo.qpos_idx]
    j = int(np.argmax(q.max(axis=0) - q.min(axis=0)))  # the joint that moves most
    robot = copy.copy(exo)
    robot.joint_range = exo.joint_range.copy()
    robot.joint_range[j, 1] = max(plan[j, 1], q[:, j].max()) + 3 * LIMIT_ROOM
    row = int(np.searchsorted(tr[:, 0], exo_record.events[0].time)) + 50
    drifted = tr.copy()
    drifted[row, 1 + exo.qpos_idx[j]] = robot.joint_range[j, 1] - LIMIT_ROOM / 2
    assert joint_at_limit(robot, drifted, plan) == (exo.spec.joints[j], "upper", row)
    # the cause names it with the step it happened in, and the advice is the joint margin
    cause, joint = probable_cause(robot, exo_gait, replace(exo_record, trajectory=drifted), None)
    assert joint == exo.spec.joints[j]
    assert f"{joint} reached the upper end of its range in step 2" in cause
    tips = advice(robot, exo_gait, Config(), cause, limit_joint=joint)
    assert any("--override generate.joint_margin=0.1; now 0 rad" in a for a in tips)


def test_the_gait_is_solved_again_only_after_a_joint_reached_its_limit(exo):  # type: ignore[no-untyped-def]
    fell = WalkCheck(20, 31, True, "tilt", "pd", cause="hip_roll reached ...", limit_joint="hip_roll")
    assert retry_margin(exo, Config(), fell) == pytest.approx(0.1)
    assert retry_margin(exo, Config(), replace(fell, limit_joint=None)) is None  # tipped, saturated, ...
    assert retry_margin(exo, Config(), replace(fell, fell=False)) is None
    cfg = Config()
    for margin, expected in ((0.1, None), (0.2, None), (0.05, 0.1)):
        given = replace(cfg, generate=replace(cfg.generate, joint_margin=margin))
        assert retry_margin(exo, given, fell) == expected
    never = replace(cfg, generate=replace(cfg.generate, retry_joint_margin=0.0))
    assert retry_margin(exo, never, fell) is None


def test_the_walk_plan_says_how_far_it_walks() -> None:
    cfg = Config()
    assert walk_plan(cfg) == ("at least 20 steps, on until its switching states settle and hold 64 steps: at most 164, "
                              "or 300 if they do not settle")
    stop = replace(cfg, generate=replace(cfg.generate, walk_unsettled=0))
    assert walk_plan(stop) == "at least 20 steps, on until its switching states settle and hold 64 steps: at most 164"
    fixed = replace(cfg, generate=replace(cfg.generate, walk_settle=False, walk_steps=30))
    assert walk_plan(fixed) == "30 steps"


@pytest.mark.slow
def test_the_walk_check_walks_until_the_orbit_rule_has_its_answer(exo, exo_gait):  # type: ignore[no-untyped-def]
    """exo's gait: the check walks until its band has held, and reports the orbit the certificate's search finds."""
    from robustgait.certificate import Walking, find_orbit

    cfg = Config()
    checked = walk_check(exo, exo_gait, cfg)
    assert checked.passed and checked.orbit == "ok"
    orbit = find_orbit(Walking(exo, exo_gait), cfg.certify)
    assert checked.taken == orbit.steps and f"settled by step {orbit.settled}" in checked.orbit_text
    short = walk_check(exo, exo_gait, replace(cfg, generate=replace(cfg.generate, walk_settle=False)))
    assert short.taken == 20 and short.orbit == ""


@pytest.mark.slow
def test_a_walk_that_does_not_settle_is_walked_on_to_see_whether_it_falls(exo, exo_gait):  # type: ignore[no-untyped-def]
    """exo's gait under an orbit rule it cannot meet (a band 1e-3 of its scatter wide): the rule answers unsettled at
    its max_steps, and the check walks on to generate.walk_unsettled steps — or stops at the answer with 0."""
    cfg = Config()
    strict = replace(cfg.certify, orbit=replace(cfg.certify.orbit, max_steps=32, settle_multiple=1e-3, drift=1e-3))
    on = replace(cfg, certify=strict, generate=replace(cfg.generate, walk_unsettled=60))
    checked = walk_check(exo, exo_gait, on)
    assert checked.orbit == "unsettled" and checked.passed and checked.taken == 60
    assert checked.text().startswith("walked 60 steps under pd; its switching states did not settle")
    stop = walk_check(exo, exo_gait, replace(on, generate=replace(on.generate, walk_unsettled=0)))
    assert stop.orbit == "unsettled" and stop.passed and 20 <= stop.taken < 60


@pytest.mark.slow
def test_a_gait_felled_at_a_joint_limit_is_solved_again_with_room_there(exo, monkeypatch):  # type: ignore[no-untyped-def]
    """The retry's control flow on exo, whose gaits walk: the first walk check is replaced by a fall at a joint limit;
    the second solve keeps generate.retry_joint_margin inside the ranges, says so in its file, and is checked."""
    from robustgait.gaitgen import GaitGenerator, walkcheck

    real, calls = walkcheck.walk_check, []

    def first_falls(robot, gait, config, check=None):  # type: ignore[no-untyped-def]
        calls.append(config.generate.joint_margin)
        if len(calls) == 1:
            return WalkCheck(20, 30, True, "tilt", "pd", cause="left_knee reached ...", limit_joint="left_knee")
        return real(robot, gait, config, check)

    monkeypatch.setattr(walkcheck, "walk_check", first_falls)
    cfg = Config(gait=exo.default_params)
    said: list[str] = []
    done = walkcheck.generate_walking(exo, cfg.params, cfg, GaitGenerator(exo, cfg.generate), say=said.append)
    assert calls == [None, pytest.approx(0.1)] and done.margin == pytest.approx(0.1)
    assert done.first is not None and done.first.limit_joint == "left_knee"
    assert done.passed and done.result.gait is not None
    assert done.result.gait.solver["joint_margin"] == pytest.approx(0.1)
    assert any("solving again with 0.1 rad" in line for line in said)
    lo, hi = exo.joint_range[:, 0], exo.joint_range[:, 1]
    plan = planned_envelope(exo, done.result.gait)
    assert np.all(plan[:, 0] >= lo + 0.1 - 1e-3) and np.all(plan[:, 1] <= hi - 0.1 + 1e-3)


@pytest.mark.parametrize("name", ["exo", "atalante"])
def test_a_tipping_sole_is_read_in_its_foot_frame(name, request):  # type: ignore[no-untyped-def]
    """sole_tipping reads the sole's SoleBox, not its geom's axes: Atalante's sole boxes have their normal along the
    geom's x axis (exo's along z), and each robot rolled about the forward axis tips its stance sole by the roll over a
    side edge — rolled left side up, the right sole stands on its right edge, its outer one — and stands on it level
    below TIP_ANGLE; mirrored, the left sole stands on its left (outer) edge."""
    robot = request.getfixturevalue(name)
    nq = robot.model.nq
    for roll, tipped in ((0.03, False), (0.3, True)):
        state = np.zeros(1 + nq + robot.model.nv)
        state[1 + 2] = 1.0
        state[1 + 3:1 + 7] = [np.cos(roll / 2), np.sin(roll / 2), 0.0, 0.0]  # left side up: the right foot stands
        found = sole_tipping(robot, state[None])
        if not tipped:
            assert found is None
            continue
        assert found is not None
        side, tilt, edge, _ = found
        assert side == "right" and tilt == pytest.approx(roll, abs=0.02) and edge == "outer"
        state[1 + 3:1 + 7] = [np.cos(roll / 2), -np.sin(roll / 2), 0.0, 0.0]  # right side up: the left foot stands
        found = sole_tipping(robot, state[None])
        assert found is not None and found[0] == "left" and found[2] == "outer"


def test_a_line_foot_rolls_freely_and_tips_over_its_toe_or_heel(tmp_path):  # type: ignore[no-untyped-def]
    """A line foot (the inline closed-chain biped of tests/robots/test_loops.py) is free to roll about its line: rolled
    0.3 rad about the forward axis (the left foot lifted) its stance foot has not tipped; pitched 0.3 rad as well, it
    tipped over its toe, and the walk check says so in the line foot's terms (its length, not a width of 0 cm)."""
    import mujoco

    from robustgait import load_robot
    from robustgait.cli import main
    from tests.inspection.biped import SERVO_RULE, write
    from tests.robots.test_loops import chain_xml

    model, spec = write(tmp_path, chain_xml(), "chain.xml"), tmp_path / "chain.toml"
    assert main(["robot", "init", str(model), "-o", str(spec), *SERVO_RULE]) == 0
    robot = load_robot(spec)
    assert robot.spec.feet == {"left": "line", "right": "line"}
    nq = robot.model.nq
    state = np.zeros(1 + nq + robot.model.nv)
    state[1:1 + nq] = robot.model.qpos0
    state[1 + 2] = 1.0

    def tilted(roll: float, pitch: float) -> np.ndarray:
        q = np.zeros(4)
        mujoco.mju_mulQuat(q, np.array([np.cos(roll / 2), np.sin(roll / 2), 0.0, 0.0]),
                           np.array([np.cos(pitch / 2), 0.0, np.sin(pitch / 2), 0.0]))
        out = state.copy()
        out[1 + 3:1 + 7] = q
        return out[None]

    assert sole_tipping(robot, tilted(0.3, 0.0)) is None  # the right foot stands, rolled on its line: not tipped
    found = sole_tipping(robot, tilted(0.1, 0.3))
    assert found is not None
    side, tilt, edge, _ = found
    assert side == "right" and edge == "toe" and tilt == pytest.approx(0.3, abs=0.01)
    found = sole_tipping(robot, tilted(0.1, -0.3))  # leaning back: on its heel
    assert found is not None and found[2] == "heel"
    text = "the right stance foot tipped over its heel (17°; the line foot is 16.0 cm long)"
    assert tipping_text(robot, found) == text


def test_a_walk_check_that_passed_says_when_the_walk_is_not_the_gaits_speed() -> None:
    """The check passes a walk that marches in place or backwards (it walks), and its line and JSON say so."""
    note = "the walk advances backwards, -0.072 m/s, -19 % of the gait's planned 0.377 m/s"
    check = WalkCheck(20, 107, False, None, "pd+hlip", orbit="ok", orbit_text="its switching states settled",
                      speed_note=note)
    assert check.passed and check.text().endswith(f"settled; note: {note}") and check.to_dict()["speed_note"] == note
    assert "note:" not in WalkCheck(20, 107, False, None, "pd").text()
