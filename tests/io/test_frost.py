import json

import mujoco
import numpy as np
import pytest

from robustgait import Gait, GaitParams, RobustGaitError, load_gait
from robustgait.io.gaitfile import gait_from_dict, import_frost_yaml, save_gait
from tests.conftest import write_frost_yaml


def test_frost_import_reshapes_fortran_order(atalante, atalante_gait):
    g = atalante_gait
    assert g.stance == "right" and g.domain_graph == "flat" and g.step_duration == 1.0
    beta = g.domains[0].beta
    assert beta.shape == (12, 8)
    # column 0 of the Fortran-order reshape is the initial joint position of the orbit
    np.testing.assert_allclose(beta[:, 0], g.initial_state.qpos[7:], atol=1e-5)
    assert g.joints == atalante.spec.joints
    assert g.meta["frost_inputparams"]["desired_stepduration"] == 1.0


def test_frost_import_of_a_written_file(tmp_path, exo, exo_gait):
    """The FROST importer on a file written from exo's gait: β back exactly (Fortran order), state, meta."""
    p = write_frost_yaml(exo_gait, tmp_path / "g.yaml", inputparams={"desired_stepduration": 0.7})
    g = import_frost_yaml(p, exo)
    assert g.stance == "right" and g.domain_graph == "flat" and g.step_duration == exo_gait.step_duration
    np.testing.assert_array_equal(g.domains[0].beta, exo_gait.domains[0].beta)
    np.testing.assert_allclose(g.initial_state.qpos, exo_gait.initial_state.qpos, atol=1e-12)
    np.testing.assert_array_equal(g.initial_state.qvel, exo_gait.initial_state.qvel)
    assert g.joints == exo.spec.joints and g.meta["frost_inputparams"]["desired_stepduration"] == 0.7


def test_json_round_trip_is_exact(tmp_path, flat_robot_gait):
    robot, gait = flat_robot_gait
    g = gait.mirrored(robot)
    g = Gait(**{**g.__dict__, "params": GaitParams(0.12, 1.0, 0.3, 0.1), "solver": {"status": "x", "iter": 3}})
    p = tmp_path / "g.json"
    save_gait(g, p)
    back = load_gait(p, robot)
    assert back.to_dict() == g.to_dict()
    assert np.array_equal(back.domains[0].beta, g.domains[0].beta)
    assert back.params == g.params
    assert json.loads(p.read_text())["schema_version"] == 1


def test_mirror_is_an_involution_and_matches_the_lab_relabeling(flat_robot_gait):
    robot, g = flat_robot_gait
    m = g.mirrored(robot)
    assert m.stance == "left"
    b, bm = g.domains[0].beta, m.domains[0].beta
    sign = np.array([-1, -1, 1, 1, 1, -1], float)
    np.testing.assert_array_equal(bm[:6], b[6:] * sign[:, None])
    np.testing.assert_array_equal(bm[6:], b[:6] * sign[:, None])
    mm = m.mirrored(robot)
    np.testing.assert_allclose(mm.domains[0].beta, b)
    np.testing.assert_allclose(mm.initial_state.qpos, g.initial_state.qpos)
    np.testing.assert_allclose(mm.initial_state.qvel, g.initial_state.qvel)


def test_mirrored_state_is_the_reflected_pose(flat_robot_gait):
    """Mirroring the state must mirror every body's world position about the sagittal (xz) plane."""
    robot, gait = flat_robot_gait
    model = robot.model
    d0, d1 = mujoco.MjData(model), mujoco.MjData(model)
    s = gait.initial_state
    qp, qv = robot.mirror_state(s.qpos, s.qvel)
    d0.qpos[:], d0.qvel[:] = s.qpos, s.qvel
    d1.qpos[:], d1.qvel[:] = qp, qv
    mujoco.mj_forward(model, d0)
    mujoco.mj_forward(model, d1)
    lsole, rsole = robot.sole_geom_id["left"], robot.sole_geom_id["right"]
    flip = np.array([1.0, -1.0, 1.0])
    np.testing.assert_allclose(d1.geom_xpos[rsole], d0.geom_xpos[lsole] * flip, atol=2e-4)
    np.testing.assert_allclose(d1.geom_xpos[lsole], d0.geom_xpos[rsole] * flip, atol=2e-4)
    # the base's world-frame angular velocity maps as a pseudo-vector: (−ωx, ωy, −ωz)
    w0 = d0.xmat[robot.base_body_id].reshape(3, 3) @ s.qvel[3:6]
    w1 = d1.xmat[robot.base_body_id].reshape(3, 3) @ qv[3:6]
    np.testing.assert_allclose(w1, w0 * np.array([-1.0, 1.0, -1.0]), atol=1e-12)


def test_gait_params_bounds():
    assert GaitParams().step_length == 0.15
    assert GaitParams().step_duration is None and GaitParams().resolved("multicontact").step_duration == 0.9
    for bad, message in (({"step_duration": 0.0}, "step_duration: must satisfy 0.1 ≤ x ≤ 5 s"),
                         ({"step_height": -0.01}, "step_height: must satisfy"),
                         ({"step_length": float("nan")}, "step_length: must be a finite number")):
        with pytest.raises(RobustGaitError, match=f"GaitParams.{message}"):
            GaitParams(**bad)


@pytest.mark.parametrize("mutate, message", [
    (lambda d: d["domains"][0].__setitem__("beta", [row[:7] for row in d["domains"][0]["beta"]]),
     r"domains\[0\]\.beta\[0\]: must have exactly 8 items \(got 7\)"),
    (lambda d: d["domains"][0]["beta"][3].__setitem__(2, float("nan")),
     r"domains\[0\]\.beta\[3\]\[2\]: must be a finite number \(got nan\)"),
    (lambda d: d["joints"].__setitem__(0, "NoSuchJoint"), "joints: unknown joint name 'NoSuchJoint'"),
    (lambda d: d.__setitem__("schema_version", 99), r"schema_version: must be one of 1 \(got 99\)"),
    (lambda d: d.__setitem__("stance", "middle"), "stance: must be one of 'left', 'right'"),
])
def test_bad_gait_json(tmp_path, flat_robot_gait, mutate, message):
    robot, gait = flat_robot_gait
    d = gait.to_dict()
    mutate(d)
    p = tmp_path / "bad.json"
    p.write_text(json.dumps(d))
    with pytest.raises(RobustGaitError, match=message) as err:
        load_gait(p, robot)
    assert str(p) in str(err.value) and "\n" not in str(err.value)


def test_malformed_files(tmp_path, exo):
    p = tmp_path / "x.json"
    p.write_text("{not json")
    with pytest.raises(RobustGaitError, match="malformed JSON"):
        load_gait(p, exo)
    y = tmp_path / "x.yaml"
    y.write_text("coeff_jt: [1, 2\nstep_dur: 1")
    with pytest.raises(RobustGaitError, match="malformed YAML"):
        load_gait(y, exo)
    with pytest.raises(RobustGaitError, match="not found"):
        load_gait(tmp_path / "missing.json", exo)
    with pytest.raises(RobustGaitError, match=r"list\.json: expected an object, got a list"):
        gait_from_dict([1, 2], "list.json")


def test_frost_wrong_coefficient_count(tmp_path, exo, exo_gait):
    import yaml

    p = write_frost_yaml(exo_gait, tmp_path / "g.yaml")
    data = yaml.safe_load(p.read_text())
    data["coeff_jt"] = data["coeff_jt"][1:]
    p.write_text(yaml.safe_dump(data))
    with pytest.raises(RobustGaitError, match="coeff_jt: has 95 coefficients, expected 96"):
        import_frost_yaml(p, exo)
