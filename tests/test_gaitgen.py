import dataclasses
import json

import mujoco
import numpy as np
import pytest

from robustgait import GaitParams, load_gait, load_robot, walk
from robustgait.certify import CertifyConfig, certify_gait
from robustgait.cli import main
from robustgait.estimators import SequentialConfig
from robustgait.gaitgen import GaitGenerator, generate_gait
from robustgait.gaitgen.check import check_solution
from tests.conftest import ATALANTE_SPEC, needs_atalante


@pytest.fixture(scope="module")
def exo():
    return load_robot("exo")


@pytest.fixture(scope="module")
def gen(exo):
    return GaitGenerator(exo)


@pytest.fixture(scope="module")
def default(gen):
    res = gen.solve(GaitParams())
    assert res.success, res.reason
    return res


def test_default_gait_passes_the_physics_check(exo, gen, default):
    c = default.check
    assert c.passed and c.dynamics_residual <= 1e-6 and c.periodicity <= 1e-6 and c.stance_drift <= 1e-6
    assert max(c.step_length_error, c.step_width_error, c.step_height_error) <= 1e-3 and c.duration_error <= 1e-3
    ns = default.nodes
    f = ns.lam[:, :3]
    assert np.all(f[:, 2] >= gen.config.min_normal_force - 1e-6)
    assert np.all(np.abs(f[:, :2]) <= gen.config.friction * f[:, 2:3] + 1e-6)
    assert np.all(np.abs(ns.u) <= exo.torque_limit + 1e-6)
    g = default.gait
    assert g.domains[0].beta.shape == (12, 8) and g.domains[0].ff_torque.shape == (17, 12)
    assert g.params == GaitParams() and g.solver["status"] == "Solve_Succeeded"
    # both soles flat on the floor at τ = 0, the feet a step apart (MuJoCo kinematics)
    m, d = exo.model, mujoco.MjData(exo.model)
    d.qpos[:] = g.initial_state.qpos
    mujoco.mj_kinematics(m, d)
    for side in ("left", "right"):
        gid = exo.sole_geom_id[side]
        bottom = d.geom_xpos[gid][2] - m.geom_size[gid][np.argmin(m.geom_size[gid])]
        assert abs(bottom) < 1e-9
        np.testing.assert_allclose(d.geom_xmat[gid].reshape(3, 3)[2], [0, 0, 1], atol=1e-9)
    dx = d.geom_xpos[exo.sole_geom_id["right"]] - d.geom_xpos[exo.sole_geom_id["left"]]
    np.testing.assert_allclose(dx[:2], [0.15, -0.25], atol=1e-9)


def test_physics_check_catches_a_wrong_solution(gen, default):
    ns = dataclasses.replace(default.nodes, u=default.nodes.u * 1.01)
    bad = check_solution(gen.dyn, gen.problem, default.params, ns, default.params.step_duration)
    assert not bad.passed and bad.dynamics_residual > 1e-4 and "dynamics residual" in bad.failures[0]


def test_default_gait_walks_and_gets_a_certificate(exo, default):
    res = walk(exo, default.gait, steps=50)
    assert res.steps_taken == 50 and not res.fell
    nominal = 0.15 / 0.7
    assert abs(res.mean_speed - nominal) <= 0.2 * nominal
    cert = certify_gait(exo, default.gait, CertifyConfig(n_samples=50))
    assert cert.ok and cert.r_star > 0
    # the sequential estimator, small: ε = 0.2 (17 verification samples), 40 exploration samples
    seq = certify_gait(exo, default.gait, CertifyConfig(method="sequential", sequential=SequentialConfig(
        epsilon=0.2, first_round=50, round_size=20, explore=40, budget=300)))
    c = seq.certificate
    assert seq.ok and c is not None and 0 < c.r_star <= cert.r_star  # round 1 is the uniform draw above
    assert c.rounds[0].r_hat == cert.r_star and c.n_inside >= 17
    assert c.violation_bound <= 0.2 or c.budget_exhausted


def test_warm_start_converges_faster(gen, default):
    params = GaitParams(step_length=0.17)
    cold, warm = gen.solve(params), gen.solve(params, warm_start=default.gait)
    assert cold.success and warm.success
    assert warm.iterations < cold.iterations
    np.testing.assert_allclose(warm.gait.domains[0].beta, cold.gait.domains[0].beta, atol=1e-4)
    # a warm start from the other stance is relabeled first
    mirrored = gen.solve(params, warm_start=default.gait.mirrored(load_robot("exo")))
    assert mirrored.success and mirrored.iterations == warm.iterations


def test_grid_of_step_lengths_and_durations(gen):
    ok = 0
    for length in (0.10, 0.15, 0.20):
        for duration in (0.6, 0.8, 1.0):
            res = gen.solve(GaitParams(step_length=length, step_duration=duration))
            ok += bool(res.success and res.check.passed)
    assert ok >= 8


@pytest.mark.parametrize("kwargs, reason", [
    ({"step_width": 0.1}, "feet collide"),
    ({"step_length": 1.3}, "beyond the leg reach"),
    ({"step_duration": 0.0}, "step_duration"),
    ({"step_height": -0.01}, "step_height"),
])
def test_infeasible_parameters_fail_with_a_reason(exo, gen, kwargs, reason):
    res = generate_gait(exo, **kwargs, generator=gen)
    assert not res.success and res.gait is None and res.status == "Infeasible_Parameters" and reason in res.reason


def test_cli_generate_errors_exit_2_and_write_nothing(tmp_path, capsys):
    out = tmp_path / "g.json"
    for extra in (["--step-duration", "0"], ["--step-height", "0"], ["--nodes", "4"]):
        assert main(["gait", "generate", "--robot", "exo", "-o", str(out), *extra]) == 2
        err = capsys.readouterr().err
        assert err.startswith("robustgait: error:") and len(err.strip().splitlines()) == 1
    assert not out.exists()


@needs_atalante
def test_atalante_generated_gait_walks(tmp_path, capsys):
    out = tmp_path / "atalante.json"
    assert main(["gait", "generate", "--robot", str(ATALANTE_SPEC), "-o", str(out), "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["check"]["passed"] and summary["check"]["dynamics_residual"] <= 1e-6
    robot = load_robot(ATALANTE_SPEC)
    res = walk(robot, load_gait(out, robot), steps=30)
    assert res.steps_taken >= 30
