"""robustgait: synthesize robust walking gaits — HZD gait generation, MuJoCo simulation, discrete-time
barrier-function certificates of the step-to-step map, and preference-based learning.

Public API (everything else is reachable from the submodules)::

    robot = robustgait.load_robot("exo")                 # or a spec .toml path
    gait = robustgait.load_gait("gait.json", robot)      # or a FROST/ambersim .yaml
    result = robustgait.walk(robot, gait, steps=50)
    cert = robustgait.certify_gait(robot, gait)          # cert.status, cert.r_star (paper's estimator)
    cert = robustgait.certify_gait(robot, gait, robustgait.CertifyConfig(method="sequential"))
    res = robustgait.validate_gait(robot, gait, kinds=["push"])  # disturbed walks, certificate check
    gen = robustgait.GaitGenerator(robot)                # build the HZD problem once, then gen.solve(params)
    robustgait.create_study("runs/rob", robustgait.StudyConfig(robot="exo"))   # the learning loop
    robustgait.run_study("runs/rob"); robustgait.study_status("runs/rob")["best"]
"""

import os

# Offscreen rendering needs a headless GL backend, and MuJoCo reads the choice once, at import.
os.environ.setdefault("MUJOCO_GL", "egl")

from typing import TYPE_CHECKING, Any

from robustgait.barrier import Certificate, certify_map, invariant_radius
from robustgait.certify import CertifyConfig, GaitCertificate, certify_gait
from robustgait.errors import RobustGaitError
from robustgait.estimators import SequentialConfig, certify_map_sequential
from robustgait.gait import Gait, GaitParams, load_gait
from robustgait.robots import Robot, load_robot
from robustgait.sim import SimConfig, StepEngine, WalkResult, walk
from robustgait.validate import ValidateConfig, ValidationResult, validate_gait

if TYPE_CHECKING:
    from robustgait.gaitgen import GaitGenerator, generate_gait
    from robustgait.study import (
        EvaluationConfig,
        RunOptions,
        StudyConfig,
        create_study,
        evaluate,
        run_study,
        study_status,
    )

__version__ = "0.1.0"


_STUDY = ("EvaluationConfig", "RunOptions", "StudyConfig", "create_study", "evaluate", "run_study", "study_status")


def __getattr__(name: str) -> Any:
    # gait generation imports CasADi and adam (about a second), studies torch and Optuna: load them when asked
    if name in ("GaitGenerator", "generate_gait"):
        from robustgait import gaitgen

        return getattr(gaitgen, name)
    if name in _STUDY:
        from robustgait import study

        return getattr(study, name)
    raise AttributeError(f"module 'robustgait' has no attribute {name!r}")


__all__ = [
    "Certificate",
    "CertifyConfig",
    "EvaluationConfig",
    "Gait",
    "GaitCertificate",
    "GaitGenerator",
    "GaitParams",
    "Robot",
    "RobustGaitError",
    "RunOptions",
    "SequentialConfig",
    "SimConfig",
    "StepEngine",
    "StudyConfig",
    "ValidateConfig",
    "ValidationResult",
    "WalkResult",
    "__version__",
    "certify_gait",
    "certify_map",
    "certify_map_sequential",
    "create_study",
    "evaluate",
    "generate_gait",
    "invariant_radius",
    "load_gait",
    "load_robot",
    "run_study",
    "study_status",
    "validate_gait",
    "walk",
]
