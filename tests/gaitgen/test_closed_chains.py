"""Closed chains in the gait problem (robustgait.closure, robustgait.dynamics, gaitgen; docs/gaitgen.md, "Closed
chains"), on the inline biped of tests/robots/test_loops.py: a knee driving a passive tarsus through a rod on a ball
joint, a shin spring, line feet. The planning model drops the rods for distance rows; its kinematics must be MuJoCo's,
and the initial guess built from any β must satisfy every equality row the loops add. Its feet are lines: the stance
foot stands on its line, free to roll (robustgait.gaitgen.linefoot), and the default gait solves with the loop rows
held at every node."""

from __future__ import annotations

from dataclasses import replace

import casadi as cs
import mujoco
import numpy as np
import pytest

from robustgait import GaitParams, load_robot
from robustgait.cli import main
from robustgait.config import GenerationConfig
from robustgait.dynamics import Dynamics, base_transform
from robustgait.gait import BEZIER_DEGREE
from robustgait.gaitgen.check import CheckModel, check_solution, node_residual, spring_problem
from robustgait.gaitgen.problem import ROW_SCALE, GaitProblem
from robustgait.gaitgen.solve import GaitGenerator, kinematic_states, pack, unpack
from robustgait.gaitgen.states import to_mujoco_state
from robustgait.robots import Robot
from robustgait.robots.loops import closed_chains, loop_residuals
from tests.inspection.biped import SERVO_RULE, write
from tests.robots.test_loops import chain_xml

TARSUS = '<joint name="{s}_tarsus" axis="0 1 0" range="-1.5 1.5"/>'


@pytest.fixture(scope="module")
def chain(tmp_path_factory: pytest.TempPathFactory) -> Robot:
    """The biped with a reference angle on each tarsus (as Cassie's knee and tarsus have: MuJoCo measures the angle
    from it, adam from 0), its spec written by robot init."""
    tmp = tmp_path_factory.mktemp("chain")
    xml = chain_xml()
    for s in ("left", "right"):
        xml = xml.replace(TARSUS.format(s=s), TARSUS.format(s=s).replace('range=', 'ref="0.3" range='))
    model, spec = write(tmp, xml, "chain.xml"), tmp / "chain.toml"
    assert main(["robot", "init", str(model), "-o", str(spec), *SERVO_RULE]) == 0
    return load_robot(spec)


@pytest.fixture(scope="module")
def dyn(chain: Robot) -> Dynamics:
    return Dynamics(chain)


def test_the_planning_model_drops_the_rods_and_keeps_the_mass(chain: Robot, dyn: Dynamics) -> None:
    assert [lp.kind for lp in dyn.loops] == ["distance", "distance", "spring", "spring"]
    assert set(dyn.passive) == {f"{s}_{j}" for s in ("left", "right") for j in ("shin_spring", "tarsus")}
    assert dyn.total_mass == pytest.approx(chain.mass, rel=1e-12)
    assert dyn.loops[0].length == pytest.approx(0.35, abs=1e-12)


def test_adam_kinematics_is_mujocos_with_reference_angles(chain: Robot, dyn: Dynamics) -> None:
    m = chain.model
    rng = np.random.default_rng(0)
    data = mujoco.MjData(m)
    for _ in range(5):
        q = m.qpos0.copy()
        q[:7] = [0.1, -0.2, 0.9, 0.95, 0.1, -0.2, 0.1]
        q[:7][3:] /= np.linalg.norm(q[3:7])
        q[dyn.qpos_idx] += rng.normal(0.0, 0.3, dyn.qpos_idx.size)
        data.qpos[:] = q
        mujoco.mj_kinematics(m, data)
        H, s = base_transform(q), dyn.joint_positions(q)
        for body in ("left_shin", "left_tarsus", "left_foot", "right_foot"):
            pose = np.asarray(dyn.frame_fun(body)(H, s))
            assert np.abs(pose[:3, 3] - data.xpos[m.body(body).id]).max() < 1e-12
            assert np.abs(pose[:3, :3] - data.xmat[m.body(body).id].reshape(3, 3)).max() < 1e-12


def test_the_loop_rows_vanish_where_mujocos_loops_close(chain: Robot, dyn: Dynamics) -> None:
    s0 = dyn.closed_posture
    zero = np.zeros(dyn.n_joints)
    assert np.abs(np.asarray(dyn.loop_fun(s0, zero, zero)[0])).max() < 1e-6  # close_loops stops at 1e-6 m
    # moved knees: the passive joints solved by the planning model close MuJoCo's own loops, rods solved too
    s = s0.copy()
    s[[chain.spec.joints.index(f"{x}_knee") for x in ("left", "right")]] += 0.2
    s = dyn.close_passive(s)
    assert np.abs(np.asarray(dyn.loop_fun(s, zero, zero)[0])).max() < 1e-12
    qpos, _ = to_mujoco_state(chain, np.eye(4), s, np.zeros(6), zero)
    loops, _ = closed_chains(chain.model)
    assert max(loop_residuals(chain.model, qpos, loops).values()) < 1e-8


def test_the_initial_guess_holds_the_loops_and_the_dynamics(chain: Robot, dyn: Dynamics) -> None:
    prob = GaitProblem(dyn, GenerationConfig(nodes=5))
    assert prob.n_passive == 4 and prob.n_loop == 4 and prob.line_feet
    posture = np.asarray(chain.spec.posture)
    beta = np.repeat(posture[:, None], BEZIER_DEGREE + 1, axis=1)
    beta[[chain.spec.joints.index(f"{x}_hip_pitch") for x in ("left", "right")], -1] += 0.1  # a moving β
    params = GaitParams(0.1, 0.6, chain.sole_spacing, 0.05)
    states = kinematic_states(dyn, prob, beta, params.step_duration, params=params)
    x0 = pack(prob, [beta], [states])
    p = [params.step_length, params.step_duration, params.step_width, params.step_height, 0.0]
    g = np.asarray(cs.Function("g", [prob.x, prob.p], [prob.g])(x0, p)).ravel()
    for name in ("loop_position", "loop_velocity", "loop_acceleration", "stance_position", "stance_orientation",
                 "stance_velocity", "stance_acceleration", "stance_roll", "roll_collocation", "roll_periodicity",
                 "impact_map", "impact_contact", "bezier"):
        assert np.abs(g[prob.rows[name]]).max() < 1e-8, name
    # the guess holds the stance foot flat, which takes a roll moment a line cannot: it shows in the dynamics' moment
    # and joint rows only, never in the base's forces (rows 0-2 of each node's 6 + n)
    forces = [r for start in prob.rows["dynamics"][::6 + dyn.n_joints] for r in range(start, start + 3)]
    assert np.abs(g[forces]).max() < 1e-8


def test_the_physics_check_holds_a_closed_chain_to_its_planning_model_with_the_loop_forces(chain: Robot,
                                                                                         dyn: Dynamics) -> None:
    # the initial guess's nodes violate the dynamics' moment rows (a flat stance foot on a line): the check's residual
    # in MuJoCo's compiled planning model, loop forces included, is the NLP's own row residual at every node
    prob = GaitProblem(dyn, GenerationConfig(nodes=5))
    posture = np.asarray(chain.spec.posture)
    beta = np.repeat(posture[:, None], BEZIER_DEGREE + 1, axis=1)
    beta[[chain.spec.joints.index(f"{x}_hip_pitch") for x in ("left", "right")], -1] += 0.1
    params = GaitParams(0.1, 0.6, chain.sole_spacing, 0.05)
    states = kinematic_states(dyn, prob, beta, params.step_duration, params=params)
    x0 = pack(prob, [beta], [states])
    p = [params.step_length, params.step_duration, params.step_width, params.step_height, 0.0]
    g = np.asarray(cs.Function("g", [prob.x, prob.p], [prob.g])(x0, p)).ravel()
    rows = np.asarray(prob.rows["dynamics"]).reshape(-1, 6 + dyn.n_joints)
    ev = CheckModel(dyn)
    contacts = prob.graph.domains[0].contacts
    for i, node_rows in enumerate(rows):
        r = node_residual(ev, contacts, prob.stance, states, i).r
        assert np.linalg.norm(r) == pytest.approx(ROW_SCALE * np.linalg.norm(g[node_rows]), rel=1e-8, abs=1e-8)
        assert np.linalg.norm(r[:3]) < 1e-8  # the base's forces hold (the flat foot's extra moment is a moment)
    # without the loops' forces the same nodes fail by the forces the loops carry
    dropped = replace(states, lamh=np.zeros_like(states.lamh))
    assert np.abs(states.lamh).max() > 1.0
    stance = prob.stance
    worst = max(float(np.linalg.norm(node_residual(ev, contacts, stance, dropped, i).r
                                     - node_residual(ev, contacts, stance, states, i).r)) for i in range(len(rows)))
    assert worst > 1.0


def test_a_spring_whose_deflection_leaves_its_range_is_one_line_naming_it_and_the_figures(chain: Robot,
                                                                                       dyn: Dynamics) -> None:
    # the biped's shin springs: 800 N m/rad, range ±0.3 rad. A solution's spring row force λ is the torque the spring
    # must hold, so it deflects by −λ / k: 160 N m is 0.2 rad (in range), 320 N m is 0.4 rad (out)
    prob = GaitProblem(dyn, GenerationConfig(nodes=5))
    posture = np.asarray(chain.spec.posture)
    beta = np.repeat(posture[:, None], BEZIER_DEGREE + 1, axis=1)
    params = GaitParams(0.1, 0.6, chain.sole_spacing, 0.05)
    states = kinematic_states(dyn, prob, beta, params.step_duration, params=params)
    col = [lp.joint for lp in dyn.loops].index("right_shin_spring")
    for torque, out in ((160.0, False), (-320.0, True)):
        lamh = states.lamh.copy()
        lamh[:, col] = 0.0
        lamh[2, col] = torque
        line = spring_problem(dyn, [replace(states, lamh=lamh)])
        assert (line is not None) == out
    assert line is not None and "\n" not in line
    assert "'right_shin_spring'" in line and "0.4 rad" in line and "[-0.3, 0.3]" in line


@pytest.mark.slow  # one IPOPT solve, about 15 s
def test_the_default_gait_solves_with_the_loops_closed(chain: Robot) -> None:
    gen = GaitGenerator(chain)
    prob, params = gen.problem, chain.default_params.resolved("flat")
    x0 = gen.initial_guess(params)
    p = [params.step_length, params.step_duration, params.step_width, params.step_height, params.rolling_fraction]
    sol = gen.solver(x0=x0, p=p, lbx=prob.lbx, ubx=prob.ubx, lbg=prob.lbg, ubg=prob.ubg)
    assert gen.solver.stats()["success"]
    x = np.asarray(sol["x"]).ravel()
    g = np.asarray(cs.Function("g", [prob.x, prob.p], [prob.g])(x, p)).ravel()
    assert np.maximum(prob.lbg - g, g - prob.ubg).max() < 1e-8
    # the loops closed at every node: the NLP's rows, and MuJoCo's own connects on the solution's states
    for name in ("loop_position", "loop_velocity", "loop_acceleration"):
        assert np.abs(g[prob.rows[name]]).max() < 1e-8, name
    _, states = unpack(prob, x, [params.step_duration])
    loops, _ = closed_chains(chain.model)
    for H, s, vb, sd in zip(states[0].H, states[0].s, states[0].vb, states[0].sd, strict=True):
        qpos, _ = to_mujoco_state(chain, H, s, vb, sd)
        assert max(loop_residuals(chain.model, qpos, loops).values()) < 1e-8
    # the stance foot rolls on its line (the degree of freedom a flat sole would lock), periodic after relabeling
    roll = np.array([x[node["roll"]] for node in prob.layout.nodes])
    assert np.abs(roll[:, 0]).max() > 0.01
    # the physics check passes it: MuJoCo's planning model with the loops' forces, periodic with the passive joints
    # mirrored (gait generate refused it before the loops' forces were in the check)
    check = check_solution(gen.dyn, prob, params, states, [params.step_duration])
    assert check.passed, check.failures
    assert check.dynamics_residual < 1e-8 and check.periodicity < 1e-6


def test_compliant_springs_lose_their_rows_and_carry_the_models_torque(chain: Robot) -> None:
    """``generate.springs = "compliant"``: the springs' rigid rows go, the loops solve the other passive joints, and
    the springs' torque is MuJoCo's own (qfrc_spring + qfrc_damper) at any state."""
    dyn = Dynamics(chain, "compliant")
    assert [lp.kind for lp in dyn.loops] == ["distance", "distance"]
    names = [*chain.spec.joints, *dyn.passive]
    assert sorted(names[sp.index] for sp in dyn.springs) == ["left_shin_spring", "right_shin_spring"]
    assert sorted(names[j] for j in dyn.solved) == ["left_tarsus", "right_tarsus"]
    assert all(sp.stiffness == 800.0 and sp.ref == 0.0 for sp in dyn.springs)
    m, d = chain.model, mujoco.MjData(chain.model)
    rng = np.random.default_rng(3)
    s, sd = dyn.closed_posture + 0.05 * rng.standard_normal(dyn.n_joints), rng.standard_normal(dyn.n_joints)
    d.qpos[dyn.qpos_idx], d.qvel[dyn.dof_idx] = s, sd
    mujoco.mj_forward(m, d)
    want = (d.qfrc_spring + d.qfrc_damper)[dyn.dof_idx]
    got = dyn.spring_torque(s, sd)
    springs = [sp.index for sp in dyn.springs]
    assert np.abs(got[springs]).min() > 1.0 and got == pytest.approx(np.where(np.isin(np.arange(dyn.n_joints),
                                                                                        springs), want, 0.0))
    # the closed posture's springs at their springref; closing the loops moves the tarsus only
    q = dyn.close_passive(s)
    assert q[springs] == pytest.approx(s[springs]) and np.abs(np.asarray(dyn.loop_fun(q, q, q)[0])).max() < 1e-10
    prob = GaitProblem(dyn, GenerationConfig(springs="compliant"))
    assert prob.n_loop == 2 and {"spring_collocation", "spring_position_periodicity",
                                 "spring_velocity_periodicity"} <= set(prob.rows)
    assert sorted((names[j], names[k], sign) for j, k, sign in prob.spring_mirror) == [
        ("left_shin_spring", "right_shin_spring", 1.0), ("right_shin_spring", "left_shin_spring", 1.0)]


@pytest.mark.slow  # robot init and one IPOPT solve, about two minutes
def test_the_compliant_default_gait_passes_the_physics_check_with_its_springs_moving(
        tmp_path_factory: pytest.TempPathFactory) -> None:
    """The springs as free coordinates of the gait problem (FROST's compliant Cassie): the solution passes the physics
    check, whose dynamics carry MuJoCo's own spring torque, and its springs deflect over the step, periodic after
    relabeling. On the biped as tests/robots/test_loops.py writes it (no reference angles): IPOPT needs about 270
    iterations there (the fixture's biped, tarsi at a reference angle, did not converge in 300), hence the limit."""
    tmp = tmp_path_factory.mktemp("chain_compliant")
    spec = tmp / "chain.toml"
    assert main(["robot", "init", str(write(tmp, chain_xml(), "chain.xml")), "-o", str(spec), *SERVO_RULE]) == 0
    chain = load_robot(spec)
    gen = GaitGenerator(chain, GenerationConfig(springs="compliant", max_iter=600))
    res = gen.solve(chain.default_params)
    assert res.success and res.check is not None and res.nodes is not None, res.reason
    assert res.check.passed and res.check.dynamics_residual < 1e-6 and res.check.periodicity < 1e-6
    ns, prob = res.nodes[0], gen.problem
    springs = [sp.index for sp in gen.dyn.springs]
    assert np.ptp(ns.s[:, springs], axis=0).min() > 0.005  # each spring moves [rad]
    for j, k, sign in prob.spring_mirror:
        assert ns.s[0, j] == pytest.approx(sign * ns.s[-1, k], abs=1e-8)
    # the planned dynamics hold with MuJoCo's spring torque, which is not small: without it they would not
    ev = CheckModel(gen.dyn)
    res_node = node_residual(ev, prob.graph.domains[0].contacts, prob.stance, ns, 8)
    spring_force = (ev.d.qfrc_spring + ev.d.qfrc_damper)[ev.vadr[springs]]
    assert np.linalg.norm(res_node.r) < 1e-6 * res_node.scale
    assert np.abs(spring_force).max() > 1e-3 * res_node.scale
