"""Comfort figures of a walk (sim/comfort.py, docs/comfort.md): each formula against a known answer, the recording
against MuJoCo itself, and the figures of the real exo gait against what they must satisfy."""

from __future__ import annotations

import json
import math

import mujoco
import numpy as np
import pytest

from robustgait import RobustGaitError, SimConfig, StepEngine, walk
from robustgait.config import ComfortConfig
from robustgait.rotations import quat_to_mat, roll_pitch_yaw
from robustgait.sim.comfort import (
    FIGURES,
    Comfort,
    actuator_torque,
    cost_of_transport,
    excursion,
    jerk,
    lowpass,
    peak,
    pelvis_acceleration,
    rms,
    sole_contact_geoms,
    sole_normal_force,
)

DT = 1e-3


def test_constant_velocity_has_zero_acceleration_and_jerk():
    n = 3000
    v = np.tile([0.3, -0.1, 0.02], (n + 1, 1))
    yaw = np.linspace(-1.0, 2.0, n)  # whatever the heading
    a = pelvis_acceleration(v, yaw, DT, 20.0, 4)
    assert a.shape == (n, 3) and np.all(a == 0.0)
    assert np.all(jerk(a, DT) == 0.0)


def test_constant_acceleration_in_the_heading_frame():
    """A world-frame acceleration a along x, seen from a base yawed by ψ: (a cos ψ, −a sin ψ, 0), no jerk."""
    n, acc, psi = 2000, 1.5, 0.4
    t = np.arange(n + 1) * DT
    v = np.stack([acc * t, np.zeros_like(t), np.zeros_like(t)], -1)
    a = pelvis_acceleration(v, np.full(n, psi), DT, 20.0, 4)
    np.testing.assert_allclose(a, np.tile([acc * math.cos(psi), -acc * math.sin(psi), 0.0], (n, 1)), atol=1e-9)
    np.testing.assert_allclose(jerk(a, DT), 0.0, atol=1e-6)


def test_a_sinusoid_gives_its_rms_and_peak():
    """v_z = A sin ωt at 1 Hz over whole periods: a = Aω cos ωt (RMS Aω/√2, peak Aω), jerk −Aω² sin ωt; the 20 Hz
    low-pass leaves 1 Hz alone."""
    amp, f, n = 0.05, 1.0, 10_000
    w = 2 * math.pi * f
    t = np.arange(n + 1) * DT
    v = np.stack([np.zeros_like(t), np.zeros_like(t), amp * np.sin(w * t)], -1)
    a = pelvis_acceleration(v, np.zeros(n), DT, 20.0, 4)
    inner = slice(1000, -1000)  # the filter's padded ends (a walk's figures keep a step on either side) aside
    assert rms(a[inner])[2] == pytest.approx(amp * w / math.sqrt(2), rel=1e-4)
    assert peak(a[inner])[2] == pytest.approx(amp * w, rel=1e-4)
    assert rms(a)[2] == pytest.approx(amp * w / math.sqrt(2), rel=1e-3)
    assert peak(a)[2] == pytest.approx(amp * w, rel=1e-3)
    j = jerk(a, DT)
    assert rms(j[inner])[2] == pytest.approx(amp * w * w / math.sqrt(2), rel=1e-4)
    assert peak(j[inner])[2] == pytest.approx(amp * w * w, rel=1e-4)
    np.testing.assert_allclose(rms(a)[:2], 0.0)


def test_lowpass_removes_what_is_above_the_cutoff_and_refuses_a_cutoff_beyond_nyquist():
    t = np.arange(4000) * DT
    slow, fast = np.sin(2 * math.pi * 2 * t), 0.5 * np.sin(2 * math.pi * 200 * t)
    out = lowpass(slow + fast, DT, 20.0, 4)
    assert np.abs(out - slow)[200:-200].max() < 1e-3  # 200 Hz is 10× the cutoff: −160 dB after both passes
    ramp = np.stack([t, 3 - 2 * t], -1)
    np.testing.assert_allclose(lowpass(ramp[:50], DT, 20.0, 4), ramp[:50], atol=1e-12)  # lines pass, even short
    gain = rms(lowpass(np.sin(2 * math.pi * 20 * t), DT, 20.0, 4)[1000:-1000]) / rms(slow[1000:-1000])
    assert gain == pytest.approx(0.5, rel=1e-3)  # −6 dB at the cutoff, as forward-backward Butterworth
    with pytest.raises(RobustGaitError, match=r"comfort\.cutoff: 600 Hz is not below the Nyquist frequency 500 Hz"):
        lowpass(slow, DT, 600.0, 4)


def test_lowpass_is_scipys_forward_backward_butterworth():
    """Away from the ends, the FFT filter equals scipy.signal.sosfiltfilt of the order-4 Butterworth to 1e-4 of the
    signal's size (the bilinear transform's warping is the difference)."""
    signal = pytest.importorskip("scipy.signal")
    rng = np.random.default_rng(0)
    x = np.cumsum(rng.normal(size=(8000, 3)), axis=0) * 0.01 + np.sin(2 * math.pi * 3 * np.arange(8000) * DT)[:, None]
    ours = lowpass(x, DT, 20.0, 4)
    ref = signal.sosfiltfilt(signal.butter(4, 20.0, fs=1 / DT, output="sos"), x, axis=0)
    assert np.abs(ours - ref)[500:-500].max() < 1e-4 * np.abs(ref).max()


def test_rms_and_peak():
    x = np.array([[3.0, -1.0], [-4.0, 1.0]])
    np.testing.assert_allclose(rms(x), [math.sqrt(12.5), 1.0])
    np.testing.assert_allclose(peak(x), [4.0, 1.0])


def test_a_known_power_gives_its_cost_of_transport():
    """10 N m at 2 rad/s on one joint for 1 s (20 J), the other joint absorbing 5 W (counted as |τ q̇|), 10 kg
    carried 2 m: CoT = (20 + 5) J / (10 kg · 9.81 m/s² · 2 m)."""
    n = 1000
    torque = np.tile([10.0, -5.0], (n, 1))
    speed = np.tile([2.0, 1.0], (n, 1))
    assert cost_of_transport(torque, speed, DT, 10.0, 9.81, 2.0) == pytest.approx(25.0 / (10 * 9.81 * 2))
    assert cost_of_transport(torque, speed, DT, 10.0, 9.81, 0.0) is None  # no forward progress: undefined


def test_excursion_is_the_largest_per_step_range():
    angle = np.array([0.0, 0.1, -0.1, 0.05, 0.3, 0.2])
    assert excursion(angle, [(0, 2), (2, 5)]) == pytest.approx(0.4)  # rows 2–5: −0.1 … 0.3
    assert excursion(angle, [(0, 1)]) == pytest.approx(0.1)


def test_roll_pitch_yaw_round_trip():
    rng = np.random.default_rng(0)
    rpy = rng.uniform([-0.5, -0.5, -3.0], [0.5, 0.5, 3.0], (20, 3))
    quats = []
    for r, p, y in rpy:  # q = q_z(ψ) q_y(θ) q_x(φ)
        qx = np.array([math.cos(r / 2), math.sin(r / 2), 0, 0])
        qy = np.array([math.cos(p / 2), 0, math.sin(p / 2), 0])
        qz = np.array([math.cos(y / 2), 0, 0, math.sin(y / 2)])
        q = np.empty(4)
        mujoco.mju_mulQuat(q, qz, qy)
        mujoco.mju_mulQuat(q, q, qx)
        quats.append(q)
    np.testing.assert_allclose(roll_pitch_yaw(np.array(quats)), rpy, atol=1e-12)
    np.testing.assert_allclose(quat_to_mat(np.array(quats))[:, 2, 2], np.cos(rpy[:, 0]) * np.cos(rpy[:, 1]))


def test_actuator_torque_is_mujocos_actuator_force(exo):
    """The formula equals MjData.actuator_force after a forward pass, clamping included (random states and
    controls, some beyond the torque limits)."""
    m, d = exo.model, mujoco.MjData(exo.model)
    rng = np.random.default_rng(1)
    nstate = mujoco.mj_stateSize(m, mujoco.mjtState.mjSTATE_FULLPHYSICS)
    states = np.zeros((30, nstate))
    mujoco.mj_getState(m, d, states[0], mujoco.mjtState.mjSTATE_FULLPHYSICS)
    states[:] = states[0]
    states[:, 1 + exo.qpos_idx] = rng.uniform(-0.3, 0.3, (30, exo.n_joints))
    states[:, 1 + m.nq + exo.dof_idx] = rng.uniform(-3, 3, (30, exo.n_joints))
    controls = rng.uniform(-0.05, 0.05, (30, m.nu))
    tau = actuator_torque(m, states, controls)
    assert np.any(np.abs(tau) == exo.torque_limit)  # some clamped
    for s, c, t in zip(states, controls, tau, strict=True):
        mujoco.mj_setState(m, d, s, mujoco.mjtState.mjSTATE_FULLPHYSICS)
        d.ctrl[:] = c
        mujoco.mj_forward(m, d)
        np.testing.assert_allclose(d.actuator_force, t, rtol=1e-12, atol=1e-9)


@pytest.mark.parametrize("controller", ["pd", "passivity"])
def test_recorded_controls_replay_the_recorded_states(exo, exo_gait, controller):
    """StepBatch.controls row j, applied by mj_step to the state before trajectory row j on the engine's
    physics_model, gives trajectory row j: the alignment the comfort figures rely on (both engines)."""
    from robustgait.sim.factory import make_engine

    with make_engine(exo, exo_gait, SimConfig(controller=controller)) as eng:
        start = eng.full_states(exo_gait.initial_state.qpos[None], exo_gait.initial_state.qvel[None])[0]
        batch = eng.step(exo_gait.initial_state.qpos[None], exo_gait.initial_state.qvel[None], exo_gait.stance,
                         record=True)
        model = eng.physics_model
    tr, ctrl = batch.trajectory[0], batch.controls[0]
    assert tr.shape[0] == ctrl.shape[0] > 600 and ctrl.shape[1] == model.nu
    before = np.vstack([start[None], tr[:-1]])
    d = mujoco.MjData(model)
    for j in (0, 1, 99, 100, 101, 350, tr.shape[0] - 1):  # across the rollout's chunks of 100
        mujoco.mj_setState(model, d, before[j], mujoco.mjtState.mjSTATE_FULLPHYSICS)
        d.ctrl[:] = ctrl[j]
        mujoco.mj_step(model, d)
        after = np.empty_like(start)
        mujoco.mj_getState(model, d, after, mujoco.mjtState.mjSTATE_FULLPHYSICS)
        # the walk's solver warm start is the previous step's (zero at a chunk start): equal to solver tolerance
        np.testing.assert_allclose(after[1:], tr[j, 1:], atol=1e-6)
    no = StepEngine(exo, exo_gait).step(exo_gait.initial_state.qpos[None], exo_gait.initial_state.qvel[None],
                                        exo_gait.stance)
    assert no.controls == [] and no.trajectory == []


def test_the_soles_carry_the_weight_over_a_step(exo, exo_gait):
    """Over one step of the periodic walk (touchdown to touchdown, the impact included) the mean of the two soles'
    normal forces, replayed state by state with the recorded controls, is the robot's weight m g: the vertical
    momentum of a periodic step does not change (flat floor: normal = vertical)."""
    ev = walk(exo, exo_gait, SimConfig(step_cap=10)).events[-1]
    stance = "left" if ev.stance == "right" else "right"
    qpos, qvel = np.array(ev.qpos)[None], np.array(ev.qvel)[None]
    with StepEngine(exo, exo_gait) as eng:
        batch = eng.step(qpos, qvel, stance, record=True)
        start = eng.full_states(qpos, qvel)[0]
    states = np.vstack([start[None], batch.trajectory[0][:-1]])
    m, d = exo.model, mujoco.MjData(exo.model)
    total = []
    for s, c in zip(states, batch.controls[0], strict=True):
        mujoco.mj_setState(m, d, s, mujoco.mjtState.mjSTATE_FULLPHYSICS)
        d.ctrl[:] = c
        mujoco.mj_forward(m, d)
        d.qacc_warmstart[:] = d.qacc
        total.append(sum(sole_normal_force(m, d, sole_contact_geoms(exo, side), exo.floor_geom_id)
                         for side in ("left", "right")))
    assert np.mean(total) == pytest.approx(exo.mass * 9.81, rel=0.005)
    assert max(total) > 3 * exo.mass * 9.81  # the touchdown's impact is in it


def test_a_virtual_soles_contacts_are_its_foot_bodys(tmp_path):
    """A sole named by a foot body and a geom class (sphere feet, a virtual box): its contacts are those of every geom
    of the foot body, as its contact sensor counts them; a sole box: that geom."""
    from robustgait import load_robot
    from tests.robots.test_any_robot import biped_spec, biped_xml

    legs = '[legs.left]\nsole_body = "left_foot"\nsole_class = "foot"\n[legs.right]\nsole_body = "right_foot"\n'
    robot = load_robot(biped_spec(tmp_path, xml=biped_xml(spheres=True), legs=legs))
    m = robot.model
    for side in ("left", "right"):
        geoms = sole_contact_geoms(robot, side)
        spheres = {g for g in geoms if m.geom_type[g] == int(mujoco.mjtGeom.mjGEOM_SPHERE)}
        assert len(spheres) == 4 and robot.sole_geom_id[side] in geoms and len(geoms) == 5
    (tmp_path / "box").mkdir()
    box = load_robot(biped_spec(tmp_path / "box", xml=biped_xml()))
    assert sole_contact_geoms(box, "left") == {box.sole_geom_id["left"]}


@pytest.fixture(scope="module")
def exo_walk(exo, exo_gait):  # type: ignore[no-untyped-def]
    return walk(exo, exo_gait, SimConfig(step_cap=30), comfort=ComfortConfig())


def test_exo_gait_comfort_invariants(exo, exo_gait, exo_walk):
    c = exo_walk.comfort
    cfg = ComfortConfig()
    assert c is not None and c.first_step == cfg.skip_steps + 1 and c.steps == cfg.steps
    p = exo_gait.params
    assert c.duration == pytest.approx(cfg.steps * p.step_duration, rel=0.01)
    assert c.speed == pytest.approx(p.step_length / p.step_duration, rel=0.02)
    assert c.speed == pytest.approx(exo_walk.mean_speed, rel=0.02)
    assert c.step_length == pytest.approx(p.step_length, rel=0.02)
    assert c.cadence == pytest.approx(60 / p.step_duration, rel=0.01)
    for kind in ("acc", "jerk"):
        for ax in ("forward", "lateral", "vertical"):
            r, pk = getattr(c, f"pelvis_{kind}_{ax}_rms"), getattr(c, f"pelvis_{kind}_{ax}_peak")
            assert 0 < r < pk
    assert 0.5 < c.pelvis_acc_vertical_rms < 5 and c.pelvis_acc_vertical_peak < 3 * 9.81  # no free fall, no crash
    limits = dict(zip((*exo.spec.joints, *exo.spec.held_names), exo.servo_limit, strict=True))
    assert 0 < c.torque_rms <= c.torque_peak <= max(limits.values())
    assert all(c.torque_rms_joint[j] <= c.torque_peak_joint[j] <= limits[j] + 1e-9 for j in limits)
    assert c.cost_of_transport is not None and 0 < c.cost_of_transport < 5
    weight = exo.mass * 9.81
    assert c.touchdowns == cfg.steps and c.impact_force is not None and c.impact_force >= weight
    assert c.impact_force_ratio == pytest.approx(c.impact_force / weight)
    assert c.touchdown_speed is not None and c.touchdown_vertical_speed is not None
    assert 0 < c.touchdown_vertical_speed <= c.touchdown_speed < 2
    assert 0 < c.pelvis_roll_excursion < 0.2 and 0 < c.pelvis_pitch_excursion < 0.2
    assert set(FIGURES) <= set(c.to_dict())


@pytest.mark.slow  # seconds of its own: plain pytest stays ≤ 60 s; CI runs it
def test_comfort_is_deterministic_serialized_and_optional(exo, exo_gait, exo_walk):
    again = walk(exo, exo_gait, SimConfig(step_cap=30), comfort=ComfortConfig())
    assert again.comfort == exo_walk.comfort
    d = json.loads(exo_walk.to_json())["comfort"]
    assert Comfort.from_dict(d) == exo_walk.comfort
    assert walk(exo, exo_gait, SimConfig(step_cap=8)).comfort is None  # not asked for
    short = walk(exo, exo_gait, SimConfig(step_cap=5), comfort=ComfortConfig())
    assert short.comfort is None  # the walk ended before the first measured step
    few = walk(exo, exo_gait, SimConfig(step_cap=8), comfort=ComfortConfig(skip_steps=5, steps=20))
    # steps 6–8; the touchdown ending step 8 has no next step to land in
    assert few.comfort is not None and few.comfort.steps == 3 and few.comfort.touchdowns == 2
    with pytest.raises(RobustGaitError, match=r"comfort\.cutoff"):
        walk(exo, exo_gait, SimConfig(step_cap=8), comfort=ComfortConfig(cutoff=800.0))


@pytest.mark.slow  # seconds of its own: plain pytest stays ≤ 60 s; CI runs it
def test_multicontact_and_passivity_walks_have_comfort(exo, exo_gait, exo_mc_gait):
    """Heel strike ends single support and the impact lands in the double support; the passivity law's torques
    come from its own recorded controls."""
    cfg = ComfortConfig(skip_steps=2, steps=4)
    mc = walk(exo, exo_mc_gait, SimConfig(step_cap=8), comfort=cfg).comfort
    assert mc is not None and mc.steps == 4 and mc.touchdowns == 4 and mc.impact_force is not None
    assert mc.impact_force >= exo.mass * 9.81
    pas = walk(exo, exo_gait, SimConfig(step_cap=8, controller="passivity"), comfort=cfg).comfort
    assert pas is not None and pas.steps == 4 and 0 < pas.torque_rms <= pas.torque_peak <= exo.servo_limit.max()


def test_report_figure_and_table_of_a_studys_comfort(tmp_path, exo_walk):
    """The study report's comfort part (report/comfort.py) from a status with two measured gaits, one reused and one
    without figures: one row per measured gait, the figure written."""
    from robustgait.config import Config, to_dict
    from robustgait.report.comfort import COLUMNS, comfort_rows, measured_trials, plot_comfort

    c = exo_walk.comfort.to_dict()
    slower = {**c, "speed": 0.1, "pelvis_acc_vertical_rms": 2.0, "cost_of_transport": None}
    trial = {"state": "COMPLETE", "reused_from": None, "params": {"step_length": 0.15}, "status": "certified",
             "value": 20.0, "estimate": 21.0, "verified": True, "comfort": c}
    status = {"certificate": "push", "unit": "N s", "config": to_dict(Config()),
              "trials": [{**trial, "number": 0}, {**trial, "number": 1, "status": "fell", "value": None,
                                                   "comfort": slower},
                         {**trial, "number": 2, "reused_from": 0}, {**trial, "number": 3, "comfort": None}]}
    assert [t["number"] for t in measured_trials(status)] == [0, 1]
    header, rows = comfort_rows(status)
    assert len(header) == 4 + len(COLUMNS) and [r[0] for r in rows] == ["0", "1"]
    assert rows[0][3] == "20 (verified)" and rows[1][3] == "—" and rows[1][header.index("cost of transport")] == "—"
    assert rows[0][header.index("speed [m/s]")] == f"{c['speed']:.3f}"
    png = plot_comfort(status, tmp_path / "comfort.png")
    assert png.stat().st_size > 10_000
