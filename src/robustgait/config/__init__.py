"""robustgait's configuration: the single owner of every default, bound and choice (``docs/design.md``).

One tree of frozen dataclasses, one section per box of the pipeline; each field has its type, default, unit,
limits and one line of help (:mod:`robustgait.config.base`). The command line is generated from it
(:mod:`robustgait.cli.options`), ``robustgait config show`` prints it as TOML, ``--config FILE.toml`` reads it back,
and every result saves the sections it was made with.

=========== ======================= =============================================================
section     class                   used by
=========== ======================= =============================================================
gait        :class:`GaitParams`     ``gait generate`` (the four essential constraints)
generate    :class:`GenerationConfig` gait generation (HZD problem options), studies
sim         :class:`SimConfig`      every simulation: walk, certify, validate, studies
comfort     :class:`ComfortConfig`  the comfort figures of a walk: walk, studies (saved with the study)
certify     :class:`CertifyConfig`  certify, validate, studies, compare
validate    :class:`ValidateConfig` validate, study validate
study       :class:`StudyConfig`    study run (saved with the study)
person      :class:`PersonConfig`   studies ranked by a person or a simulated one (saved with the study)
web         :class:`WebConfig`      the page of a person study (where: not saved)
run         :class:`RunConfig`      study run / resume, demo (how, not what: not saved)
compare     :class:`CompareConfig`  study compare
report      :class:`ReportConfig`   study report, gait tiles
robot       :class:`RobotConfig`    robot init, robot check (with ``scale`` and ``check``)
=========== ======================= =============================================================
"""

from __future__ import annotations

import dataclasses
from typing import Any

from robustgait.config.base import (
    ConfigError,
    Doc,
    FieldInfo,
    FieldProblem,
    choices_of,
    config,
    field_at,
    fields_of,
    from_dict,
    merge,
    nest,
    to_dict,
    to_markdown,
    to_toml,
)
from robustgait.config.certify import (
    DEFAULT_R_MAX,
    R_MAX_UNIT,
    STATE_CHOICE_DEFAULTS,
    Barrier,
    CertifiedSet,
    CertifyConfig,
    CertifyDisturbance,
    EllipsoidConfig,
    Frame,
    MapKind,
    Method,
    OrbitConfig,
    PushConfig,
    Reconstruction,
    SequentialConfig,
    State,
    radius_name,
    study_disturbance,
)
from robustgait.config.comfort import ComfortConfig
from robustgait.config.gait import (
    DEFAULT_STEP_DURATION,
    GAIT_FORMATS,
    ROBOT_SCALED,
    DomainGraph,
    GaitFormat,
    GaitParams,
    GenerationConfig,
    RobotScale,
    Stance,
    relative_generation_defaults,
)
from robustgait.config.person import PersonConfig, SimulatedPersonConfig, WebConfig, parse_requirement
from robustgait.config.robot import Plan, RobotCheckConfig, RobotConfig, ScaleRules
from robustgait.config.sim import Controller, SimConfig, Switching
from robustgait.config.study import (
    PERSON_METRICS,
    CompareConfig,
    LearnerConfig,
    LearnerName,
    Metric,
    PreferenceModelConfig,
    ReportConfig,
    RunConfig,
    StudyConfig,
    default_workers,
)
from robustgait.config.validate import KINDS, Disturbance, DisturbanceKind, ValidateConfig


@config
class Config:
    """The whole configuration (module docstring). ``Config()`` is the shipped defaults."""

    gait: GaitParams = dataclasses.field(default_factory=GaitParams)
    generate: GenerationConfig = dataclasses.field(default_factory=GenerationConfig)
    sim: SimConfig = dataclasses.field(default_factory=SimConfig)
    comfort: ComfortConfig = dataclasses.field(default_factory=ComfortConfig)
    certify: CertifyConfig = dataclasses.field(default_factory=CertifyConfig)
    validate: ValidateConfig = dataclasses.field(default_factory=ValidateConfig)
    study: StudyConfig = dataclasses.field(default_factory=StudyConfig)
    person: PersonConfig = dataclasses.field(default_factory=PersonConfig)
    web: WebConfig = dataclasses.field(default_factory=WebConfig)
    run: RunConfig = dataclasses.field(default_factory=RunConfig)
    compare: CompareConfig = dataclasses.field(default_factory=CompareConfig)
    report: ReportConfig = dataclasses.field(default_factory=ReportConfig)
    robot: RobotConfig = dataclasses.field(default_factory=RobotConfig)

    def __post_init__(self) -> None:
        if self.study.metric == "push" and self.certify.chooses_a_state:
            raise FieldProblem("study.metric", "push ranks gaits by J*, which has no reduced state, set or horizon "
                               f"(certify: state {self.certify.state}, set {self.certify.set}, horizon "
                               f"{self.certify.horizon}); to rank by a state certificate use metric = robustness")

    @property
    def study_certify(self) -> CertifyConfig:
        """The certificate a study's evaluation computes: ``certify``, of pushes (J*) for the ``push`` metric and of
        states (r*) for ``robustness``."""
        disturbance = study_disturbance(self.study.metric, self.certify.disturbance)
        return self.certify if disturbance == self.certify.disturbance else dataclasses.replace(
            self.certify, disturbance=disturbance)

    @property
    def params(self) -> GaitParams:
        """The gait parameters with the step duration resolved for ``generate.domains``."""
        return self.gait.resolved(self.generate.domains)

    def unset(self) -> dict[str, str]:
        """What each field that is not set (None) resolves to, for :func:`to_toml`."""
        d = self.generate.domains
        return {
            "gait.step_duration": f"not set: {DEFAULT_STEP_DURATION[d]:g} s, the default of {d} gaits",
            "certify.r_max": "not set: " + ", ".join(f"{v:g} {R_MAX_UNIT[k]} ({k})" for k, v in DEFAULT_R_MAX.items()),
            "generate.ds_free_joints": "not set: picked from the joint axes",
            **{f"generate.{k}": "not set: the robot spec's [generation] value, else relative to the robot (its help)"
               for k in ROBOT_SCALED},
            "study.storage": "not set: a SQLite file in the study directory",
            "person.floor": "not set: person.floor_fraction × the certificate of the grid gait nearest the robot's "
                            "default gait (the gait section), the first batch's first gait (person.reference_in_batch)",
            "run.workers": f"not set: min(cores, 2) = {default_workers()} here",
            "run.address": "not set: start a local Ray",
            "compare.samples": "not set: study A's",
            "robot.name": "not set: the model's name, lower case",
            "robot.keyframe": "not set: the model's first keyframe (none: every joint at 0 clipped to its range)",
        }

    def show(self, header: str = "") -> str:
        """The configuration as TOML, each key with its help, unit and limits (``robustgait config show``)."""
        top = "".join(f"# {line}\n" for line in header.splitlines())
        return top + to_toml(self, unset=self.unset())

    @classmethod
    def markdown(cls) -> str:
        """Every field as markdown tables, one per section (``docs/configuration.md``; ``config show --markdown``)."""
        return to_markdown(cls, cls().unset())


# Named configurations shipped with the package: overrides of the defaults, as a config file would hold them.
PRESETS: dict[str, dict[str, Any]] = {
    # `robustgait demo`: a study of exo ranked by J* (the default metric, its gaits ranked on their estimates), 3
    # iterations × 4 gaits, on 2 workers, the gaits it shows verified with a lighter statement (ε = 0.05: a first
    # verification batch of 60 pushes) so that it ends in minutes on 2 cores.
    "demo": {"study": {"iterations": 3, "batch": 4},
             "certify": {"sequential": {"epsilon": 0.05, "budget": 1500}},
             "run": {"workers": 2}},
}


# `robustgait demo`: the robot it studies and the directory it writes, unless told otherwise
DEMO_ROBOT = "exo"
DEMO_DIRECTORY = "robustgait-demo"


def preset(name: str) -> Config:
    """A shipped configuration (:data:`PRESETS`) over the defaults."""
    if name not in PRESETS:
        raise ConfigError(f"unknown preset {name!r} (shipped: {', '.join(PRESETS)})")
    return from_dict(Config, PRESETS[name], f"preset {name}")


# fields that only a state certificate has: naming one without ``certify.disturbance`` asks for a state certificate
STATE_CERTIFICATE_FIELDS = ("state", "set", "horizon")


def with_implied_choices(overrides: dict[str, Any]) -> dict[str, Any]:
    """``overrides`` with ``certify.disturbance = "state"`` (and ``study.metric = "robustness"``) when its
    ``certify`` table names a field of a state certificate (:data:`STATE_CERTIFICATE_FIELDS`) but not the
    disturbance (nor the metric): ``--state velocity`` or a config file's ``[certify] state = "velocity"`` means a
    state certificate — and a study ranked by it — not the default push certificate with an unused state."""
    cert = overrides.get("certify")
    if not isinstance(cert, dict) or not any(k in cert for k in STATE_CERTIFICATE_FIELDS):
        return overrides
    out = dict(overrides)
    if "disturbance" not in cert:
        out["certify"] = {**cert, "disturbance": "state"}
        study = overrides.get("study", {})
        if isinstance(study, dict) and "metric" not in study:  # (a malformed table is left to validation)
            out["study"] = {**study, "metric": "robustness"}
    return out


def with_overrides(base: Config, overrides: dict[str, Any], source: str | None = None) -> Config:
    """``base`` with the values of ``overrides`` (nested dicts, as in a config file; :func:`with_implied_choices`) on
    top, validated."""
    return from_dict(Config, merge(to_dict(base), with_implied_choices(overrides)), source, "toml")


__all__ = [
    "DEFAULT_R_MAX",
    "DEFAULT_STEP_DURATION",
    "DEMO_DIRECTORY",
    "DEMO_ROBOT",
    "GAIT_FORMATS",
    "KINDS",
    "PERSON_METRICS",
    "PRESETS",
    "ROBOT_SCALED",
    "R_MAX_UNIT",
    "STATE_CERTIFICATE_FIELDS",
    "STATE_CHOICE_DEFAULTS",
    "Barrier",
    "CertifiedSet",
    "CertifyConfig",
    "CertifyDisturbance",
    "ComfortConfig",
    "CompareConfig",
    "Config",
    "ConfigError",
    "Controller",
    "Disturbance",
    "DisturbanceKind",
    "Doc",
    "DomainGraph",
    "EllipsoidConfig",
    "FieldInfo",
    "Frame",
    "GaitFormat",
    "GaitParams",
    "GenerationConfig",
    "LearnerConfig",
    "LearnerName",
    "MapKind",
    "Method",
    "Metric",
    "OrbitConfig",
    "PersonConfig",
    "Plan",
    "PreferenceModelConfig",
    "PushConfig",
    "Reconstruction",
    "ReportConfig",
    "RobotCheckConfig",
    "RobotConfig",
    "RobotScale",
    "RunConfig",
    "ScaleRules",
    "SequentialConfig",
    "SimConfig",
    "SimulatedPersonConfig",
    "Stance",
    "State",
    "StudyConfig",
    "Switching",
    "ValidateConfig",
    "WebConfig",
    "choices_of",
    "config",
    "default_workers",
    "field_at",
    "fields_of",
    "from_dict",
    "merge",
    "nest",
    "parse_requirement",
    "preset",
    "radius_name",
    "relative_generation_defaults",
    "study_disturbance",
    "to_dict",
    "to_markdown",
    "to_toml",
    "with_implied_choices",
    "with_overrides",
]
