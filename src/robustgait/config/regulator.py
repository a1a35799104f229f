"""Options of the step-to-step balance regulator (:mod:`robustgait.sim.regulator`, ``docs/simulation.md``, "Step-to-step
balance"): when it runs, its gain, and how far it may move a foot. The rules that read them (whether it runs, its share
of the gain, the step-start blend) are :mod:`robustgait.sim.regulator_rules`'s: this module holds data only."""

from __future__ import annotations

from typing import Annotated, Literal

from robustgait.config.base import Bool, Doc, Float, config

RegulatorMode = Literal["auto", "on", "off"]
RegulatorGain = Literal["deadbeat", "lqr"]


@config
class RegulatorConfig:
    """The H-LIP foot-placement regulator on top of a flat-foot gait's tracking controller. ``auto``: on when the sole
    is narrow for the robot (sole width / leg length < ``narrow_ratio``,
    :func:`robustgait.sim.regulator_rules.regulator_rule`)."""

    mode: Annotated[RegulatorMode, Doc(
        "H-LIP step regulator: auto (on when sole width / leg length < narrow_ratio, flat-foot gaits), on, or off")
    ] = "auto"
    narrow_ratio: Annotated[Float, Doc("auto mode: the regulator is on below this sole width / leg length", ge=0.0,
                                       le=1.0)] = 0.10
    gain: Annotated[RegulatorGain, Doc(
        "stepping gain: deadbeat (the S2S error dies in two steps) or lqr (dimensionless LQR weights)")] = "deadbeat"
    placement_width: Annotated[Float, Doc(
        "sole width / leg length at which foot placement fades out: the share of the H-LIP gain applied is "
        "max(0, 1 − (ratio / placement_width)²) — all of it for a line or point foot, none for a sole wide enough to "
        "hold the CoM through the ankle", gt=0.0, le=1.0)] = 0.06
    gain_scale: Annotated[Float | None, Doc(
        "share of the H-LIP gain applied, overriding placement_width's rule (0: no foot placement, only the "
        "step-start blend)", ge=0.0, le=1.0)] = None
    growth_limit: Annotated[Float, Doc(
        "a walk whose lateral CoM error grows more than this factor per step under placement_width's share, or "
        "falls (:func:`robustgait.sim.regulator.lateral_growth`, measured once per gait), is not held through its "
        "ankle: it gets the H-LIP's whole gain (κ = 1) instead if the error grows less under it", gt=1.0,
        le=100.0)] = 2.0
    predict: Annotated[Bool, Doc(
        "predict the CoM error at touchdown with the H-LIP's pendulum flow (a point-foot model); off: the error "
        "measured now is the estimate (a flat foot the joint PD holds does not let it grow that way)")] = False
    update_interval: Annotated[Float, Doc(
        "time between two updates of the landing change (the engine's chunks on a regulated robot: round(interval / "
        "timestep) physics steps), in seconds so that the regulated controller is the same at any timestep",
        unit="s", gt=0.0, le=1.0)] = 0.05
    land_tau: Annotated[Float, Doc("phase by which the swing foot's correction is fully applied", gt=0.0,
                                   le=1.0)] = 0.8
    freeze_tau: Annotated[Float, Doc("phase after which the correction is no longer updated (≤ land_tau)", ge=0.0,
                                     le=1.0)] = 0.7
    carry_tau: Annotated[Float, Doc(
        "phase by which the joint error at the step start (the previous step's landing correction) is blended out "
        "of the references with no foot placement (κ = 0; 0: not blended); it grows by carry_share × κ", ge=0.0,
        le=1.0)] = 0.2
    carry_share: Annotated[Float, Doc(
        "added to carry_tau per unit of the share κ of the H-LIP gain applied: the larger the landing corrections, "
        "the longer the next stance leg takes to blend them out", ge=0.0, le=1.0)] = 0.2
    max_step_change: Annotated[Float, Doc("largest change of the landing point per axis, as a fraction of the leg "
                                          "length", gt=0.0, le=1.0)] = 0.2
    foot_gap: Annotated[Float, Doc("least lateral gap between the soles' edges a correction leaves, as a fraction "
                                   "of the leg length", ge=0.0, le=1.0)] = 0.02

