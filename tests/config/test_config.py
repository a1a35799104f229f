"""The configuration (robustgait.config): every field documented and bounded, one-line errors from pydantic's error
objects, the TOML of ``config show`` round-tripping through ``--config``, presets, and what depends on another
choice resolved in the config."""

from __future__ import annotations

import dataclasses
import sys
from typing import Any

import pytest

from robustgait.cli import main
from robustgait.config import (
    DEFAULT_STEP_DURATION,
    CertifyConfig,
    Config,
    ConfigError,
    GaitParams,
    SequentialConfig,
    SimConfig,
    field_at,
    fields_of,
    from_dict,
    preset,
    to_dict,
    with_overrides,
)
from robustgait.errors import RobustGaitError
from tests.conftest import EXO_GAIT

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib


def test_every_field_has_help_a_default_and_limits():
    fields = list(fields_of(Config))
    assert len(fields) >= 90
    for f in fields:
        assert f.doc.help, f.path  # one line of help
        assert f.default is not dataclasses.MISSING, f.path
        if f.scalar in (int, float) and not f.choices:
            assert f.doc.bounded, f"{f.path}: a number without limits"
        if f.scalar in (int, float) and f.default is not None and not f.choices:
            assert f.doc.contains(f.default), f"{f.path}: default {f.default} outside {f.doc.text()}"
    assert field_at(Config, "certify.sequential.epsilon").doc.text() == "0 < x < 1"
    assert field_at(Config, "certify.method").choices == ("sequential", "uniform")


def test_errors_name_the_field_and_the_limit():
    cases: list[tuple[Any, str]] = [
        (lambda: CertifyConfig(alpha=2), "CertifyConfig.alpha: must satisfy 0 < x < 1 (got 2)"),
        (lambda: CertifyConfig(alpha="0.1"), "CertifyConfig.alpha: expected a number, got a string ('0.1'): a quoted "
                                             "number is text, remove the quotes"),
        (lambda: CertifyConfig(n_samples=True), "CertifyConfig.n_samples: expected an integer, got a boolean (true)"),
        (lambda: CertifyConfig(r_max=float("nan")), "CertifyConfig.r_max: must be a finite number (got nan)"),
        (lambda: CertifyConfig(frame="north"), "CertifyConfig.frame: must be one of 'heading', 'world', 'body' "
                                               "(got 'north')"),
        (lambda: CertifyConfig(sequential={"budget": 0}), "CertifyConfig.sequential.budget: must satisfy 1 ≤ x ≤ "
                                                          "10000 (got 0)"),
        (lambda: SimConfig(chunk=3), "SimConfig.chunk: unknown key (known: switching, min_switch_tau"),
        (lambda: CertifyConfig(horizon=2), "CertifyConfig.disturbance: a push certificate (J*) has no reduced state, "
                                           "set or horizon (got state omega, set ball, horizon 2)"),
    ]
    for make, message in cases:
        with pytest.raises(ConfigError) as err:
            make()
        assert str(err.value).startswith(message), str(err.value)
        assert "\n" not in str(err.value)
    with pytest.raises(ConfigError, match=r"c.toml: certify.alpha: must satisfy 0 < x < 1 \(got 2\) \(and 1 more "
                       r"problem\)"):
        from_dict(Config, {"certify": {"alpha": 2, "beta": 7}}, "c.toml", "toml")
    with pytest.raises(ConfigError, match=r"c.toml: sim: expected a table, got an array \(1 item\)"):
        from_dict(Config, {"sim": [1]}, "c.toml", "toml")


def test_replace_validates():
    cfg = CertifyConfig()
    assert dataclasses.replace(cfg, alpha=0.1).alpha == 0.1
    with pytest.raises(ConfigError, match="alpha"):
        dataclasses.replace(cfg, alpha=1.0)


def test_the_step_duration_depends_on_the_domain_graph_in_the_config():
    assert GaitParams().step_duration is None
    for domains, t in DEFAULT_STEP_DURATION.items():
        cfg = with_overrides(Config(), {"generate": {"domains": domains}})
        assert cfg.params.step_duration == t == GaitParams().resolved(domains).step_duration
    assert with_overrides(Config(), {"gait": {"step_duration": 1.0}, "generate": {"domains": "multicontact"}}) \
        .params.step_duration == 1.0


def test_presets_are_overrides_of_the_defaults():
    demo = preset("demo")
    assert (demo.study.iterations, demo.study.batch, demo.run.workers) == (3, 4, 2)
    assert demo.certify.sequential.epsilon == 0.05 and demo.certify.alpha == Config().certify.alpha
    with pytest.raises(ConfigError, match="unknown preset"):
        preset("huge")


def _show(capsys: pytest.CaptureFixture[str], *argv: str) -> str:
    assert main(["config", "show", *argv]) == 0
    return capsys.readouterr().out


@pytest.mark.parametrize("argv", [(), ("--domains", "multicontact"), ("--preset", "demo"), ("--robot", "exo"),
                                  ("--override", "certify.sequential.spread=0.3", "--override", "run.workers=3")])
def test_config_show_round_trips_through_config(tmp_path, capsys, argv):
    text = _show(capsys, *argv)
    raw = tomllib.loads(text)
    expected = from_dict(Config, raw, "shown", "toml")
    path = tmp_path / "c.toml"
    path.write_text(text)
    assert tomllib.loads(_show(capsys, "--config", str(path))) == raw  # show → --config → show: a fixed point
    from robustgait.cli import build_parser
    from robustgait.cli.options import config_from

    for cmd in (["certify", str(EXO_GAIT), "--robot", "exo"], ["walk", str(EXO_GAIT), "--robot", "exo"],
                ["study", "run", "d", "--robot", "exo"], ["gait", "generate", "--robot", "exo", "-o", "g.json"]):
        args = build_parser().parse_args([*cmd, "--config", str(path)])
        assert config_from(args) == expected, cmd


def test_config_show_documents_every_field(capsys):
    text = _show(capsys, "--robot", "exo")
    for f in fields_of(Config):
        assert f"{f.name} = " in text and f.doc.help.split(";")[0] in text, f.path
    assert "# step_duration = ...  (not set: 0.7 s, the default of flat gaits)" in text
    assert "robot exo" in text and "action space (studies)" in text


def test_flags_override_the_file_and_the_overrides(tmp_path, capsys):
    from robustgait.cli import build_parser
    from robustgait.cli.options import config_from

    path = tmp_path / "c.toml"
    path.write_text("[certify]\nn_samples = 10\nalpha = 0.2\n[certify.sequential]\nspread = 0.3\n")
    args = build_parser().parse_args(["certify", str(EXO_GAIT), "--robot", "exo", "--config", str(path), "--samples",
                                      "12", "--method", "uniform", "--override", "certify.alpha=0.3"])
    cfg = config_from(args)
    assert (cfg.certify.n_samples, cfg.certify.alpha, cfg.certify.sequential.spread) == (12, 0.3, 0.3)
    assert to_dict(cfg)["sim"] == to_dict(Config())["sim"]  # what the file does not set keeps its default


def test_naming_a_state_field_asks_for_a_state_certificate(tmp_path):
    """J* is the default; --state / --set / --horizon (or a file's [certify] state) without the disturbance in the
    same source mean a state certificate and a study ranked by it; naming the disturbance or the metric wins."""
    from robustgait.cli import build_parser
    from robustgait.cli.options import config_from

    def cfg(*argv: str) -> Config:
        return config_from(build_parser().parse_args(["study", "run", "d", "--robot", "exo", *argv]))

    assert (Config().certify.disturbance, Config().study.metric) == ("push", "push")
    c = cfg("--state", "velocity")
    assert (c.certify.disturbance, c.certify.state, c.study.metric) == ("state", "velocity", "robustness")
    assert cfg("--horizon", "2", "--metric", "stability").study.metric == "stability"
    assert cfg("--set", "ellipsoid").study_certify.set == "ellipsoid"
    assert cfg("--override", "certify.state=centroidal").certify.disturbance == "state"
    assert cfg("--method", "uniform").certify.disturbance == "push"  # not a state field
    path = tmp_path / "c.toml"
    path.write_text('[certify]\nstate = "centroidal"\n')
    assert cfg("--config", str(path)).study_certify.state == "centroidal"
    with pytest.raises(RobustGaitError, match="push ranks gaits by J"):  # both named: a conflict, refused
        cfg("--state", "velocity", "--metric", "push")
    with pytest.raises(RobustGaitError, match=r"a push certificate \(J\*\) has no reduced state"):
        config_from(build_parser().parse_args(["certify", str(EXO_GAIT), "--robot", "exo", "--state", "velocity",
                                               "--disturbance", "push"]))
    assert with_overrides(Config(), {"certify": {"state": "velocity"}}).certify.disturbance == "state"


@pytest.mark.parametrize("text, message", [
    ("[certify]\nalpah = 0.1\n", "certify.alpah: unknown key (known: method, state, set, horizon, disturbance,"),
    ("[cerify]\nalpha = 0.1\n", "cerify: unknown key (known: gait, generate, sim, comfort, certify, validate"),
    ('[certify]\nalpha = "0.1"\n', "certify.alpha: expected a number, got a string ('0.1'): a quoted number is text"),
    ("[certify]\nn_samples = 1.5\n", "certify.n_samples: expected an integer, got a number (1.5)"),
    ("[certify]\nalpha = 1.5\n", "certify.alpha: must satisfy 0 < x < 1 (got 1.5)"),
    ("[sim]\nstep_cap = 0\n", "sim.step_cap: must satisfy 1 ≤ x ≤ 1000 (got 0)"),
    ('[certify]\nmethod = "grid"\n', "certify.method: must be one of 'sequential', 'uniform' (got 'grid')"),
    ("[validate]\npush_phase = [0.5]\n", "validate.push_phase: must have exactly 2 items (got 1)"),
    ("[certify\n", "malformed TOML"),
])
def test_bad_config_file_is_one_line_exit_2(tmp_path, capsys, text, message):
    path = tmp_path / "bad.toml"
    path.write_text(text)
    out_json = tmp_path / "c.json"
    code = main(["certify", str(EXO_GAIT), "--robot", "exo", "--config", str(path), "-o", str(out_json)])
    out, err = capsys.readouterr()
    assert code == 2 and out == "" and not out_json.exists()
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"robustgait: error: {path}: {message}"), lines


def test_bad_overrides_are_one_line(capsys):
    for argv, message in ((["--override", "certify.alpha"], "expected KEY=VALUE"),
                          (["--override", "certify.nope=1"], "certify.nope: unknown setting"),
                          (["--override", "certify.alpha=3"], "--override certify.alpha=3: certify.alpha: must "
                                                              "satisfy 0 < x < 1 (got 3.0)")):
        assert main(["config", "show", *argv]) == 2
        err = capsys.readouterr().err
        assert len(err.strip().splitlines()) == 1 and message in err, err
    assert main(["config", "show", "--config", "c.yaml"]) == 2
    assert "expected .toml" in capsys.readouterr().err


def test_the_configuration_page_lists_every_field():
    from pathlib import Path

    page = (Path(__file__).resolve().parents[2] / "docs" / "configuration.md").read_text()
    assert Config.markdown() in page, "docs/configuration.md is stale: robustgait config show --markdown"


@pytest.mark.parametrize("argv, message", [
    (["certify", "{g}", "--robot", "exo", "--override", "certify.sequential.verify_margin=0.5"],
     "--override certify.sequential.verify_margin=0.5: a push certificate draws its verification disk from its fall "
     "curve"),
    (["certify", "{g}", "--robot", "exo", "--disturbance", "state", "--override", "certify.push.horizon=5"],
     "--override certify.push.horizon=5: push options do nothing to a state certificate"),
    (["certify", "{g}", "--robot", "exo", "--samples", "20"],
     "argument --samples: n_samples is the uniform estimator's"),
    (["certify", "{g}", "--robot", "exo", "--method", "uniform", "--override", "certify.sequential.explore=10"],
     "the sequential estimator's options do nothing to method = uniform"),
    (["certify", "{g}", "--robot", "exo", "--disturbance", "state", "--override", "certify.ellipsoid.fit_samples=9"],
     "ellipsoid options do nothing unless set = ellipsoid"),
    # a study's certificate is the study's (study_certify): J* for the push metric, whatever certify.disturbance says
    (["study", "run", "{t}/s", "--robot", "exo", "--override", "certify.disturbance=state", "--override",
      "certify.sequential.verify_margin=0.9"], "a push certificate draws its verification disk"),
])
def test_an_option_that_does_nothing_to_the_certificate_is_refused(tmp_path, capsys, no_work, argv, message):
    """One estimator configuration: an option set for a certificate it does not apply to is an error — one line,
    exit 2, nothing written — never silently ignored."""
    code = main([a.format(g=EXO_GAIT, t=tmp_path) for a in argv])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and message in err[0], err
    assert not (tmp_path / "s").exists()


def test_the_estimator_resolves_its_defaults_by_what_is_certified():
    """[certify.sequential] serves both certificates: the unset round sizes are the push certificate's (50, 100, 50,
    25 pushes, 0.9 of β first) or the state certificate's (200, 600, 200, 0, 0.5); a value set applies to both."""
    push, state = CertifyConfig().estimator, CertifyConfig(disturbance="state").estimator
    assert (push.first_round, push.explore, push.explore_after_failure, push.verify_chunk, push.first_share) == (
        50, 100, 50, 25, 0.9)
    assert (state.first_round, state.explore, state.explore_after_failure, state.verify_chunk, state.first_share) == (
        200, 600, 200, 0, 0.5)
    both = SequentialConfig(explore=70)
    assert CertifyConfig(sequential=both).estimator.explore == CertifyConfig(
        disturbance="state", sequential=both).estimator.explore == 70
    assert CertifyConfig().inapplicable("sequential.epsilon") is None  # ε, β's shares and the budget serve both
