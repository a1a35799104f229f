"""A robot's gait values scaled by its size (``docs/robots.md``, "Your robot"): the rules that `robot init` writes
the ``[gait]``, ``[action_space]``, ``[gait_quality]``, ``[generation]`` and ``[fall]`` values with.

Lengths scale with the leg length l (dynamic similarity of walking: Alexander, *Principles of Animal Locomotion*,
2003, ch. 4 — walkers of different sizes move alike at equal Froude number v²/(g l)), times with √(l/g), speeds and
rates with √(g/l), heights with the standing height h. The constants are :class:`robustgait.config.ScaleRules`
(calibrated on exo). The generation options that scale with the robot (normal forces ∝ m g, the centre-of-pressure
margin and the feet's clearance ∝ the sole's width) are the loader's rules,
:func:`robustgait.config.relative_generation_defaults`, written out. The sizes are a
:class:`robustgait.config.RobotScale` (the loader's type, with what ``robot init`` measures besides).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from robustgait.config import GaitParams, RobotScale, ScaleRules, field_at, relative_generation_defaults
from robustgait.config.gait import least_step_width
from robustgait.config.regulator import RegulatorConfig
from robustgait.sim.regulator_rules import regulator_rule

# the [generation] keys a written spec carries (the landing-velocity bounds are left to the loader's rules, which
# use its own leg length)
GENERATION_KEYS = ("min_normal_force", "min_line_force", "cop_margin", "foot_gap")
GAIT_AXES = ("step_length", "step_duration", "step_width", "step_height")


def step_length(size: RobotScale, rules: ScaleRules) -> float:
    """Default step length = c · l [m]."""
    return rules.step_length * size.leg_length


def duration_constant(size: RobotScale, rules: ScaleRules, multicontact: bool = False) -> float:
    """c of the default step duration c · √(l/g): ``step_duration_multicontact``; flat-foot, ``step_duration_line``
    on line feet (their lateral error grows as a point foot's, e^(λT) over a single support, until the next foothold:
    docs/robots.md, "Closed chains, springs and line feet"), ``step_duration_narrow`` when the soles are narrow
    (:func:`narrow_soles`), else ``step_duration``."""
    if multicontact:
        return rules.step_duration_multicontact
    if size.line_feet:
        return rules.step_duration_line
    return rules.step_duration_narrow if narrow_soles(size) else rules.step_duration


def step_duration(size: RobotScale, rules: ScaleRules, multicontact: bool = False) -> float:
    """Default step duration = c · √(l/g) [s] (:func:`duration_constant`)."""
    return duration_constant(size, rules, multicontact) * math.sqrt(size.leg_length / size.gravity)


def step_width(size: RobotScale, rules: ScaleRules) -> float:
    """Default step width = the hip spacing (feet under the hips), at least sole width + c · the feet's clearance
    (``generate.foot_gap``'s robot-relative rule) [m]; legs without an ankle roll: the soles' spacing in the posture,
    the only width at which both feet land flat under a level pelvis (:mod:`robustgait.robots.legs`)."""
    if not size.ankle_roll:
        return size.sole_spacing
    gap = float(relative_generation_defaults(size)["foot_gap"])
    return max(size.hip_spacing, size.sole_width + rules.step_width_gap * gap)


def least_width(size: RobotScale) -> float:
    """The narrowest step width gait generation takes [m]: the sole's width + ``generate.foot_gap`` as the spec writes
    it (the robot-relative rule, 3 significant digits), its pre-check that the soles do not touch."""
    return least_step_width(size.sole_width, sig(float(relative_generation_defaults(size)["foot_gap"])))


def above_least(axis: tuple[float, float, float], least: float) -> tuple[float, float, float]:
    """A step-width axis [low, high, step] whose low end is the first grid point at or above ``least`` [m] (its high end
    when none is): a grid point narrower than the feet allow is never solved."""
    low, high, step = axis
    if low >= least - 1e-9:
        return axis
    return min(round(math.ceil(least / step - 1e-9) * step, 9), high), high, step


def hip_roll_angle(size: RobotScale) -> float:
    """φ = atan((w/2) / h_u) [rad] (w the soles' spacing, h_u the upper body's height over the hips): the pelvis roll
    that carries the upper body's centre of mass over the stance foot. Legs without an ankle roll move their centre
    of pressure sideways only so (the hip strategy): their gait-quality bound on the pelvis roll."""
    return math.atan2(size.sole_spacing / 2.0, max(size.upper_body_height, 1e-9))


def hips_balance(size: RobotScale) -> bool:
    """The robot balances sideways with its hips (:func:`hip_roll_angle`): legs without an ankle roll on treads that
    take a roll moment (``size.roll_support``: flat soles, and a heel point and toe bar planned as a line). Not on a
    true line foot (one capsule): it takes no roll moment, so no posture of the upper body over it moves its centre of
    pressure sideways; such a robot balances sideways by where it puts its next foot (the H-LIP's stepping: Xiong &
    Ames, "3-D underactuated bipedal walking via H-LIP based gait synthesis and stepping stabilization", IEEE T-RO
    38(4), 2022; the step regulator, :mod:`robustgait.sim.regulator`), as a point foot does."""
    return not size.ankle_roll and size.roll_support


def pelvis_roll_bound(size: RobotScale, rules: ScaleRules) -> float:
    """The gait-quality bound on the pelvis roll [rad]: exo's (``robot.scale.pelvis_roll``), or for a robot whose hips
    balance it sideways (:func:`hips_balance`) :func:`hip_roll_angle`, if larger."""
    return max(rules.pelvis_roll, hip_roll_angle(size)) if hips_balance(size) else rules.pelvis_roll


def step_height(size: RobotScale, rules: ScaleRules) -> float:
    """Default swing-sole clearance = c · l [m]."""
    return rules.step_height * size.leg_length


def angular_velocity_bound(size: RobotScale, rules: ScaleRules) -> float:
    """Bound on each component of the pelvis angular velocity = c · √(g/l) [rad/s]; when the hips balance the robot
    sideways (:func:`hips_balance`) at least 2π φ / T (φ the :func:`pelvis_roll_bound`, T the default step duration):
    the pelvis rolls over each stance foot and back within a step."""
    rate = rules.angular_velocity * math.sqrt(size.gravity / size.leg_length)
    if not hips_balance(size):
        return rate
    return max(rate, 2.0 * math.pi * pelvis_roll_bound(size, rules) / step_duration(size, rules))


def joint_velocity_bound(size: RobotScale, rules: ScaleRules) -> float:
    """Bound on each joint's speed = c · √(g/l) [rad/s]."""
    return rules.joint_velocity * math.sqrt(size.gravity / size.leg_length)


def pelvis_height_band(size: RobotScale, rules: ScaleRules) -> tuple[float, float]:
    """Band of the pelvis origin above the stance sole = (c_low, c_high) · h [m]."""
    return rules.pelvis_height[0] * size.standing_height, rules.pelvis_height[1] * size.standing_height


def fall_height(size: RobotScale, rules: ScaleRules) -> float:
    """Fall criterion: the base lower than c · h [m] (above the floor)."""
    return rules.fall_height * size.standing_height


def generation(size: RobotScale, rules: ScaleRules) -> dict[str, float]:
    """The spec's ``[generation]`` values (:data:`GENERATION_KEYS`): the loader's robot-relative rules, and for
    narrow soles (:func:`narrow_soles`) a joint margin of ``joint_margin_narrow`` when it is above 0."""
    loader = relative_generation_defaults(size)
    out = {k: float(loader[k]) for k in GENERATION_KEYS}
    if narrow_soles(size) and rules.joint_margin_narrow > 0:
        out["joint_margin"] = rules.joint_margin_narrow
    return out


def balance(size: RobotScale) -> tuple[bool, str]:
    """Whether the step regulator runs for the robot's flat-foot gaits, and why: its rule
    (:func:`~robustgait.sim.regulator_rules.regulator_rule`) with the default ``sim.regulator``."""
    return regulator_rule(RegulatorConfig(), size.sole_width, size.leg_length, 1)


def narrow_soles(size: RobotScale) -> bool:
    """The soles are narrow for the robot: :func:`balance` turns the step regulator on."""
    return balance(size)[0]


@dataclass(frozen=True)
class Balance:
    """The default gait's step-to-step balance as its walk measured it
    (:func:`robustgait.robotinit.init.measured_balance`): ``share`` κ, the share of the H-LIP's stepping gain the step
    regulator settled on (:meth:`robustgait.sim.regulator.StepRegulator.settle_share`), ``rate`` λ = √(g/z0)
    [1/s], the H-LIP's rate at the gait's CoM height z0, and ``ends_fail``: the axes of :data:`TRIED_ENDS` whose end
    of a point-foot walker's window, with the other parameters at the default, does not pass ``gait generate``
    (:func:`robustgait.robotinit.init.window_end`)."""

    share: float
    rate: float
    ends_fail: tuple[str, ...] = ()

    def point_foot(self, rules: ScaleRules) -> bool:
        """The robot balances by foot placement: κ ≥ ``point_foot_share`` (its ankle does not hold the centre of
        mass)."""
        return self.share >= rules.point_foot_share


def duration_rule(size: RobotScale, rules: ScaleRules, balance: Balance | None = None) -> tuple[float, float, int]:
    """The flat-foot action space's duration axis rule: ``action_step_duration``, its high end capped at
    ``narrow_step_duration`` · √(l/g) when the soles are narrow (:func:`narrow_soles`), and for a point-foot walker
    (:meth:`Balance.point_foot`) at λT = ``point_foot_step`` (``line_foot_step`` on capsule line feet,
    :func:`capsule_line_feet`), T ≤ that λT / λ — never below the default step, which walked."""
    low, high, points = rules.action_step_duration
    if narrow_soles(size):
        high = min(high, rules.narrow_step_duration / duration_constant(size, rules))
    if balance is not None and balance.point_foot(rules):
        step = rules.line_foot_step if capsule_line_feet(size) else rules.point_foot_step
        high = min(high, max(1.0, step / (balance.rate * step_duration(size, rules))))
    return low, high, points


def capsule_line_feet(size: RobotScale) -> bool:
    """The feet are true lines (a capsule each, Cassie's): planned as lines and without roll support, unlike a heel
    point and toe bar planned as a line (``size.roll_support``)."""
    return size.line_feet and not size.roll_support


def height_rule(size: RobotScale, rules: ScaleRules) -> tuple[float, float, int]:
    """The flat-foot action space's swing-clearance axis rule: ``action_step_height``, its low end raised to
    ``line_foot_height`` × the default on capsule line feet (:func:`capsule_line_feet`)."""
    low, high, points = rules.action_step_height
    if capsule_line_feet(size):
        low = max(low, rules.line_foot_height)
    return low, max(high, low), points


# the end of each axis that robot init tries for a point-foot walker, with the other parameters at the default: the
# narrowest step (less room for the feet to correct sideways) and the longest (the centre of pressure nearer the toe)
TRIED_ENDS = {"step_width": 0, "step_length": 1}  # axis → index of the end in (low, high)


def tried_rule(axis: str, rules: ScaleRules, balance: Balance | None = None) -> tuple[float, float, int]:
    """The flat-foot action space's rule of an axis of :data:`TRIED_ENDS` (``action_{axis}``), its tried end moved to
    the default for a point-foot walker (:meth:`Balance.point_foot`) whose gait at that end does not pass ``gait
    generate`` (:attr:`Balance.ends_fail`): the window then stops where a step was seen to walk, as the duration
    rule's end is never below the default step."""
    low, high, points = getattr(rules, f"action_{axis}")
    if balance is not None and balance.point_foot(rules) and axis in balance.ends_fail:
        if TRIED_ENDS[axis] == 0:
            low = max(low, 1.0)
        else:
            high = min(high, 1.0)
    return low, high, points


def nice_step(x: float) -> float:
    """The grid step nearest ``x`` among 1, 2, 2.5 and 5 × 10^k."""
    k = math.floor(math.log10(x))
    return min((f * 10.0**k for f in (1.0, 2.0, 2.5, 5.0, 10.0)), key=lambda s: abs(math.log(s / x)))


def axis_range(axis: str, default: float, rule: tuple[float, float, int]) -> tuple[float, float, float]:
    """An action-space axis [low, high, step]: ``rule`` = (low, high) multiples of ``default`` and the most grid
    steps; the step rounded to a nice number, low to a multiple of it, both ends within the GaitParams bounds of
    ``axis``.

    The grid stops at the grid point nearest high × default, with at most ``points`` steps: a nice step larger
    than (high − low) default / points must not stretch the range past the multiples, which were calibrated on
    exo's grid: a stretched grid would reach step durations past the 3.6 √(l/g) that exo's grid ends at."""
    lo_f, hi_f, points = rule
    lo, hi = default * lo_f, default * hi_f
    step = nice_step((hi - lo) / max(points, 1))
    doc = field_at(GaitParams, axis).doc
    low_bound = doc.low if doc.low is not None else 0.0
    high_bound = doc.high if doc.high is not None else math.inf
    lo = max(round(round(lo / step) * step, 9), math.ceil(low_bound / step - 1e-9) * step)
    steps = min(points, max(1, round((hi - lo) / step)))
    hi = min(round(lo + steps * step, 9), math.floor(high_bound / step + 1e-9) * step)
    return round(lo, 9), round(hi, 9), step


@dataclass(frozen=True)
class Scaled:
    """Every scaled value of a spec (see the functions above): the default gait, the action spaces, the
    gait-quality bands and bounds, the generation margins and forces, the fall height."""

    gait: dict[str, float]
    action_space: dict[str, tuple[float, float, float]]
    multicontact_action_space: dict[str, tuple[float, float, float]] | None
    angular_velocity: float
    pelvis_roll: float
    joint_velocity: float
    pelvis_height: tuple[float, float]
    fall_height: float
    generation: dict[str, float]


def sig(x: float, digits: int = 3) -> float:
    """``x`` rounded to ``digits`` significant digits (what a spec file shows)."""
    if x == 0.0 or not math.isfinite(x):
        return x
    return round(x, digits - 1 - math.floor(math.log10(abs(x))))


def scale(size: RobotScale, rules: ScaleRules, balance: Balance | None = None) -> Scaled:
    """All the rules applied to a robot (values rounded to 3 significant digits); ``balance``: the default gait's
    measured balance, which bounds a point-foot walker's step durations, widths and lengths (:func:`duration_rule`,
    :func:`tried_rule`)."""
    width = sig(step_width(size, rules), 3 if size.ankle_roll else 4)  # parallel legs: to 0.1 mm at a 0.2 m width
    gait = {"step_length": sig(step_length(size, rules)), "step_duration": sig(step_duration(size, rules)),
            "step_width": width, "step_height": sig(step_height(size, rules))}
    mc_gait = {**gait, "step_duration": sig(step_duration(size, rules, multicontact=True))}
    rule = ({"step_duration": duration_rule(size, rules, balance), "step_height": height_rule(size, rules)}
            | {a: tried_rule(a, rules, balance) for a in TRIED_ENDS})
    flat = {a: axis_range(a, gait[a], rule.get(a, getattr(rules, f"action_{a}"))) for a in GAIT_AXES}
    mc: dict[str, tuple[float, float, float]] | None = None
    if size.ankle_roll:  # multi-contact gaits roll the heel's edge flat with the ankle roll
        mc = {a: axis_range(a, mc_gait[a], getattr(rules, f"multicontact_{a}")) for a in GAIT_AXES}
        mc["rolling_fraction"] = rules.rolling_fraction
        flat["step_width"] = above_least(flat["step_width"], least_width(size))
        mc["step_width"] = above_least(mc["step_width"], least_width(size))
    else:  # the feet land flat at one width only: the axis holds it
        flat["step_width"] = (width, width, flat["step_width"][2])
    band = pelvis_height_band(size, rules)
    return Scaled(
        gait=gait, action_space=flat, multicontact_action_space=mc,
        angular_velocity=sig(angular_velocity_bound(size, rules)), pelvis_roll=sig(pelvis_roll_bound(size, rules)),
        joint_velocity=sig(joint_velocity_bound(size, rules)),
        pelvis_height=(sig(band[0]), sig(band[1])),
        fall_height=sig(fall_height(size, rules)),
        generation={k: sig(v) for k, v in generation(size, rules).items()})
