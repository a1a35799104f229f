"""HZD gait generation (DESIGN §4): full-order trajectory optimization with essential constraints."""

from robustgait.gaitgen.config import DEFAULT_STEP_DURATION, GaitGenConfig, default_params
from robustgait.gaitgen.problem import FlatFootProblem, GaitProblem
from robustgait.gaitgen.solve import GaitGenerator, GaitGenResult, generate_gait

__all__ = ["DEFAULT_STEP_DURATION", "FlatFootProblem", "GaitGenConfig", "GaitGenResult", "GaitGenerator",
           "GaitProblem", "default_params", "generate_gait"]
