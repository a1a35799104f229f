"""HZD gait generation (DESIGN §4): full-order trajectory optimization with essential constraints."""

from robustgait.gaitgen.config import GaitGenConfig
from robustgait.gaitgen.problem import FlatFootProblem, GaitProblem
from robustgait.gaitgen.solve import GaitGenerator, GaitGenResult, generate_gait

__all__ = ["FlatFootProblem", "GaitGenConfig", "GaitGenResult", "GaitGenerator", "GaitProblem", "generate_gait"]
