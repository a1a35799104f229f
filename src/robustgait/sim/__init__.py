"""MuJoCo walking simulation: tracking controller, stance switching, falls, batched one-step rollouts, the comfort
figures of a walk."""

from robustgait.sim.comfort import FIGURES, Comfort
from robustgait.sim.engine import FALL_REASONS, StepBatch, StepEngine, StepInputs
from robustgait.sim.walk import SwitchEvent, WalkResult, render_video, walk

__all__ = ["FALL_REASONS", "FIGURES", "Comfort", "StepBatch", "StepEngine", "StepInputs", "SwitchEvent", "WalkResult",
           "render_video", "walk"]
