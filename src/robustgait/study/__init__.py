"""Studies (``docs/studies.md``): the simulation-in-the-loop preference-learning loop — ``evaluate`` (generate, walk,
certify), the study configuration, its Optuna storage, the executors (local processes, Ray), status,
comparison of studies, validation of every gait of a study.

Submodules load lazily: a worker process that only evaluates gaits does not import torch or Optuna."""

from typing import TYPE_CHECKING

from robustgait._lazy import lazy_exports

if TYPE_CHECKING:
    from robustgait.io.studyfile import StudySetup, load_config
    from robustgait.study.evaluate import Evaluation, evaluate
    from robustgait.study.run import create_study, run_study
    from robustgait.study.status import study_status
    from robustgait.study.validate import validate_study

_EXPORTS = {
    "StudySetup": "config", "load_config": "config", "Evaluation": "evaluate", "evaluate": "evaluate",
    "create_study": "run", "run_study": "run", "study_status": "status",
    "compare_studies": "compare", "validate_study": "validate",
}


__getattr__ = lazy_exports(__name__, _EXPORTS)

__all__ = [
    "Evaluation",
    "StudySetup",
    "compare_studies",
    "create_study",
    "evaluate",
    "load_config",
    "run_study",
    "study_status",
    "validate_study",
]
