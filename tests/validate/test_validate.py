"""Validation of a gait under disturbances on the shipped robot ``exo``, and its statistics."""

from __future__ import annotations

import json
import math
from pathlib import Path

import mujoco
import numpy as np
import pytest

from robustgait import RobustGaitError, load_robot
from robustgait.certificate.certify import certify_gait
from robustgait.cli import main
from robustgait.config import CertifyConfig, ReportConfig, SimConfig, ValidateConfig
from robustgait.io.gaitfile import save_gait
from robustgait.sim import StepEngine, StepInputs
from robustgait.sim.engine import servo_noise_offset
from robustgait.validate import (
    CertificateRef,
    Draws,
    Validator,
    draw,
    logistic_fit,
    wilson_interval,
)
from robustgait.validate import disturbances as dist

# one worker runs the whole module, so its module fixtures (orbits, certificates, validators) are made once
pytestmark = pytest.mark.xdist_group("validate_module")


def test_wilson_interval_known_values():
    # reference values: Wilson (1927) score interval, z = 1.959964 (also scipy's binomtest(...).proportion_ci)
    for (k, n), (lo, hi) in {(0, 10): (0.0, 0.27753), (5, 10): (0.23659, 0.76341), (10, 10): (0.72247, 1.0),
                             (1, 20): (0.00888, 0.23613), (81, 263): (0.25529, 0.36621)}.items():
        got = wilson_interval(k, n)
        assert got == pytest.approx((lo, hi), abs=5e-5), (k, n)
    assert wilson_interval(0, 0) == (0.0, 1.0)
    scipy_stats = pytest.importorskip("scipy.stats")
    ci = scipy_stats.binomtest(37, 200).proportion_ci(method="wilson")
    assert wilson_interval(37, 200) == pytest.approx((ci.low, ci.high), abs=1e-12)
    with pytest.raises(ValueError):
        wilson_interval(3, 2)


def test_logistic_fit_finds_the_half_failure_size():
    rng = np.random.default_rng(0)
    s = rng.uniform(0, 60, 2000)
    p = 1 / (1 + np.exp(-(6.0 - 0.2 * s)))  # half fail at 30
    fit = logistic_fit(s, rng.uniform(size=s.size) < p)
    assert fit.converged and fit.in_range and fit.s50 is not None and fit.s50_se is not None
    assert abs(fit.s50 - 30.0) < 3 * fit.s50_se and fit.s50_se < 1.5
    assert fit.b == pytest.approx(-0.2, rel=0.2)
    assert logistic_fit(s, np.ones(s.size, bool)).s50 is None  # nothing fell
    separated = logistic_fit(s, s < 30)
    assert not separated.converged and "separate" in separated.note and separated.s50 is not None
    assert separated.s50 == pytest.approx(30.0, abs=0.5) and separated.s50_se is not None and separated.s50_se < 0.5


def test_draws_depend_on_seed_and_robot_only():
    robot = load_robot("exo")
    cfg = ValidateConfig(trials=50)
    a, b = draw("push", 50, cfg, robot), draw("push", 50, cfg, robot)
    np.testing.assert_array_equal(a.size, b.size)
    assert a.size.max() <= robot.mass * cfg.push_dv_max
    c = draw("push", 50, ValidateConfig(seed=1), robot)
    assert not np.array_equal(a.size, c.size)
    with pytest.raises(RobustGaitError, match="unknown disturbance"):
        draw("earthquake", 5, cfg, robot)
    with pytest.raises(RobustGaitError, match=r"ValidateConfig.trials: must satisfy 1 ≤ x ≤ 10000 \(got 0\)"):
        ValidateConfig(trials=0)
    with pytest.raises(RobustGaitError, match=r"ValidateConfig.friction_range\[0\]: must satisfy 0 < x ≤ 10"):
        ValidateConfig(friction_range=(0.0, 1.0))
    with pytest.raises(RobustGaitError, match=r"ValidateConfig.push_phase: must be \[low, high\] with low ≤ high"):
        ValidateConfig(push_phase=(0.5, 0.2))


def test_noise_is_encoder_noise_and_a_servo_control_offset():
    robot = load_robot("exo")
    noise = dist.noise_draws(robot, np.array([0.0, 0.01]), 50.0, 400, seed=0, kind_step=0)
    assert noise.shape == (2, 400, 2, robot.n_joints)
    assert np.all(noise[0] == 0.0)
    np.testing.assert_allclose(noise[1, :, 0].std(), 0.01, rtol=0.1)  # n_q
    np.testing.assert_allclose(noise[1, :, 1].std(), 0.5, rtol=0.1)  # n_v = 50 σ_q
    # for the PD servos: −(n_q + kd/kp n_v), per joint variance σ² (1 + (50 kd/kp)²)
    off = servo_noise_offset(robot, noise)
    expect = 0.01 * np.sqrt(1 + (50 * robot.kd / robot.kp) ** 2)
    np.testing.assert_allclose(off[1].std(axis=0), expect, rtol=0.15)


def test_noise_and_terrain_realizations_do_not_depend_on_the_gait():
    """A longer step (horizon) or a longer terrain (more tile rows, longer steps) only appends numbers: the
    noise of each trial at each physics step and every tile in front of the robot stay the same, so gaits of
    a study validated with one seed meet the same disturbances."""
    robot = load_robot("exo")
    sigma = np.array([0.005, 0.01, 0.02])
    short = dist.noise_draws(robot, sigma, 50.0, 300, seed=3, kind_step=1)
    long = dist.noise_draws(robot, sigma, 50.0, 420, seed=3, kind_step=1)
    np.testing.assert_array_equal(long[:, :300], short)
    near = dist.TerrainLayout(x0=-1.0, rough_from=0.1, y0=-1.0, tile=0.3, nx=8, ny=7)
    far = dist.TerrainLayout(x0=-1.2, rough_from=0.12, y0=-0.9, tile=0.3, nx=13, ny=7)
    (l1, s1), (l2, s2) = dist.terrain_tiles(near, 0.02, seed=5), dist.terrain_tiles(far, 0.02, seed=5)
    np.testing.assert_array_equal(l2[:8], l1)
    np.testing.assert_array_equal(s2[:8], s1)


def test_latency_offsets_shift_the_command():
    ctrl = np.arange(20.0)[:, None] * np.ones((1, 2))
    prev = 100 + np.arange(20.0)[:, None] * np.ones((1, 2))
    off = dist.latency_offsets(ctrl, prev, np.array([0, 3]), np.array([15, 15]))
    assert np.all(off[0] == 0)
    delayed = ctrl + off[1]
    np.testing.assert_array_equal(delayed[:3, 0], [112, 113, 114])  # previous step's tail before its event
    np.testing.assert_array_equal(delayed[3:, 0], ctrl[:-3, 0])


@pytest.fixture(scope="module")
def small_cert(exo, exo_gait):
    return certify_gait(exo, exo_gait, CertifyConfig(method="uniform", disturbance="state", n_samples=20))


@pytest.fixture(scope="module")
def validator(exo, exo_gait, small_cert):
    with Validator(exo, exo_gait, ValidateConfig(trials=6, steps_after=3), certificate=small_cert) as v:
        yield v


def test_engine_inputs_keep_undisturbed_samples_bit_identical(exo, exo_gait, small_cert):
    fp = small_cert.fixed_point
    qpos, qvel = np.tile(fp.qpos, (2, 1)), np.tile(fp.qvel, (2, 1))
    with StepEngine(exo, exo_gait) as eng:
        ref = eng.step(qpos, qvel, exo_gait.stance)
        wrench = np.zeros((2, eng.horizon, 6))
        wrench[1, 100:200, 0] = 300.0  # sample 1 pushed: the rollout carries xfrc_applied for both
        pushed = eng.step(qpos, qvel, exo_gait.stance, inputs=StepInputs(
            base_wrench=wrench, ctrl_offset=np.zeros((2, eng.horizon, exo.n_joints)), models=[exo.model] * 2))
    np.testing.assert_array_equal(pushed.qpos[0], ref.qpos[0])
    np.testing.assert_array_equal(pushed.qvel[0], ref.qvel[0])
    assert pushed.duration[0] == ref.duration[0]
    assert not np.array_equal(pushed.qvel[1], ref.qvel[1])
    with StepEngine(exo, exo_gait) as eng, pytest.raises(RobustGaitError, match="base_wrench"):
        eng.step(qpos, qvel, exo_gait.stance, inputs=StepInputs(base_wrench=np.zeros((3, 10, 6))))


def test_zero_push_reproduces_the_undisturbed_walk_exactly(validator):
    n = 3
    zero = Draws("push", np.zeros(n), {"direction": np.linspace(0, 3, n), "phase": np.full(n, 0.3)})
    res = validator.run("push", draws=zero)
    fp = validator.fixed_point
    # the undisturbed walk from the same state with the same engine, no inputs at all
    from robustgait.validate import simulate_trials

    ok, _, _, first, steps = simulate_trials(validator.engine, fp.qpos[None], fp.qvel[None], 1 + 3, 1,
                                             lambda *a: None, first_at=validator.nominal_at)
    assert ok[0] and res.success.all()
    nq = validator.robot.model.nq
    x1 = validator.certificate.to_z(validator.reduced.phi(first[:, :nq], first[:, nq:]))
    for i in range(n):
        np.testing.assert_array_equal(res.x_first[i], x1[0])
    assert res.physics_steps == n * steps
    # x̄₁ of the undisturbed walk is the map's image of x̄*: within the fixed point's residual
    assert res.distance[0] < 0.02 and res.inside.all()


def test_huge_push_always_falls(validator, exo):
    n = 6
    huge = Draws("push", np.full(n, exo.mass * 5.0), {"direction": np.linspace(0, 2 * math.pi, n, endpoint=False),
                                                       "phase": np.linspace(0.0, 0.6, n)})
    res = validator.run("push", draws=huge)
    assert not res.success.any()
    assert all(r is not None for r in res.fall_reason) and np.all(res.fall_step >= 1)
    chk = res.certificate_check()
    assert chk["inside"].n == 0  # type: ignore[union-attr]


def test_zero_slope_walks_like_the_floor_and_steep_slopes_fall(validator):
    """Slopes tilt gravity (a rigid rotation of the world): a 0° slope is the flat floor exactly, whatever its
    direction; 30° downhill ahead and 30° sideways fall, and fall detection reports it (relative to the ground)."""
    z = Draws("push", np.zeros(1), {"direction": np.zeros(1), "phase": np.zeros(1)})
    floor = validator.run("push", draws=z)
    d = Draws("slope", np.array([0.0, 0.0, 30.0, 30.0]), {"direction": np.array([0.0, 2.0, 0.0, math.pi / 2])})
    res = validator.run("slope", draws=d)
    np.testing.assert_array_equal(res.x_first[:2], np.repeat(floor.x_first, 2, axis=0))
    assert res.success[:2].all() and not res.success[2:].any()
    assert all(r in ("tilt", "base_low", "non_foot_contact") for r in res.fall_reason[2:])
    g = validator._base_model().opt.gravity
    from robustgait.validate.disturbances import slope_gravity

    up = slope_gravity(g, 10.0, math.pi, 0.0)  # uphill ahead: gravity pulls back, along −x
    assert up[0] < 0 and abs(up[1]) < 1e-12 and np.linalg.norm(up) == pytest.approx(np.linalg.norm(g))
    assert math.degrees(math.acos(-up[2] / np.linalg.norm(up))) == pytest.approx(10.0)


@pytest.mark.slow  # seconds of its own: plain pytest stays ≤ 60 s; CI runs it
def test_every_kind_runs_and_summarizes(validator):
    for kind in ("mass", "friction", "latency", "noise", "slope"):
        res = validator.run(kind)
        s = res.summary()
        assert s["trials"] == 6 and 0 <= s["success"]["k"] <= 6
        assert sum(b["n"] for b in s["binned"]) == 6
        json.dumps(res.to_dict(), allow_nan=False)


@pytest.mark.slow  # seconds of its own: plain pytest stays ≤ 60 s; CI runs it
def test_latency_under_the_passivity_law_delays_its_commands(exo, exo_gait, small_cert):
    """Under a central state-feedback law latency delays the law's command (the engine's delay line, with the
    commands carried from step to step), not the PD servos' reference: a zero delay walks like no delay, and the
    PD's command-offset latency is not used."""
    sim = SimConfig(controller="passivity")
    with Validator(exo, exo_gait, ValidateConfig(trials=3, steps_after=2), certificate=small_cert, sim=sim) as v:
        assert v.engine.latency == "torque"
        res = v.run("latency", draws=Draws("latency", np.array([0.0, 0.0, 0.012]), {}))
        assert res.success[:2].all() and np.array_equal(res.x_first[0], res.x_first[1])
        free = v.run("push", draws=Draws("push", np.zeros(1), {"direction": np.zeros(1), "phase": np.zeros(1)}))
        np.testing.assert_allclose(res.x_first[0], free.x_first[0], atol=1e-7)
        assert not np.allclose(res.x_first[2], res.x_first[0], atol=1e-6, equal_nan=True)


def test_flat_terrain_walks_and_non_foot_contact_with_terrain_is_a_fall(validator, exo, exo_gait):
    flat = Draws("terrain", np.zeros(2), {"terrain_seed": np.array([1.0, 2.0])})
    res = validator.run("terrain", draws=flat)
    assert res.success.all()  # soles on the heightfield are footfalls, not falls
    fp = validator.fixed_point
    layout = dist.terrain_layout(exo, fp.qpos, exo_gait.stance, validator.config, validator.step_length)
    m = dist.terrain_model(exo, layout)
    level, slope = dist.terrain_tiles(layout, 0.03, seed=0)
    assert np.all(np.abs(level) + (np.abs(slope) * layout.tile / 2).sum(axis=-1) <= 0.03 + 1e-12)
    rough = dist.terrain_models(m, layout, Draws("terrain", np.array([0.03]), {"terrain_seed": np.array([0.0])}))[0]
    dr = mujoco.MjData(rough)
    mujoco.mj_forward(rough, dr)
    x = layout.rough_from + 0.5 * layout.tile
    y = layout.y0 + 0.5 * layout.tile
    for dx, dy in ((0, 0), (0.1, 0), (0, -0.1)):  # the ray hits the tile's tilted top where its plane says
        got = 5.0 - mujoco.mj_ray(rough, dr, np.array([x + dx, y + dy, 5.0]), np.array([0, 0, -1.0]), None, 1, -1,
                                  np.zeros(1, np.int32))
        assert got == pytest.approx(level[0, 0] + slope[0, 0, 0] * dx + slope[0, 0, 1] * dy, abs=1e-9)
    d = mujoco.MjData(m)
    d.qpos[:] = fp.qpos
    mujoco.mj_forward(m, d)
    sens = {s: d.sensordata[exo.sensor_adr[n]] for s, n in zip(
        ("left", "right", "floor"), ("robustgait_contact_left", "robustgait_contact_right", "robustgait_contact_floor"),
        strict=True)}
    assert sens["floor"] - sens["left"] - sens["right"] == 0 and sens["left"] + sens["right"] > 0
    d.qpos[0] = x + 0.3  # over the tiles: the pelvis box sinks into them
    d.qpos[2] = 0.05
    mujoco.mj_forward(m, d)
    assert d.sensordata[exo.sensor_adr["robustgait_contact_floor"]] > 0
    assert d.sensordata[exo.sensor_adr["robustgait_contact_left"]] == 0


@pytest.mark.slow  # seconds of its own: plain pytest stays ≤ 60 s; CI runs it
def test_certificate_ref_round_trip_and_errors(tmp_path, exo, exo_gait, small_cert):
    p = tmp_path / "cert.json"
    p.write_text(json.dumps(small_cert.to_dict()))
    ref = CertificateRef.load(p)
    assert ref.value == small_cert.value and ref.map == "auto" and dict(ref.orbit)["map"] == "auto"
    np.testing.assert_allclose(ref.x_star, small_cert.certificate.x_star)
    assert ref.space == "omega" and ref.set == "ball" and ref.horizon == 1
    bad = tmp_path / "bad.json"
    bad.write_text('{"r_star": 1}')
    with pytest.raises(RobustGaitError, match=r"bad\.json: attained: required, but missing"):
        CertificateRef.load(bad)
    failed = tmp_path / "failed.json"
    failed.write_text('{"status": "no_fixed_point", "reason": "no iterate converged", "r_star": 0.0}')
    with pytest.raises(RobustGaitError, match="status 'no_fixed_point'"):
        CertificateRef.load(failed)
    gait_path = tmp_path / "gait.json"
    save_gait(exo_gait, gait_path)
    code = main(["validate", str(gait_path), "--robot", "exo", "--certificate", str(p), "--trials", "4",
                 "--steps-after", "2", "--json", "--plot", str(tmp_path / "v.png"), "-o", str(tmp_path / "v.json")])
    assert code == 0
    full = json.loads((tmp_path / "v.json").read_text())
    assert full["kinds"]["push"]["trials"] == 4 and len(full["kinds"]["push"]["trials_detail"]["size"]) == 4
    assert (tmp_path / "v.png").stat().st_size > 10_000
    assert main(["validate", str(gait_path), "--robot", "exo", "--certificate", str(bad)]) == 2


@pytest.mark.slow  # seconds of its own: plain pytest stays ≤ 60 s; CI runs it
def test_a_push_certificate_with_an_unused_state_choice_still_loads(tmp_path, exo, exo_gait):
    """Before J* and a state choice were exclusive, `certify --disturbance push --state velocity` wrote the unused
    state into the certificate's config: it loads as the push certificate it is."""
    gc = certify_gait(exo, exo_gait, CertifyConfig(disturbance="push", method="uniform", n_samples=4,
                                                    push={"horizon": 1}))
    d = gc.to_dict()
    d["config"] = {**d["config"], "state": "velocity", "set": "ellipsoid", "horizon": 2}
    # a certificate of the fixed-point search's version: fields it had that the orbit search retired are dropped
    d["config"]["fp_window"], d["config"]["push"]["steps"] = 20, 3
    p = tmp_path / "push.json"
    p.write_text(json.dumps(d))
    ref = CertificateRef.load(p)
    assert ref.space == "push" and ref.value == gc.value
    assert ref.certify_config(CertifyConfig()).state_choice() == ("omega", "ball", 1)


@pytest.mark.slow  # keeps plain pytest within 60 s; CI runs it
def test_gait_tiles_are_a_real_image(tmp_path, exo, exo_gait):
    import imageio.v2 as imageio

    from robustgait.report.tiles import render_tiles

    out = tmp_path / "tiles.png"
    shape = render_tiles(exo, exo_gait, out, ReportConfig(tile_frames=4, tile_warmup_steps=2), width=160, height=240)
    img = imageio.imread(out)
    assert shape == (480, 640) and img.shape[:2] == (480, 640)
    assert img.std() > 20  # not blank
    tiles = [img[:240, i * 160:(i + 1) * 160].astype(float) for i in range(4)]
    assert np.abs(tiles[0] - tiles[2]).mean() > 1.0  # the legs move between frames
    assert np.abs(img[:240].astype(float) - img[240:].astype(float)).mean() > 5  # side and front differ


# ---- multi-contact gaits: a step is the previous leg's double support, then single support to heel strike -----
@pytest.fixture(scope="module")
def mc_validator(exo, exo_mc_gait):
    cert = certify_gait(exo, exo_mc_gait, CertifyConfig(method="uniform", disturbance="state", n_samples=8))
    with Validator(exo, exo_mc_gait, ValidateConfig(trials=4, steps_after=2), certificate=cert) as v:
        yield v


def test_multicontact_zero_push_in_either_domain_is_the_undisturbed_walk(mc_validator):
    v = mc_validator
    ds = v.gait.domains[1].duration / v.gait.step_duration  # the step from x* starts with double support
    assert len(v.segment_horizons) == 2 and 0.05 < ds < 0.6
    zero = Draws("push", np.zeros(2), {"direction": np.zeros(2), "phase": np.array([0.5 * ds, 0.55])})
    res = v.run("push", draws=zero)
    from robustgait.validate import simulate_trials

    fp = v.fixed_point
    ok, _, _, first, _ = simulate_trials(v.engine, fp.qpos[None], fp.qvel[None], 3, 1, lambda *a: None,
                                         first_at=v.nominal_at)
    nq = v.robot.model.nq
    x1 = v.certificate.to_z(v.reduced.phi(first[:, :nq], first[:, nq:]))
    assert ok[0] and res.success.all()
    np.testing.assert_array_equal(res.x_first, np.repeat(x1, 2, axis=0))
    # x̄₁ is the heel-strike section after one step: the map's image of x̄*, within the orbit's own scatter (a
    # multi-contact gait's band is noisy: σ 0.02 rad/s in ω)
    assert res.distance.max() < 0.05


def test_multicontact_pushes_act_in_the_domain_they_start_in(mc_validator, exo):
    """A push in double support and one in single support, both large: each changes the walk from its own segment
    on (the same push later in the step changes nothing before it), and a huge one falls."""
    v = mc_validator
    ds = v.gait.domains[1].duration / v.gait.step_duration
    d = Draws("push", np.array([40.0, 40.0, exo.mass * 5.0, 0.0]),
              {"direction": np.full(4, math.pi / 2), "phase": np.array([0.2 * ds, 0.55, 0.3, 0.55])})
    res = v.run("push", draws=d)
    assert not res.success[2] and res.success[3]
    moved = np.linalg.norm(res.x_first[:2] - res.x_first[3], axis=1)
    assert np.all(moved[np.isfinite(moved)] > 1e-3)
    wrench = dist_push_windows(v, d)
    assert wrench[0] < v.segment_horizons[0] <= wrench[1]  # the first push starts in double support, the second after


def dist_push_windows(v, d):  # type: ignore[no-untyped-def]
    """Physics step of each push's start in the first step (from its phase)."""
    return np.round(d.params["phase"] * v.gait.step_duration / v.robot.dt).astype(int)


@pytest.mark.slow  # keeps plain pytest within 60 s; CI runs it
def test_every_kind_runs_on_a_multicontact_gait(mc_validator):
    for kind in ("mass", "latency", "noise", "terrain", "slope"):
        s = mc_validator.run(kind).summary()
        assert s["trials"] == 4 and 0 <= s["success"]["k"] <= 4


def test_terrain_replaces_the_floor_the_loader_resolved(tmp_path):
    """The terrain replaces the robot's floor as loaded — here the plane ``add_floor`` adds — not only a floor the
    spec names (``floor_geom``)."""
    exo_xml = Path(dist.__file__).parents[1] / "robots" / "exo" / "exo.xml"
    mjs = mujoco.MjSpec.from_file(str(exo_xml))
    mjs.delete(mjs.geom("floor"))
    (tmp_path / "exo.xml").write_text(mjs.to_xml())
    text = exo_xml.with_name("spec.toml").read_text()
    assert 'floor_geom = "floor"' in text
    (tmp_path / "spec.toml").write_text(text.replace('floor_geom = "floor"', "add_floor = true"))
    robot = load_robot(tmp_path / "spec.toml")
    assert robot.spec.floor_geom is None
    m = dist.terrain_model(robot, dist.TerrainLayout(x0=-1.0, rough_from=0.3, y0=-1.0, tile=0.5, nx=2, ny=4))
    assert m.geom_type[m.geom(robot.floor_name).id] == mujoco.mjtGeom.mjGEOM_BOX
    assert m.geom("robustgait_tile_1_3").id > 0
