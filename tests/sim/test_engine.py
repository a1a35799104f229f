import itertools
from pathlib import Path

import mujoco
import numpy as np
import pytest

from robustgait import RobustGaitError, SimConfig, StepEngine, load_robot, walk
from robustgait.sim import render_video


@pytest.mark.slow  # seconds of its own: plain pytest stays ≤ 60 s; CI runs it
def test_gait_walks_on_a_mirrored_period_one_orbit(robot_gait):
    robot, gait = robot_gait
    res = walk(robot, gait, steps=40, keep_trajectory=True)
    assert res.steps_taken == 40 and not res.fell
    assert res.min_base_height > 0.85 and np.all(res.trajectory[:, 3] > 0.85)
    taus = np.array([e.tau for e in res.events])
    if robot.name == "atalante":
        # the lab's FROST gait (designed for its controller, which switched after τ = 0.8) lands early
        assert 0.08 <= res.mean_speed <= 0.20 and np.all((taus >= 0.8) & (taus < 1.0))
    else:
        # a generated gait walks at its nominal speed L/T and lands where it was planned, at τ = 1
        p = gait.params
        assert res.mean_speed == pytest.approx(p.step_length / p.step_duration, rel=0.03)
        assert np.all(np.abs(taus[5:] - 1.0) < 0.01)
    # stances alternate and the reduced state (base angular velocity) settles into a mirrored period-1 orbit
    assert [e.stance for e in res.events[:4]] == ["right", "left", "right", "left"]
    w = np.array([e.qvel[3:6] for e in res.events[-4:]])
    np.testing.assert_allclose(w[2], w[0], atol=0.02)
    np.testing.assert_allclose(w[1], w[0] * [-1, 1, -1], atol=0.03)


@pytest.mark.slow  # seconds of its own: plain pytest stays ≤ 60 s; CI runs it
def test_generated_gait_keeps_the_pelvis_level(exo, exo_gait):
    """The exoskeleton-grade bounds of gait generation hold in simulation: pelvis roll within ±6°."""
    from robustgait.rotations import quat_to_mat

    res = walk(exo, exo_gait, steps=50, keep_trajectory=True)
    r = quat_to_mat(res.trajectory[:, 4:8])
    roll = np.degrees(np.arctan2(r[:, 2, 1], r[:, 2, 2]))
    assert res.steps_taken == 50 and np.abs(roll).max() < 6.0


def test_stance_foot_does_not_slip(robot_gait):
    robot, gait = robot_gait
    res = walk(robot, gait, steps=6, keep_trajectory=True)
    m, d = robot.model, mujoco.MjData(robot.model)
    times = [0.0] + [e.time for e in res.events]
    stance = gait.stance
    tr = res.trajectory
    for t0, t1 in itertools.pairwise(times):
        pos = []
        # single support, after the post-impact weight transfer (which rolls the foot by up to ~1 cm)
        for t in (t0 + 0.3, t1 - 0.05):
            mujoco.mj_setState(m, d, tr[np.argmin(np.abs(tr[:, 0] - t))], mujoco.mjtState.mjSTATE_FULLPHYSICS)
            mujoco.mj_kinematics(m, d)
            pos.append(d.geom_xpos[robot.sole_geom_id[stance]].copy())
        assert np.linalg.norm(pos[1][:2] - pos[0][:2]) < 0.003
        stance = "left" if stance == "right" else "right"


def test_batch_matches_single_and_detects_falls(robot_gait):
    robot, gait = robot_gait
    s = gait.initial_state
    qpos = np.tile(s.qpos, (4, 1))
    qvel = np.tile(s.qvel, (4, 1))
    qvel[2, 3] += 4.0  # a violent roll-rate kick: must fall, not crash
    qvel[3, 5] = np.nan  # a NaN state has diverged: a fall
    with StepEngine(robot, gait) as eng:
        batch = eng.step(qpos, qvel, "right")
        single = eng.step(qpos[:1], qvel[:1], "right")
    assert list(batch.fell) == [False, False, True, True]
    assert batch.fall_reason[3] == "diverged" and batch.fall_reason[2] in ("tilt", "base_low", "non_foot_contact",
                                                                           "no_touchdown")
    np.testing.assert_array_equal(batch.qpos[0], single.qpos[0])
    np.testing.assert_array_equal(batch.qvel[0], batch.qvel[1])
    assert np.isnan(batch.qpos[2]).all()
    assert 0.8 <= batch.tau[0] < 1.05


def test_time_switching_switches_at_tau_one(robot_gait):
    robot, gait = robot_gait
    with StepEngine(robot, gait, SimConfig(switching="time")) as eng:
        s = gait.initial_state
        b = eng.step(s.qpos, s.qvel, "right")
    assert not b.fell[0] and b.tau[0] == pytest.approx(1.0)


def test_bad_sim_inputs(exo, exo_gait):
    with pytest.raises(RobustGaitError):
        SimConfig(switching="sometimes")
    with pytest.raises(RobustGaitError, match="steps must be"):
        walk(exo, exo_gait, steps=0)
    with StepEngine(exo, exo_gait) as eng, pytest.raises(RobustGaitError, match="states must be"):
        eng.step(np.zeros((2, 5)), np.zeros((2, 18)), "right")


def mp4_facts(path: Path) -> dict[str, object]:
    """What a browser needs of an .mp4: its codec, pixel format, size, frames per second and frames (decoded to the
    last), and whether its index (``moov``) comes before the frames (``mdat``: playable as it loads)."""
    import imageio_ffmpeg

    reader = imageio_ffmpeg.read_frames(str(path))
    meta = next(reader)
    frames = sum(1 for _ in reader)
    data = path.read_bytes()
    return {"codec": meta["codec"], "pix_fmt": meta["pix_fmt"].split("(")[0], "size": tuple(meta["size"]),
            "fps": meta["fps"], "frames": frames, "index_first": 0 <= data.find(b"moov") < data.find(b"mdat")}


@pytest.mark.slow  # rendering / a second map: keeps plain pytest ≤ 60 s; CI runs it
def test_video(tmp_path, exo, exo_gait):
    res = walk(exo, exo_gait, steps=1, keep_trajectory=True)
    out = tmp_path / "walk.mp4"
    try:
        frames = render_video(exo, res.trajectory, out, fps=10, width=96, height=64)
    except RobustGaitError as exc:  # no EGL/OSMesa on this machine: the message must say what to do
        assert "MUJOCO_GL" in str(exc)
        return
    # a frame every 0.1 s of physics steps from the first: ceil(n / every), played at 10 fps, H.264 a browser plays
    every = round(0.1 / exo.dt)
    assert frames == -(-len(res.trajectory) // every) == pytest.approx(res.time * 10, abs=1)
    assert mp4_facts(out) == {"codec": "h264", "pix_fmt": "yuv420p", "size": (96, 64), "fps": 10.0, "frames": frames,
                              "index_first": True}
    fast = tmp_path / "fast.mp4"
    assert render_video(exo, res.trajectory, fast, fps=10, width=96, height=64, shadows=False,
                        antialias=False) == frames
    assert mp4_facts(fast)["frames"] == frames


@pytest.mark.slow  # rendering: keeps plain pytest ≤ 60 s; CI runs it
def test_fast_rendering_draws_the_same_robot(exo, exo_gait):
    """Without shadows, reflections and multisampling (the reports' videos) a frame draws the same robot in the same
    place; the robot's own model keeps its settings; the pose drawn from qpos alone (pose_for_drawing) is the one
    mj_forward gives, pixel for pixel."""
    from robustgait.sim.walk import offscreen_renderer, pose_for_drawing, scene_option

    res = walk(exo, exo_gait, steps=1, keep_trajectory=True)
    state = res.trajectory[len(res.trajectory) // 2]
    m = exo.model
    samples = m.vis.quality.offsamples
    cam = mujoco.MjvCamera()
    cam.type, cam.trackbodyid = mujoco.mjtCamera.mjCAMERA_TRACKING, exo.base_body_id
    cam.distance, cam.elevation, cam.azimuth = 3.0, -15.0, 120.0
    images = {}
    for shadows, pose in ((True, mujoco.mj_forward), (True, pose_for_drawing), (False, pose_for_drawing)):
        try:
            renderer = offscreen_renderer(exo, 160, 120, shadows=shadows, antialias=shadows)
        except RobustGaitError:  # no EGL/OSMesa here: test_video checks the message
            return
        with renderer:
            assert bool(renderer.scene.flags[mujoco.mjtRndFlag.mjRND_SHADOW]) == shadows
            data = mujoco.MjData(m)
            mujoco.mj_setState(m, data, state, mujoco.mjtState.mjSTATE_FULLPHYSICS.value)
            pose(m, data)
            renderer.update_scene(data, cam, scene_option=scene_option(exo))
            images[(shadows, pose.__name__)] = renderer.render().astype(int)
    assert m.vis.quality.offsamples == samples
    np.testing.assert_array_equal(images[(True, "mj_forward")], images[(True, "pose_for_drawing")])
    # the robot covers the same pixels, give or take its edges
    skin = {k: np.ptp(v, axis=2) > 40 for k, v in images.items()}  # the passenger's orange: the floor is grey
    fast, full = skin[(False, "pose_for_drawing")], skin[(True, "mj_forward")]
    assert fast.sum() > 300 and (fast ^ full).sum() < 0.15 * fast.sum()


def test_a_diverging_sample_is_a_silent_fall(tmp_path, monkeypatch, capfd):
    """MuJoCo warns (QACC) from its rollout threads when a sample blows up: the engine counts it as a fall
    'diverged' and nothing reaches the terminal or a MUJOCO_LOG.TXT."""
    from tests.conftest import standing_gait

    robot = load_robot("exo")
    gait = standing_gait(robot)
    monkeypatch.chdir(tmp_path)
    s = gait.initial_state
    qpos, qvel = np.tile(s.qpos, (3, 1)), np.tile(s.qvel, (3, 1))
    qvel[1, 3] += 1e6  # MuJoCo's bad-acceleration warning, and its automatic reset
    qvel[2, 4] += 1e3  # faster than SimConfig.max_speed
    with StepEngine(robot, gait) as eng:
        batch = eng.step(qpos, qvel, gait.stance)
    assert batch.fall_reason == [None, "diverged", "diverged"] and list(batch.fell) == [False, True, True]
    out, err = capfd.readouterr()
    assert "WARNING" not in out + err and not (tmp_path / "MUJOCO_LOG.TXT").exists()
    config = mujoco.MjLogConfig.get()  # restored after the rollout
    assert config.logto_console and config.logto_file


@pytest.mark.slow  # keeps plain pytest within 60 s; CI runs it
def test_multicontact_gait_rolls_both_feet(exo, exo_mc_gait):
    """Heel strike → rolling double support → foot-flat: in every double support of a 50-step walk the back sole
    pitches toe-down and the front sole from toe-up to flat, each by ≥ 10°, and double
    support ends at foot-flat by τ = 1."""
    res = walk(exo, exo_mc_gait, steps=50, keep_trajectory=True)
    assert res.steps_taken == 50 and not res.fell
    p = exo_mc_gait.params
    assert res.mean_speed == pytest.approx(p.step_length / p.step_duration, rel=0.03)
    m, d = exo.model, mujoco.MjData(exo.model)
    tr = res.trajectory
    t_ds = exo_mc_gait.domains[1].duration

    def pitch(k, side):
        mujoco.mj_setState(m, d, tr[k], mujoco.mjtState.mjSTATE_FULLPHYSICS)
        mujoco.mj_kinematics(m, d)
        return np.degrees(-np.arcsin(d.geom_xmat[exo.sole_geom_id[side]].reshape(3, 3)[2, 0]))

    for e in res.events[10:20]:
        k0 = int(np.argmin(np.abs(tr[:, 0] - e.time)))
        ks = range(k0, k0 + round(t_ds / exo.dt), 5)
        back, front = e.stance, "left" if e.stance == "right" else "right"
        b, f = [pitch(k, back) for k in ks], [pitch(k, front) for k in ks]
        assert max(b) - min(b) >= 10.0 and max(f) - min(f) >= 10.0
        assert min(f) < -10.0 and abs(f[-1]) < 2.0  # toe up at heel strike, flat at the end


def test_multicontact_domains_in_the_engine(exo, exo_mc_gait):
    with StepEngine(exo, exo_mc_gait) as eng:
        assert len(eng.graph) == 2 and eng.horizons[1] == round(exo_mc_gait.domains[1].duration / exo.dt)
        s = exo_mc_gait.initial_state
        ss = eng.step(s.qpos, s.qvel, "right", domain=0)
        ds = eng.step(ss.qpos, ss.qvel, "right", domain=1)
        assert not ss.fell[0] and not ds.fell[0] and 0.8 <= ds.tau[0] <= 1.0
        with pytest.raises(RobustGaitError, match="no domain 2"):
            eng.step(s.qpos, s.qvel, "right", domain=2)
