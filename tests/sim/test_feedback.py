"""The feedback engine (sim/feedback.py), the batched rigid-body dynamics (sim/rigidbody.py) and the
passivity-based law (sim/passivity.py), on the shipped exo."""

from __future__ import annotations

import copy

import mujoco
import numpy as np
import pytest

from robustgait.errors import RobustGaitError
from robustgait.sim.engine import StepEngine, StepInputs
from robustgait.sim.feedback import STAGE_VEL, FeedbackEngine, PDController
from robustgait.sim.passivity import PassivityController, PassivityGains
from robustgait.sim.rigidbody import TreeDynamics
from robustgait.sim.walk import walk


def _random_datas(robot, gait, n, seed, *, spread=0.15, speed=1.0):
    m = robot.model
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(n):
        d = mujoco.MjData(m)
        d.qpos[:] = gait.initial_state.qpos
        d.qpos[7:] += rng.normal(0.0, spread, robot.n_joints)
        quat = np.array([1.0, 0.0, 0.0, 0.0]) + rng.normal(0.0, 0.2, 4)
        d.qpos[3:7] = quat / np.linalg.norm(quat)
        d.qvel[:] = rng.normal(0.0, speed, m.nv)
        mujoco.mj_forward(m, d)
        out.append(d)
    return out


def _start_states(gait, k, seed, *, spread=0.01, speed=0.1):
    rng = np.random.default_rng(seed)
    q = np.tile(gait.initial_state.qpos, (k, 1))
    v = np.tile(gait.initial_state.qvel, (k, 1))
    q[:, 7:] += rng.normal(0.0, spread, (k, q.shape[1] - 7))
    v += rng.normal(0.0, speed, v.shape)
    return q, v


# ------------------------------------------------------------------------------------- rigid-body dynamics
@pytest.mark.parametrize("slab", [False, True])
def test_tree_dynamics_matches_mujoco(exo, exo_gait, slab):
    m = exo.model
    ds = _random_datas(exo, exo_gait, 5, 0)
    dyn = TreeDynamics(m)
    dyn.slab_threshold = 1 if slab else 10**9  # both implementations of velocity_terms
    st = dyn.prepare(np.stack([d.cdof for d in ds]), np.stack([d.cinert for d in ds]))
    mass = dyn.mass_matrix(st)
    c, acc = dyn.velocity_terms(st, np.stack([d.qvel for d in ds])[:, None])
    grav = dyn.gravity(st)
    acc_rand = np.random.default_rng(9).normal(size=(len(ds), m.nv))
    ma = dyn.acceleration_terms(st, acc_rand)
    for i, d in enumerate(ds):
        ref = np.zeros((m.nv, m.nv))
        mujoco.mj_fullM(m, d, ref)
        assert np.abs(mass[i] - ref).max() < 1e-9
        assert np.abs(ma[i] - ref @ acc_rand[i] - grav[i]).max() < 1e-9
        assert np.abs(grav[i] + c[i, 0] - d.qfrc_bias).max() < 1e-9
        for body in exo.sole_geom_id.values():
            b = int(m.geom_bodyid[body])
            jdp, jdr = np.zeros((3, m.nv)), np.zeros((3, m.nv))
            mujoco.mj_jacDot(m, d, jdp, jdr, d.xpos[b], b)
            jp = np.zeros((3, m.nv))
            mujoco.mj_jac(m, d, jp, None, d.xpos[b], b)
            a = acc[i, 0, b]  # spatial, at the com-based origin: shift to the body origin, add ω × v
            lin = a[3:] + np.cross(a[:3], d.xpos[b] - d.subtree_com[0]) + np.cross(d.cvel[b, :3], jp @ d.qvel)
            assert np.abs(jdr @ d.qvel - a[:3]).max() < 1e-9
            assert np.abs(jdp @ d.qvel - lin).max() < 1e-9


# ----------------------------------------------------------------------------------------- passivity law
@pytest.fixture(scope="module")
def passivity(exo, exo_gait):
    return FeedbackEngine(exo, exo_gait, PassivityController()).controller


def _jac_body(m, d, body):
    jp, jr = np.zeros((3, m.nv)), np.zeros((3, m.nv))
    mujoco.mj_jacBody(m, d, jp, jr, body)
    return np.vstack([jp, jr])


def _bias(m, d, q, v):
    """c(q, v) + G(q) by MuJoCo's RNE (mj_rne after mj_forward at velocity v)."""
    d.qpos[:] = q
    d.qvel[:] = v
    mujoco.mj_forward(m, d)
    out = np.zeros(m.nv)
    mujoco.mj_rne(m, d, 0, out)
    return out


def _formula(robot, d0, stance, foot, lam, kd, y, dy, ddy):
    """τ of the module docstring from dense MuJoCo quantities of one state: mj_fullM, mj_jacBody, mj_jacDot,
    mj_rne (independent of TreeDynamics)."""
    m = robot.model
    d = copy.copy(d0)
    ia = robot.dof_idx
    q = d0.qpos.copy()
    qa, dqa = q[robot.qpos_idx], d0.qvel[ia]
    e = qa - y
    dqr, ddqr = dy - lam * e, ddy - lam * (dqa - dy)
    s = dqa - dqr
    mass = np.zeros((m.nv, m.nv))
    mujoco.mj_fullM(m, d0, mass)
    jac = _jac_body(m, d0, foot)
    t = np.zeros((m.nv, robot.n_joints))
    t[:6] = -np.linalg.solve(jac[:, :6], jac[:, ia])
    t[ia] = np.eye(robot.n_joints)
    grav = _bias(m, d, q, np.zeros(m.nv))
    c, h = [], []
    for x in (dqa + dqr, dqa - dqr):
        v = t @ x
        c.append(_bias(m, d, q, v) - grav)
        jdp, jdr = np.zeros((3, m.nv)), np.zeros((3, m.nv))
        mujoco.mj_jacDot(m, d, jdp, jdr, d.xpos[foot], foot)
        h.append(np.concatenate([jdp @ v, jdr @ v]))
    dc, dh = 0.25 * (c[0] - c[1]), 0.25 * (h[0] - h[1])
    a = t @ ddqr
    a[:6] -= np.linalg.solve(jac[:, :6], dh)
    return t.T @ (mass @ a + grav + dc) - kd * s


@pytest.mark.parametrize("stance", ["right", "left"])
def test_passivity_law_equals_formula(exo, exo_gait, passivity, stance):
    rng = np.random.default_rng(1)
    ds = _random_datas(exo, exo_gait, 4, 2 if stance == "right" else 3)
    n = exo.n_joints
    y, dy, ddy = rng.normal(0, 0.3, (3, 4, n))
    ctl = passivity
    tau = ctl.law(np.stack([d.cdof for d in ds]), np.stack([d.cinert for d in ds]),
                  np.stack([d.qpos[exo.qpos_idx] for d in ds]), np.stack([d.qvel[exo.dof_idx] for d in ds]),
                  y, dy, ddy, stance)
    for i, d in enumerate(ds):
        ref = _formula(exo, d, stance, ctl.foot[stance], ctl.lam, ctl.kd_s, y[i], dy[i], ddy[i])
        assert np.abs(tau[i] - ref).max() < 1e-9, np.abs(tau[i] - ref).max()


def test_reduced_dynamics_is_the_constrained_dynamics(exo, exo_gait, passivity):
    """With the stance sole held by a rigid contact, the law at zero error (y_d = q_a, ẏ_d = q̇_a, ÿ_d = q̈_a)
    is the torque that produces q̈_a: solve the full KKT system for q̈ given random τ and compare."""
    m = exo.model
    rng = np.random.default_rng(4)
    ctl = passivity
    foot = ctl.foot["right"]
    ia = exo.dof_idx
    for d in _random_datas(exo, exo_gait, 3, 5):
        jac = _jac_body(m, d, foot)
        dqa = rng.normal(0, 1, exo.n_joints)
        d.qvel[:] = 0.0
        d.qvel[ia] = dqa
        d.qvel[:6] = -np.linalg.solve(jac[:, :6], jac[:, ia] @ dqa)
        mujoco.mj_forward(m, d)
        assert np.abs(d.cvel[foot]).max() < 1e-12
        jdp, jdr = np.zeros((3, m.nv)), np.zeros((3, m.nv))
        mujoco.mj_jacDot(m, d, jdp, jdr, d.xpos[foot], foot)
        mass = np.zeros((m.nv, m.nv))
        mujoco.mj_fullM(m, d, mass)
        tau = rng.normal(0, 50, exo.n_joints)
        rhs = -d.qfrc_bias.copy()
        rhs[ia] += tau
        kkt = np.block([[mass, -jac.T], [jac, np.zeros((6, 6))]])
        qdd = np.linalg.solve(kkt, np.concatenate([rhs, -np.concatenate([jdp @ d.qvel, jdr @ d.qvel])]))[:m.nv]
        qa = d.qpos[exo.qpos_idx]
        got = ctl.law(d.cdof[None], d.cinert[None], qa[None], dqa[None], qa, dqa, qdd[ia], "right")[0]
        assert np.abs(got - tau).max() < 1e-9


def test_reduced_coriolis_is_christoffel(exo, exo_gait, passivity):
    """C̃ from polarization: C̃ q̇_a = c̃, C̃(u) w = C̃(w) u, and dM̃/dt − 2 C̃ skew-symmetric (finite differences
    of M̃ along the constrained motion)."""
    m = exo.model
    ctl = passivity
    rng = np.random.default_rng(6)
    d = _random_datas(exo, exo_gait, 1, 7)[0]
    q0 = d.qpos.copy()

    def kin(q):
        d.qpos[:] = q
        mujoco.mj_kinematics(m, d)
        mujoco.mj_comPos(m, d)
        return d.cdof[None].copy(), d.cinert[None].copy()

    cdof, cinert = kin(q0)
    u, w = rng.normal(0, 1, (2, exo.n_joints))
    _, cu, gt = ctl.reduced_model(cdof, cinert, u[None], "right")
    _, cw, _ = ctl.reduced_model(cdof, cinert, w[None], "right")
    assert np.abs(cu[0] @ w - cw[0] @ u).max() < 1e-9
    qa = q0[exo.qpos_idx]
    law = ctl.law(cdof, cinert, qa[None], u[None], qa, u, np.zeros(exo.n_joints), "right")[0]
    assert np.abs(law - (cu[0] @ u + gt[0])).max() < 1e-9
    v = ctl.reduced(cdof, "right")[1][0] @ u
    h = 1e-5
    qp, qm = q0.copy(), q0.copy()
    mujoco.mj_integratePos(m, qp, v, h)
    mujoco.mj_integratePos(m, qm, v, -h)
    mdot = (ctl.reduced_model(*kin(qp), u[None], "right")[0][0]
            - ctl.reduced_model(*kin(qm), u[None], "right")[0][0]) / (2 * h)
    n = mdot - 2 * cu[0]
    assert np.abs(n + n.T).max() < 1e-6 * np.abs(mdot).max()


@pytest.mark.slow  # seconds of its own: plain pytest stays ≤ 60 s; CI runs it
def test_passivity_with_perturbed_plants(exo, exo_gait):
    """Per-sample models perturb the simulated plant; the law keeps the nominal model (its kinematics come
    from the robot's model), so a heavier pelvis changes the outcome but not the law's model."""
    q, v = _start_states(exo_gait, 2, 8)
    heavy = copy.copy(exo.model)
    heavy.body_mass[1] *= 1.3
    mujoco.mj_setConst(heavy, mujoco.MjData(heavy))
    with FeedbackEngine(exo, exo_gait, PassivityController()) as eng:
        nominal = eng.step(q, v, "right")
        perturbed = eng.step(q, v, "right", inputs=StepInputs(models=[exo.model, heavy]))
        assert not nominal.fell.any() and not perturbed.fell.any()
        assert np.abs(perturbed.qvel[0] - nominal.qvel[0]).max() < 1e-9  # sample 0 keeps the nominal plant
        assert np.abs(perturbed.qvel[1] - nominal.qvel[1]).max() > 1e-3
        assert eng.controller.kinematics.model is exo.model


def test_passivity_refuses_multicontact(exo, exo_mc_gait):
    with pytest.raises(RobustGaitError, match="flat-foot"):
        FeedbackEngine(exo, exo_mc_gait, PassivityController())


# ------------------------------------------------------------------------------- PD = the rollout engine
def _assert_same(a, b, tol=1e-9):
    assert a.fall_reason == b.fall_reason
    assert np.array_equal(a.fell, b.fell)
    assert np.array_equal(a.duration, b.duration) and np.array_equal(a.tau, b.tau)
    assert a.physics_steps == b.physics_steps
    ok = ~a.fell
    assert np.abs(a.qpos[ok] - b.qpos[ok]).max(initial=0.0) <= tol
    assert np.abs(a.qvel[ok] - b.qvel[ok]).max(initial=0.0) <= tol
    for x, y in zip(a.trajectory, b.trajectory, strict=True):
        assert x.shape == y.shape
        assert np.abs(x - y).max(initial=0.0) <= tol


def test_pd_feedback_equals_rollout(exo, exo_gait):
    q, v = _start_states(exo_gait, 12, 0, spread=0.03, speed=0.4)
    q[-1, 2] = 0.3  # a fall (base_low)
    ref = StepEngine(exo, exo_gait)
    a = ref.step(q, v, "right", record=True)
    assert not all(a.fell) and any(a.fell)
    with FeedbackEngine(exo, exo_gait, PDController()) as fb:
        b = fb.step(q, v, "right", record=True)
        _assert_same(a, b)
        b2 = fb.step(*exo.mirror_state(q, v), "left", record=True)  # the other stance, same engine
    _assert_same(ref.step(*exo.mirror_state(q, v), "left", record=True), b2)
    with FeedbackEngine(exo, exo_gait, PDController(servo_exact=True)) as fb:
        _assert_same(a, fb.step(q, v, "right", record=True), tol=0.0)  # bit-identical


class _StagedPD(PDController):
    """The PD asking for MuJoCo's velocity stage at each state (a persistent batch): checks that path."""

    stage = STAGE_VEL
    fields = ("cdof", "qfrc_bias")

    def torque(self, k, obs):
        assert obs.fields["cdof"].shape == (obs.qpos.shape[0], 18, 6) and np.all(obs.fields["qfrc_bias"] != 0)
        return super().torque(k, obs)


def test_pd_feedback_with_mujoco_stages_equals_rollout(exo, exo_gait):
    q, v = _start_states(exo_gait, 5, 4, spread=0.03, speed=0.4)
    a = StepEngine(exo, exo_gait).step(q, v, "right", record=True)
    with FeedbackEngine(exo, exo_gait, _StagedPD(servo_exact=True)) as fb:
        _assert_same(a, fb.step(q, v, "right", record=True), tol=0.0)


@pytest.mark.slow  # seconds of its own: plain pytest stays ≤ 60 s; CI runs it
def test_pd_feedback_equals_rollout_with_inputs(exo, exo_gait):
    from robustgait.validate.disturbances import physics_model

    k = 6
    rng = np.random.default_rng(3)
    q, v = _start_states(exo_gait, k, 1)
    wrench = np.zeros((k, 250, 6))
    wrench[:, 100:200, 1] = rng.normal(0.0, 150.0, (k, 1))
    inputs = [StepInputs(ctrl_offset=rng.normal(0.0, 0.005, (k, 300, exo.n_joints)), base_wrench=wrench)]
    for base in (exo.model, physics_model(exo)):  # same layout as the robot's, and another (no visual geoms)
        models = []
        for _ in range(k):
            mm = copy.copy(base)
            mm.body_mass[1] *= 1.0 + rng.uniform(-0.2, 0.2)
            mujoco.mj_setConst(mm, mujoco.MjData(mm))
            models.append(mm)
        inputs.append(StepInputs(models=models, base_wrench=wrench))
    ref = StepEngine(exo, exo_gait)
    with FeedbackEngine(exo, exo_gait, PDController()) as fb:
        for inp in inputs:
            _assert_same(ref.step(q, v, "right", inputs=inp, record=True),
                         fb.step(q, v, "right", inputs=inp, record=True))
        # after per-sample models, the engine is back on the robot's own model
        _assert_same(ref.step(q, v, "right"), fb.step(q, v, "right"))


def test_sensor_noise_is_read_by_the_law(exo, exo_gait):
    """Encoder noise: the servo PD of the rollout engine takes it as the exact control offset −(n_q + kd/kp n_v)
    (bit-identical), the PD through the feedback engine reads it and matches (1e-9), and the passivity law is
    evaluated at the noisy joint state — not at the true one, and not through the servo's offset."""
    k, n, nu = 4, 300, exo.n_joints
    rng = np.random.default_rng(8)
    q, v = _start_states(exo_gait, k, 2)
    noise = np.zeros((k, n, 2, nu))
    noise[:, :, 0] = rng.normal(0.0, 0.004, (k, n, nu))
    noise[:, :, 1] = rng.normal(0.0, 0.2, (k, n, nu))
    noisy = StepInputs(sensor_noise=noise)
    off = -(noise[:, :, 0] + (exo.kd / exo.kp) * noise[:, :, 1])
    ref = StepEngine(exo, exo_gait)
    a = ref.step(q, v, "right", inputs=noisy, record=True)
    b = ref.step(q, v, "right", inputs=StepInputs(ctrl_offset=off), record=True)
    _assert_same(a, b, tol=0.0)
    assert np.abs(a.qvel - ref.step(q, v, "right").qvel).max() > 1e-4  # the noise does act
    with FeedbackEngine(exo, exo_gait, PDController()) as fb:
        _assert_same(a, fb.step(q, v, "right", inputs=noisy, record=True))
        with pytest.raises(RobustGaitError, match=r"sensor_noise must be \(K=4, n, 2, 12\)"):
            fb.step(q, v, "right", inputs=StepInputs(sensor_noise=noise[:, :, 0]))

    class Recording(PassivityController):
        def torque(self, kk, obs):
            seen.append((kk, obs.qpos[:, self.qpos_idx].copy(), obs.qvel[:, self.dof_idx].copy()))
            return super().torque(kk, obs)

    seen: list = []
    with FeedbackEngine(exo, exo_gait, Recording()) as fb:
        c = fb.step(q, v, "right", inputs=noisy, record=True)
    assert c.fall_reason == [None] * k
    for kk, qa, _ in seen[1:20]:
        # the state the law saw at physics step kk = the recorded true state of step kk + the noise
        true = np.stack([t[kk - 1] for t in c.trajectory])[:, 1:1 + exo.model.nq][:, exo.qpos_idx]  # (time, qpos, …)
        np.testing.assert_allclose(qa - true, noise[:, kk, 0], atol=1e-12)
    kk, _, qd = seen[0]
    np.testing.assert_allclose(qd - v[:, exo.dof_idx], noise[:, 0, 1], atol=1e-12)


def test_delay_line_of_a_central_law():
    """The torque applied at step k is the one computed at k − d; before the step, the tail's (or the step's
    first torque without one); the tail handed on holds the T torques before each sample's event."""
    hist = np.arange(2 * 6 * 1, dtype=float).reshape(2, 6, 1)  # sample 0: 0..5, sample 1: 6..11
    inp = StepInputs(delay_steps=np.array([2, 0]), torque_tail=np.array([[[-2.0], [-1.0]], [[-4.0], [-3.0]]]))
    both = np.array([0, 1])
    assert FeedbackEngine._delayed(hist, inp, both, 0)[:, 0].tolist() == [-2.0, 6.0]
    assert FeedbackEngine._delayed(hist, inp, both, 1)[:, 0].tolist() == [-1.0, 7.0]
    assert FeedbackEngine._delayed(hist, inp, both, 4)[:, 0].tolist() == [2.0, 10.0]
    no_tail = StepInputs(delay_steps=np.array([2, 0]))
    assert FeedbackEngine._delayed(hist, no_tail, both, 1)[:, 0].tolist() == [0.0, 7.0]
    tail = FeedbackEngine._torque_tail(hist, inp, np.array([5, 1]))  # events after 5 and 1 physics steps
    assert tail[:, :, 0].tolist() == [[3.0, 4.0], [-3.0, 6.0]]


@pytest.mark.slow  # seconds of its own: plain pytest stays ≤ 60 s; CI runs it
def test_latency_delays_the_passivity_law_and_not_the_pd_servo(exo, exo_gait):
    k = 3
    q, v = _start_states(exo_gait, k, 4)

    class Recording(PassivityController):
        def torque(self, kk, obs):
            tau, e = super().torque(kk, obs)
            # the central command: the law's torque + the drives' damping, per sample in the batch
            computed.append((kk, obs.samples.copy(), tau + self.kd_s * obs.qvel[:, exo.dof_idx]))
            return tau, e

    computed: list = []
    with FeedbackEngine(exo, exo_gait, Recording()) as fb:
        assert fb.latency == "torque"
        free = fb.step(q, v, "right")
        zero = fb.step(q, v, "right", inputs=StepInputs(delay_steps=np.zeros(k, dtype=np.int64)))
        _assert_same(free, zero, tol=1e-7)  # a zero delay is no delay (to the rounding of (τ + D q̇) − D q̇)
        computed.clear()
        late = fb.step(q, v, "right", inputs=StepInputs(delay_steps=np.array([0, 20, 40])))
    assert np.abs(late.qvel[1] - free.qvel[1]).max() > 1e-3 and np.abs(late.qvel[0] - free.qvel[0]).max() < 1e-7
    assert late.torque_tail is not None and late.torque_tail.shape == (k, 40, exo.n_joints)
    hist = np.full((k, 2000, exo.n_joints), np.nan)
    for kk, samples, cmd in computed:
        hist[samples, kk] = cmd
    for i in range(k):
        np.testing.assert_array_equal(late.torque_tail[i], hist[i, late.control_steps[i] - 40:late.control_steps[i]])
    with pytest.raises(RobustGaitError, match="delay_steps is the latency of a state-feedback law"):
        StepEngine(exo, exo_gait).step(q, v, "right", inputs=StepInputs(delay_steps=np.zeros(k, dtype=np.int64)))
    with FeedbackEngine(exo, exo_gait, PDController()) as fb:
        assert fb.latency == "command"
        with pytest.raises(RobustGaitError, match="delay_steps is the latency"):
            fb.step(q, v, "right", inputs=StepInputs(delay_steps=np.zeros(k, dtype=np.int64)))


def test_pd_feedback_multicontact_domains(exo, exo_mc_gait):
    q, v = _start_states(exo_mc_gait, 3, 2)
    ref = StepEngine(exo, exo_mc_gait)
    with FeedbackEngine(exo, exo_mc_gait, PDController()) as fb:
        a, b = ref.step(q, v, "right"), fb.step(q, v, "right")
        _assert_same(a, b)
        ok = ~a.fell
        _assert_same(ref.step(a.qpos[ok], a.qvel[ok], "right", domain=1),
                     fb.step(b.qpos[ok], b.qvel[ok], "right", domain=1))


def test_saturation_counted(exo, exo_gait):
    """The count of |τ| > limit equals the count recomputed from the rollout engine's trajectory (the PD
    torque of each recorded state, before each sample's event)."""
    q, v = _start_states(exo_gait, 4, 5, spread=0.05, speed=1.5)
    ref = StepEngine(exo, exo_gait)
    a = ref.step(q, v, "right", record=True)
    ctl = PDController()
    with FeedbackEngine(exo, exo_gait, ctl) as fb:
        b = fb.step(q, v, "right")
        des = ctl.desired[("right", 0)]
        for i in range(len(q)):
            n = int(b.control_steps[i])
            states = np.vstack([fb.full_states(q[i:i + 1], v[i:i + 1]), a.trajectory[i]])[:n]
            qa, dqa = states[:, 1 + exo.qpos_idx], states[:, 1 + exo.model.nq + exo.dof_idx]
            tau = exo.kp * (des.y[:n] - qa) + exo.kd * (des.dy[:n] - dqa) + des.uff[:n]
            assert np.array_equal(b.saturation[i], (np.abs(tau) > exo.torque_limit).sum(axis=0))
            assert np.allclose(b.error_sq[i], ((qa - des.y[:n]) ** 2).sum(axis=0), rtol=1e-9, atol=1e-15)
        assert b.saturation.sum() > 0
        assert fb.stats.summary()["saturation"] == int(b.saturation.sum())


# ------------------------------------------------------------------------- passivity walks the default gait
def _walks(robot, gait, steps):
    out = {}
    for name, ctl in (("pd", PDController()), ("passivity", PassivityController())):
        with FeedbackEngine(robot, gait, ctl) as eng:
            res = walk(robot, gait, steps=steps, engine=eng)
            out[name] = (res, eng.stats.summary())
    return out


def _check_tracking(walks, steps):
    (pd, pd_s), (pa, pa_s) = walks["pd"], walks["passivity"]
    assert pd.steps_taken == pa.steps_taken == steps and not pa.fell
    assert abs(pa.mean_speed - pd.mean_speed) < 0.01
    # measured (spec gains, 50 steps): RMS 0.22 vs 0.59 mrad, max 2.2 vs 7.4 mrad
    assert pa_s["rms"] < 0.6 * pd_s["rms"]
    assert pa_s["max"] < 0.6 * pd_s["max"]
    assert pa_s["steps"] > steps * 650  # every physics step of every step was controlled and counted
    for _, summary in walks.values():  # saturation is counted (the first ms after touchdown: < 0.5 %)
        assert summary["saturation"] > 0 and summary["saturation_fraction"] < 0.005


@pytest.mark.slow  # keeps plain pytest within 60 s; CI runs it
def test_passivity_tracks_better_than_pd(exo, exo_gait):
    _check_tracking(_walks(exo, exo_gait, 8), 8)


@pytest.mark.slow
def test_passivity_walks_50_steps_better_than_pd(exo, exo_gait):
    _check_tracking(_walks(exo, exo_gait, 50), 50)


def test_passivity_gains_from_spec(exo):
    g = PassivityGains.from_robot(exo)
    assert exo.spec.passivity is not None
    assert g.lam == exo.spec.passivity.lam and g.kd == exo.spec.passivity.kd
    with pytest.raises(RobustGaitError):
        PassivityGains((1.0, 2.0), (1.0,))


@pytest.mark.parametrize(("table", "message"), [
    ("[controller.passivity]\nlambda = [20.0]\nkd = [1.0]\n", "controller.passivity.lambda: must be a list of 12"),
    ("[controller.passivity]\nlambda = [0.0]\nkd = [1.0]\n", "controller.passivity.lambda"),
    ("[controller.pd]\nkp = 1\n", "controller"),
])
def test_passivity_spec_table_is_validated(exo, tmp_path, table, message):
    from robustgait.io.robotfile import read_spec as parse_spec

    src = exo.spec.source.read_text()
    start = src.index("[controller.passivity]")
    end = src.index("[legs.left]")
    text = src[:start] + table + "\n" + src[end:]
    text = text.replace('mjcf = "exo.xml"', f'mjcf = "{exo.spec.mjcf}"')
    (tmp_path / "spec.toml").write_text(text)
    with pytest.raises(RobustGaitError, match=message.replace(".", r"\.")):
        parse_spec(tmp_path / "spec.toml")
    # without the table the law has no gains: one line naming the spec and the table
    plain = (src[:start] + src[end:]).replace('mjcf = "exo.xml"', f'mjcf = "{exo.spec.mjcf}"')
    (tmp_path / "plain.toml").write_text(plain)
    from robustgait.io.robotfile import load_robot

    plain_robot = load_robot(tmp_path / "plain.toml")
    assert plain_robot.spec.passivity is None
    with pytest.raises(RobustGaitError, match=r"plain\.toml: no \[controller\.passivity\] gains"):
        PassivityGains.from_robot(plain_robot)
    gains = PassivityGains.matching_pd(plain_robot)
    assert np.allclose(gains.lam, exo.kp / exo.kd) and np.allclose(gains.kd, exo.kd)


# ---- the controller as a configuration choice --------------------------------------------------------------
def test_make_engine_follows_the_controller_option(exo, exo_gait, exo_mc_gait):
    from robustgait.config import SimConfig
    from robustgait.sim.factory import MULTICONTACT_NOTE, make_engine

    with make_engine(exo, exo_gait) as pd, make_engine(exo, exo_gait, SimConfig(controller="passivity")) as pb:
        assert type(pd) is StepEngine and pd.controller_name == "pd" and pd.controller_note == ""
        assert isinstance(pb, FeedbackEngine) and pb.controller_name == "passivity"
    # multi-contact gaits keep the joint PD in both domains (the paper's choice), and say so
    with make_engine(exo, exo_mc_gait, SimConfig(controller="passivity")) as mc:
        assert type(mc) is StepEngine and mc.controller_name == "pd" and mc.controller_note == MULTICONTACT_NOTE


def test_walk_reports_its_controller_tracking_and_saturation(exo, exo_gait):
    """The rollout engine's PD, recomputed from the recorded states, counts what the feedback engine's PD counts
    on the same walk (the two engines agree to 1e-13)."""
    from robustgait.config import SimConfig

    rollout = walk(exo, exo_gait, SimConfig(), steps=4)
    with FeedbackEngine(exo, exo_gait, PDController()) as eng:
        fb = walk(exo, exo_gait, SimConfig(), steps=4, engine=eng)
    assert rollout.controller == fb.controller == "pd"
    a, b = rollout.tracking, fb.tracking
    assert a["steps"] == b["steps"] > 2000 and a["saturation"] == b["saturation"]
    assert a["rms"] == pytest.approx(b["rms"], rel=1e-6) and a["max"] == pytest.approx(b["max"], rel=1e-6)
    assert 0 < a["rms"] < a["max"] < 0.05



def test_walk_fills_the_tracking_totals_it_is_given(exo, exo_gait):
    """``walk(..., tracking=stats)`` adds the walk's tracking to ``stats`` (its per-joint totals, for a caller such as
    benchmarks/experiments/robot_grid) and changes nothing in the result."""
    from robustgait.config import SimConfig
    from robustgait.sim.controller import TrackingStats

    stats = TrackingStats()
    given = walk(exo, exo_gait, SimConfig(), steps=3, tracking=stats)
    plain = walk(exo, exo_gait, SimConfig(), steps=3)
    assert given.tracking == plain.tracking == stats.summary()
    assert stats.saturation is not None and stats.saturation.shape == (len(exo.spec.joints),)
    assert given.steps_taken == plain.steps_taken == 3
    assert [(e.qpos, e.qvel) for e in given.events] == [(e.qpos, e.qvel) for e in plain.events]

def test_cli_controller_errors_are_one_line(exo, tmp_path, capsys):
    from robustgait.cli import main
    from tests.conftest import EXO_GAIT

    assert main(["walk", str(EXO_GAIT), "--robot", "exo", "--controller", "torque"]) == 2
    err = capsys.readouterr().err
    assert "argument --controller: must be one of 'pd', 'passivity' (got 'torque')" in err
    src = exo.spec.source.read_text()
    start, end = src.index("[controller.passivity]"), src.index("[legs.left]")
    plain = (src[:start] + src[end:]).replace('mjcf = "exo.xml"', f'mjcf = "{exo.spec.mjcf}"')
    spec = tmp_path / "nogains.toml"
    spec.write_text(plain)
    assert main(["walk", str(EXO_GAIT), "--robot", str(spec), "--controller", "passivity", "--steps", "1"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("robustgait: error:") and "no [controller.passivity] gains" in err
    assert len(err.strip().splitlines()) == 1
    bad = spec.with_name("badgains.toml")
    bad.write_text(src.replace("lambda = [20, 20,", "lambda = [-20, 20,").replace(
        'mjcf = "exo.xml"', f'mjcf = "{exo.spec.mjcf}"'))
    assert main(["walk", str(EXO_GAIT), "--robot", str(bad), "--controller", "passivity", "--steps", "1"]) == 2
    err = capsys.readouterr().err
    assert "controller.passivity.lambda" in err and "must satisfy 0 < x" in err
