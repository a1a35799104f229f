"""Options of robot inspection (:mod:`robustgait.inspection`): how ``robot init`` reads a model and makes its gains,
the constants of the rules that scale a spec's gait values with the robot (leg length l, standing height h, the
model's gravity g), and the thresholds of ``robot check``. (The generation options that scale with the robot —
normal forces, margins — have their rules in :func:`robustgait.config.relative_generation_defaults`.)

The scaling constants are calibrated on the shipped exo (l = 0.93 m, h = 0.92 m, 126 kg), so that the rules give
back its hand-written spec; ``docs/robots.md`` compares what they give for exo and Atalante with their specs."""

from __future__ import annotations

import dataclasses
import itertools
from typing import Annotated, Literal

from robustgait.config.base import Bool, Doc, FieldProblem, Float, Int, Str, config

Plan = Literal["legs", "all"]
TimestepRule = Literal["accuracy", "servo"]
# a candidate's reference walk runs at half of it, which a spec's timestep may still be (io.limits.TIMESTEP: ≥ 0.1 ms)
Candidate = Annotated[Float, Doc(unit="s", ge=2e-4, le=0.05)]
Factor = Annotated[Float, Doc(gt=0.0, le=100.0)]
Fraction = Annotated[Float, Doc(gt=0.0, le=1.0)]
Angle = Annotated[Float, Doc(ge=-1.0, le=1.0)]
GridPoints = Annotated[Int, Doc(ge=1, le=20)]
AxisRule = Annotated[tuple[Factor, Factor, GridPoints], Doc(
    "[low, high] as multiples of the default, and the most grid steps between them (the grid stops at the "
    "grid point nearest high × default)")]


@config
class ScaleRules:
    """The constants of the rules that scale a written spec with the robot (:mod:`robustgait.inspection.scale`)."""

    step_length: Annotated[Float, Doc("default step length ÷ leg length", gt=0.0, le=2.0)] = 0.16
    step_duration: Annotated[Float, Doc("default flat-foot step duration ÷ √(l/g)", gt=0.0, le=20.0)] = 2.3
    step_duration_multicontact: Annotated[Float, Doc("default multi-contact step duration ÷ √(l/g)", gt=0.0,
                                                     le=20.0)] = 2.9
    step_height: Annotated[Float, Doc("default swing-sole clearance ÷ leg length", gt=0.0, le=1.0)] = 0.075
    step_width_gap: Annotated[Float, Doc("least step width: sole width + this multiple of the feet's clearance "
                                         "generate.foot_gap (the default step width is the hip spacing, at least "
                                         "this)", ge=0.0, le=10.0)] = 2.0
    step_duration_narrow: Annotated[Float, Doc(
        "default flat-foot step duration ÷ √(l/g) when the soles are narrow (sole width / leg length < "
        "sim.regulator.narrow_ratio): the step regulator corrects once a step, and over a long single support the "
        "error grows past what a narrow sole holds", gt=0.0, le=20.0)] = 2.0
    step_duration_line: Annotated[Float, Doc(
        "default flat-foot step duration ÷ √(l/g) when the feet are lines (no support width: Cassie's): the lateral "
        "CoM error of a line foot grows as a point foot's, e^(λT) over a single support, until the next foothold "
        "corrects it", gt=0.0, le=20.0)] = 1.24
    narrow_step_duration: Annotated[Float, Doc(
        "longest flat-foot step of the action space ÷ √(l/g) when the soles are narrow (sole width / leg length < "
        "sim.regulator.narrow_ratio): a long single support on a narrow sole falls whatever the next foothold",
        gt=0.0, le=20.0)] = 3.0
    point_foot_share: Annotated[Float, Doc(
        "a robot balances by foot placement (a point-foot walker) when the step regulator applies at least this share "
        "κ of the H-LIP's stepping gain on its default gait (sim.regulator: the sole's width rule, raised to the whole "
        "gain when the measured walk's lateral error grows past growth_limit: the ankle does not hold the centre of "
        "mass)", gt=0.0, le=1.0)] = 0.5
    point_foot_step: Annotated[Float, Doc(
        "longest flat-foot step of a point-foot walker's action space (point_foot_share) as λT (λ = √(g/z0), the "
        "H-LIP's rate at the default gait's CoM height z0): a CoM error grows as e^(λT) over a single support before "
        "the next foothold corrects it; never below the default gait's own step, which walked", gt=0.0,
        le=20.0)] = 2.0
    line_foot_step: Annotated[Float, Doc(
        "longest flat-foot step of a capsule line foot's action space (no roll support: Cassie's) as λT, tighter "
        "than point_foot_step: the rigid plan's springs deflect in simulation and the stance foot rolls onto its "
        "heel, so the centre of pressure is not where the plan puts it and the error a foothold must correct grows "
        "faster; never below the default gait's own step, which walked (docs/robots.md, \"Closed chains, springs "
        "and line feet\")",
        gt=0.0, le=20.0)] = 1.3
    line_foot_height: Annotated[Float, Doc(
        "lowest swing clearance of a capsule line foot's action space, as a multiple of the default: the pelvis of a "
        "sprung leg on a line pitches forward by degrees over a step, turning the swing sole's toe down with it, and a "
        "lower swing scuffs (docs/robots.md, \"Closed chains, springs and line feet\")", gt=0.0, le=2.0)] = 1.0
    joint_margin_narrow: Annotated[Float, Doc(
        "generate.joint_margin written when the soles are narrow (sole width / leg length < "
        "sim.regulator.narrow_ratio), if above 0: the step regulator moves the swing foot by joint offsets, which a "
        "trajectory on a joint's limit cannot take; a margin for every gait costs the widest steps their range, so "
        "gait generate and studies add one only where a walk fell at a joint limit (generate.retry_joint_margin)",
        unit="rad", ge=0.0, le=0.5)] = 0.0
    action_step_length: AxisRule = (0.67, 1.47, 6)
    action_step_duration: AxisRule = (0.86, 1.57, 5)
    action_step_width: AxisRule = (0.88, 1.2, 4)
    action_step_height: AxisRule = (0.57, 1.43, 3)
    multicontact_step_length: AxisRule = (0.67, 1.33, 5)
    multicontact_step_duration: AxisRule = (0.89, 1.22, 3)
    multicontact_step_width: AxisRule = (0.88, 1.12, 3)
    multicontact_step_height: AxisRule = (0.57, 1.43, 3)
    rolling_fraction: Annotated[tuple[Fraction, Fraction, Fraction], Doc(
        "multi-contact action space of the rolling fraction: [low, high, step]")] = (0.15, 0.25, 0.05)
    angular_velocity: Annotated[Float, Doc("pelvis angular velocity bound ÷ √(g/l)", gt=0.0, le=10.0)] = 0.15
    joint_velocity: Annotated[Float, Doc("joint velocity bound ÷ √(g/l)", gt=0.0, le=100.0)] = 1.23
    pelvis_height: Annotated[tuple[Factor, Factor], Doc(
        "pelvis height band above the stance sole ÷ the standing height")] = (0.87, 1.03)
    fall_height: Annotated[Float, Doc("fall when the base is lower than this fraction of the standing height",
                                      gt=0.0, le=1.0)] = 0.65
    timestep: Annotated[Float, Doc("the servo rule's largest physics step ÷ √(l/g) (the model's step is lowered to a "
                                   "nice value below it; exo: 1 ms of 0.308 s)", gt=0.0, le=0.1)] = 0.0035
    pelvis_roll: Annotated[Float, Doc("gait-quality bound on the pelvis roll relative to the stance sole (an angle: "
                                      "no scale; exo's)", unit="rad", gt=0.0, le=1.0)] = 0.05
    pelvis_yaw: Annotated[Float, Doc("gait-quality bound on the pelvis yaw (exo's)", unit="rad", gt=0.0,
                                     le=1.0)] = 0.08
    pelvis_pitch: Annotated[tuple[Angle, Angle], Doc("gait-quality band of the pelvis pitch (exo's)",
                                                     unit="rad")] = (-0.05, 0.15)
    swing_tilt: Annotated[Float, Doc("gait-quality bound on the swing sole's roll and pitch (exo's)", unit="rad",
                                     gt=0.0, le=1.0)] = 0.05
    swing_yaw: Annotated[Float, Doc("gait-quality bound on the swing sole's yaw (exo's)", unit="rad", gt=0.0,
                                    le=1.0)] = 0.05

    def __post_init__(self) -> None:
        for f in dataclasses.fields(self):
            v = getattr(self, f.name)
            if isinstance(v, tuple) and len(v) >= 2 and v[0] >= v[1]:
                raise FieldProblem(f.name, f"must be [low, high, ...] with low < high, got {list(v)}")


@config
class RobotCheckConfig:
    """Thresholds of ``robot check`` (:mod:`robustgait.inspection.check`): a check fails beyond them."""

    stance_stiffness: Annotated[Float, Doc("least ratio of a stance-chain servo's kp to gravity's tipping stiffness "
                                           "about its joint, on one foot", ge=1.0, le=100.0)] = 2.0
    stand_time: Annotated[Float, Doc("how long the posture stands under its servos", unit="s", gt=0.0,
                                     le=60.0)] = 2.0
    stand_drop: Annotated[Float, Doc("largest drop of the base while standing ÷ the standing height", gt=0.0,
                                     le=1.0)] = 0.05
    stand_tilt: Annotated[Float, Doc("largest tilt of the base from vertical while standing", unit="rad", gt=0.0,
                                     le=1.5)] = 0.1
    stand_slip: Annotated[Float, Doc("largest horizontal slide of a sole while standing ÷ the sole's length",
                                     gt=0.0, le=1.0)] = 0.1
    sole_tilt: Annotated[Float, Doc("largest angle between a sole's normal and vertical in the posture", unit="rad",
                                    gt=0.0, le=1.5)] = 0.035
    sole_gap: Annotated[Float, Doc("largest height difference of the two soles in the posture", unit="m", ge=0.0,
                                   le=0.1)] = 0.002
    track_amplitude: Annotated[Float, Doc("amplitude of the test sinusoid of every planned joint (robot hanging)",
                                          unit="rad", gt=0.0, le=1.0)] = 0.1
    track_frequency: Annotated[Float, Doc("frequency of the test sinusoid", unit="Hz", gt=0.0, le=50.0)] = 1.5
    track_time: Annotated[Float, Doc("duration of the tracking test (the first period is not scored)", unit="s",
                                     gt=0.0, le=60.0)] = 3.0
    track_rms: Annotated[Float, Doc("largest tracking error RMS of a joint ÷ the amplitude", gt=0.0, le=1.0)] = 0.2
    track_saturation: Annotated[Float, Doc("largest fraction of a joint's physics steps at its torque limit",
                                           gt=0.0, le=1.0)] = 0.05
    torque_margin: Annotated[Float, Doc("largest static torque ÷ torque limit that holds the posture (double "
                                        "support)", gt=0.0, le=1.0)] = 0.5
    timestep: Annotated[Bool, Doc(
        "re-check the spec's timestep: generate the default gait and walk it at the spec's step and at half of it, "
        "within robot.timestep_tolerance (tens of seconds)")] = True


@config
class RobotConfig:
    """How ``robot init`` makes a spec from a model (docs/robots.md, "Your robot"): which joints the gait plans,
    the standing posture, PD gains from each joint's reflected inertia, tolerances of the discovery."""

    name: Annotated[Str | None, Doc("the written spec's name; not set: the model's name, lower case")] = None
    plan: Annotated[Plan, Doc("joints the gait plans: legs (the others are held at the posture) or all")] = "legs"
    keyframe: Annotated[Str | None, Doc("the model's keyframe of the standing posture; not set: its first (none: "
                                        "every joint at 0 clipped to its range)")] = None
    bandwidth: Annotated[Float, Doc("servo bandwidth f: kp = I_stance (2π f)² before the torque cap", unit="Hz",
                                    gt=0.0, le=100.0)] = 5.0
    damping_ratio: Annotated[Float, Doc("damping ratio ζ of a servo on its swing inertia: kd = 2 ζ √(kp I_swing)",
                                        gt=0.0, le=10.0)] = 1.0
    tracking_error: Annotated[Float, Doc("kp ≤ torque limit ÷ this error: a larger error saturates anyway",
                                         unit="rad", gt=0.0, le=1.0)] = 0.02
    timestep_rule: Annotated[TimestepRule, Doc(
        "how the spec's timestep is chosen: accuracy (the largest of robot.timestep_candidates whose default gait's "
        "settled switching states lie within robot.timestep_tolerance of those at half the step, stable PD; walks "
        "the gait: tens of seconds) or servo (the model's step lowered by robot.servo_steps and "
        "robot.scale.timestep, no walk)")] = "accuracy"
    timestep_candidates: Annotated[tuple[Candidate, ...], Doc(
        "the timesteps the accuracy rule tries, largest first (with the model's own step among them)",
        unit="s")] = (0.002, 0.001, 0.0005, 0.00025)
    timestep_tolerance: Annotated[Float, Doc(
        "largest difference of the default gait's settled switching-state band centres at a timestep and at half "
        "of it (band coordinates): two-thirds of the recovery band's floor certify.push.recovery_radius, so that "
        "the step's error stays well inside the band a pushed walk must come back to", gt=0.0, le=1.0)] = 0.02
    servo_steps: Annotated[Float, Doc("least physics steps per natural period of the fastest servo (on its swing "
                                      "inertia): the servo rule's timestep is the model's, lowered to a nice value "
                                      "that gives this many (exo: 15 at 1 ms)", ge=2.0, le=1000.0)] = 12.0
    torque_limit_factor: Annotated[Float, Doc("a joint without a torque limit in the model gets this multiple of "
                                              "the largest static torque it holds (on one foot, the weight at a "
                                              "sole's corner, its subtree's weight × COM distance)", ge=1.0,
                                              le=100.0)] = 2.0
    foot_level: Annotated[Float, Doc("the two feet's lowest points agree within this fraction of the standing "
                                        "height (else one leg)", gt=0.0, le=1.0)] = 0.1
    sole_tolerance: Annotated[Float, Doc("a foot's collision geoms within this height of its lowest point form the "
                                         "sole", unit="m", gt=0.0, le=0.05)] = 0.005
    stand_fraction: Annotated[Float, Doc(
        "the posture's centre of mass stands over the soles when it lies within this middle fraction of their length "
        "(a servo-held stand with the mass over the last tenth of the sole tips over it); robot init leans the legs "
        "to bring it to the middle otherwise", gt=0.0, le=1.0)] = 0.8
    mirror_tolerance: Annotated[Float, Doc("largest mirror residual: position error of a body, and how far a "
                                           "partner's axis line may pass from the reflected anchor (a model file's "
                                           "placement rounding is not an asymmetry)", unit="m", gt=0.0,
                                           le=0.1)] = 2e-3
    mirror_angle_tolerance: Annotated[Float, Doc("largest mirror residual: orientation error of a body", unit="rad",
                                                 gt=0.0, le=0.5)] = 1e-3
    side_mass_tolerance: Annotated[Float, Doc(
        "left and right differ when a body and its mirror image differ in mass by more than this fraction of the "
        "heavier and by more than 1 g (a model file's rounding is not a difference)", ge=0.0, le=1.0)] = 1e-3
    side_inertia_tolerance: Annotated[Float, Doc(
        "... or in a principal inertia by more than this fraction of the larger", ge=0.0, le=1.0)] = 0.01
    mirror_samples: Annotated[Int, Doc("random configurations of the mirror's forward-kinematics check", ge=1,
                                       le=10_000)] = 20
    seed: Annotated[Int, Doc("seed of the mirror check's configurations", ge=0, le=2**63 - 1)] = 0
    scale: ScaleRules = dataclasses.field(default_factory=ScaleRules)
    check: RobotCheckConfig = dataclasses.field(default_factory=RobotCheckConfig)

    def __post_init__(self) -> None:
        c = self.timestep_candidates
        if not c or any(a <= b for a, b in itertools.pairwise(c)):
            raise FieldProblem("timestep_candidates", f"must be one or more timesteps, largest first, got {list(c)}")


LOOP_TOLERANCE = 1e-4
"""[m] the largest gap robot init leaves in a closed chain of its posture (MuJoCo's equality residual, after solving
the passive joints): a loop that stays further open cannot close at the keyframe (``robots.loops.close_loops``)."""


SETTLE_ITERATIONS = 20
"""Most rounds of settling a posture's springs at their static deflection under the robot's weight
(``inspection.gains.settle_springs``: the load moves with the posture, so the deflection is found again from it)."""

SETTLE_TOLERANCE = 1e-9
"""[rad or m] the change of every spring's deflection below which ``inspection.gains.settle_springs`` stops."""

LOAD_ROUNDS = 4
"""Most rounds of settling the springs and levelling the soles in robot init's loaded posture
(``robotinit.posture.level_under_load``: the load moves with the ankles a little)."""
