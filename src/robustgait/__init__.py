"""robustgait: synthesize robust walking gaits — HZD gait generation, MuJoCo simulation, discrete-time
barrier-function certificates of the step-to-step map, and preference-based learning.

Public API (everything else is reachable from the submodules)::

    robot = robustgait.load_robot("exo")                 # or a spec .toml path
    gait = robustgait.load_gait("gait.json", robot)      # or a FROST/ambersim .yaml
    result = robustgait.walk(robot, gait, steps=50)
"""

import os

# Offscreen rendering needs a headless GL backend, and MuJoCo reads the choice once, at import.
os.environ.setdefault("MUJOCO_GL", "egl")

from robustgait.errors import RobustGaitError
from robustgait.gait import Gait, GaitParams, load_gait
from robustgait.robots import Robot, load_robot
from robustgait.sim import SimConfig, StepEngine, WalkResult, walk

__version__ = "0.1.0"

__all__ = [
    "Gait",
    "GaitParams",
    "Robot",
    "RobustGaitError",
    "SimConfig",
    "StepEngine",
    "WalkResult",
    "__version__",
    "load_gait",
    "load_robot",
    "walk",
]
