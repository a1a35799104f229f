"""MuJoCo walking simulation: tracking controller, stance switching, falls, batched one-step rollouts."""

from robustgait.sim.engine import FALL_REASONS, StepBatch, StepEngine, StepInputs
from robustgait.sim.walk import SwitchEvent, WalkResult, render_video, walk

__all__ = ["FALL_REASONS", "StepBatch", "StepEngine", "StepInputs", "SwitchEvent", "WalkResult",
           "render_video", "walk"]
