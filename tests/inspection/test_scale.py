"""The scaling rules (robustgait.inspection.scale) against exo's spec, narrow soles, point feet, the grid's axes."""

from __future__ import annotations

import dataclasses
import sys

import pytest

from robustgait.config import RobotScale, ScaleRules
from robustgait.inspection.scale import axis_range, nice_step, scale

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover - exercised on 3.10 only
    import tomli as tomllib

from tests.inspection.biped import REPO


# ----------------------------------------------------------------------------------------------- scaling
def test_the_rules_give_back_exos_spec() -> None:
    size = RobotScale(leg_length=0.93, standing_height=0.921, mass=126.0, gravity=9.81, hip_spacing=0.25,
                     sole_length=0.27, sole_width=0.12)
    s = scale(size, ScaleRules())
    spec = tomllib.loads((REPO / "src" / "robustgait" / "robots" / "exo" / "spec.toml").read_text())
    for axis, value in spec["action_space"].items():
        if axis != "multicontact":
            assert s.action_space[axis] == pytest.approx(tuple(value)), axis
    for axis, value in spec["action_space"]["multicontact"].items():
        assert s.multicontact_action_space[axis] == pytest.approx(tuple(value)), axis
    q = spec["gait_quality"]
    assert s.angular_velocity == pytest.approx(q["pelvis_angular_velocity"], rel=0.03)
    assert s.joint_velocity == pytest.approx(q["joint_velocity"], rel=0.03)
    assert s.pelvis_height == pytest.approx(tuple(q["pelvis_height"]), rel=0.03)
    assert s.fall_height == pytest.approx(spec["fall"]["min_base_height"], rel=0.03)
    rules = ScaleRules()  # the gait-quality angles are exo's (scale-free)
    for k in ("pelvis_roll", "pelvis_yaw", "swing_tilt", "swing_yaw"):
        assert getattr(rules, k) == q[k], k
    assert rules.pelvis_pitch == tuple(q["pelvis_pitch"])
    assert s.gait == pytest.approx({"step_length": 0.15, "step_duration": 0.7, "step_width": 0.25,
                                    "step_height": 0.07}, rel=0.03)
    assert [nice_step(x) for x in (0.019, 0.11, 0.0024, 3.3)] == [0.02, 0.1, 0.0025, 2.5]


def test_narrow_soles_get_shorter_default_steps_and_a_shorter_grid() -> None:
    """PNDbotics Adam Lite's size (sole 0.05 m on a 0.896 m leg: narrow): the default step is 2.0 √(l/g), where the
    same robot with 0.12 m soles gets 2.3 √(l/g); the narrow grid ends at 3.0 √(l/g)."""
    import math

    narrow = RobotScale(leg_length=0.896, standing_height=0.929, mass=58.2, gravity=9.81, hip_spacing=0.234,
                       sole_length=0.22, sole_width=0.05)
    wide = dataclasses.replace(narrow, sole_width=0.12)
    t = math.sqrt(0.896 / 9.81)
    assert scale(narrow, ScaleRules()).gait["step_duration"] == pytest.approx(2.0 * t, rel=1e-2)
    assert scale(wide, ScaleRules()).gait["step_duration"] == pytest.approx(2.3 * t, rel=1e-2)
    assert scale(narrow, ScaleRules()).action_space["step_duration"][1] <= 3.0 * t + 1e-9
    assert scale(narrow, ScaleRules()).multicontact_action_space == scale(wide, ScaleRules()).multicontact_action_space


def test_line_feet_get_quicker_default_steps_than_narrow_soles() -> None:
    """Cassie's size (line feet 0.16 m long, no ankle roll, a 1.021 m leg): the default step is 1.24 √(l/g) = 0.40 s
    (λT = 1.3 at its CoM height), not the narrow soles' 2.0 √(l/g) = 0.645 s at which its default gait fell in step
    6 (docs/robots.md); the grid still ends at 3.0 √(l/g)."""
    import math

    cassie = RobotScale(leg_length=1.021, standing_height=1.01, mass=33.3, gravity=9.81, hip_spacing=0.27,
                        sole_length=0.16, sole_width=0.0002, ankle_roll=False, sole_spacing=0.2701,
                        upper_body_height=0.0284, line_feet=True)
    t = math.sqrt(1.021 / 9.81)
    rules = ScaleRules()
    assert scale(cassie, rules).gait["step_duration"] == pytest.approx(rules.step_duration_line * t, rel=1e-2)
    assert scale(cassie, rules).gait["step_duration"] == pytest.approx(0.40, abs=0.005)
    flat = dataclasses.replace(cassie, line_feet=False)
    assert scale(flat, rules).gait["step_duration"] == pytest.approx(2.0 * t, rel=1e-2)
    assert scale(cassie, rules).action_space["step_duration"][1] <= 3.0 * t + 1e-9


def test_a_point_foot_walker_steps_end_at_its_lambda_t() -> None:
    """Adam Lite's size: a walk that balances by foot placement (κ ≥ ``point_foot_share``) ends its step durations at
    λT = ``point_foot_step`` — never below the default step, which walked; an ankle that holds the centre of mass
    (κ below it), or no measurement, leaves the narrow-sole grid as it is, and nothing else of the spec moves."""
    import math

    from robustgait.inspection.scale import Balance

    size = RobotScale(leg_length=0.896, standing_height=0.929, mass=58.2, gravity=9.81, hip_spacing=0.234,
                     sole_length=0.22, sole_width=0.05)
    rules = ScaleRules()
    plain = scale(size, rules)
    assert scale(size, rules, Balance(share=0.49, rate=3.3)) == plain
    assert scale(size, rules, Balance(share=0.5, rate=3.3)) == scale(size, rules, Balance(share=1.0, rate=3.3))
    capped = scale(size, rules, Balance(share=1.0, rate=3.3))
    low, high, step = capped.action_space["step_duration"]
    assert high * 3.3 == pytest.approx(rules.point_foot_step, abs=3.3 * step / 2 + 1e-9)  # the nearest grid point
    default = plain.gait["step_duration"]
    assert abs(low - rules.action_step_duration[0] * default) <= step / 2 + 1e-9  # the same low multiple, finer step
    assert high < plain.action_space["step_duration"][1]
    assert {k: v for k, v in capped.action_space.items() if k != "step_duration"} == {
        k: v for k, v in plain.action_space.items() if k != "step_duration"}
    assert dataclasses.replace(capped, action_space=plain.action_space) == plain
    fast = scale(size, rules, Balance(share=1.0, rate=1.5 * rules.point_foot_step / default))  # default's λT 1.5 × cap
    assert fast.action_space["step_duration"][1] >= default - fast.action_space["step_duration"][2] / 2
    assert default == pytest.approx(2.0 * math.sqrt(0.896 / 9.81), rel=1e-2)


def test_a_point_foot_walker_whose_tried_end_fails_stops_that_axis_at_its_default() -> None:
    """Adam Lite's size: when the window's narrowest step (or its longest) does not pass gait generate, a point-foot
    walker's widths start (its lengths end) at the grid point nearest the default, which walked, and the other end
    stays; the failure moves nothing for an ankle that holds (κ below ``point_foot_share``), and nothing but that
    axis moves."""
    from robustgait.inspection.scale import Balance

    size = RobotScale(leg_length=0.896, standing_height=0.929, mass=58.2, gravity=9.81, hip_spacing=0.192,
                     sole_length=0.22, sole_width=0.05)
    rules = ScaleRules()
    walks = scale(size, rules, Balance(share=1.0, rate=3.3))
    for axis, end in (("step_width", 0), ("step_length", 1)):
        fails = scale(size, rules, Balance(share=1.0, rate=3.3, ends_fail=(axis,)))
        default = walks.gait[axis]
        moved, step = fails.action_space[axis][end], fails.action_space[axis][2]
        assert abs(walks.action_space[axis][end] - default) > step  # the rule reaches past the default there
        assert abs(moved - default) <= step / 2 + 1e-9
        other = fails.action_space[axis][1 - end]
        assert other == pytest.approx(walks.action_space[axis][1 - end], abs=step)
        assert {k: v for k, v in fails.action_space.items() if k != axis} == {
            k: v for k, v in walks.action_space.items() if k != axis}
        assert scale(size, rules, Balance(share=0.49, rate=3.3, ends_fail=(axis,))) == scale(size, rules)


def test_the_width_axis_starts_where_the_feet_do_not_touch() -> None:
    """Robotis OP3's size: 0.88 × its 0.104 m default width rounds to a 0.09 m grid point, narrower than its 0.078 m
    soles and their 0.013 m gap allow (gait generation refuses 0.09); the axis starts at the next grid point, for the
    flat-foot and the multi-contact grids, and nothing else moves."""
    from robustgait.inspection.scale import above_least, least_width

    size = RobotScale(leg_length=0.279, standing_height=0.3, mass=3.15, gravity=9.81, hip_spacing=0.104,
                     sole_length=0.12, sole_width=0.078)
    out = scale(size, ScaleRules())
    least = least_width(size)
    assert least == pytest.approx(0.078 + 0.013, abs=1e-9)
    for space in (out.action_space, out.multicontact_action_space):
        assert space is not None
        low, high, step = space["step_width"]
        assert least <= low < least + step and low <= high
    assert above_least((0.2, 0.3, 0.02), 0.15) == (0.2, 0.3, 0.02)  # already clear: unchanged
    assert above_least((0.09, 0.1, 0.01), 0.2) == (0.1, 0.1, 0.01)  # none clears: the high end only


def test_a_grid_stops_at_the_grid_point_nearest_its_high_multiple() -> None:
    # Booster T1's durations: 0.86–1.57 × 0.548 s = 0.47–0.86 s; the nice step 0.1 (not 0.078) must not stretch the
    # five steps to 1.0 s: the grid stops at 0.9 s, the grid point nearest 0.86 s
    assert axis_range("step_duration", 0.548, (0.86, 1.57, 5)) == (0.5, 0.9, 0.1)
    assert axis_range("step_duration", 0.708, (0.86, 1.57, 5)) == (0.6, 1.1, 0.1)  # exo's: all five steps
    assert axis_range("step_length", 0.1, (1.0, 1.05, 4))[1] > 0.1  # at least one step


def test_capsule_line_feet_end_their_steps_sooner_and_swing_higher() -> None:
    """Cassie's size: on capsule line feet (no roll support) the step durations end at λT = ``line_foot_step``, below a
    point foot's ``point_foot_step``, never below the default step, and the swing clearances start at
    ``line_foot_height`` × the default; a heel point and toe bar planned as a line (H1's: roll support) keeps a point
    foot's window, and nothing but those two axes moves (and the pelvis roll the tread's hips take)."""
    from robustgait.inspection.scale import Balance

    capsule = RobotScale(leg_length=1.021, standing_height=1.01, mass=33.3, gravity=9.81, hip_spacing=0.27,
                         sole_length=0.16, sole_width=0.0002, ankle_roll=False, sole_spacing=0.2701,
                         upper_body_height=0.0284, line_feet=True, roll_support=False)
    tread = dataclasses.replace(capsule, roll_support=True)
    rules = ScaleRules()
    rate = 3.28
    line, point = scale(capsule, rules, Balance(share=1.0, rate=rate)), scale(tread, rules, Balance(share=1.0,
                                                                                                    rate=rate))
    default = line.gait["step_duration"]
    assert line.gait == point.gait
    t_line, t_point = line.action_space["step_duration"], point.action_space["step_duration"]
    assert t_line[1] < t_point[1]
    step = t_line[2]
    assert t_line[1] >= min(rules.line_foot_step / rate, default) - step - 1e-9  # the end nearest λT or the default
    assert t_line[1] <= max(rules.line_foot_step / rate, default) + step / 2 + 1e-9
    h_line, h_point = line.action_space["step_height"], point.action_space["step_height"]
    assert h_line[0] >= rules.line_foot_height * line.gait["step_height"] - h_line[2] / 2 - 1e-9
    assert h_point[0] < h_line[0] and h_line[1] >= h_line[0]
    same = {k for k in line.action_space if k not in ("step_duration", "step_height")}
    assert {k: line.action_space[k] for k in same} == {k: point.action_space[k] for k in same}
    # the tread's roll support also gives it the hips' pelvis roll (hips_balance); everything else is the same
    assert dataclasses.replace(line, action_space=point.action_space, pelvis_roll=point.pelvis_roll,
                               angular_velocity=point.angular_velocity) == point
