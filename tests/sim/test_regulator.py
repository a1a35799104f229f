"""The H-LIP step regulator (robustgait.sim.regulator) and the walk check of gait generate (robustgait.gaitgen.
walkcheck): when it runs, what it measures and commands, that it leaves the other robots bit for bit, and that a
narrow-footed humanoid walks with it and is refused without it."""

from __future__ import annotations

import json
from dataclasses import replace

import mujoco
import numpy as np
import pytest

from robustgait.cli import main
from robustgait.config import Config, SimConfig
from robustgait.config.regulator import RegulatorConfig
from robustgait.errors import RobustGaitError
from robustgait.sim.engine import StepEngine
from robustgait.sim.factory import make_engine
from robustgait.sim.regulator import com_state, landing_map, nominal_com, sole_frame, swing_dofs
from robustgait.sim.regulator_rules import carry_phase, placement_share, regulator_rule
from robustgait.sim.walk import walk

ON = SimConfig(regulator=RegulatorConfig(mode="on", gain_scale=0.25))


def test_the_whole_gain_is_taken_only_where_the_error_grows_and_it_helps(exo, exo_gait) -> None:  # type: ignore[no-untyped-def]
    """settle_share: the width rule's κ when the walk's lateral error grows ≤ growth_limit under it; κ = 1 when it grows
    more (or falls) and grows less under κ = 1; the rule's κ when κ = 1 is no better."""
    reg = StepEngine(exo, exo_gait, SimConfig(regulator=RegulatorConfig(mode="on", gain_scale=0.25))).regulator
    assert reg is not None
    inf = float("inf")
    for under_rule, under_whole, share in ((1.1, None, 0.25), (inf, 0.8, 1.0), (3.0, 2.5, 1.0), (inf, inf, 0.25),
                                           (3.0, 4.0, 0.25)):
        reg.set_share(0.25)
        reg.growth_whole = None
        asked: list[float] = []

        def measure(k: float, a: float = under_rule, b: float | None = under_whole, log: list[float] = asked
                    ) -> float:
            log.append(k)
            return a if k == 0.25 else (inf if b is None else b)
        reg.settle_share(measure)
        assert reg.share == share and reg.growth == under_rule
        assert asked == ([0.25] if under_whole is None else [0.25, 1.0])


@pytest.mark.xdist_group("narrow_gait")  # one worker computes the shared module fixture
@pytest.mark.slow  # its T1 specs: robot init walks the default gait to choose the timestep (tens of seconds)
def test_the_growth_probe_measures_the_walk_once_and_leaves_no_trace(t1_narrow, narrow_gait):  # type: ignore[no-untyped-def]
    """The narrow T1's ankle holds a lateral error (it grows ×1.1 a step without foot placement, under the limit of
    2): κ stays the sole's share. The probe runs once per gait in a process, and its steps are not counted as the
    walk's corrections."""
    from robustgait.sim import regulator as reg_module

    eng = make_engine(t1_narrow, narrow_gait)
    reg = eng.regulator
    assert reg is not None and reg.growth is not None and 0.5 < reg.growth < 2.0
    assert reg.share == pytest.approx(placement_share(RegulatorConfig(), 0.03, t1_narrow.leg_length))
    assert reg.updates == 0 and reg.largest == 0.0
    cached = len(reg_module._GROWTH)
    again = make_engine(t1_narrow, narrow_gait).regulator
    assert again is not None and again.growth == reg.growth and len(reg_module._GROWTH) == cached
    given = make_engine(t1_narrow, narrow_gait, SimConfig(regulator=RegulatorConfig(gain_scale=0.5))).regulator
    assert given is not None and given.growth is None and given.share == 0.5


@pytest.mark.slow  # its T1 specs: robot init walks the default gait to choose the timestep (tens of seconds)
def test_robots_with_wide_soles_run_without_it_bit_for_bit(exo, exo_gait, exo_mc_gait, t1):  # type: ignore[no-untyped-def]
    """auto leaves exo and T1 alone: no regulator object, the engine's code path is the one without it, and a walk
    with mode = off is the same walk to the last bit."""
    for gait in (exo_gait, exo_mc_gait):
        assert make_engine(exo, gait).regulator is None
    from tests.conftest import standing_gait

    held = tuple((h.name, h.angle) for h in t1.spec.held)
    assert make_engine(t1, replace(standing_gait(t1), held=held)).regulator is None
    off = SimConfig(regulator=RegulatorConfig(mode="off"))
    a = walk(exo, exo_gait, steps=3, keep_trajectory=True)
    b = walk(exo, exo_gait, off, steps=3, keep_trajectory=True)
    assert a.controller == b.controller == "pd"
    assert a.trajectory is not None and b.trajectory is not None
    assert np.array_equal(a.trajectory, b.trajectory)


def test_nominal_com_is_the_gaits_own_state_at_its_preimpact_instant(exo, exo_gait):  # type: ignore[no-untyped-def]
    x, z0 = nominal_com(exo, exo_gait, np.array([0.0, 1.0]))
    assert 0.5 * exo.leg_length < z0 < 1.2 * exo.leg_length
    eng = StepEngine(exo, exo_gait, ON)
    for tau, state in ((0, exo_gait.initial_state), (1, exo_gait.pre_impact_state)):
        qp, qv = state.qpos, state.qvel
        measured = com_state(exo, mujoco.MjData(exo.model), eng.full_states(qp[None], qv[None]), exo_gait.stance)
        np.testing.assert_allclose(measured[0], x[tau], atol=2e-3)


def test_landing_map_moves_the_swing_sole_flat_by_the_asked_amount(exo, exo_gait):  # type: ignore[no-untyped-def]
    g, rel = landing_map(exo, exo_gait)
    swing = "left" if exo_gait.stance == "right" else "right"
    assert rel[1] > 0.1  # the left foot lands on the left of the right stance foot
    assert set(np.flatnonzero(np.abs(g).sum(axis=1))) <= set(swing_dofs(exo, swing))
    m, d = exo.model, mujoco.MjData(exo.model)

    def sole(q):  # type: ignore[no-untyped-def]
        d.qpos[:] = q
        mujoco.mj_kinematics(m, d)
        st = exo.sole_geom_id[exo_gait.stance]
        r = d.geom_xmat[st].reshape(3, 3).T
        return r @ (d.geom_xpos[exo.sole_geom_id[swing]] - d.geom_xpos[st]), r @ d.geom_xmat[
            exo.sole_geom_id[swing]].reshape(3, 3)

    from robustgait.sim.regulator import _posture

    q0 = _posture(exo, exo_gait, np.array([1.0]))[0]
    p0, r0 = sole(q0)
    for du in (np.array([0.002, 0.0]), np.array([0.0, -0.002])):
        q = q0.copy()
        q[exo.qpos_idx] += g @ du
        p, r = sole(q)
        np.testing.assert_allclose((p - p0)[:2], du, atol=1e-4)   # first order: 2 mm within 0.1 mm
        assert np.abs(r - r0).max() < 1e-3                        # the sole keeps its orientation


def test_landing_map_of_a_closed_chain_line_foot_moves_it_through_the_loops_at_any_roll(tmp_path):  # type: ignore[no-untyped-def]
    # the inline biped of tests/robots/test_loops.py: no ankle roll, the knee drives the tarsus through a rod, line feet
    from robustgait import load_robot
    from robustgait.robots.loops import closed_posture
    from robustgait.sim.regulator import _posture
    from tests.conftest import standing_gait
    from tests.inspection.biped import SERVO_RULE, write
    from tests.robots.test_loops import chain_xml

    model, spec = write(tmp_path, chain_xml(), "chain.xml"), tmp_path / "chain.toml"
    assert main(["robot", "init", str(model), "-o", str(spec), *SERVO_RULE]) == 0
    robot = load_robot(spec)
    gait = standing_gait(robot)
    g, _ = landing_map(robot, gait)
    # the foot moves sideways by the hip roll, not by a near-singular mix that keeps a line's roll (hundreds of rad/m)
    assert np.abs(g).max() < 5.0
    roll = robot.spec.joints.index("left_hip_roll")
    assert abs(g[roll, 1]) > 0.9  # ≈ 1 / the leg length (a roll-holding least-squares compromise: 0.50)
    m, d = robot.model, mujoco.MjData(robot.model)

    def sole(q):  # type: ignore[no-untyped-def]
        d.qpos[:] = q
        mujoco.mj_kinematics(m, d)
        st = robot.sole_geom_id["right"]
        r = d.geom_xmat[st].reshape(3, 3).T
        return r @ (d.geom_xpos[robot.sole_geom_id["left"]] - d.geom_xpos[st]), r @ d.geom_xmat[
            robot.sole_geom_id["left"]].reshape(3, 3)

    q0 = _posture(robot, gait, np.array([1.0]))[0]
    p0, r0 = sole(q0)
    for du in (np.array([0.002, 0.0]), np.array([0.0, -0.002])):
        q = q0.copy()
        q[robot.qpos_idx] += g @ du
        p, r = sole(closed_posture(m, robot.passive_ids, q))  # the tarsus follows the knee through its rod
        np.testing.assert_allclose((p - p0)[:2], du, atol=1e-4)
        assert np.abs(r[:, 0] - r0[:, 0]).max() < 1e-3  # the line keeps its direction (pitch, yaw); its roll is free


def test_on_the_orbit_it_commands_nothing_and_a_batch_is_its_samples_one_by_one(exo, exo_gait):  # type: ignore[no-untyped-def]
    eng = StepEngine(exo, exo_gait, ON)
    reg = eng.regulator
    assert reg is not None and eng.controller_name == "pd+hlip"
    qp, qv = exo_gait.initial_state.qpos, exo_gait.initial_state.qvel
    states = eng.full_states(qp[None], qv[None])
    reg.begin(exo_gait.stance, states)
    off = reg.offsets(np.array([0]), states, 0, 50)
    assert off.shape == (1, 50, exo.model.nu) and np.abs(off).max() < 2e-3
    rng = np.random.default_rng(0)
    qvs = np.repeat(qv[None], 3, axis=0)
    qvs[:, :2] += rng.normal(0.0, 0.1, (3, 2))
    batch = eng.step(np.repeat(qp[None], 3, axis=0), qvs, exo_gait.stance)
    for i in range(3):
        one = eng.step(qp[None], qvs[i:i + 1], exo_gait.stance)
        assert np.array_equal(one.qpos[0], batch.qpos[i]) and one.duration[0] == batch.duration[i]
    assert reg.updates > 0 and reg.largest > 0.0


def test_the_feedback_engine_refuses_it_in_one_line(exo, exo_gait):  # type: ignore[no-untyped-def]
    cfg = replace(ON, controller="passivity")
    with pytest.raises(RobustGaitError, match="runs with the pd controller") as e:
        make_engine(exo, exo_gait, cfg)
    assert "\n" not in str(e.value)


@pytest.mark.slow  # its T1 specs: robot init walks the default gait to choose the timestep (tens of seconds)
def test_robot_init_says_whether_it_is_on(t1_narrow, t1):  # type: ignore[no-untyped-def]
    assert t1_narrow.sole_width == t1_narrow.scale.sole_width == pytest.approx(0.03)
    assert regulator_rule(RegulatorConfig(), t1_narrow.sole_width, t1_narrow.leg_length, 1)[0]
    assert not regulator_rule(RegulatorConfig(), t1.sole_width, t1.leg_length, 1)[0]


@pytest.mark.slow  # its T1 specs: robot init walks the default gait to choose the timestep (tens of seconds)
def test_a_tipping_sole_under_part_of_the_gain_is_told_to_try_all_of_it(t1_narrow, t1, exo_gait):  # type: ignore[no-untyped-def]
    """The walk check's advice: a narrow sole that tipped under the share κ its width gives (0.22 on the narrow T1) is
    told to try the H-LIP's whole gain; with κ = 1 already, or a wide sole (the regulator off), it is not."""
    from robustgait.gaitgen.walkcheck import advice

    tipped = "the left stance sole tipped over its outer edge (3°; the sole is 3.0 cm wide)"
    tips = advice(t1_narrow, exo_gait, Config(), tipped)
    assert any("sim.regulator.gain_scale=1; the sole's rule gives 0.22" in a for a in tips)
    whole = Config(sim=SimConfig(regulator=RegulatorConfig(gain_scale=1.0)))
    assert not any("gain_scale" in a for a in advice(t1_narrow, exo_gait, whole, tipped))
    assert not any("gain_scale" in a for a in advice(t1_narrow, exo_gait, Config(), tipped, share=1.0))  # measured
    # the probe measured the whole gain too and it did not help: not advised
    assert not any("gain_scale" in a for a in advice(t1_narrow, exo_gait, Config(), tipped, whole_tried=True))
    assert not any("gain_scale" in a for a in advice(t1, exo_gait, Config(), tipped))
    assert not any("gain_scale" in a for a in advice(t1_narrow, exo_gait, Config(), "no_touchdown"))
    # under the stepping regulator a tipping sole is told to step quicker (the error grows over a long single
    # support), under the PD alone slower; both shorter and wider
    quick = f"shorter, quicker steps (--step-length; --step-duration under this gait's {exo_gait.step_duration:.3g} s)"
    assert quick in tips and "a wider step (--step-width)" in tips
    assert "shorter, slower steps (--step-length, --step-duration)" in advice(t1, exo_gait, Config(), tipped)


@pytest.fixture(scope="module")
def narrow_gait(t1_narrow):  # type: ignore[no-untyped-def]
    from robustgait.gaitgen import GaitGenerator

    res = GaitGenerator(t1_narrow).solve(t1_narrow.default_params)
    assert res.gait is not None, res.reason
    return res.gait


@pytest.mark.xdist_group("narrow_gait")  # one worker computes the shared module fixture
@pytest.mark.slow
def test_a_narrow_footed_humanoid_walks_with_the_regulator_and_falls_without(t1_narrow, narrow_gait):  # type: ignore[no-untyped-def]
    """Four 5 mm spheres per foot on a 4 cm footprint: the default gait falls within 20 steps under the joint PD alone
    (a stance sole tips over its edge); with the regulator (on by the rule) it walks 50 steps."""
    with_it = walk(t1_narrow, narrow_gait, steps=50)
    assert with_it.controller == "pd+hlip" and not with_it.fell and with_it.steps_taken == 50
    without = walk(t1_narrow, narrow_gait, SimConfig(regulator=RegulatorConfig(mode="off")), steps=20)
    assert without.fell and without.steps_taken < 20


@pytest.mark.slow
def test_gait_generate_refuses_a_gait_that_does_not_walk_and_says_why(t1_narrow, tmp_path, capsys):  # type: ignore[no-untyped-def]
    spec = str(t1_narrow.spec.source)
    out = tmp_path / "g.json"
    assert main(["gait", "generate", "--robot", spec, "-o", str(out), "--override", "sim.regulator.mode=off"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and not out.exists()
    assert "gait generation failed (Walk_Check_Failed): the gait fell in step" in err
    assert "tipped over its" in err and "sim.regulator.mode=on" in err
    assert main(["gait", "generate", "--robot", spec, "-o", str(out), "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["walk_check"]["controller"] == "pd+hlip" and not summary["walk_check"]["fell"]
    assert out.exists()


@pytest.mark.xdist_group("narrow_gait")  # one worker computes the shared module fixture
@pytest.mark.slow
def test_the_narrow_footed_humanoid_is_certified_with_the_defaults(t1_narrow, narrow_gait):  # type: ignore[no-untyped-def]
    from robustgait import certify_gait

    cert = certify_gait(t1_narrow, narrow_gait, Config().certify)
    assert cert.status == "ok", cert.reason
    assert cert.controller == "pd+hlip" and cert.value > 0.5


@pytest.mark.slow
def test_a_line_footed_humanoid_walks_with_the_hlip_gain_its_sole_leaves_to_the_foot(tmp_path_factory):  # type: ignore[no-untyped-def]
    """Spheres 5 mm apart: nearly a line foot (sole width / leg 0.009): without foot placement it falls within the
    probe's 3 steps, so the regulator applies the H-LIP's whole gain, and the default gait walks 100 steps; with the
    share the 3 cm sole gets (0.22) it falls."""
    from robustgait import load_robot
    from robustgait.gaitgen import GaitGenerator
    from tests.conftest import T1_MODEL
    from tests.models import narrow_t1_xml

    if not T1_MODEL.is_file():
        pytest.skip("../shared/robots/booster_t1 (Booster T1) is not beside the repository")
    d = tmp_path_factory.mktemp("t1_line")
    assert main(["robot", "init", str(narrow_t1_xml(T1_MODEL, d, width=0.015)), "-o", str(d / "t1.toml")]) == 0
    robot = load_robot(d / "t1.toml")
    res = GaitGenerator(robot).solve(robot.default_params)
    assert res.gait is not None, res.reason
    w = walk(robot, res.gait, steps=100)
    assert w.controller == "pd+hlip" and w.regulator is not None and w.regulator["share"] > 0.95
    assert not w.fell and w.steps_taken == 100
    weak = walk(robot, res.gait, SimConfig(regulator=RegulatorConfig(mode="on", gain_scale=0.22)), steps=100)
    assert weak.fell
    # a point-foot walker: robot init measured it and ends the grid's step durations at λT = point_foot_step
    import tomllib

    from robustgait.config import ScaleRules

    text = (d / "t1.toml").read_text()
    assert "balances by foot placement" in text
    low, high, step = tomllib.loads(text)["action_space"]["step_duration"]
    lam = float(w.regulator["lambda"])
    assert low <= robot.default_params.step_duration <= high + 1e-9
    cap = max(ScaleRules().point_foot_step / lam, robot.default_params.step_duration)  # never below the default
    assert high <= cap + step / 2 + 1e-9  # the grid point nearest the cap


def test_the_step_start_blend_lengthens_with_the_share_of_the_gain(exo, exo_gait):  # type: ignore[no-untyped-def]
    """The regulator's τ_c follows its share κ (:func:`carry_phase`): a point-foot walker's larger landing corrections
    are blended out of the next stance leg more slowly."""
    reg = StepEngine(exo, exo_gait, ON).regulator
    assert reg is not None and reg.carry_tau == pytest.approx(carry_phase(ON.regulator, 0.25))
    reg.set_share(1.0)
    assert reg.carry_tau == pytest.approx(carry_phase(ON.regulator, 1.0)) and reg.carry_tau > carry_phase(
        ON.regulator, 0.25)


@pytest.mark.parametrize("name", ["exo", "atalante"])
def test_the_regulator_reads_the_sole_box_whichever_geom_axis_is_its_normal(name, request):  # type: ignore[no-untyped-def]
    """The sole's heading frame and the CoM over it are the foot frame's (x heel to toe, y left, z up) of its
    SoleBox: Atalante's sole boxes have their normal along the geom's x axis and the toe along −z, exo's are the foot
    frame. Its heading points forward (Atalante's zero posture turns the feet by 8°) and turns with the base's yaw;
    the gait's CoM stands above the sole, about a leg high."""
    robot = request.getfixturevalue(name)
    gait = request.getfixturevalue(f"{name}_gait")
    data = mujoco.MjData(robot.model)
    heading = []
    for yaw in (0.0, 0.7):
        data.qpos[:] = robot.model.qpos0
        data.qpos[3:7] = [np.cos(yaw / 2), 0.0, 0.0, np.sin(yaw / 2)]
        mujoco.mj_kinematics(robot.model, data)
        _, rot = sole_frame(data, robot.sole_boxes[gait.stance])
        assert rot @ rot.T == pytest.approx(np.eye(2))
        heading.append(np.arctan2(rot[0, 1], rot[0, 0]))  # rot = R_z(ψ)ᵀ
    assert abs(heading[0]) < 0.2 and heading[1] - heading[0] == pytest.approx(0.7)
    x, z0 = nominal_com(robot, gait, np.linspace(0.0, 1.0, 5))
    assert 0.5 * robot.leg_length < z0 < 1.2 * robot.leg_length
    assert np.all(np.abs(x[:, :, 0]) < 0.5 * robot.leg_length)  # the CoM's horizontal offset from the sole
