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
certify     :class:`CertifyConfig`  certify, validate, studies, compare
validate    :class:`ValidateConfig` validate, study validate
study       :class:`StudyConfig`    study run (saved with the study)
run         :class:`RunConfig`      study run / resume, demo (how, not what: not saved)
compare     :class:`CompareConfig`  study compare
report      :class:`ReportConfig`   study report, gait tiles
=========== ======================= =============================================================
"""

from __future__ import annotations

import dataclasses
from typing import Any

from robustgait.config.base import (
    ConfigError,
    Doc,
    FieldInfo,
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
    Barrier,
    CertifiedSet,
    CertifyConfig,
    CertifyDisturbance,
    EllipsoidConfig,
    Frame,
    MapKind,
    Method,
    Reconstruction,
    SequentialConfig,
    State,
    verification_beta,
    verification_size,
)
from robustgait.config.gait import DEFAULT_STEP_DURATION, DomainGraph, GaitParams, GenerationConfig, Stance
from robustgait.config.sim import Controller, SimConfig, Switching
from robustgait.config.study import (
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
    certify: CertifyConfig = dataclasses.field(default_factory=CertifyConfig)
    validate: ValidateConfig = dataclasses.field(default_factory=ValidateConfig)
    study: StudyConfig = dataclasses.field(default_factory=StudyConfig)
    run: RunConfig = dataclasses.field(default_factory=RunConfig)
    compare: CompareConfig = dataclasses.field(default_factory=CompareConfig)
    report: ReportConfig = dataclasses.field(default_factory=ReportConfig)

    @property
    def study_certify(self) -> CertifyConfig:
        """The certificate a study's evaluation computes: ``certify``, of pushes (J*) for the ``push`` metric."""
        if self.study.metric == "push":
            return dataclasses.replace(self.certify, disturbance="push")
        return self.certify

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
            "study.storage": "not set: a SQLite file in the study directory",
            "run.workers": f"not set: min(cores, 2) = {default_workers()} here",
            "run.address": "not set: start a local Ray",
            "compare.samples": "not set: study A's",
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
    # `robustgait demo`: a robustness study of exo, 3 iterations × 4 gaits, with a lighter sequential certificate
    # (ε = 0.05, 200 exploration samples: ≈ 470 samples and 7.6 s per gait on one thread instead of ≈ 980 and 16 s;
    # r* within ≈ 4 % instead of ≈ 1 % between seeds) so that it ends in a few minutes on 2 cores (docs/studies.md).
    "demo": {"study": {"iterations": 3, "batch": 4},
             "certify": {"sequential": {"epsilon": 0.05, "explore": 200, "explore_after_failure": 100,
                                        "budget": 1500}},
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


def with_overrides(base: Config, overrides: dict[str, Any], source: str | None = None) -> Config:
    """``base`` with the values of ``overrides`` (nested dicts, as in a config file) on top, validated."""
    return from_dict(Config, merge(to_dict(base), overrides), source, "toml")


__all__ = [
    "DEFAULT_R_MAX",
    "DEFAULT_STEP_DURATION",
    "DEMO_DIRECTORY",
    "DEMO_ROBOT",
    "KINDS",
    "PRESETS",
    "R_MAX_UNIT",
    "Barrier",
    "CertifiedSet",
    "CertifyConfig",
    "CertifyDisturbance",
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
    "GaitParams",
    "GenerationConfig",
    "LearnerConfig",
    "LearnerName",
    "MapKind",
    "Method",
    "Metric",
    "PreferenceModelConfig",
    "Reconstruction",
    "ReportConfig",
    "RunConfig",
    "SequentialConfig",
    "SimConfig",
    "Stance",
    "State",
    "StudyConfig",
    "Switching",
    "ValidateConfig",
    "choices_of",
    "config",
    "default_workers",
    "field_at",
    "fields_of",
    "from_dict",
    "merge",
    "nest",
    "preset",
    "to_dict",
    "to_markdown",
    "to_toml",
    "verification_beta",
    "verification_size",
    "with_overrides",
]
