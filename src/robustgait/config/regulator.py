"""Options of the step-to-step balance regulator (:mod:`robustgait.sim.regulator`, ``docs/simulation.md``, "Step-to-step
balance"): when it runs, its gain, and how far it may move a foot."""

from __future__ import annotations

from typing import Annotated, Literal

from robustgait.config.base import Bool, Doc, Float, config

RegulatorMode = Literal["auto", "on", "off"]
RegulatorGain = Literal["deadbeat", "lqr"]


@config
class RegulatorConfig:
    """The H-LIP foot-placement regulator on top of a flat-foot gait's tracking controller. ``auto``: on when the sole
    is narrow for the robot (sole width / leg length < ``narrow_ratio``, :func:`regulator_rule`)."""

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


def placement_share(config: RegulatorConfig, sole_width: float, leg_length: float) -> float:
    """κ by the sole's width, the share of the H-LIP stepping gain the regulator applies before the walk is measured
    (:meth:`robustgait.sim.regulator.StepRegulator.settle_share` may raise it to 1): ``gain_scale`` if set, else
    max(0, 1 − (r / ``placement_width``)²) with r = sole_width / leg_length. A point-foot pendulum (r → 0) needs all
    of it; a flat foot that the joint PD holds keeps part of the CoM error from growing, and a wide one all of it."""
    if config.gain_scale is not None:
        return config.gain_scale
    return max(0.0, 1.0 - (sole_width / leg_length / config.placement_width) ** 2)


def carry_phase(config: RegulatorConfig, share: float) -> float:
    """τ_c = ``carry_tau`` + ``carry_share`` κ, clipped to [0, 1]: the phase by which the step-start joint error e0 is
    blended out of the references when the regulator applies the share κ ∈ [0, 1] of the H-LIP gain. e0 holds the
    previous landing correction, which grows with κ; blending a larger one out as fast moves the stance leg faster
    and tips a narrow sole. 0 when ``carry_tau`` is 0 (no blend)."""
    if config.carry_tau <= 0.0:
        return 0.0
    return min(1.0, config.carry_tau + config.carry_share * share)


def regulator_rule(config: RegulatorConfig, sole_width: float, leg_length: float, domains: int
                   ) -> tuple[bool, str]:
    """Whether the regulator runs for a robot whose sole is ``sole_width`` [m] wide and whose leg is ``leg_length``
    [m] long, on a gait of ``domains`` domains, and why (one line). ``auto``: on iff the gait is flat-foot (one
    domain) and sole_width / leg_length < ``narrow_ratio``; ``on`` is refused for multi-contact gaits (their
    rolling double support has no H-LIP step)."""
    ratio = sole_width / leg_length
    what = f"sole {sole_width:.3f} m / leg {leg_length:.3f} m = {ratio:.3f}"
    if domains != 1:
        if config.mode == "on":
            raise ValueError("sim.regulator.mode = on is for flat-foot gaits; this gait is multi-contact")
        return False, "multi-contact gait: H-LIP step regulator off"
    if config.mode != "auto":
        return config.mode == "on", f"H-LIP step regulator {config.mode} (sim.regulator.mode; {what})"
    if ratio < config.narrow_ratio:
        return True, f"{what} < {config.narrow_ratio:g}: narrow soles, H-LIP step regulator on"
    return False, f"{what} ≥ {config.narrow_ratio:g}: H-LIP step regulator off"
