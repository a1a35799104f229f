"""The walk's summary: whether it went where the gait was planned to (:meth:`WalkResult.speed_note`)."""

from __future__ import annotations

from robustgait.sim.walk import WalkResult


def result(speed: float, planned: float | None, fell: bool = False) -> WalkResult:
    return WalkResult(steps_taken=300, fell=fell, fall_reason="tilt" if fell else None, time=110.0, mean_speed=speed,
                      min_base_height=1.0, max_steps=300, switching="impact", planned_speed=planned)


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
