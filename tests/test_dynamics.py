"""The symbolic model (adam + CasADi) against MuJoCo, on the shipped exo and the Atalante example.

Tolerances: both sides compute the same rigid-body quantities in double precision by different
algorithms (adam: CRBA/RNEA in a mixed frame; MuJoCo: composite rigid bodies / RNE in its own frames),
so they agree to round-off (measured ~1e-15 relative). 1e-8 relative leaves room for the conversion
and for ill-conditioned random poses while catching any modelling error (a wrong offset, inertia or
gravity of 9.80665 instead of 9.81 shows up at 1e-4 or more).
"""

from __future__ import annotations

from pathlib import Path

import casadi as cs
import mujoco
import numpy as np
import pytest

from robustgait.dynamics import FOOT_FRAME_KINDS, Dynamics, base_transform, foot_frame, quat_to_rotation
from robustgait.io.robotfile import load_robot
from robustgait.robots import Robot

REPO = Path(__file__).resolve().parents[1]
ATALANTE_SPEC = REPO / "robots" / "atalante" / "spec.toml"
ATALANTE_MJCF = REPO.parent / "shared" / "atalante" / "loadedExo.xml"
EXO_DIR = REPO / "src" / "robustgait" / "robots" / "exo"
SIDES = ("left", "right")
N_STATES = 8
REL_TOL = 1e-8

ROBOTS = [
    pytest.param("exo", id="exo"),
    pytest.param(str(ATALANTE_SPEC), id="atalante", marks=pytest.mark.skipif(
        not ATALANTE_MJCF.is_file(), reason=f"Atalante model not found at {ATALANTE_MJCF}")),
]
_CACHE: dict[str, Dynamics] = {}


@pytest.fixture(params=ROBOTS)
def dyn(request: pytest.FixtureRequest) -> Dynamics:
    name = request.param
    if name not in _CACHE:
        _CACHE[name] = Dynamics(load_robot(name))
    return _CACHE[name]


def random_states(robot: Robot, n: int = N_STATES, seed: int = 0) -> list[tuple[np.ndarray, np.ndarray]]:
    """Random base pose (uniform unit quaternion), joints within limits, velocities ~ N(0, 1)."""
    rng = np.random.default_rng(seed)
    m = robot.model
    states = []
    for _ in range(n):
        qpos = m.qpos0.copy()
        qpos[:3] = rng.uniform(-2.0, 2.0, 3)
        quat = rng.normal(size=4)
        qpos[3:7] = quat / np.linalg.norm(quat)
        qpos[robot.qpos_idx] = rng.uniform(*robot.joint_range.T)
        states.append((qpos, rng.normal(size=m.nv)))
    return states


def mujoco_at(robot: Robot, qpos: np.ndarray, qvel: np.ndarray) -> mujoco.MjData:
    d = mujoco.MjData(robot.model)
    d.qpos[:] = qpos
    d.qvel[:] = qvel
    mujoco.mj_forward(robot.model, d)
    return d


def rel_err(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.linalg.norm(a - b) / np.linalg.norm(b))


def test_total_mass(dyn: Dynamics) -> None:
    assert dyn.total_mass == pytest.approx(dyn.robot.mass, rel=1e-9)


def test_mass_matrix_matches_mujoco(dyn: Dynamics) -> None:
    m = dyn.robot.model
    for qpos, qvel in random_states(dyn.robot):
        d = mujoco_at(dyn.robot, qpos, qvel)
        M = np.zeros((m.nv, m.nv))
        mujoco.mj_fullM(m, d, M)
        assert rel_err(dyn.mass_matrix(qpos), M) < REL_TOL


def test_bias_forces_match_mujoco(dyn: Dynamics) -> None:
    for qpos, qvel in random_states(dyn.robot, seed=1):
        d = mujoco_at(dyn.robot, qpos, qvel)
        assert rel_err(dyn.bias_forces(qpos, qvel), d.qfrc_bias) < REL_TOL
        # at rest the bias is gravity only: checks g = 9.81 (not adam's default 9.80665)
        d0 = mujoco_at(dyn.robot, qpos, np.zeros_like(qvel))
        h0 = dyn.bias_forces(qpos, np.zeros_like(qvel))
        assert rel_err(h0, d0.qfrc_bias) < REL_TOL
        assert h0[2] == pytest.approx(9.81 * dyn.robot.mass, rel=1e-12)


def test_velocity_conversion(dyn: Dynamics) -> None:
    m = dyn.robot.model
    for qpos, qvel in random_states(dyn.robot, seed=2):
        d = mujoco_at(dyn.robot, qpos, qvel)
        nu = dyn.to_mixed(qpos, qvel)
        vel = np.zeros(6)  # [angular, linear] of the base, world orientation, at the base origin
        mujoco.mj_objectVelocity(m, d, mujoco.mjtObj.mjOBJ_XBODY, dyn.robot.base_body_id, vel, 0)
        np.testing.assert_allclose(nu[:3], vel[3:], atol=1e-12)
        np.testing.assert_allclose(nu[3:6], vel[:3], atol=1e-12)
        np.testing.assert_array_equal(nu[6:], qvel[dyn.robot.dof_idx])
        np.testing.assert_allclose(dyn.to_mujoco(qpos, nu), qvel, atol=1e-12)
        np.testing.assert_allclose(base_transform(qpos)[:3, :3], d.xmat[dyn.robot.base_body_id].reshape(3, 3),
                                   atol=1e-14)


def test_base_transform_numeric_and_symbolic() -> None:
    np.testing.assert_allclose(quat_to_rotation([2.0, 0.0, 0.0, 0.0]), np.eye(3))
    c, s = np.cos(0.3), np.sin(0.3)
    np.testing.assert_allclose(quat_to_rotation([c, 0.0, 0.0, s]), [[c * c - s * s, -2 * c * s, 0.0],
                                                                     [2 * c * s, c * c - s * s, 0.0],
                                                                     [0.0, 0.0, 1.0]], atol=1e-15)
    # the symbolic form (CasADi) evaluates to the numeric one, normalization included
    q = cs.SX.sym("q", 19)
    H_fun = cs.Function("H", [q], [base_transform(q)])
    qpos = np.concatenate([[0.3, -0.2, 0.9], [0.5, -1.0, 0.25, 2.0], np.zeros(12)])
    np.testing.assert_allclose(np.asarray(H_fun(qpos)), base_transform(qpos), atol=1e-15)
    np.testing.assert_allclose(base_transform(qpos)[3], [0.0, 0.0, 0.0, 1.0])


def test_exo_frames_match_mujoco_frame_bodies() -> None:
    dyn = _CACHE.setdefault("exo", Dynamics(load_robot("exo")))
    m = dyn.robot.model
    assert set(dyn.frames) == {foot_frame(s, k) for s in SIDES for k in FOOT_FRAME_KINDS}
    for qpos, qvel in random_states(dyn.robot, seed=3):
        d = mujoco_at(dyn.robot, qpos, qvel)
        for name, (pos, rot) in dyn.foot_frames(qpos).items():
            b = m.body(name).id
            np.testing.assert_allclose(pos, d.xpos[b], rtol=0, atol=1e-9)
            np.testing.assert_allclose(rot, d.xmat[b].reshape(3, 3), rtol=0, atol=1e-9)


@pytest.mark.slow  # seconds of its own: plain pytest stays ≤ 60 s; CI runs it
@pytest.mark.skipif(not ATALANTE_MJCF.is_file(), reason=f"Atalante model not found at {ATALANTE_MJCF}")
def test_atalante_foot_frames_sit_on_the_sole_box() -> None:
    """Atalante has no frame bodies: they are added from the sole box (bottom face, toe/heel edges), placed as
    exact mirror images of each other — Atalante's two sole boxes both sit 33 µm to the right of their feet,
    so each frame is within that of its box and the pair is symmetric to 1e-12."""
    dyn = _CACHE.setdefault(str(ATALANTE_SPEC), Dynamics(load_robot(ATALANTE_SPEC)))
    robot = dyn.robot
    m = robot.model
    signs = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)], dtype=float)
    d0 = mujoco_at(robot, m.qpos0, np.zeros(m.nv))
    for qpos, qvel in random_states(robot, seed=4):
        d = mujoco_at(robot, qpos, qvel)
        for side in SIDES:
            g = robot.sole_geom_id[side]
            local = signs * m.geom_size[g]  # the 8 corners in the geom frame
            # bottom face and toe edge picked in the zero posture (feet flat, facing +x)
            corners0 = d0.geom_xpos[g] + local @ d0.geom_xmat[g].reshape(3, 3).T
            bottom = np.argsort(corners0[:, 2])[:4]
            toe = bottom[np.argsort(corners0[bottom, 0])[2:]]
            heel = bottom[np.argsort(corners0[bottom, 0])[:2]]
            corners = d.geom_xpos[g] + local @ d.geom_xmat[g].reshape(3, 3).T
            for kind, idx in (("sole", bottom), ("toe", toe), ("heel", heel)):
                pos, rot = dyn.frame_pose(foot_frame(side, kind), qpos)
                np.testing.assert_allclose(pos, corners[idx].mean(axis=0), rtol=0, atol=3.4e-5)
                np.testing.assert_allclose(rot.T @ rot, np.eye(3), atol=1e-12)
            pos_toe, rot = dyn.frame_pose(foot_frame(side, "toe"), qpos)
            pos_heel, _ = dyn.frame_pose(foot_frame(side, "heel"), qpos)
            x_axis = (pos_toe - pos_heel) / np.linalg.norm(pos_toe - pos_heel)
            np.testing.assert_allclose(rot[:, 0], x_axis, atol=1e-9)
    for kind in ("sole", "toe", "heel"):
        left, _ = dyn.frame_pose(foot_frame("left", kind), m.qpos0)
        right, _ = dyn.frame_pose(foot_frame("right", kind), m.qpos0)
        np.testing.assert_allclose(left - m.qpos0[:3], (right - m.qpos0[:3]) * [1, -1, 1], atol=1e-12)


def _write_exo_variant(tmp_path: Path, edit: dict[str, str]) -> Path:
    xml = (EXO_DIR / "exo.xml").read_text()
    for old, new in edit.items():
        assert old in xml
        xml = xml.replace(old, new)
    (tmp_path / "exo.xml").write_text(xml)
    (tmp_path / "spec.toml").write_text((EXO_DIR / "spec.toml").read_text())
    return tmp_path / "spec.toml"


def test_joint_offsets_and_static_bodies_are_handled(tmp_path: Path) -> None:
    """Joints with ``pos`` != 0 (adam mishandles them) and a massive static body beside the robot."""
    spec = _write_exo_variant(tmp_path, {
        '<joint name="left_hip_roll"': '<joint name="left_hip_roll" pos="0.05 0 0.02"',
        '<joint name="left_knee"': '<joint name="left_knee" pos="0.02 -0.01 0.03"',
        '<joint name="right_ankle_roll"': '<joint name="right_ankle_roll" pos="0 0.01 -0.02"',
        "<!-- pelvis:": '<body name="crate" pos="2 0 0.2"><inertial pos="0 0 0" mass="10" diaginertia="1 1 1"/>'
                        '<geom type="box" size="0.2 0.2 0.2"/></body>\n<!-- pelvis:',
    })
    dyn = Dynamics(load_robot(spec))
    m = dyn.robot.model
    assert dyn.total_mass == pytest.approx(dyn.robot.mass, rel=1e-9)
    for qpos, qvel in random_states(dyn.robot, n=4, seed=5):
        d = mujoco_at(dyn.robot, qpos, qvel)
        M = np.zeros((m.nv, m.nv))
        mujoco.mj_fullM(m, d, M)
        assert rel_err(dyn.mass_matrix(qpos), M) < REL_TOL
        assert rel_err(dyn.bias_forces(qpos, qvel), d.qfrc_bias) < REL_TOL
        for name, (pos, _) in dyn.foot_frames(qpos).items():
            np.testing.assert_allclose(pos, d.xpos[m.body(name).id], rtol=0, atol=1e-9)


def test_missing_frame_bodies_are_added_from_the_sole(tmp_path: Path) -> None:
    edit = {f'<body name="{side}_{kind}_frame"': f'<site name="{side}_{kind}_site"'
            for side in SIDES for kind in FOOT_FRAME_KINDS}
    dyn = Dynamics(load_robot(_write_exo_variant(tmp_path, edit)))
    ref = _CACHE.setdefault("exo", Dynamics(load_robot("exo")))
    for qpos, _ in random_states(dyn.robot, n=3, seed=6):
        for name, (pos, rot) in dyn.foot_frames(qpos).items():
            pos_ref, rot_ref = ref.frame_pose(name, qpos)
            np.testing.assert_allclose(pos, pos_ref, rtol=0, atol=1e-12)
            np.testing.assert_allclose(rot, rot_ref, rtol=0, atol=1e-12)


def test_armature_is_added_to_the_mass_matrix(tmp_path: Path) -> None:
    spec = _write_exo_variant(tmp_path, {'armature="0"': 'armature="0.3"'})
    dyn = Dynamics(load_robot(spec))
    m = dyn.robot.model
    assert np.all(m.dof_armature[6:] == 0.3)
    qpos, qvel = random_states(dyn.robot, n=1, seed=7)[0]
    d = mujoco_at(dyn.robot, qpos, qvel)
    M = np.zeros((m.nv, m.nv))
    mujoco.mj_fullM(m, d, M)
    assert rel_err(dyn.mass_matrix(qpos), M) < REL_TOL


def test_frame_jacobians_match_mujoco(dyn: Dynamics) -> None:
    """adam's sole-frame Jacobian in MuJoCo coordinates equals mj_jac at the frame's point."""
    robot = dyn.robot
    m = robot.model
    for qpos, qvel in random_states(robot, seed=7):
        d = mujoco_at(robot, qpos, qvel)
        for side in SIDES:
            frame = foot_frame(side, "sole")
            pos, _ = dyn.frame_pose(frame, qpos)
            jp, jr = np.zeros((3, m.nv)), np.zeros((3, m.nv))
            mujoco.mj_jac(m, d, jp, jr, pos, int(m.geom_bodyid[robot.sole_geom_id[side]]))
            assert rel_err(dyn.frame_jacobian(frame, qpos), np.vstack([jp, jr])) < 1e-10


def test_jacobian_dot_qvel_matches_finite_differences(dyn: Dynamics) -> None:
    """J̇ q̇ = d/dt (J(q) q̇) at constant q̇, by central differences along MuJoCo's own position integration."""
    robot = dyn.robot
    m = robot.model
    h = 1e-6
    for qpos, qvel in random_states(robot, n=3, seed=8):
        frame = foot_frame("left", "toe")
        ahead, behind = qpos.copy(), qpos.copy()
        mujoco.mj_integratePos(m, ahead, qvel, h)
        mujoco.mj_integratePos(m, behind, qvel, -h)
        fd = (dyn.frame_jacobian(frame, ahead) @ qvel - dyn.frame_jacobian(frame, behind) @ qvel) / (2 * h)
        exact = dyn.frame_jacobian_dot_qvel(frame, qpos, qvel)
        assert np.linalg.norm(exact - fd) <= 1e-6 * max(np.linalg.norm(exact), 1.0)


def test_impact_map_is_plastic(dyn: Dynamics) -> None:
    """After the impact the sole is still (J q̇⁺ = 0), the momentum jump is a sole wrench (M Δq̇ = Jᵀ Λ) and
    the kinetic energy does not increase."""
    robot = dyn.robot
    for qpos, qvel in random_states(robot, n=3, seed=9):
        plus, impulse = dyn.impact_map(qpos, qvel, "right")
        J = dyn.frame_jacobian(foot_frame("right", "sole"), qpos)
        M = dyn.mass_matrix(qpos)
        assert np.linalg.norm(J @ plus) < 1e-10 * max(np.linalg.norm(J @ qvel), 1.0)
        assert rel_err(M @ (plus - qvel), J.T @ impulse) < 1e-10
        assert plus @ M @ plus <= qvel @ M @ qvel + 1e-9
