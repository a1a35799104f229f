"""Mirroring a closed chain's passive joints (robustgait.robots.passivemirror, Robot.mirror_state) on the inline biped
of tests/robots/test_loops.py: a rod on a ball joint, a shin spring and a passive tarsus per leg. A mirrored state must
close the loops where the state closed them, mirroring twice must give the state back, and a symmetric state is its
own mirror image, rods and springs included."""

from __future__ import annotations

from pathlib import Path

import mujoco
import numpy as np
import pytest

from robustgait import load_robot
from robustgait.cli import main
from robustgait.errors import RobustGaitError
from robustgait.robots import Robot
from robustgait.robots.loops import close_loops, closed_chains, complete_rods, loop_residuals, loop_rows
from robustgait.robots.passivemirror import passive_mirror
from tests.inspection.biped import SERVO_RULE, write
from tests.robots.test_loops import chain_xml


@pytest.fixture(scope="module")
def chain(tmp_path_factory: pytest.TempPathFactory) -> Robot:
    tmp = tmp_path_factory.mktemp("mirror")
    model, spec = write(tmp, chain_xml(), "chain.xml"), tmp / "chain.toml"
    assert main(["robot", "init", str(model), "-o", str(spec), *SERVO_RULE]) == 0
    return load_robot(spec)


def _closed(robot: Robot, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """A random state of the robot whose loops close (springs deflected, rods solved), its velocities on the loops."""
    m = robot.model
    loops, passive = closed_chains(m)
    q = m.qpos0.copy()
    q[:3] += rng.normal(0.0, 0.1, 3)
    q[robot.qpos_idx] += rng.normal(0.0, 0.1, robot.n_joints)
    springs = [j for j in passive if m.jnt_stiffness[j] > 0]
    q[m.jnt_qposadr[springs]] = rng.normal(0.0, 0.05, len(springs))
    q = close_loops(m, q, loops, tuple(j for j in passive if j not in springs), 1e-10)
    v = rng.normal(0.0, 0.5, m.nv)
    data = mujoco.MjData(m)
    data.qpos[:] = q
    _, jac = loop_rows(m, data, loops)
    v -= np.linalg.pinv(jac) @ (jac @ v)  # onto the loops' velocities
    return q, v


def test_a_mirrored_state_closes_the_loops_and_mirroring_twice_gives_it_back(chain: Robot) -> None:
    m = chain.model
    loops, _ = closed_chains(m)
    data = mujoco.MjData(m)
    rng = np.random.default_rng(3)
    for _ in range(4):
        q, v = _closed(chain, rng)
        mq, mv = chain.mirror_state(q, v)
        assert max(loop_residuals(m, mq, loops).values()) < 1e-9
        data.qpos[:] = mq
        _, jac = loop_rows(m, data, loops)
        assert np.abs(jac @ mv).max() < 1e-9
        # the left spring's deflection is the right one's, mirrored (not left where it was)
        left, right = (m.jnt_qposadr[m.joint(f"{s}_shin_spring").id] for s in ("left", "right"))
        assert mq[right] == pytest.approx(q[left], abs=1e-12) and mq[left] == pytest.approx(q[right], abs=1e-12)
        qq, vv = chain.mirror_state(mq, mv)
        assert np.abs(qq - q).max() < 1e-12 and np.abs(vv - v).max() < 1e-12
    # batched as the certificate mirrors: rows alike
    qs, vs = np.stack([q, mq]), np.stack([v, mv])
    bq, bv = chain.mirror_state(qs, vs)
    assert np.abs(bq[0] - mq).max() < 1e-15 and np.abs(bv[1] - v).max() < 1e-12


def test_a_symmetric_state_is_its_own_mirror_image(chain: Robot) -> None:
    m = chain.model
    loops, passive = closed_chains(m)
    q = m.qpos0.copy()
    q[[m.jnt_qposadr[m.joint(f"{s}_knee").id] for s in ("left", "right")]] = 0.4
    q = close_loops(m, q, loops, tuple(j for j in passive if m.jnt_stiffness[j] == 0), 1e-10)
    q, v = complete_rods(m, q, np.zeros(m.nv))  # the rods solved on each side alike
    mq, _ = chain.mirror_state(q, v)
    assert np.abs(mq - q).max() < 1e-9


def test_a_passive_joint_without_a_partner_is_one_line_naming_it(tmp_path: Path) -> None:
    # the right rod's ball moved 1 cm forward: the left rod's has no passive joint at its mirror image
    xml = chain_xml()
    right = xml.index('name="right_rod"')
    xml = xml[:right] + xml[right:].replace('pos="-0.06 0 -0.05"', 'pos="-0.05 0 -0.05"', 1)
    m = mujoco.MjModel.from_xml_string(xml)
    _, passive = closed_chains(m)
    with pytest.raises(RobustGaitError, match="passive joint 'left_rod_ball': 0 passive joints"):
        passive_mirror(m, passive, m.body("pelvis").id, (1, -1, 1, -1, 1, -1), "chain.xml")
