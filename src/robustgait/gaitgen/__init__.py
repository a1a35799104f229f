"""HZD gait generation (``docs/gaitgen.md``): full-order trajectory optimization with essential constraints. Its
options are :class:`robustgait.config.GenerationConfig` and :class:`robustgait.config.GaitParams`."""

from robustgait.gaitgen.problem import GaitProblem
from robustgait.gaitgen.solve import GaitGenerator, GaitGenResult, generate_gait

__all__ = ["GaitGenResult", "GaitGenerator", "GaitProblem", "generate_gait"]
