"""The walk's summary: whether it went where the gait was planned to (:meth:`WalkResult.speed_note`), and how far its
stance sole turned (:func:`stance_sole_turn`)."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

from robustgait.sim.walk import SwitchEvent, WalkResult, mean_sole_turn, stance_sole_turn


def result(speed: float, planned: float | None, fell: bool = False, turn: float | None = None) -> WalkResult:
    return WalkResult(steps_taken=300, fell=fell, fall_reason="tilt" if fell else None, time=110.0, mean_speed=speed,
                      min_base_height=1.0, max_steps=300, switching="impact", planned_speed=planned, sole_turn=turn)


def test_a_walk_that_marches_in_place_or_backwards_is_noted_and_one_that_keeps_its_speed_is_not() -> None:
    assert result(0.30, 0.377).speed_note(0.5) == ""           # 80 % of the plan: within half of it
    note = result(-0.079, 0.377).speed_note(0.5)                # H1 on its own feet
    assert note.startswith("the walk advances backwards, -0.079 m/s, -21 % of the gait's planned 0.377 m/s")
    assert "it does not walk the gait as planned" in note
    assert "backwards" not in result(0.02, 0.31).speed_note(0.5) and result(0.02, 0.31).speed_note(0.5)
    assert result(0.50, 0.377).speed_note(0.5) == ""           # 133 %: within the band above too
    assert result(0.60, 0.377).speed_note(0.5).startswith("the walk advances 0.600 m/s, 159 %")  # too fast as well
    assert result(0.50, 0.377).speed_note(0.2)                 # a tighter sim.speed_agreement
    assert result(-0.079, 0.377, fell=True).speed_note(0.5) == ""  # a fall's speed is the fall's
    assert result(-0.079, None).speed_note(0.5) == ""          # a FROST import has no planned speed


def test_the_note_says_how_far_the_stance_sole_turned() -> None:
    """H1 on its own feet: the note gives the sole's mean turn, toe up or down; a walk without events has none."""
    note = result(-0.062, 0.377, turn=math.radians(1.69)).speed_note(0.5)
    assert note.endswith("its stance sole ends single support turned 1.69° toe up on average, where the plan holds it "
                         "flat (docs/robots.md: soft contacts turn a sole)")
    assert "0.50° toe down" in result(0.02, 0.31, turn=math.radians(-0.5)).speed_note(0.5)
    assert "turned" not in result(-0.062, 0.377).speed_note(0.5)
    assert result(0.30, 0.377, turn=0.1).speed_note(0.5) == ""  # a walk at its speed gets no note, turned or not


def test_the_sole_turn_follows_the_whole_robot_turned_about_the_lateral_axis(exo, exo_gait) -> None:  # type: ignore[no-untyped-def]
    """Turning the whole robot by δ about the world's y axis, toe up, turns the stance sole by δ (to first order in the
    sole's own yaw and roll): θ(R_y(−δ) q) − θ(q) = δ; the mean over events is the mean of each event's."""
    data = mujoco.MjData(exo.model)
    qpos = np.array(exo_gait.initial_state.qpos)
    base = stance_sole_turn(exo, data, qpos, exo_gait.stance)
    assert abs(base) < math.radians(0.5)  # the gait's start: the stance sole flat on the floor
    for delta in (0.01, 0.05):
        turned = qpos.copy()
        q = np.zeros(4)
        mujoco.mju_mulQuat(q, np.array([math.cos(-delta / 2), 0.0, math.sin(-delta / 2), 0.0]), qpos[3:7])
        turned[3:7] = q
        assert stance_sole_turn(exo, data, turned, exo_gait.stance) - base == pytest.approx(delta, rel=2e-2)
    events = [SwitchEvent(k + 1, 0.7 * (k + 1), exo_gait.stance, 1.0, q.tolist(), [0.0] * exo.model.nv)
              for k, q in enumerate((qpos, turned))]
    assert mean_sole_turn(exo, events) == pytest.approx(
        (base + stance_sole_turn(exo, data, turned, exo_gait.stance)) / 2, abs=1e-12)
    assert mean_sole_turn(exo, []) is None
