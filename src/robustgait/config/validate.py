"""Options of a validation (:mod:`robustgait.validate`): disturbed walks from a gait's fixed point."""

from __future__ import annotations

import math
from typing import Annotated, Literal

from robustgait.config.base import Doc, FieldProblem, Float, Int, config
from robustgait.config.certify import SEED_LIMIT

DisturbanceKind = Literal["push", "mass", "friction", "latency", "noise", "terrain", "slope"]
Disturbance = Literal["push", "mass", "friction", "latency", "noise", "terrain", "slope", "all"]
# the index of a kind seeds its draws: new kinds go at the end, so the others' draws stay the same
KINDS: tuple[str, ...] = ("push", "mass", "friction", "latency", "noise", "terrain", "slope")

Phase = Annotated[Float, Doc(ge=0.0, le=1.0)]
Friction = Annotated[Float, Doc(gt=0.0, le=10.0)]


@config
class ValidateConfig:
    """Trials per kind, their seed (the draws depend on the seed and the robot only, so every gait validated with
    one config meets the same disturbances), the steps walked after the disturbance, and the ranges the sizes are
    drawn from (uniformly; ``docs/validation.md``)."""

    trials: Annotated[Int, Doc("trials per disturbance kind", ge=1, le=10_000)] = 200
    seed: Annotated[Int, Doc("seed of the disturbances (the same for every gait)", ge=0, le=SEED_LIMIT)] = 0
    disturbance: Annotated[Disturbance, Doc("disturbance kind (all: every kind in turn)")] = "push"
    steps_after: Annotated[Int, Doc("steps to walk after the first switching event after the disturbance", ge=1,
                                    le=1000)] = 20
    workers: Annotated[Int, Doc("study validate: gaits validated in parallel processes, each with cores / workers "
                                "rollout threads (1: one process, the rollout on every core)", ge=1, le=256)] = 1
    push_dv_max: Annotated[Float, Doc("push impulse up to mass × this velocity change", unit="m/s", ge=0.0,
                                      le=100.0)] = 0.6
    push_duration: Annotated[Float, Doc("push duration", unit="s", gt=0.0, le=10.0)] = 0.1
    push_phase: Annotated[tuple[Phase, Phase], Doc("[low, high] phase of the step at which a push starts")] = (
        0.0, 0.6)
    mass_max: Annotated[Float, Doc("relative change of the base (passenger) mass at severity 1", ge=0.0,
                                   lt=1.0)] = 0.4
    com_offset_max: Annotated[Float, Doc("horizontal shift of the base's centre of mass at severity 1", unit="m",
                                         ge=0.0, le=1.0)] = 0.08
    inertia_max: Annotated[Float, Doc("relative change of every body's inertia at severity 1", ge=0.0,
                                      le=10.0)] = 0.3
    friction_range: Annotated[tuple[Friction, Friction], Doc("[low, high] sliding friction coefficient μ")] = (
        0.05, 1.0)
    latency_max: Annotated[Float, Doc("largest command delay", unit="s", ge=0.0, le=10.0)] = 0.1
    noise_q_max: Annotated[Float, Doc("largest encoder noise σ_q", unit="rad", ge=0.0, le=math.pi)] = 0.02
    noise_v_ratio: Annotated[Float, Doc("velocity noise σ_v = this × σ_q", unit="1/s", ge=0.0, le=1e4)] = 50.0
    terrain_max: Annotated[Float, Doc("largest terrain amplitude", unit="m", ge=0.0, le=1.0)] = 0.03
    terrain_tile: Annotated[Float, Doc("side of a terrain tile", unit="m", gt=0.0, le=10.0)] = 0.3
    slope_max: Annotated[Float, Doc("steepest slope of the (smooth) ground, in a random direction: uphill, downhill, "
                                    "sideways or between", unit="deg", ge=0.0, le=45.0)] = 5.0

    def __post_init__(self) -> None:
        for name in ("push_phase", "friction_range"):
            lo, hi = getattr(self, name)
            if lo > hi:
                raise FieldProblem(name, f"must be [low, high] with low ≤ high, got [{lo:g}, {hi:g}]")

    @property
    def kinds(self) -> tuple[str, ...]:
        """The kinds to run: ``disturbance``, or every kind for ``all``."""
        return KINDS if self.disturbance == "all" else (self.disturbance,)
