"""Writing gaits as FROST/ambersim YAML (robustgait.io.gaitfile.save_frost_yaml, ``gait convert --to frost``):
the file the importer reads back walks bit for bit as the original; what the layout cannot hold is refused with
one line, nothing written. Reading either format and its bad inputs: tests/io/test_io.py, tests/cli/test_inputs.py."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import yaml

from robustgait import load_gait
from robustgait.gait import Gait
from robustgait.io.gaitfile import frost_yaml_dict, import_frost_yaml, save_frost_yaml, save_gait
from robustgait.sim.walk import WalkResult, walk
from tests.conftest import ATALANTE_GAIT, ATALANTE_SPEC, EXO_GAIT, EXO_MC_GAIT, needs_atalante, standing_gait
from tests.io.test_io import cli, one_error_line

WALK_STEPS = 20


def assert_same_gait(a: Gait, b: Gait) -> None:
    """β, T, feedforward and the initial state equal to the last bit (and of the same shapes)."""
    assert (a.stance, a.domain_graph, len(a.domains)) == (b.stance, b.domain_graph, len(b.domains))
    for da, db in zip(a.domains, b.domains, strict=True):
        assert da.duration == db.duration
        assert np.array_equal(da.beta, db.beta)
        for x, y in ((da.ff_tau, db.ff_tau), (da.ff_torque, db.ff_torque)):
            assert (x is None) == (y is None) and (x is None or np.array_equal(x, y))
    sa, sb = a.initial_state, b.initial_state
    assert (sa is None) == (sb is None)
    if sa is not None and sb is not None:
        assert np.array_equal(sa.qpos, sb.qpos) and np.array_equal(sa.qvel, sb.qvel)


def assert_same_walk(a: WalkResult, b: WalkResult) -> None:
    """The same steps, falls and switching-event states to the last bit."""
    assert (a.steps_taken, a.fell, a.fall_reason, a.time) == (b.steps_taken, b.fell, b.fall_reason, b.time)
    assert a.tracking == b.tracking
    assert len(a.events) == len(b.events)
    for ea, eb in zip(a.events, b.events, strict=True):
        assert (ea.step, ea.time, ea.stance, ea.tau) == (eb.step, eb.time, eb.stance, eb.tau)
        assert np.array_equal(ea.qpos, eb.qpos) and np.array_equal(ea.qvel, eb.qvel)


def convert(src, out, *extra):  # type: ignore[no-untyped-def]
    code, stdout, err = cli("gait", "convert", src, "--robot", "exo", "-o", out, *extra)
    assert code == 0, err
    return stdout


def test_exo_gait_round_trip_walks_bit_for_bit(tmp_path, exo, exo_gait):
    """The stored exo gait (feedforward torques, params, solver report) → FROST YAML → read back: the same
    β, T, feedforward and initial state, and a 20-step walk whose every switching state is identical."""
    assert exo_gait.domains[0].ff_torque is not None
    out = tmp_path / "g.yaml"
    assert "FROST/ambersim YAML" in convert(EXO_GAIT, out)
    back = load_gait(out, exo)
    assert_same_gait(exo_gait, back)
    a, b = walk(exo, exo_gait, steps=WALK_STEPS), walk(exo, back, steps=WALK_STEPS)
    assert a.steps_taken == WALK_STEPS and not a.fell
    assert_same_walk(a, b)
    # the layout ambersim reads: coeff_jt in Fortran order, the initial state split into base and joints
    raw = yaml.safe_load(out.read_text())
    assert raw["coeff_jt"] == exo_gait.domains[0].beta.ravel(order="F").tolist()
    assert raw["ffPos"] + raw["startingPos"] == exo_gait.initial_state.qpos.tolist()
    assert raw["step_dur"] == 0.7 and len(raw["ff_torque"]) == len(raw["ff_tau"])
    assert not {"params", "solver", "meta", "pre_impact_state"} & set(raw)


def test_to_frost_and_yml_suffix(tmp_path, exo, exo_gait):
    out = tmp_path / "g.yml"
    convert(EXO_GAIT, out, "--to", "frost")
    assert_same_gait(exo_gait, load_gait(out, exo))
    convert(out, tmp_path / "g.json", "--to", "json")
    assert_same_gait(exo_gait, load_gait(tmp_path / "g.json", exo))


def test_floats_read_back_exactly(tmp_path, exo):
    """Coefficients, durations and states with every bit used (thirds, tiny and large magnitudes, −0.0)."""
    g = standing_gait(exo, extras=True)
    rng = np.random.default_rng(7)
    d = g.domains[0]
    beta = d.beta + rng.normal(size=d.beta.shape) / 3.0 * 10.0 ** rng.integers(-12, 2, size=d.beta.shape)
    beta[0, :3] = [-0.0, 5e-324, 1.0 / 3.0]
    torque = rng.normal(size=d.ff_torque.shape) * 37.0
    s = g.initial_state
    qvel = s.qvel + rng.normal(size=s.qvel.shape) * 1e-3
    g = dataclasses.replace(g, domains=(dataclasses.replace(d, duration=0.7000000000000001, beta=beta,
                                                            ff_torque=torque),),
                            initial_state=dataclasses.replace(s, qvel=qvel))
    save_frost_yaml(g, tmp_path / "f.yaml")
    back = import_frost_yaml(tmp_path / "f.yaml", exo)
    assert_same_gait(g, back)
    assert str(back.domains[0].beta[0, 0]) == "-0.0"


def test_without_initial_state_or_feedforward(tmp_path, exo):
    g = dataclasses.replace(standing_gait(exo), initial_state=None)
    save_frost_yaml(g, tmp_path / "f.yaml")
    raw = yaml.safe_load((tmp_path / "f.yaml").read_text())
    assert set(raw) == {"coeff_jt", "step_dur"}
    assert_same_gait(g, load_gait(tmp_path / "f.yaml", exo))


def test_left_stance_is_refused_and_mirror_writes_it_right(tmp_path, exo, exo_gait):
    left = tmp_path / "left.json"
    save_gait(exo_gait.mirrored(exo), left)
    out = tmp_path / "l.yaml"
    code, stdout, err = cli("gait", "convert", left, "--robot", "exo", "-o", out)
    assert code == 2 and stdout == "" and not out.exists()
    one_error_line(err, f"{left}: stance: a left-stance gait", "--mirror")
    convert(left, out, "--mirror")  # relabeled back to right stance: sign flips and a permutation are exact
    back = load_gait(out, exo)
    assert_same_gait(exo_gait, back)


def test_multicontact_is_refused(tmp_path):
    out = tmp_path / "m.yaml"
    out.write_text("keep: me\n")
    code, stdout, err = cli("gait", "convert", EXO_MC_GAIT, "--robot", "exo", "-o", out)
    assert code == 2 and stdout == "" and out.read_text() == "keep: me\n"
    one_error_line(err, f"{EXO_MC_GAIT}: domain_graph: a multicontact gait has 2 domains", "keep it as .json")
    assert list(tmp_path.iterdir()) == [out]  # no temporary file left


@pytest.mark.parametrize("name, to, message", [
    ("g.json", "frost", "--to frost writes a .yaml or .yml file, but the output is named '.json'"),
    ("g.yaml", "json", "--to json writes a .json file, but the output is named '.yaml'"),
])
def test_to_contradicting_the_suffix_is_refused(tmp_path, name, to, message):
    code, stdout, err = cli("gait", "convert", EXO_GAIT, "--robot", "exo", "-o", tmp_path / name, "--to", to)
    assert code == 2 and stdout == "" and not list(tmp_path.iterdir())
    one_error_line(err, f"{tmp_path / name}: ", message)


def test_unknown_suffix_is_refused_while_parsing(tmp_path):
    code, _, err = cli("gait", "convert", EXO_GAIT, "--robot", "exo", "-o", tmp_path / "g.txt")
    assert code == 2
    one_error_line(err, "unknown gait file format '.txt' (expected .json, .yaml or .yml)")


def test_what_the_importer_would_refuse_is_not_written(tmp_path, exo, exo_gait):
    """FROST's own keys carried in meta are written back only if they read back."""
    bad = dataclasses.replace(exo_gait, meta={"frost_coeff_b": ["a"]})
    src = tmp_path / "bad.json"
    save_gait(bad, src)
    code, _, err = cli("gait", "convert", src, "--robot", "exo", "-o", tmp_path / "b.yaml")
    assert code == 2 and not (tmp_path / "b.yaml").exists()
    one_error_line(err, f"{src}: coeff_b[0]: expected a number, got a string")


@pytest.mark.parametrize("mutate, message", [
    (lambda d: d.pop("ff_torque"), "ff_torque: missing: the feedforward needs all of ff_tau, ff_torque"),
    (lambda d: d["ff_tau"].__setitem__(1, d["ff_tau"][0]), "ff_tau: phases must increase strictly"),
    (lambda d: d["ff_torque"][2].pop(), "ff_torque[2]: must be"),
    (lambda d: d["ff_torque"].pop(), "ff_torque: must be"),
    (lambda d: d["ff_tau"].__setitem__(0, "0"), "ff_tau[0]: expected a number, got a string"),
])
def test_bad_feedforward_keys(tmp_path, exo, exo_gait, mutate, message):
    data = frost_yaml_dict(exo_gait)
    mutate(data)
    p = tmp_path / "f.yaml"
    p.write_text(yaml.safe_dump(data))
    code, _, err = cli("walk", p, "--robot", "exo", "--steps", "1")
    assert code == 2
    one_error_line(err, f"{p}: {message}")


@pytest.mark.slow  # seconds of its own: plain pytest stays ≤ 60 s; CI runs it
@needs_atalante
def test_atalante_frost_to_json_to_frost_walks_bit_for_bit(tmp_path, atalante, atalante_gait):
    """AMBER's Atalante file → robustgait JSON → FROST YAML → read again: the same walk, and FROST's own
    coeff_b and inputparams written back unchanged."""
    j, y = tmp_path / "a.json", tmp_path / "a.yaml"
    for src, out in ((ATALANTE_GAIT, j), (j, y)):
        code, _, err = cli("gait", "convert", src, "--robot", ATALANTE_SPEC, "-o", out)
        assert code == 0, err
    back = load_gait(y, atalante)
    assert_same_gait(atalante_gait, back)
    a, b = walk(atalante, atalante_gait, steps=WALK_STEPS), walk(atalante, back, steps=WALK_STEPS)
    assert a.steps_taken == WALK_STEPS
    assert_same_walk(a, b)
    original, written = yaml.safe_load(ATALANTE_GAIT.read_text()), yaml.safe_load(y.read_text())
    for key in ("coeff_jt", "step_dur", "ffPos", "startingPos", "ffVel", "startingVel", "coeff_b", "inputparams"):
        assert written[key] == original[key], key


def test_a_line_break_in_a_name_stays_in_the_comment(tmp_path, exo):
    g = dataclasses.replace(standing_gait(exo), robot="exo\nstep_dur: 5.0\u2028coeff_b: [1.0]")
    save_frost_yaml(g, tmp_path / "f.yaml")
    raw = yaml.safe_load((tmp_path / "f.yaml").read_text())
    assert raw["step_dur"] == 0.7 and "coeff_b" not in raw


def test_a_robot_with_held_joints(tmp_path):
    """startingPos/startingVel carry every joint (held ones too, MJCF order); the importer takes the held angles
    from the robot spec, so the gait reads back whole."""
    from robustgait import load_robot
    from tests.robots.test_any_robot import biped_spec, biped_xml

    robot = load_robot(biped_spec(tmp_path, xml=biped_xml()))
    held = tuple((h.name, h.angle) for h in robot.spec.held)
    g = dataclasses.replace(standing_gait(robot), held=held)
    save_frost_yaml(g, tmp_path / "b.yaml")
    raw = yaml.safe_load((tmp_path / "b.yaml").read_text())
    assert len(raw["coeff_jt"]) == 10 * 8 and len(raw["startingPos"]) == 12
    back = load_gait(tmp_path / "b.yaml", robot)
    assert_same_gait(g, back)
    assert back.held == held == (("left_shoulder", 0.3), ("right_shoulder", 0.3))
    with pytest.raises(Exception, match=r"startingPos: has 12 values, expected 10 \(one per joint\)"):
        import_frost_yaml(tmp_path / "b.yaml")  # without the robot nothing says two joints are held
