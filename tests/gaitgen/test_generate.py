import dataclasses
import json

import mujoco
import numpy as np
import pytest

from robustgait import GaitParams, RobustGaitError, load_gait, load_robot, walk
from robustgait.certificate.certify import certify_gait
from robustgait.cli import main
from robustgait.config import CertifyConfig, GenerationConfig, SequentialConfig
from robustgait.gaitgen import GaitGenerator, generate_gait
from robustgait.gaitgen.check import check_solution
from robustgait.gaitgen.solve import pack
from tests.conftest import ATALANTE_SPEC, EXO_GAIT, EXO_MC_GAIT, needs_atalante


# The generator's build (≈ 7 s) and default solve make most of this module slow: plain `pytest` covers
# generated gaits through the stored ones (tests/data), CI runs everything.
@pytest.fixture(scope="module")
def gen(exo):
    return GaitGenerator(exo)


@pytest.fixture(scope="module")
def default(gen):
    res = gen.solve(GaitParams())
    assert res.success, res.reason
    return res


@pytest.mark.xdist_group("exo_generator")  # one worker computes the shared module fixture
@pytest.mark.slow
def test_default_gait_passes_the_physics_check(exo, gen, default):
    c = default.check
    assert c.passed and c.dynamics_residual <= 1e-6 and c.periodicity <= 1e-6 and c.stance_drift <= 1e-6
    assert max(c.step_length_error, c.step_width_error, c.step_height_error) <= 1e-3 and c.duration_error <= 1e-3
    ns = default.nodes[0]
    f = ns.lam[:, :3]
    assert np.all(f[:, 2] >= gen.config.min_normal_force - 1e-6)
    assert np.all(np.abs(f[:, :2]) <= gen.config.friction * f[:, 2:3] + 1e-6)
    assert np.all(np.abs(ns.u) <= exo.torque_limit + 1e-6)
    g = default.gait
    assert g.domains[0].beta.shape == (12, 8) and g.domains[0].ff_torque.shape == (17, 12)
    assert g.params == GaitParams().resolved("flat") and g.solver["status"] == "Solve_Succeeded"
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


@pytest.mark.xdist_group("exo_generator")  # one worker computes the shared module fixture
@pytest.mark.slow
def test_physics_check_catches_a_wrong_solution(gen, default):
    ns = dataclasses.replace(default.nodes[0], u=default.nodes[0].u * 1.01)
    bad = check_solution(gen.dyn, gen.problem, default.params, [ns], [default.params.step_duration])
    assert not bad.passed and bad.dynamics_residual > 1e-4 and "dynamics residual" in bad.failures[0]


@pytest.mark.xdist_group("exo_generator")  # one worker computes the shared module fixture
@pytest.mark.slow
def test_default_gait_meets_the_gait_quality_bounds(exo, gen, default):
    """Pelvis bands, angular velocity, joint speeds and the swing sole's attitude hold at every node."""
    from robustgait.dynamics import foot_frame
    from robustgait.gaitgen.problem import matrix_to_rpy

    q, ns, tol = gen.problem.quality, default.nodes[0], 1e-6
    rpy = np.array([matrix_to_rpy(h[:3, :3]) for h in ns.H])
    assert np.all(np.abs(rpy[:, 0]) <= q.pelvis_roll + tol) and np.all(np.abs(rpy[:, 2]) <= q.pelvis_yaw + tol)
    assert np.all((rpy[:, 1] >= q.pelvis_pitch[0] - tol) & (rpy[:, 1] <= q.pelvis_pitch[1] + tol))
    assert np.all((ns.H[:, 2, 3] >= q.pelvis_height[0] - tol) & (ns.H[:, 2, 3] <= q.pelvis_height[1] + tol))
    assert np.all(np.abs(ns.vb[:, 3:]) <= q.pelvis_angular_velocity + tol)
    assert np.all(np.abs(ns.sd) <= np.asarray(q.joint_velocity) + tol)
    for i in range(1, len(ns.s) - 1):
        h = np.asarray(gen.dyn.frame_fun(foot_frame(gen.problem.swing, "sole"))(ns.H[i], ns.s[i]))
        assert max(abs(h[2, 0]), abs(h[2, 1])) <= np.sin(q.swing_tilt) + tol
        assert abs(h[1, 0]) <= np.sin(q.swing_yaw) + tol
        # flat approach: every sole corner at least half as high as the sole centre
        a, b = gen.problem.half_length, gen.problem.half_width
        corners = [h[2, 3] + sx * a * h[2, 0] + sy * b * h[2, 1] for sx in (-1, 1) for sy in (-1, 1)]
        assert min(corners) >= gen.config.flat_approach * h[2, 3] - tol


@pytest.mark.xdist_group("exo_generator")  # one worker computes the shared module fixture
@pytest.mark.slow
def test_stored_test_gait_is_what_the_generator_makes(exo, default):
    """tests/data/exo_gait.json (used by the simulator, return-map and certificate tests) is today's default."""
    stored = load_gait(EXO_GAIT, exo)
    assert stored.params == default.params
    assert stored.solver["objective"] == pytest.approx(default.objective, rel=1e-6)
    np.testing.assert_allclose(stored.domains[0].beta, default.gait.domains[0].beta, atol=1e-3)


def _pelvis_roll_deg(trajectory):
    from robustgait.rotations import quat_to_mat

    r = quat_to_mat(trajectory[:, 4:8])
    return np.degrees(np.arctan2(r[:, 2, 1], r[:, 2, 2]))


def _walks_like_an_exoskeleton(robot, gait, max_speed_error=0.03):
    """50 steps, pelvis roll within ±6°, speed within ±3 % of L/T, ‖x̄*‖ ≤ 1 rad/s."""
    res = walk(robot, gait, steps=50, keep_trajectory=True)
    assert res.steps_taken == 50 and not res.fell, (gait.params, res.fall_reason)
    assert np.abs(_pelvis_roll_deg(res.trajectory)).max() < 6.0, gait.params
    p = gait.params
    assert res.mean_speed == pytest.approx(p.step_length / p.step_duration, rel=max_speed_error), gait.params
    return res


@pytest.mark.xdist_group("exo_generator")  # one worker computes the shared module fixture
@pytest.mark.slow
def test_default_gait_walks_and_gets_a_certificate(exo, default):
    _walks_like_an_exoskeleton(exo, default.gait)
    cert = certify_gait(exo, default.gait, CertifyConfig(method="uniform", disturbance="state", n_samples=50))
    assert cert.ok and np.linalg.norm(cert.fixed_point.omega) <= 1.0 and cert.value > 0
    # the sequential estimator, small: ε = 0.2 (17 verification samples), 40 exploration samples
    seq = certify_gait(exo, default.gait, CertifyConfig(method="sequential", disturbance="state",
                                                        sequential=SequentialConfig(epsilon=0.2, first_round=50,
                                                                                    round_size=20, explore=40,
                                                                                    budget=300)))
    c = seq.certificate
    assert seq.ok and c is not None and 0 < c.radius <= cert.value  # round 1 is the uniform draw above
    assert c.rounds[0].r_hat == cert.value and c.n_inside >= 17
    assert c.violation_bound <= 0.2 or c.budget_exhausted


@pytest.mark.xdist_group("exo_generator")  # one worker computes the shared module fixture
@pytest.mark.slow
def test_warm_start_converges_faster(gen, default):
    params = GaitParams(step_length=0.17)
    cold, warm = gen.solve(params), gen.solve(params, warm_start=default.gait)
    assert cold.success and warm.success
    assert warm.iterations < cold.iterations
    # the same optimum: equal cost; β equal up to a nearly flat direction of the cost (the swing ankle roll
    # moves by ~4e-4 rad between the two solutions at 5e-8 relative cost)
    assert warm.objective == pytest.approx(cold.objective, rel=1e-6)
    np.testing.assert_allclose(warm.gait.domains[0].beta, cold.gait.domains[0].beta, atol=1e-3)
    # a warm start from the other stance is relabeled first
    mirrored = gen.solve(params, warm_start=default.gait.mirrored(load_robot("exo")))
    assert mirrored.success and mirrored.iterations == warm.iterations


@pytest.mark.xdist_group("exo_generator")  # one worker computes the shared module fixture
@pytest.mark.slow
def test_a_cold_start_that_does_not_converge_is_continued_from_the_default_gait(exo, gen, monkeypatch):
    """The first cold solve of L 0.17 is made to stop at IPOPT's iteration limit (the solve itself stubbed); the
    generator then solves it from the robot's default gait, says so, and counts both solves; a pre-check's refusal, a
    user's warm start or ``continuation = false`` are not continued."""
    from robustgait.gaitgen.solve import GaitGenResult

    real, calls = gen._solve, []
    kept = gen._default is not None  # the default gait's own cold solve (the ``default`` fixture's) is kept

    def cold_stalls(p, warm, continued=""):  # type: ignore[no-untyped-def]
        calls.append((p.step_length, warm is None, continued))
        if warm is None and p.step_length == 0.17:
            return GaitGenResult(False, "Maximum_Iterations_Exceeded", "IPOPT: Maximum_Iterations_Exceeded",
                                 p.resolved("flat"), iterations=300, solve_seconds=1.0)
        return real(p, warm, continued)

    monkeypatch.setattr(gen, "_solve", cold_stalls)
    res = gen.solve(GaitParams(step_length=0.17))
    assert res.success and res.continued == "Maximum_Iterations_Exceeded" and res.iterations > 300
    assert res.summary()["continued"] == "Maximum_Iterations_Exceeded" and "continued" not in gen.solve(
        GaitParams(step_length=0.18)).summary()
    assert res.gait.solver["continued_from"] == ("the robot's default gait (the cold start: "
                                                  "Maximum_Iterations_Exceeded)")
    default = gen.default_gait()
    assert default is not None and default.params.step_length == exo.default_params.step_length
    # the default gait is solved once per generator: here, unless its own cold solve was kept before
    assert sum(1 for c in calls if c[0] == exo.default_params.step_length) == (0 if kept else 1)
    assert gen.default_gait() is default and sum(1 for c in calls if c[0] == exo.default_params.step_length) == (
        0 if kept else 1)
    warm = gen.solve(GaitParams(step_length=0.17), warm_start=default)
    assert warm.success and not warm.continued
    assert gen.solve(GaitParams(step_width=0.05)).continued == ""  # Infeasible_Parameters: no other start helps
    monkeypatch.setattr(gen, "config", dataclasses.replace(gen.config, continuation=False))
    off = gen.solve(GaitParams(step_length=0.17))
    assert not off.success and off.status == "Maximum_Iterations_Exceeded" and not off.continued


@pytest.mark.slow
def test_grid_over_the_action_space_walks(exo, gen):
    """The corners of the action space — step length × duration (default width, height), then width × height —
    every gait solves, passes the physics check and walks like an exoskeleton. (The whole 4 × 4 + 4 grid is
    benchmarks/experiments/gait_generation/run.py's; the corners, where gaits are most extreme, keep CI within its
    time.)"""
    a = exo.spec.action_space
    grid = [GaitParams(step_length=float(L), step_duration=float(T))
            for L in (a["step_length"].low, a["step_length"].high)
            for T in (a["step_duration"].low, a["step_duration"].high)]
    grid += [GaitParams(step_width=W, step_height=h) for W in (a["step_width"].low, a["step_width"].high)
             for h in (a["step_height"].low, a["step_height"].high)]
    for params in grid:
        res = gen.solve(params)
        assert res.success and res.check.passed, (params, res.reason)
        _walks_like_an_exoskeleton(exo, res.gait)


@pytest.mark.xdist_group("exo_generator")  # one worker computes the shared module fixture
@pytest.mark.parametrize("kwargs, reason", [
    ({"step_width": 0.1}, "feet collide"),
    ({"step_length": 1.3}, "beyond generate.max_step_length"),
    ({"step_length": 0.5, "step_width": 1.0, "step_duration": 1.5}, "beyond the leg reach"),
])
@pytest.mark.slow
def test_infeasible_parameters_fail_with_a_reason(exo, gen, kwargs, reason):
    res = generate_gait(exo, GaitParams(**kwargs), generator=gen)
    assert not res.success and res.gait is None and res.status == "Infeasible_Parameters" and reason in res.reason


@pytest.mark.parametrize("kwargs, field", [({"step_duration": 0.0}, "step_duration"),
                                           ({"step_height": -0.01}, "step_height")])
def test_parameters_out_of_their_bounds_are_refused(kwargs, field):
    with pytest.raises(RobustGaitError, match=f"GaitParams.{field}: must satisfy"):
        GaitParams(**kwargs)


def test_cli_generate_errors_exit_2_and_write_nothing(tmp_path, capsys):
    out = tmp_path / "g.json"
    for extra in (["--step-duration", "0"], ["--step-height", "0"], ["--nodes", "4"]):
        assert main(["gait", "generate", "--robot", "exo", "-o", str(out), *extra]) == 2
        err = capsys.readouterr().err
        assert err.startswith("robustgait: error:") and len(err.strip().splitlines()) == 1
    assert not out.exists()


@pytest.mark.slow
def test_cli_generate_prints_ipopt_log_only_with_verbose(tmp_path, capfd):
    out = tmp_path / "g.json"
    for verbose in (False, True):
        assert main(["gait", "generate", "--robot", "exo", "-o", str(out), *(["--verbose"] if verbose else [])]) == 0
        printed = capfd.readouterr().out  # IPOPT writes to the C-level stdout
        assert ("iter    objective" in printed) is verbose and "physics check passed" in printed
        assert "walk check passed: the gait walked" in printed and "under pd; its switching states settled" in printed


@pytest.mark.slow
@needs_atalante
def test_atalante_generated_gait_walks(tmp_path, capsys):
    out = tmp_path / "atalante.json"
    assert main(["gait", "generate", "--robot", str(ATALANTE_SPEC), "-o", str(out), "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["check"]["passed"] and summary["check"]["dynamics_residual"] <= 1e-6
    robot = load_robot(ATALANTE_SPEC)
    gait = load_gait(out, robot)
    _walks_like_an_exoskeleton(robot, gait)
    cert = certify_gait(robot, gait, CertifyConfig(method="uniform", disturbance="state", n_samples=20))
    assert np.linalg.norm(cert.fixed_point.omega) <= 1.0


@pytest.mark.slow
@needs_atalante
def test_atalante_multicontact_gait_walks_and_is_certified_with_its_falling_probes_below_j_star():
    """Atalante rolls heel-to-toe only with its swing sole free to leave toe-off toe-down
    (gait_quality.swing_toe_down_until = 0.5 in robots/atalante/spec.toml): then the T = 1.0 s gait walks 50 steps,
    striking at the planned time, at L/T, and 300 steps undisturbed in a band it holds (σ 0.017). Some of the orbit
    search's eight probing pushes of 4 N s fell it and the others came back to the band: the falls measure its basin,
    not the orbit, so it is certified (docs/gaitgen.md), and its orbit line says that J* lies below the probe."""
    robot = load_robot(ATALANTE_SPEC)
    assert robot.spec.gait_quality.swing_toe_down_until == 0.5
    res = GaitGenerator(robot, GenerationConfig(domains="multicontact")).solve(GaitParams(step_duration=1.0))
    assert res.success and res.check.passed, res.reason
    w = walk(robot, res.gait, steps=50)
    assert w.steps_taken == 50 and not w.fell
    assert all(abs(e.tau - 1.0) < 0.02 for e in w.events)  # no early heel strike
    assert w.mean_speed == pytest.approx(0.15 / 1.0, rel=0.05)
    cfg = CertifyConfig(method="uniform", disturbance="state", n_samples=24, r_max=1.0, seed=3)
    cert = certify_gait(robot, res.gait, cfg)
    assert cert.status == "ok", cert.reason
    probe = cert.orbit.probe
    assert probe is not None and probe.ok and probe.impulse < 5.0
    assert 1 <= sum(probe.fell) < len(probe.fell) and any(probe.recovered) and not any(probe.diverging)
    assert "J* lies below it" in cert.orbit.describe()


@pytest.mark.slow
def test_multicontact_generation(exo):
    """The 2-domain problem: solves from a cold start, passes the physics check in both domains and through both
    impacts, reproduces the stored multi-contact test gait, and warm-starts faster."""
    from robustgait.bezier import bezier

    gen = GaitGenerator(exo, GenerationConfig(domains="multicontact"))
    params = GaitParams().resolved("multicontact")
    res = gen.solve(params)
    assert res.success, res.reason
    c = res.check
    assert c.dynamics_residual <= 1e-6 and c.periodicity <= 1e-6 and c.impact_residual <= 1e-6
    assert c.stance_drift <= 1e-6 and c.min_normal_force >= gen.config.min_line_force - 1e-6
    g = res.gait
    assert g.domain_graph == "multicontact" and [d.name for d in g.domains] == ["single_support", "double_support"]
    assert g.domains[1].duration == pytest.approx(params.rolling_fraction * params.step_duration)
    assert g.step_duration == pytest.approx(params.step_duration)
    # the free joints of double support are fitted Béziers; the outputs are exact
    ns, taus = res.nodes[1], gen.problem.domain_taus[1]
    err = np.abs(bezier(g.domains[1].beta, taus) - ns.s)
    assert err[:, gen.problem.outputs[1]].max() < 1e-9 and err.max() < 2e-3
    stored = load_gait(EXO_MC_GAIT, exo)
    assert stored.solver["objective"] == pytest.approx(res.objective, rel=1e-6)
    warm = gen.solve(params, warm_start=stored)
    assert warm.success and warm.iterations < res.iterations
    # a warm start is rebuilt with its own step and torques: x₀ is its solution, whatever the new parameters
    x_sol = pack(gen.problem, [d.beta for d in g.domains], res.nodes)
    np.testing.assert_allclose(gen.initial_guess(GaitParams(step_length=0.17, step_duration=0.9), g), x_sol,
                               atol=1e-6)
    # so a neighbour converges in a fraction of the cold iterations (measured: 32 against 185)
    near = gen.solve(GaitParams(step_length=0.17, step_duration=0.9), warm_start=g)
    assert near.success and near.iterations <= res.iterations // 3


def test_cli_multicontact_bad_rolling_fraction(tmp_path, capsys):
    out = tmp_path / "g.json"
    assert main(["gait", "generate", "--robot", "exo", "--domains", "multicontact", "--rolling-fraction", "0.9",
                 "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert "--rolling-fraction: must satisfy 0.05 ≤ x ≤ 0.6 (got 0.9)" in err and len(err.strip().splitlines()) == 1
    assert not out.exists()


def test_a_request_no_leg_of_that_size_walks_is_refused_before_any_solve(tmp_path, capsys, no_work):
    """Step length in leg lengths, speed as a Froude number, swing height in leg lengths: a request far beyond exo
    (0.7 m in 0.2 s, 0.3 m high: 3.5 m/s, Froude 1.36) is refused in one line, exit 2, nothing written, without
    building the problem; every point of exo's action spaces passes."""
    from robustgait.cli import main
    from robustgait.config.gait import reach_problem
    from robustgait.learn.space import ActionSpace

    exo = load_robot("exo")
    cfg = GenerationConfig()
    out = tmp_path / "g.json"
    code = main(["gait", "generate", "--robot", "exo", "--step-length", "0.7", "--step-duration", "0.2",
                 "--step-height", "0.3", "-o", str(out)])
    err = capsys.readouterr().err
    assert code == 2 and not out.exists()  # before the problem is built (no_work)
    assert len(err.strip().splitlines()) == 1 and "Froude number 1.36, beyond generate.max_froude = 0.5" in err
    assert "beyond generate.max_step_height" in reach_problem(
        GaitParams(step_length=0.2, step_duration=0.8, step_height=0.3), exo.scale, cfg)
    assert "beyond generate.max_step_length" in reach_problem(
        GaitParams(step_length=0.8, step_duration=2.0), exo.scale, cfg)
    for graph in ("flat", "multicontact"):
        space = ActionSpace.from_robot(exo, graph)
        assert all(reach_problem(space.params(i).resolved(graph), exo.scale, cfg) is None for i in range(space.size))


def test_the_joint_margin_keeps_trajectories_inside_their_ranges() -> None:
    """μ = min(margin, range/4) off each finite end; an unlimited end stays infinite; no margin, the range itself."""
    from robustgait.gaitgen.problem import inner_range

    rng = np.array([[-0.26, 2.53], [-0.3, 0.3], [-np.inf, np.inf], [-1.0, np.inf]])
    out = inner_range(rng, 0.1)
    np.testing.assert_allclose(out[0], [-0.16, 2.43])
    np.testing.assert_allclose(out[1], [-0.2, 0.2])          # 0.6 wide: 0.1 ≤ 0.15
    np.testing.assert_allclose(inner_range(np.array([[-0.1, 0.1]]), 0.1)[0], [-0.05, 0.05])  # a quarter at most
    assert np.isinf(out[2]).all() and out[3, 0] == pytest.approx(-0.9) and np.isinf(out[3, 1])
    assert np.array_equal(inner_range(rng, 0.0), rng)
