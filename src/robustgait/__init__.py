"""robustgait: synthesize robust walking gaits — HZD gait generation, MuJoCo simulation, certificates of the
step-to-step map (by default J*, the push impulse a gait survives with a stated confidence; or the paper's r*, a ball
of reduced states in which a discrete-time barrier condition holds), and preference-based learning.

Public API (everything else is reachable from the submodules)::

    robot = robustgait.load_robot("exo")                 # or a spec .toml path
    gait = robustgait.load_gait("gait.json", robot)      # or a FROST/ambersim .yaml
    result = robustgait.walk(robot, gait)                # SimConfig: switching, step cap, ...
    result = robustgait.walk(robot, gait, comfort=robustgait.ComfortConfig())   # result.comfort: the passenger
    cert = robustgait.certify_gait(robot, gait)          # cert.status, cert.j_star [N s] (.value), cert.statement()
    cert = robustgait.certify_gait(robot, gait, robustgait.CertifyConfig(method="uniform"))  # the paper's
    res = robustgait.validate_gait(robot, gait)          # disturbed walks, certificate check
    gen = robustgait.GaitGenerator(robot)                # build the HZD problem once, then gen.solve(params)
    robustgait.create_study("runs/rob", "exo")           # the learning loop (Config().study: 10 × 5)
    robustgait.run_study("runs/rob"); robustgait.study_status("runs/rob")["best"]

Every option is a field of :class:`Config` (:mod:`robustgait.config`). Names load their module on first use:
``import robustgait`` itself costs nothing (MuJoCo, CasADi, torch and Optuna load with what needs them).
"""

import os
from typing import TYPE_CHECKING, Any

# Offscreen rendering needs a headless GL backend, and MuJoCo reads the choice once, at import.
os.environ.setdefault("MUJOCO_GL", "egl")

from robustgait._lazy import lazy_exports

if TYPE_CHECKING:
    from robustgait.certificate.barrier import Certificate, certify_map, invariant_radius
    from robustgait.certificate.certify import GaitCertificate, certify_gait
    from robustgait.certificate.estimators import certify_map_sequential
    from robustgait.config import (
        CertifyConfig,
        ComfortConfig,
        Config,
        GaitParams,
        GenerationConfig,
        SequentialConfig,
        SimConfig,
        StudyConfig,
        ValidateConfig,
    )
    from robustgait.errors import RobustGaitError
    from robustgait.gait import Gait
    from robustgait.gaitgen import GaitGenerator, generate_gait
    from robustgait.io.gaitfile import load_gait, save_gait
    from robustgait.io.robotfile import load_robot
    from robustgait.robots import Robot
    from robustgait.sim import Comfort, StepEngine, WalkResult, walk
    from robustgait.study import create_study, evaluate, run_study, study_status
    from robustgait.validate import ValidationResult, validate_gait

__version__ = "0.1.0"

_EXPORTS = {
    **dict.fromkeys(("Certificate", "certify_map", "invariant_radius"), "certificate.barrier"),
    **dict.fromkeys(("GaitCertificate", "certify_gait"), "certificate.certify"),
    **dict.fromkeys(("CertifyConfig", "ComfortConfig", "Config", "GaitParams", "GenerationConfig", "SequentialConfig",
                     "SimConfig", "StudyConfig", "ValidateConfig"), "config"),
    "RobustGaitError": "errors",
    "certify_map_sequential": "certificate.estimators",
    "Gait": "gait",
    **dict.fromkeys(("GaitGenerator", "generate_gait"), "gaitgen"),
    **dict.fromkeys(("load_gait", "save_gait"), "io.gaitfile"),
    "load_robot": "io.robotfile",
    "Robot": "robots",
    **dict.fromkeys(("Comfort", "StepEngine", "WalkResult", "walk"), "sim"),
    **dict.fromkeys(("create_study", "evaluate", "run_study", "study_status"), "study"),
    **dict.fromkeys(("ValidationResult", "validate_gait"), "validate"),
}

_getattr = lazy_exports(__name__, _EXPORTS)


def __getattr__(name: str) -> Any:
    return _getattr(name)


__all__ = [
    "Certificate",
    "CertifyConfig",
    "Comfort",
    "ComfortConfig",
    "Config",
    "Gait",
    "GaitCertificate",
    "GaitGenerator",
    "GaitParams",
    "GenerationConfig",
    "Robot",
    "RobustGaitError",
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
    "save_gait",
    "study_status",
    "validate_gait",
    "walk",
]
