"""The step regulator's rules (``docs/simulation.md``, "Step-to-step balance"): whether it runs for a robot's soles
and a gait, the share of the H-LIP stepping gain its sole's width leaves to foot placement, and the phase by which the
step-start error is blended out. Their options are :class:`robustgait.config.regulator.RegulatorConfig` (data only);
the regulator that applies them is :mod:`robustgait.sim.regulator`; ``robot init`` reads the same on/off rule for the
spec it drafts (:func:`robustgait.inspection.scale.balance`)."""

from __future__ import annotations

from robustgait.config.regulator import RegulatorConfig


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
