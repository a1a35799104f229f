"""The study file ``study.json``: what a study directory holds about itself, the robot and the whole configuration it
was created with, read back on resume, status, report, compare and validate. Nested sections are saved whole,
so a field added to any section is saved and restored without changes here."""

from __future__ import annotations

import dataclasses
import platform
from dataclasses import dataclass
from importlib import metadata
from pathlib import Path
from typing import TYPE_CHECKING, Any

from robustgait.config import STATE_CHOICE_DEFAULTS, Config, GenerationConfig, from_dict, study_disturbance, to_dict
from robustgait.config.certify import ESTIMATOR_DEFAULTS, without_retired
from robustgait.errors import input_error
from robustgait.io.output import write_json
from robustgait.io.schema import read_json

if TYPE_CHECKING:
    from robustgait.learn.space import ActionSpace
    from robustgait.robots import Robot

CONFIG_FILE = "study.json"
FORMAT_VERSION = 3
# fields added to the certificate since format 2, and what a format-2 study certified (the base angular velocity in
# a ball, one step): a study resumed keeps its certificate whatever today's defaults are
_CERTIFY_BEFORE_3 = {**STATE_CHOICE_DEFAULTS, "disturbance": "state"}


def _without_unused_state_choice(raw: Any) -> Any:
    """A study whose certificate is J* (metric push, or a push certificate) with the state choice reset to the
    defaults: one written before the two were exclusive may carry a state, set or horizon it never
    used — the push certificate ignored them — which now fails validation."""
    cfg = raw.get("config") if isinstance(raw, dict) else None
    if not isinstance(cfg, dict) or not isinstance(cfg.get("certify"), dict):
        return raw
    study = cfg.get("study")
    metric = study.get("metric") if isinstance(study, dict) else None
    if study_disturbance(str(metric), cfg["certify"].get("disturbance")) != "push":
        return raw
    return {**raw, "config": {**cfg, "certify": {**cfg["certify"], **STATE_CHOICE_DEFAULTS}}}


def _retired_certify_fields(raw: Any) -> Any:
    """A study written by an older version, read by this one: the certify fields that the orbit search and the
    recovery band replaced are dropped (:func:`~robustgait.config.certify.without_retired`; a resumed study finds its
    new gaits' orbits by the orbit search, its stored results stay as they were); one written before certificates
    checked their orbit (it has no ``fp_window``) ranked a gait that walked the cap without a certificate as a
    certified r* = 0 (``uncertified_penalty`` 0) — a resumed study recomputes its history's scores from the stored
    results and must keep one rule throughout."""
    cfg = raw.get("config") if isinstance(raw, dict) else None
    if not isinstance(cfg, dict):
        return raw
    certify, study = cfg.get("certify"), cfg.get("study")
    certify = dict(certify) if isinstance(certify, dict) else {}
    study = dict(study) if isinstance(study, dict) else {}
    if "fp_window" not in certify and "orbit" not in certify:
        study.setdefault("uncertified_penalty", 0.0)
    return {**raw, "config": {**cfg, "certify": without_retired(certify), "study": study}}


# the libraries whose versions decide a study's numbers: gait generation, simulation, certificate, learner
ENVIRONMENT_PACKAGES = ("robustgait", "numpy", "scipy", "mujoco", "casadi", "adam-robotics", "torch", "gpytorch",
                        "botorch", "optuna")


def environment() -> dict[str, str]:
    """Python's and :data:`ENVIRONMENT_PACKAGES`' versions ("not installed" for a missing one). Saved in
    ``study.json``: the same study on another install may depart (a fresh install of unpinned libraries made
    exo's 10 × 5 study propose other gaits from its 8th iteration)."""
    out = {"python": platform.python_version()}
    for name in ENVIRONMENT_PACKAGES:
        try:
            out[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            out[name] = "not installed"
    return out


def environment_changes(recorded: dict[str, str] | None) -> list[str]:
    """``"name recorded → now"`` for each package whose version differs from the one ``recorded`` (empty when
    nothing was recorded: a study written before the record existed)."""
    if not recorded:
        return []
    now = environment()
    return [f"{k} {v} → {now.get(k, 'not installed')}" for k, v in recorded.items() if now.get(k, v) != v]


@dataclass(frozen=True)
class StudySetup:
    """A study's robot (a shipped robot name or the absolute path of a spec .toml) and its configuration: the
    study section (oracle, learner, budget, storage) and the sections every evaluation uses (``generate``,
    ``sim``, ``certify``); the others are saved too, unused. ``environment``: the library versions recorded in
    ``study.json`` when the study was created (None for a setup not read from a file, or a study that predates
    the record); not part of the setup's identity."""

    robot: str
    config: Config
    environment: dict[str, str] | None = dataclasses.field(default=None, compare=False)

    def action_space(self, robot: Robot | None = None) -> ActionSpace:
        """The grid this study searches: the robot spec's action space of the study's domain graph
        (``config.generate.domains``). ``robot``: the loaded ``self.robot`` (loaded here when None)."""
        from robustgait.io.robotfile import load_robot
        from robustgait.learn.space import ActionSpace

        return ActionSpace.from_robot(robot or load_robot(self.robot), self.config.generate.domains)

    def to_dict(self) -> dict[str, Any]:
        return {"robot": self.robot, "config": to_dict(self.config)}


def save_config(directory: Path, setup: StudySetup) -> Path:
    """``study.json``: the format version, the robot, the configuration and today's :func:`environment` (the
    study is being created)."""
    return write_json(directory / CONFIG_FILE, {"format_version": FORMAT_VERSION, **setup.to_dict(),
                                                "environment": environment()})


def load_config(directory: str | Path) -> StudySetup:
    path = Path(directory) / CONFIG_FILE
    if not path.is_file():
        raise input_error(directory, f"not a study directory (no {CONFIG_FILE})")
    raw = read_json(path, "study config")
    if isinstance(raw, dict) and raw.get("format_version") == 1 and isinstance(raw.get("config"), dict):
        raw = {"format_version": 2, **_from_v1(raw["config"])}
    if isinstance(raw, dict) and raw.get("format_version") == 2 and isinstance(raw.get("config"), dict):
        certify = raw["config"].get("certify")
        certify = dict(certify) if isinstance(certify, dict) else {}
        raw = {**raw, "format_version": FORMAT_VERSION,
               "config": {**raw["config"], "certify": {**_CERTIFY_BEFORE_3, **certify}}}
    certify = raw["config"].get("certify") if isinstance(raw, dict) and isinstance(raw.get("config"), dict) else None
    if isinstance(certify, dict) and ("push_steps" in certify or isinstance(certify.get("push"), dict)):
        push = {**(certify.get("push") or {})}
        if "push_steps" in certify or any(k in push for k in ESTIMATOR_DEFAULTS["push"]):
            # written when the push table held its round sizes; before chunked verification: whole batches
            push.setdefault("verify_chunk", 0)
        if "explore_horizon" not in push:  # written before cheap exploration: exploration pushes were the statement's
            push.update({"explore_horizon": push.get("horizon", 20),
                         "explore_recovery_radius": push.get("recovery_radius", 0.03),
                         "explore_recovery_steps": push.get("recovery_steps", 2), "first_share": 0.5})
        # format 3 as first written had a push_steps key: the fixed horizon the recovery band retired
        certify = {k: v for k, v in certify.items() if k != "push_steps"} | {"push": push}
        raw = {**raw, "config": {**raw["config"], "certify": certify}}
    raw = _without_unused_state_choice(_retired_certify_fields(raw))
    if isinstance(raw, dict) and isinstance(raw.get("config"), dict):
        study = raw["config"].get("study")
        study = dict(study) if isinstance(study, dict) else {}
        if "verify" not in study:  # written before studies ranked on estimates: every gait was verified
            study = {**study, "verify": "all"}
        if "first_batch" not in study:  # written before a person's shorter first batch: every batch full
            study = {**study, "first_batch": None}
        raw = {**raw, "config": {**raw["config"], "study": study}}
        person = raw["config"].get("person")
        person = dict(person) if isinstance(person, dict) else {}
        if "overdraw" not in person:  # written before over-drawn batches: its iterations evaluate the batch alone
            person = {**person, "overdraw": 0, "ahead": False}
        if "region" not in person:  # written before the floor's region: proposals anywhere, batches of one asked
            person = {**person, "region": False, "min_shown": 1}
        if "reference_in_batch" not in person:  # written before: the default gait itself beside the first batch
            person = {**person, "reference_in_batch": False}
        raw = {**raw, "config": {**raw["config"], "person": person}}
    if not (isinstance(raw, dict) and raw.get("format_version") == FORMAT_VERSION and isinstance(raw.get("robot"), str)
            and "config" in raw):
        raise input_error(path, f"unsupported study file (format_version {FORMAT_VERSION} expected)")
    env = raw.get("environment")
    return StudySetup(raw["robot"], from_dict(Config, raw["config"], str(path), "json"),
                      {str(k): str(v) for k, v in env.items()} if isinstance(env, dict) else None)


def _from_v1(old: dict[str, Any]) -> dict[str, Any]:
    """A study written by robustgait before the configuration tree (format 1: one StudyConfig holding the
    evaluation's certificate, simulation and generation options) in today's sections."""
    ev = dict(old.get("evaluation") or {})
    certify = dict(ev.get("certify") or {})
    sim = dict(certify.pop("sim", None) or {})
    if "step_cap" in ev:
        sim["step_cap"] = ev["step_cap"]
    generate = {k: v for k, v in (ev.get("gaitgen") or {}).items() if v is not None and k in _GENERATE_FIELDS}
    study = {k: old[k] for k in ("metric", "learner", "iterations", "batch", "seed", "storage", "study_name",
                                 "learning") if old.get(k) is not None}
    return {"robot": old.get("robot"),
            "config": {"study": study, "certify": certify, "sim": sim, "generate": generate}}


_GENERATE_FIELDS = frozenset(f.name for f in dataclasses.fields(GenerationConfig))
