"""Closed chains in the gait problem (robustgait.closure, robustgait.dynamics, gaitgen; docs/gaitgen.md, "Closed
chains"), on the inline biped of tests/robots/test_loops.py: a knee driving a passive tarsus through a rod on a ball
joint, a shin spring, line feet. The planning model drops the rods for distance rows; its kinematics must be MuJoCo's,
and the initial guess built from any β must satisfy every equality row the loops add."""

from __future__ import annotations

import casadi as cs
import mujoco
import numpy as np
import pytest

from robustgait import GaitParams, load_robot
from robustgait.cli import main
from robustgait.config import GenerationConfig
from robustgait.dynamics import Dynamics, base_transform
from robustgait.gait import BEZIER_DEGREE
from robustgait.gaitgen.problem import GaitProblem
from robustgait.gaitgen.solve import kinematic_states, pack
from robustgait.gaitgen.states import to_mujoco_state
from robustgait.robots import Robot
from robustgait.robots.loops import closed_chains, loop_residuals
from tests.inspection.test_inspection import SERVO_RULE, write
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
    assert prob.n_passive == 4 and prob.n_loop == 4
    posture = np.asarray(chain.spec.posture)
    beta = np.repeat(posture[:, None], BEZIER_DEGREE + 1, axis=1)
    beta[[chain.spec.joints.index(f"{x}_hip_pitch") for x in ("left", "right")], -1] += 0.1  # a moving β
    params = GaitParams(0.1, 0.6, chain.sole_spacing, 0.05)
    states = kinematic_states(dyn, prob, beta, params.step_duration, params=params)
    x0 = pack(prob, [beta], [states])
    p = [params.step_length, params.step_duration, params.step_width, params.step_height, 0.0]
    g = np.asarray(cs.Function("g", [prob.x, prob.p], [prob.g])(x0, p)).ravel()
    for name in ("loop_position", "loop_velocity", "loop_acceleration", "dynamics", "stance_position",
                 "stance_velocity", "stance_acceleration", "impact_map", "impact_contact", "bezier"):
        assert np.abs(g[prob.rows[name]]).max() < 1e-8, name
