"""A study's configuration: one frozen dataclass, saved as ``study.json`` in the study directory and read
back on resume. Nested configs (evaluation → certificate → simulator, gait generation, learner → model)
are saved whole, so a field added to any of them is saved and restored without changes here."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from robustgait.errors import RobustGaitError, input_error
from robustgait.io.output import write_json
from robustgait.io.schema import read_json
from robustgait.learn.config import LEARNERS, LearnerConfig
from robustgait.learn.oracle import METRICS
from robustgait.study.evaluate import EvaluationConfig

if TYPE_CHECKING:
    from robustgait.learn.space import ActionSpace
    from robustgait.robots import Robot

CONFIG_FILE = "study.json"
FORMAT_VERSION = 1


@dataclass(frozen=True)
class StudyConfig:
    """robot: a shipped robot name or the absolute path of a spec .toml. metric: the oracle
    (``robustness`` | ``stability``). learner: ``polar`` | ``eubo`` | ``random``. iterations × batch
    gaits. seed: the learner's seed (proposals of iteration k are seeded from (seed, k)); the
    certificate's seed is ``evaluation.certify.seed``. storage: an SQLAlchemy URL of the Optuna
    database, None for ``sqlite:///DIR/study.db``. study_name: the Optuna study's name in it."""

    robot: str = "exo"
    metric: str = "robustness"
    learner: str = "polar"
    iterations: int = 10
    batch: int = 5
    seed: int = 0
    evaluation: EvaluationConfig = field(default_factory=EvaluationConfig)
    learning: LearnerConfig = field(default_factory=LearnerConfig)
    storage: str | None = None
    study_name: str = "robustgait"

    def __post_init__(self) -> None:
        from robustgait.io import limits as L

        if self.metric not in METRICS:
            raise RobustGaitError(f"unknown metric {self.metric!r} (choose from {', '.join(METRICS)})")
        if self.learner not in LEARNERS:
            raise RobustGaitError(f"unknown learner {self.learner!r} (choose from {', '.join(LEARNERS)})")
        for name, lim in (("iterations", L.ITERATIONS), ("batch", L.BATCH), ("seed", L.SEED)):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, int) or not lim.contains(v):
                raise RobustGaitError(f"{name} must be an integer with {lim.text()}, got {v!r} (a batch is "
                                      "ranked: it needs at least 2 gaits)" if name == "batch" else
                                      f"{name} must be an integer with {lim.text()}, got {v!r}")

    @property
    def trials_planned(self) -> int:
        return self.iterations * self.batch

    def action_space(self, robot: Robot | None = None) -> ActionSpace:
        """The grid this study searches: the robot spec's action space of the study's domain graph
        (``evaluation.gaitgen.domains``). ``robot``: the loaded ``self.robot`` (loaded here when None)."""
        from robustgait.learn.space import ActionSpace
        from robustgait.robots import load_robot

        return ActionSpace.from_robot(robot or load_robot(self.robot), self.evaluation.gaitgen.domains)

    def to_dict(self) -> dict[str, Any]:
        return dataclasses.asdict(self)

    @classmethod
    def from_dict(cls, data: Any, source: str | Path = "<config>") -> StudyConfig:
        """Validate through the input layer (:func:`robustgait.io.schema.validate`): nested configs are
        rebuilt, lists become tuples, each config's own checks run; a field missing from ``data`` keeps
        its default (a study written before the field existed); unknown fields are ignored."""
        from robustgait.io.schema import validate

        return validate(data, cls, source)


def demo_config() -> StudyConfig:
    """``robustgait demo``: a robustness study of exo, 3 iterations × 4 gaits, with a lighter sequential
    certificate (ε = 0.05, 200 exploration samples: ≈ 470 samples and 7.6 s per gait on one thread instead
    of ≈ 980 and 16 s; r* within ≈ 4 % instead of ≈ 1 % between seeds) so that it ends in a few minutes on
    2 cores (docs/studies.md)."""
    base = EvaluationConfig().certify
    seq = dataclasses.replace(base.sequential, epsilon=0.05, explore=200, explore_after_failure=100, budget=1500)
    return StudyConfig(robot="exo", metric="robustness", learner="polar", iterations=3, batch=4,
                       evaluation=EvaluationConfig(certify=dataclasses.replace(base, sequential=seq)))


def save_config(directory: Path, config: StudyConfig) -> Path:
    return write_json(directory / CONFIG_FILE, {"format_version": FORMAT_VERSION, "config": config.to_dict()})


def load_config(directory: str | Path) -> StudyConfig:
    path = Path(directory) / CONFIG_FILE
    if not path.is_file():
        raise input_error(directory, f"not a study directory (no {CONFIG_FILE})")
    raw = read_json(path, "study config")
    if not isinstance(raw, dict) or raw.get("format_version") != FORMAT_VERSION or "config" not in raw:
        raise input_error(path, f"unsupported study file (format_version {FORMAT_VERSION} expected)")
    return StudyConfig.from_dict(raw["config"], path)
