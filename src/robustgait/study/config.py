"""A study's configuration: one frozen dataclass, saved as ``study.json`` in the study directory and read
back on resume. Nested configs (evaluation → certificate → simulator, gait generation, learner → model)
are saved whole, so a field added to any of them is saved and restored without changes here."""

from __future__ import annotations

import dataclasses
import json
import os
import types
import typing
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Union

from robustgait.errors import RobustGaitError, input_error
from robustgait.learn.config import LEARNERS, LearnerConfig
from robustgait.learn.oracle import METRICS
from robustgait.study.evaluate import EvaluationConfig

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
        if self.metric not in METRICS:
            raise RobustGaitError(f"unknown metric {self.metric!r} (choose from {', '.join(METRICS)})")
        if self.learner not in LEARNERS:
            raise RobustGaitError(f"unknown learner {self.learner!r} (choose from {', '.join(LEARNERS)})")
        for name in ("iterations", "batch"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, int) or v < 1:
                raise RobustGaitError(f"{name} must be an integer ≥ 1, got {v!r}")
        if self.batch < 2:
            raise RobustGaitError(f"a batch needs at least 2 gaits to be compared, got {self.batch}")

    @property
    def trials_planned(self) -> int:
        return self.iterations * self.batch

    def to_dict(self) -> dict[str, Any]:
        return dataclasses.asdict(self)

    @classmethod
    def from_dict(cls, data: dict[str, Any], source: str | Path = "<config>") -> StudyConfig:
        try:
            return build_dataclass(cls, data)
        except (TypeError, ValueError, KeyError) as exc:
            raise input_error(source, f"bad study configuration: {exc}") from None


def _hint_types(hint: Any) -> tuple[Any, ...]:
    origin = typing.get_origin(hint)
    if origin in (Union, types.UnionType):
        return tuple(a for a in typing.get_args(hint) if a is not type(None))
    return (hint,)


def _convert(hint: Any, value: Any) -> Any:
    if value is None:
        return None
    for t in _hint_types(hint):
        if dataclasses.is_dataclass(t) and isinstance(value, dict):
            return build_dataclass(t, value)  # type: ignore[arg-type]
        if typing.get_origin(t) is tuple and isinstance(value, list):
            args = typing.get_args(t)
            inner = args[0] if args else Any
            return tuple(_convert(inner, v) for v in value)
    return value


def build_dataclass(cls: type, data: dict[str, Any]) -> Any:
    """Rebuild a (nested) dataclass from :func:`dataclasses.asdict` output: lists back to tuples, dicts to
    nested dataclasses; fields missing from ``data`` keep their defaults; unknown fields are an error."""
    if not isinstance(data, dict):
        raise TypeError(f"{cls.__name__} must be a JSON object")
    hints = typing.get_type_hints(cls)
    names = {f.name for f in dataclasses.fields(cls)}
    unknown = set(data) - names
    if unknown:
        raise TypeError(f"unknown field(s) {', '.join(sorted(unknown))} of {cls.__name__}")
    return cls(**{k: _convert(hints[k], v) for k, v in data.items()})


def write_json_atomic(path: Path, payload: Any) -> None:
    """Write JSON beside ``path`` and rename it into place (nothing half-written after a crash)."""
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    try:
        tmp.write_text(json.dumps(payload, indent=1, allow_nan=False))
        tmp.replace(path)
    finally:
        tmp.unlink(missing_ok=True)


def save_config(directory: Path, config: StudyConfig) -> Path:
    path = directory / CONFIG_FILE
    write_json_atomic(path, {"format_version": FORMAT_VERSION, "config": config.to_dict()})
    return path


def load_config(directory: str | Path) -> StudyConfig:
    path = Path(directory) / CONFIG_FILE
    if not path.is_file():
        raise input_error(directory, f"not a study directory (no {CONFIG_FILE})")
    try:
        raw = json.loads(path.read_text())
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise input_error(path, f"malformed JSON: {exc}") from None
    if not isinstance(raw, dict) or raw.get("format_version") != FORMAT_VERSION or "config" not in raw:
        raise input_error(path, f"unsupported study file (format_version {FORMAT_VERSION} expected)")
    return StudyConfig.from_dict(raw["config"], path)
