"""Gait parameters (the four essential constraints) and the options of gait generation (HZD trajectory
optimization, :mod:`robustgait.gaitgen`)."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from typing import Annotated, Any, Literal

from robustgait.config.base import Doc, FieldProblem, Float, Int, Str, config

DomainGraph = Literal["flat", "multicontact"]
SpringModel = Literal["rigid", "compliant"]
Stance = Literal["left", "right"]
# The file formats a gait is written in (``gait convert --to``): robustgait's JSON, a FROST/ambersim YAML.
GaitFormat = Literal["json", "frost"]
GAIT_FORMATS: tuple[GaitFormat, ...] = ("json", "frost")

# The step duration of each domain graph when none is given [s]: multi-contact gaits of 0.7 s solve but do not
# walk on exo (the 0.14 s of rolling is too fast for the simulator's soft contacts; docs/gaitgen.md),
# 0.8–1.1 s do.
DEFAULT_STEP_DURATION: dict[str, float] = {"flat": 0.7, "multicontact": 0.9}


@config
class GaitParams:
    """The four essential constraints of a gait — step length (forward displacement of the base per step), step
    duration, step width (lateral distance between the feet centres), swing-foot height (sole clearance at
    mid-step, the maximum) — and, for multi-contact gaits, the fraction of the step spent rolling in double support.
    The bounds are generic sanity bounds; whether a robot can walk a gait is decided by the gait generator (reach,
    foot collision, IPOPT). ``step_duration`` None means the domain graph's default (:meth:`resolved`)."""

    step_length: Annotated[Float, Doc("forward displacement of the base per step", unit="m", ge=0.0, le=1.5)] = 0.15
    step_duration: Annotated[Float | None, Doc(
        "duration of a step; not set: 0.7 s flat-foot, 0.9 s multi-contact", unit="s", ge=0.1, le=5.0)] = None
    step_width: Annotated[Float, Doc("lateral distance between the feet centres", unit="m", ge=0.0, le=1.0)] = 0.25
    step_height: Annotated[Float, Doc("swing-sole clearance at mid-step", unit="m", ge=0.005, le=0.5)] = 0.07
    rolling_fraction: Annotated[Float, Doc("multi-contact: fraction of the step in rolling double support",
                                           ge=0.05, le=0.6)] = 0.2

    def resolved(self, domains: str) -> GaitParams:
        """These parameters with the step duration set (the domain graph's default when it is not)."""
        if self.step_duration is not None:
            return self
        return dataclasses.replace(self, step_duration=DEFAULT_STEP_DURATION[domains])

    @property
    def duration(self) -> float:
        """The step duration of resolved parameters [s]."""
        if self.step_duration is None:
            raise ValueError("step_duration is not set: use GaitParams.resolved(domains)")
        return self.step_duration

    def domain_durations(self, domains: str) -> list[float]:
        """Duration of each domain of a step [s]: T (flat), or T (1 − ρ) single and T ρ rolling double support
        (multi-contact)."""
        t = self.resolved(domains).duration
        return [t] if domains == "flat" else [t * (1 - self.rolling_fraction), t * self.rolling_fraction]

    def to_dict(self) -> dict[str, float]:
        """The five values (resolved parameters only: a gait file stores its actual step duration)."""
        return {"step_length": self.step_length, "step_duration": self.duration, "step_width": self.step_width,
                "step_height": self.step_height, "rolling_fraction": self.rolling_fraction}


GAIT_PARAM_NAMES = tuple(f.name for f in dataclasses.fields(GaitParams))

Pitch = Annotated[Float, Doc(unit="rad", ge=-1.5, le=1.5)]
Velocity = Annotated[Float, Doc(unit="m/s", ge=-10.0, le=10.0)]


@config
class GenerationConfig:
    """Options of the gait-generation problem (besides the :class:`GaitParams`). The gait-quality bounds a
    passenger needs (pelvis roll/yaw/pitch, swing sole, joint speeds) are the robot spec's ``[gait_quality]``."""

    domains: Annotated[DomainGraph, Doc(
        "domain graph: flat (one domain, flat foot) or multicontact (single support, heel strike, rolling double "
        "support, toe-off)")] = "flat"
    nodes: Annotated[Int, Doc("collocation nodes of single support, odd (τ = ½ is a node)", ge=5, le=101)] = 17
    ds_nodes: Annotated[Int, Doc("collocation nodes of double support (multi-contact)", ge=3, le=101)] = 17
    stance: Annotated[Stance, Doc("stance leg the gait is written for")] = "right"
    friction: Annotated[Float, Doc("μ of the friction pyramid (below the simulator's 1.0 for margin)", gt=0.0,
                                   le=2.0)] = 0.6
    torsional_friction: Annotated[Float, Doc("torsional friction coefficient μ_t", unit="m", ge=0.0, le=1.0)] = 0.02
    min_normal_force: Annotated[Float | None, Doc(
        "least normal force of a flat stance sole; not set: the robot spec's [generation] value, else 4 % of the "
        "robot's weight", unit="N", ge=0.0, le=1e5)] = None
    cop_margin: Annotated[Float | None, Doc(
        "centre of pressure margin inside the sole edges; not set: the robot spec's [generation] value, else a third "
        "of the sole's half-width", unit="m", ge=0.0, le=0.2)] = None
    joint_margin: Annotated[Float | None, Doc(
        "kept between each planned joint's trajectory and its range limits, at most a quarter of the range (room for "
        "the tracking errors and the step regulator's landing corrections); not set: the robot spec's [generation] "
        "value, else 0", unit="rad", ge=0.0, le=0.5)] = None
    impact_velocity: Annotated[tuple[Velocity, Velocity] | None, Doc(
        "[low, high] vertical velocity of the swing sole at the guard; not set: the robot spec's [generation] value, "
        "else [-0.13, -0.017] √(g l) (l: leg length)", unit="m/s")] = None
    max_impact_tangential: Annotated[Float | None, Doc(
        "bound on the swing sole's horizontal velocity at the guard; not set: the robot spec's [generation] value, "
        "else 0.05 √(g l)", unit="m/s", ge=0.0, le=10.0)] = None
    max_impact_angular: Annotated[Float, Doc("bound on each component of the swing sole's angular velocity at the "
                                             "guard", unit="rad/s", ge=0.0, le=50.0)] = 0.5
    flat_approach: Annotated[Float, Doc("every corner of the swing sole stays this fraction of the sole centre's "
                                        "height above the ground (touchdown is not a corner grazing early)",
                                        ge=0.0, le=1.0)] = 0.5
    foot_gap: Annotated[Float | None, Doc(
        "lateral clearance between the soles' edges; not set: the robot spec's [generation] value, else a third of "
        "the sole's half-width", unit="m", ge=0.0, le=1.0)] = None
    heel_strike_pitch: Annotated[tuple[Pitch, Pitch], Doc(
        "multi-contact: [min, max] toe-up pitch of the swing sole when its heel strikes", unit="rad")] = (0.2, 0.35)
    toe_off_pitch: Annotated[tuple[Pitch, Pitch], Doc(
        "multi-contact: [min, max] toe-down pitch of the stance sole at toe-off", unit="rad")] = (0.2, 0.6)
    foot_flat_rate: Annotated[Float, Doc("multi-contact: bound on the front sole's pitch rate when it lands flat",
                                         unit="rad/s", gt=0.0, le=50.0)] = 1.0
    min_line_force: Annotated[Float | None, Doc(
        "multi-contact: least normal force of each line contact; not set: the robot spec's [generation] value, "
        "else 12 % of the robot's weight", unit="N", ge=0.0, le=1e5)] = None
    ds_free_joints: Annotated[tuple[Str, ...] | None, Doc(
        "multi-contact: the 4 swing-leg joints that are not outputs in double support; not set: picked from the "
        "joint axes")] = None
    springs: Annotated[SpringModel, Doc(
        "a closed chain's springs (passive joints with a stiffness) in the gait problem: rigid (held at their "
        "springref by a holonomic row; the simulation's springs deflect under the load) or compliant (free "
        "coordinates of the problem under the model's spring and damping torque, their deflection planned); "
        "robots without springs are unaffected")] = "rigid"
    max_step_length: Annotated[Float, Doc("longest step a robot is asked for, in leg lengths (checked before any "
                                          "solve)", gt=0.0, le=2.0)] = 0.8
    max_froude: Annotated[Float, Doc("fastest walk a robot is asked for, as a Froude number (L/T)² / (g l): walking "
                                     "ends near 0.5 (checked before any solve)", gt=0.0, le=10.0)] = 0.5
    max_step_height: Annotated[Float, Doc("highest swing clearance a robot is asked for, in leg lengths (checked "
                                          "before any solve)", gt=0.0, le=1.0)] = 0.3
    max_iter: Annotated[Int, Doc("IPOPT iteration limit", ge=1, le=100_000)] = 300
    continuation: Annotated[bool, Doc("when a solve from the cold start (the posture) does not converge — IPOPT stops "
                                      "at max_iter, fails to restore feasibility or finds the problem locally "
                                      "infeasible — solve again warm-started from the robot's default gait (solved "
                                      "once per generator); a warm start given by the user is not replaced")] = True
    walk_steps: Annotated[Int, Doc("least steps the generated gait must walk in MuJoCo under the configured "
                                   "controller before gait generate calls it good (0: no walk check)", ge=0,
                                   le=1000)] = 20
    walk_settle: Annotated[bool, Doc("the walk check goes on until the orbit rule (certify.orbit) has its answer: "
                                     "the switching states settled and held their band, or did not settle by "
                                     "orbit.max_steps; a fall before then fails the check")] = True
    walk_unsettled: Annotated[Int, Doc("when the orbit rule answers that the switching states did not settle (a "
                                       "drift, a turn, a slow fall), the walk check walks on to this many steps, and "
                                       "a fall within them fails it (0: it stops at the answer)", ge=0,
                                       le=1000)] = 300
    retry_joint_margin: Annotated[Float, Doc(
        "when the walk check's gait fell after one of its joints reached the end of its range and its joint_margin "
        "is below this, gait generate solves once more with this margin (0: never)", unit="rad", ge=0.0,
        le=0.5)] = 0.1
    tol: Annotated[Float, Doc("IPOPT convergence tolerance", gt=0.0, le=1.0)] = 1e-8

    def __post_init__(self) -> None:
        if self.nodes % 2 == 0:
            raise FieldProblem("nodes", f"must be odd (τ = ½ is a node), got {self.nodes}")
        for name in ("impact_velocity", "heel_strike_pitch", "toe_off_pitch"):
            band = getattr(self, name)
            if band is not None and band[0] > band[1]:
                raise FieldProblem(name, f"must be [low, high] with low ≤ high, got [{band[0]:g}, {band[1]:g}]")

    def for_robot(self, scale: RobotScale, spec: Mapping[str, Any] | None = None) -> GenerationConfig:
        """These options with every robot-scaled field (:data:`ROBOT_SCALED`) set: the value given here, else the
        robot spec's ``[generation]`` value (``spec``), else the rule of :func:`relative_generation_defaults`."""
        rules = relative_generation_defaults(scale)
        spec = spec or {}
        given = {k: getattr(self, k) for k in ROBOT_SCALED}
        return dataclasses.replace(self, **{k: v if v is not None else spec.get(k, rules[k]) for k, v in given.items()})

    def scaled(self, name: str) -> Any:
        """A robot-scaled field's value, which must be set (:meth:`for_robot` sets them)."""
        value = getattr(self, name)
        if value is None:
            raise ValueError(f"generate.{name} is not set: resolve the options with GenerationConfig.for_robot")
        return value


def least_step_width(sole_width: float, foot_gap: float) -> float:
    """The narrowest step width [m] gait generation takes: a sole's width plus the gap ``generate.foot_gap`` [m] the
    two soles keep (its pre-check; :meth:`robustgait.gaitgen.GaitGenerator.precheck`)."""
    return sole_width + foot_gap


def reach_problem(params: GaitParams, scale: RobotScale, config: GenerationConfig) -> str | None:
    """Why a robot of leg length l (``scale``) cannot be asked for resolved ``params``, in one clause, or None: a step
    longer than ``max_step_length`` × l, a speed whose Froude number (L/T)² / (g l) exceeds ``max_froude`` (a walk,
    not a run), a swing clearance above ``max_step_height`` × l, or a step (L, W) beyond 1.2 l from the hip. Checked
    before any solve: IPOPT would spend its iteration limit on what no leg of that size walks."""
    leg, g = scale.leg_length, scale.gravity
    froude = (params.step_length / params.duration) ** 2 / (g * leg)
    if params.step_length > config.max_step_length * leg:
        return (f"step length {params.step_length:g} m is {params.step_length / leg:.2f} leg lengths, beyond "
                f"generate.max_step_length = {config.max_step_length:g} (leg length {leg:.3f} m)")
    if froude > config.max_froude:
        speed = params.step_length / params.duration
        return (f"a step of {params.step_length:g} m in {params.duration:g} s is {speed:.3g} m/s, Froude number "
                f"{froude:.3g}, beyond generate.max_froude = {config.max_froude:g} (a walk, not a run; leg length "
                f"{leg:.3f} m)")
    if params.step_height > config.max_step_height * leg:
        return (f"swing height {params.step_height:g} m is {params.step_height / leg:.2f} leg lengths, beyond "
                f"generate.max_step_height = {config.max_step_height:g} (leg length {leg:.3f} m)")
    if math.hypot(params.step_length, params.step_width) > 1.2 * leg:
        return (f"a step of {params.step_length:g} m × {params.step_width:g} m is beyond the leg reach "
                f"(leg length {leg:.3f} m)")
    return None


ROBOT_SCALED = ("min_normal_force", "min_line_force", "cop_margin", "foot_gap", "joint_margin", "impact_velocity",
                "max_impact_tangential")
"""The generation options whose defaults scale with the robot (:meth:`GenerationConfig.for_robot`)."""


@dataclasses.dataclass(frozen=True)
class RobotScale:
    """A robot's sizes, the one type of them: what robot-relative defaults (:func:`relative_generation_defaults`) and
    ``robot init``'s rules (:mod:`robustgait.inspection.scale`) scale with. ``mass`` [kg], ``gravity`` |g| [m/s²],
    ``leg_length`` l [m] and the sole's ``sole_length`` and ``sole_width`` [m] (its sole box's: a loaded robot's
    :attr:`robustgait.robots.model.Robot.scale`); and what ``robot init`` measures of a model besides
    (:class:`robustgait.inspection.discover.Legs`), which a loaded robot's scale leaves at these defaults (no loader
    rule reads them): ``standing_height`` h [m] (base above the soles in the posture), ``hip_spacing`` [m] (lateral
    distance of the legs' first joints), ``ankle_roll`` (both legs have one), ``sole_spacing`` [m] (lateral distance
    of the soles' centres in the posture), ``upper_body_height`` [m] (the centre of mass of all but the legs above
    the legs' first joints), ``line_feet`` (both soles are planned as lines: no support width,
    :func:`robustgait.inspection.discover.sole_kind`) and ``roll_support`` (the real treads take a roll moment: flat
    soles, and treads with an area planned as lines — a heel point and a toe bar; not a capsule's line)."""

    mass: float
    gravity: float
    leg_length: float
    sole_length: float
    sole_width: float
    standing_height: float = 0.0
    hip_spacing: float = 0.0
    ankle_roll: bool = True
    sole_spacing: float = 0.0
    upper_body_height: float = 0.0
    line_feet: bool = False
    roll_support: bool = True

    @property
    def sole_half_length(self) -> float:
        return self.sole_length / 2

    @property
    def sole_half_width(self) -> float:
        return self.sole_width / 2

    @property
    def weight(self) -> float:
        return self.mass * self.gravity

    @property
    def speed(self) -> float:
        """√(g l) [m/s]: the leg's pendulum speed, the scale of walking velocities (Froude scaling)."""
        return math.sqrt(self.gravity * self.leg_length)


# Fractions of the robot-relative rules, chosen to reproduce the values exo was tuned with (126 kg, l = 0.921 m,
# sole half-width 0.06 m: 50 N, 150 N, 0.02 m, 0.02 m, [-0.4, -0.05] m/s, 0.15 m/s) to within 3 %
NORMAL_FORCE_FRACTION = 0.04
LINE_FORCE_FRACTION = 0.12
SOLE_MARGIN_FRACTION = 1.0 / 3.0
IMPACT_VELOCITY_FROUDE = (-0.13, -0.017)
IMPACT_TANGENTIAL_FROUDE = 0.05
# a robot spec's gait_quality.pelvis_angular_velocity when it sets none: × √(g / l) (1.5 rad/s at a 0.92 m leg,
# 1.9 rad/s at a 0.55 m leg)
PELVIS_RATE_FROUDE = 0.44
# legs without an ankle roll land flat only under parallel legs: the step width must be the posture's sole spacing
# to within this [m] (a pelvis level at touchdown; docs/robots.md, "Legs without an ankle roll")
PARALLEL_LEGS_WIDTH_TOLERANCE = 0.001


def relative_generation_defaults(scale: RobotScale) -> dict[str, Any]:
    """The robot-relative defaults of :data:`ROBOT_SCALED`: normal forces as fractions of the weight m g (flat sole
    4 %, each line contact 12 %), the CoP margin and the feet's clearance a third of the sole's half-width, no joint
    margin (``robot init`` writes one for narrow soles only if ``robot.scale.joint_margin_narrow`` > 0), the
    swing sole's landing velocity bounds as multiples of √(g l) (Froude scaling: dynamically similar walkers of
    different sizes land at the same fraction of their pendulum speed)."""
    v = scale.speed
    return {"min_normal_force": NORMAL_FORCE_FRACTION * scale.weight,
            "min_line_force": LINE_FORCE_FRACTION * scale.weight,
            "cop_margin": SOLE_MARGIN_FRACTION * scale.sole_half_width,
            "foot_gap": SOLE_MARGIN_FRACTION * scale.sole_half_width,
            "joint_margin": 0.0,
            "impact_velocity": (IMPACT_VELOCITY_FROUDE[0] * v, IMPACT_VELOCITY_FROUDE[1] * v),
            "max_impact_tangential": IMPACT_TANGENTIAL_FROUDE * v}
