"""The bounds on a command's work (robustgait.config.work): the default configuration of every command passes its
work check on every shipped robot and example, for both domain graphs, and a mistaken setting is refused with one
line before any work. No simulation: the checks are called on the gaits' durations."""

from __future__ import annotations

import dataclasses

import pytest

from robustgait.certificate.certify import certify_steps, check_certify_work
from robustgait.certificate.reduced import section_dimension
from robustgait.cli import build_parser
from robustgait.cli.options import config_from
from robustgait.config import KINDS, CertifyConfig, Config, SimConfig, preset
from robustgait.config.work import MAX_PHYSICS_STEPS, MAX_STEP_PHYSICS_STEPS, Work, check_work, work_limit
from robustgait.errors import RobustGaitError
from robustgait.gait import Gait
from robustgait.io.gaitfile import save_gait
from robustgait.learn.space import ActionSpace
from robustgait.sim.engine import step_physics_steps
from robustgait.sim.walk import check_walk_work
from robustgait.study.run import check_evaluation_work, longest_gaits
from robustgait.validate.run import check_validate_work
from tests.conftest import ATALANTE_SPEC
from tests.io.test_io import cli, one_error_line

GRAPHS = ("flat", "multicontact")
SPEC = {"exo": "exo", "atalante": str(ATALANTE_SPEC)}


def worst_gait(robot, graph: str) -> Gait:  # type: ignore[no-untyped-def]
    """The longest-stepping gait a study of ``graph`` can generate on ``robot`` (durations only)."""
    config = defaults_of("study", "run", "d", "--robot", "exo", "--domains", graph)
    return longest_gaits(robot, config, ActionSpace.from_robot(robot, graph))[0]


@pytest.fixture(params=[(r, g, src) for r in SPEC for g in GRAPHS for src in ("stored", "action space")
                        if not (src == "stored" and (r, g) == ("atalante", "multicontact"))],
                ids=lambda p: "-".join(p))
def case(request):  # type: ignore[no-untyped-def]
    """(robot name, robot, gait): the stored gaits (exo flat and multi-contact, Atalante's FROST gait) and the
    longest-stepping gait of each action space (Atalante has no stored multi-contact gait)."""
    name, graph, src = request.param
    robot = request.getfixturevalue(name)  # atalante: skipped with the reason when ../shared is absent
    if src == "stored":
        gait = request.getfixturevalue({("exo", "flat"): "exo_gait", ("exo", "multicontact"): "exo_mc_gait",
                                        ("atalante", "flat"): "atalante_gait"}[(name, graph)])
    else:
        gait = worst_gait(robot, graph)
    assert gait.domain_graph == graph
    return name, robot, gait


def defaults_of(*argv: str, base: Config | None = None) -> Config:
    """The configuration a command runs with when given no option."""
    return config_from(build_parser().parse_args(list(argv)), base)


def test_walk_defaults_pass(case, tmp_path):
    name, robot, gait = case
    sim = defaults_of("walk", "g.json", "--robot", SPEC[name]).sim
    assert check_walk_work(robot, gait, sim, sim.step_cap).steps == 50
    for video in ("v.mp4", "v.gif"):
        check_walk_work(robot, gait, sim, sim.step_cap, tmp_path / video)


def test_certify_defaults_pass(case):
    name, robot, gait = case
    c = defaults_of("certify", "g.json", "--robot", SPEC[name])
    assert c.certify.disturbance == "push"
    worst = check_certify_work(robot, gait, c.certify, c.sim)
    # the orbit search: orbit.max_steps + orbit.hold_steps steps of the walk, the probe's pushes (orbit.probe_pushes at
    # up to 1 + orbit.probe_doublings sizes, each the pushed step and orbit.probe_horizon more); then the budget's
    # pushes, each the pushed step and push.horizon more
    o, p = c.certify.orbit, c.certify.push
    search = o.max_steps + o.hold_steps + (1 + o.probe_doublings) * o.probe_pushes * (1 + o.probe_horizon)
    assert worst == (search + c.certify.sequential.budget * (1 + p.horizon)) * step_physics_steps(gait, robot.dt,
                                                                                                  c.sim)


@pytest.mark.parametrize("kind", [*KINDS, "all"])
def test_validate_defaults_pass(case, kind):
    """Each disturbance kind (and all of them), with the certificate it computes first and with a given one."""
    name, robot, gait = case
    c = defaults_of("validate", "g.json", "--robot", SPEC[name], "--disturbance", kind)
    for certifying in (True, False):
        check_validate_work(robot, gait, c.validate, c.sim, kinds=len(c.validate.kinds), certify=c.certify,
                            certifying=certifying)


def test_study_validate_defaults_pass(case):
    """`study validate`: the study's certificates, or (``--method`` and the like) every gait certified again."""
    name, robot, gait = case
    study = defaults_of("study", "run", "d", "--robot", SPEC[name], "--domains", gait.domain_graph)
    c = defaults_of("study", "validate", "d", base=study)
    for certifying in (False, True):
        check_validate_work(robot, gait, c.validate, c.sim, kinds=len(c.validate.kinds), certify=c.study_certify,
                            certifying=certifying)


@pytest.mark.parametrize("graph", GRAPHS)
@pytest.mark.parametrize("name", SPEC)
def test_study_and_demo_defaults_pass(request, name, graph):
    """`study run` (the reported case: Atalante, multi-contact, defaults) and `demo`: their check before the study
    starts passes, and so do the checks of the walk and the certificate of an evaluation of the longest-stepping
    gait the study can generate — the evaluation no longer refuses what the study accepted."""
    robot = request.getfixturevalue(name)
    space = ActionSpace.from_robot(robot, graph)
    gait = worst_gait(robot, graph)
    study = defaults_of("study", "run", "d", "--robot", SPEC[name], "--domains", graph)
    demo = defaults_of("demo", "--override", f"generate.domains={graph}", base=preset("demo"))
    for c in (study, demo):
        check_evaluation_work(c, robot, space)
        check_walk_work(robot, gait, c.sim, c.sim.step_cap)
        check_certify_work(robot, gait, c.study_certify, c.sim)


@pytest.mark.parametrize("override", [  # on both sides of the limit: 4 × the default 63 836 steps of 1.5 T at most
    [], ["certify.sequential.budget=10000"], ["certify.push.horizon=83"], ["certify.push.horizon=84"],
    ["sim.step_cap=1000"], ["sim.max_step_tau=6"], ["sim.max_step_tau=6.1"], ["certify.disturbance=state"],
    ["certify.method=uniform", "certify.n_samples=10000", "certify.push.horizon=24"],
    ["certify.disturbance=state", "certify.horizon=10", "certify.map=stride"],
])
@pytest.mark.parametrize("graph", GRAPHS)
def test_the_study_refuses_what_its_evaluation_would(exo, graph, override):
    """The study's check and the checks its evaluation runs later agree on the longest-stepping gait."""
    argv = ["study", "run", "d", "--robot", "exo", "--domains", graph]
    for o in override:
        argv += ["--override", o]
    c = defaults_of(*argv)
    space = ActionSpace.from_robot(exo, graph)
    gait = worst_gait(exo, graph)
    assert gait.step_duration == max(space.values[space.names.index("step_duration")])
    assert step_physics_steps(gait, exo.dt, c.sim) == max(step_physics_steps(g, exo.dt, c.sim)
                                                          for g in longest_gaits(exo, c, space))

    def refused(check) -> bool:  # type: ignore[no-untyped-def]
        try:
            check()
        except RobustGaitError:
            return True
        return False

    study = refused(lambda: check_evaluation_work(c, exo, space))
    evaluation = refused(lambda: check_walk_work(exo, gait, c.sim, c.sim.step_cap)) or \
        refused(lambda: check_certify_work(exo, gait, c.study_certify, c.sim))
    assert study == evaluation


def test_the_limit_is_relative_to_the_defaults(exo, exo_gait):
    """Within 4 × the defaults' work (or 2e7) passes, beyond is refused, on the same robot and gait."""
    step = step_physics_steps(exo_gait, exo.dt, SimConfig())
    defaults = Work(certify_steps(CertifyConfig(), "flat", section_dimension(exo)), step)
    assert defaults.steps == 63_836 and work_limit(defaults) == 4 * 63_836 * 1050 > MAX_PHYSICS_STEPS
    assert check_work(Work(4 * 63_836, step), defaults, exo.dt, "x") == 4 * 63_836 * 1050
    with pytest.raises(RobustGaitError, match=r"^x: 255345 simulated steps .* over the limit of 2.7e\+08 \(4 × the "):
        check_work(Work(4 * 63_836 + 1, step), defaults, exo.dt, "x")
    small = Work(10, step)  # a small job on a robot whose defaults are small: the 2e7 floor
    assert work_limit(small) == MAX_PHYSICS_STEPS and check_work(Work(19_000, step), small, exo.dt, "x")


def test_a_mistaken_timestep_is_refused(exo, exo_gait, monkeypatch):
    """1e-5 s (the spec refuses it; a model that had it): one step alone is over the per-step limit, whatever the
    counts — also for the defaults, whose relative limit would scale with it."""
    monkeypatch.setattr(exo.model.opt, "timestep", 1e-5)
    for check in (lambda: check_walk_work(exo, exo_gait, SimConfig(step_cap=1000), 1000),
                  lambda: check_certify_work(exo, exo_gait, CertifyConfig(), SimConfig())):
        with pytest.raises(RobustGaitError) as err:
            check()
        msg = str(err.value)
        assert "\n" not in msg and "one simulated step may last 1.05 s, 105000 physics steps at a 1e-05 s " \
            f"timestep, over the limit of {MAX_STEP_PHYSICS_STEPS} per step" in msg


@pytest.mark.parametrize("argv, message", [
    (["certify", "{g}", "--robot", "exo", "--override", "certify.push.horizon=100"],
     "certify.orbit.max_steps 100 + certify.sequential.budget 3000 × 101 steps: 303836 simulated steps"),
    (["validate", "{g}", "--robot", "exo", "--trials", "10000", "--steps-after", "1000", "--disturbance", "all"],
     f"validate.trials 10000 × (validate.steps_after 1000 + 4) steps × {len(KINDS)} disturbance kinds + the "
     "certificate"),
    (["walk", "{long}", "--robot", "exo", "--override", "sim.max_step_tau=10"],
     "one simulated step may last 50 s, 50000 physics steps"),
    (["study", "run", "{t}/s", "--robot", "exo", "--override", "certify.sequential.budget=10000", "--override",
      "certify.push.horizon=30"], "study: one evaluation of a 1.1 s gait: certify.orbit.max_steps 100 + "
     "certify.sequential.budget 10000 × 31 steps"),
])
def test_mistaken_settings_are_one_line_exit_2_before_any_work(tmp_path, exo_gait, argv, message, no_work):
    g, long = save_gait(exo_gait, tmp_path / "g.json"), tmp_path / "long.json"
    save_gait(dataclasses.replace(exo_gait, domains=(dataclasses.replace(exo_gait.domains[0], duration=5.0),)), long)
    code, out, err = cli(*(a.format(g=g, long=long, t=tmp_path) for a in argv))
    assert code == 2 and out == ""
    one_error_line(err, message)
    assert not (tmp_path / "s").exists()


@pytest.mark.parametrize("config", [CertifyConfig(),
                                    CertifyConfig(disturbance="state", method="uniform", n_samples=300, horizon=2),
                                    CertifyConfig(disturbance="state", set="ellipsoid")])
def test_a_certificates_work_is_its_formula(config):
    """certify_steps = the orbit search's walk, hold and probe (+ ρ's batches when asked) + a state certificate's map
    at x* + every planned sample walking to its horizon (config/work.py): the count is the formula, not a number."""
    o, dim = config.orbit, 40
    probe = (1 + o.probe_doublings) * o.probe_pushes * (1 + o.probe_horizon) if o.probe_impulse > 0 else 0
    orbit = o.max_steps + o.hold_steps + probe
    per = 1 + config.push.horizon if config.disturbance == "push" else config.horizon * o.max_period
    at_x_star = 0 if config.disturbance == "push" else config.horizon * o.max_period
    n = config.n_samples if config.method == "uniform" else config.estimator.budget
    if config.set == "ellipsoid" and config.disturbance == "state":
        n += config.ellipsoid.fit_samples + (n if config.ellipsoid.compare_ball else 0)
    assert not o.linearization
    assert certify_steps(config, "flat", dim) == orbit + at_x_star + n * per
    assert certify_steps(config, "multicontact", dim) == certify_steps(config, "flat", dim)
