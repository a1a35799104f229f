"""Options of the MuJoCo simulation (:mod:`robustgait.sim`): stance switching, falls, the step cap, threads."""

from __future__ import annotations

import os
from dataclasses import field
from typing import Annotated, Literal

from robustgait.config.base import Bool, Doc, Float, Int, config
from robustgait.config.regulator import RegulatorConfig

Switching = Literal["impact", "time"]
Controller = Literal["pd", "passivity"]


@config
class SimConfig:
    """How a gait is walked. ``impact`` switching: stance switches when the swing sole touches the floor once
    τ ≥ ``min_switch_tau`` (a step without touchdown by τ = ``max_step_tau`` is a fall, ``no_touchdown``);
    ``time``: at τ = 1. ``step_cap``: steps walked by ``robustgait walk`` and by a study before it certifies."""

    switching: Annotated[Switching, Doc(
        "switch stance at swing-foot touchdown once τ ≥ min_switch_tau (impact) or at τ = 1 (time)")] = "impact"
    min_switch_tau: Annotated[Float, Doc("earliest phase at which a touchdown switches stance", ge=0.0,
                                         le=1.0)] = 0.8
    max_step_tau: Annotated[Float, Doc("latest phase of a touchdown; later is a fall (no_touchdown)", gt=1.0,
                                       le=10.0)] = 1.5
    controller: Annotated[Controller, Doc(
        "joint tracking law: pd (MuJoCo's position servos + feedforward, rolled out open loop) or passivity (the "
        "paper's passivity-based law for flat-foot gaits, state feedback in the batched feedback engine; "
        "multi-contact gaits keep the PD)")] = "pd"
    feedforward: Annotated[Bool, Doc("add the gait's feedforward torques to the joint PD")] = True
    step_cap: Annotated[Int, Doc("steps walked (the cap of a walk; a study walks it before certifying)", ge=1,
                                 le=1000)] = 50
    chunk_steps: Annotated[Int, Doc("physics steps per mujoco.rollout call between event scans", ge=1,
                                    le=100_000)] = 100
    n_threads: Annotated[Int, Doc("MuJoCo rollout threads (0: one per core)", ge=0, le=256)] = 0
    max_speed: Annotated[Float, Doc("a joint or base speed above this counts as diverged", unit="rad/s or m/s",
                                    gt=0.0, le=1e4)] = 100.0
    speed_agreement: Annotated[Float, Doc(
        "a walk's summary notes a mean forward speed that differs from the gait's planned one (step length / step "
        "duration) by more than this fraction of it, or goes backwards", ge=0.0, le=10.0)] = 0.5
    regulator: RegulatorConfig = field(default_factory=RegulatorConfig)

    @property
    def threads(self) -> int:
        return self.n_threads or os.cpu_count() or 1
