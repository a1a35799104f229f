"""Options of the comfort figures of a walk (:mod:`robustgait.sim.comfort`, ``docs/comfort.md``): which steps are
measured, how the pelvis acceleration is filtered, how long a touchdown's impact lasts."""

from __future__ import annotations

from typing import Annotated

from robustgait.config.base import Doc, Float, Int, config


@config
class ComfortConfig:
    """What a passenger feels, measured on whole steps of the steady part of a walk: steps ``skip_steps`` + 1 to
    ``skip_steps`` + ``steps`` (fewer if the walk falls or ends first). The pelvis acceleration is the finite
    difference of the base velocity at the physics rate, low-passed (zero-phase Butterworth, ``cutoff``,
    ``filter_order``) before its RMS, peak and jerk are taken: raw 1 kHz differences at contact are spikes of the
    stiff contact, not what a seated body feels (``docs/comfort.md`` measures both). A touchdown's impact force is
    the landing sole's largest normal force within ``impact_window`` of the touchdown."""

    skip_steps: Annotated[Int, Doc("steps at the start of a walk left out of the comfort figures (its transient)",
                                   ge=0, le=1000)] = 5
    steps: Annotated[Int, Doc("steps measured after the skipped ones (fewer if the walk ends first)", ge=1,
                              le=200)] = 20
    cutoff: Annotated[Float, Doc("low-pass cutoff of the pelvis acceleration (zero-phase Butterworth); below the "
                                 "physics rate's Nyquist frequency", unit="Hz", gt=0.0, le=1000.0)] = 20.0
    filter_order: Annotated[Int, Doc("order of the Butterworth low-pass (applied forward and backward)", ge=1,
                                     le=8)] = 4
    impact_window: Annotated[Float, Doc("time after a touchdown in which the landing sole's peak normal force is "
                                        "taken", unit="s", gt=0.0, le=1.0)] = 0.05
