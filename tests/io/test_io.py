"""The input layer and the output writer (robustgait.io): each input defect, one example each, run
through the command line in-process, plus the writer's guarantees. Property-based tests: tests/cli/test_inputs.py."""

from __future__ import annotations

import contextlib
import io
import json
import os
import stat
from pathlib import Path

import numpy as np
import pytest
import yaml

from robustgait import RobustGaitError, load_gait, load_robot
from robustgait.certificate.barrier import load_reduced_log as reexported
from robustgait.cli import main
from robustgait.io import limits as L
from robustgait.io.logs import load_reduced_log
from robustgait.io.output import atomic_output, check_output, kind_of, write_csv, write_text
from tests.conftest import REPO, standing_gait
from tests.robots.test_spec import spec_text

EXO_SPEC = spec_text("exo")


def cli(*argv: str) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main([str(a) for a in argv])
    return code, out.getvalue(), err.getvalue()


def one_error_line(err: str, *needles: str) -> str:
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("robustgait: error: ") and "Traceback" not in err
    for n in needles:
        assert n in lines[0], (n, lines[0])
    return lines[0]


@pytest.fixture(scope="module")
def exo():
    return load_robot("exo")


@pytest.fixture(scope="module")
def gait_dict(exo):
    return standing_gait(exo).to_dict()


@pytest.fixture()
def gait_file(tmp_path, gait_dict):
    def make(mutate=None, name="g.json"):
        d = json.loads(json.dumps(gait_dict))
        if mutate is not None:
            mutate(d)
        p = tmp_path / name
        p.write_text(json.dumps(d))
        return p
    return make


# ------------------------------------------------------------------------------------- gait JSON / YAML
@pytest.mark.parametrize("mutate, message", [
    (lambda d: d.__setitem__("joints", 5), "joints: expected a list, got an integer (5)"),
    (lambda d: d.__setitem__("meta", [1, 2]), "meta: expected an object, got a list"),
    (lambda d: d["domains"][0].__setitem__("duration", "0.7"),
     "domains[0].duration: expected a number, got a string ('0.7'): a quoted number is text"),
    (lambda d: d["domains"][0].__setitem__("duration", True), "domains[0].duration: expected a number, got a boolean"),
    (lambda d: d["domains"][0].__setitem__("duration", 1e6), "domains[0].duration: must satisfy 0.01 ≤ x ≤ 10 s"),
    (lambda d: d["initial_state"]["qpos"].__setitem__(slice(3, 7), [0, 0, 0, 0]),
     "initial_state.qpos[3:7]: base quaternion has norm 0"),
    (lambda d: d["domains"][0]["beta"][2].__setitem__(5, float("nan")),
     "domains[0].beta[2][5]: must be a finite number (got nan)"),
    (lambda d: d["initial_state"]["qvel"].__setitem__(4, float("inf")), "initial_state.qvel[4]: must be a finite"),
    (lambda d: d.__setitem__("inital_state", None), "inital_state: unknown key (known: schema_version"),
    (lambda d: d["initial_state"]["qpos"].pop(), "initial_state.qpos: has 18 values, expected 19"),
    (lambda d: d.__setitem__("solver", {"a": [1, {"b": float("nan")}]}), "solver.a[1].b: must be a finite number"),
    (lambda d: d.pop("domains"), "domains: required, but missing"),
])
def test_bad_gait_json_is_one_line_exit_2(gait_file, mutate, message, no_work):
    p = gait_file(mutate)
    code, out, err = cli("walk", p, "--robot", "exo", "--steps", "2")
    assert code == 2 and out == ""
    one_error_line(err, f"{p}: ", message)


def test_unit_able_quaternion_is_normalized(gait_file, exo):
    p = gait_file(lambda d: d["initial_state"]["qpos"].__setitem__(slice(3, 7), [2.0, 0, 0, 0]))
    assert load_gait(p, exo).initial_state.qpos[3:7].tolist() == [1.0, 0.0, 0.0, 0.0]


@pytest.fixture()
def frost_yaml(tmp_path, exo):
    g = standing_gait(exo)
    s = g.initial_state
    good = {"coeff_jt": g.domains[0].beta.flatten(order="F").tolist(), "step_dur": 0.7,
            "ffPos": s.qpos[:7].tolist(), "startingPos": s.qpos[7:].tolist(), "ffVel": s.qvel[:6].tolist(),
            "startingVel": s.qvel[6:].tolist(), "coeff_b": [0.0] * 48, "inputparams": {"desired_stepduration": 0.7}}

    def make(text_or_mutate=None):
        p = tmp_path / "g.yaml"
        if isinstance(text_or_mutate, bytes):
            p.write_bytes(text_or_mutate)
        else:
            d = json.loads(json.dumps(good))
            if text_or_mutate is not None:
                text_or_mutate(d)
            p.write_text(yaml.safe_dump(d))
        return p
    return make


def test_frost_yaml_round_trip(frost_yaml, tmp_path, exo):
    code, _, err = cli("gait", "convert", frost_yaml(), "--robot", "exo", "-o", tmp_path / "c.json")
    assert code == 0, err
    g = load_gait(tmp_path / "c.json", exo)
    np.testing.assert_array_equal(g.domains[0].beta, standing_gait(exo).domains[0].beta)


@pytest.mark.parametrize("mutate, message", [
    (lambda d: d.__setitem__("coeff_b", ["a"]), "coeff_b[0]: expected a number, got a string ('a')"),
    (b"coeff_jt: [1, 2]\n# caf\xe9\n", "not UTF-8 text (byte 0xe9"),
    (lambda d: d.__setitem__("step_dur", "0.7"), "step_dur: expected a number, got a string"),
    (lambda d: d.__setitem__("step_dur", True), "step_dur: expected a number, got a boolean"),
    (lambda d: d["ffPos"].__setitem__(slice(3, 7), [0, 0, 0, 0]), "ffPos[3:7]: base quaternion has norm 0"),
    (lambda d: d.pop("ffVel"), "ffVel: missing: the initial state needs all of"),
    (lambda d: d["coeff_jt"].pop(), "coeff_jt: has 95 coefficients, expected 96"),
    (b"a: &x [1, 2]\nb: *x\n", "YAML aliases"),
])
def test_bad_frost_yaml(frost_yaml, tmp_path, mutate, message):
    p = frost_yaml(mutate)
    code, out, err = cli("gait", "convert", p, "--robot", "exo", "-o", tmp_path / "c.json")
    assert code == 2 and out == "" and not (tmp_path / "c.json").exists()
    one_error_line(err, f"{p}: ", message)


def test_yaml_exponent_without_a_dot_or_sign_gets_a_hint(frost_yaml, tmp_path):
    p = frost_yaml()
    for written, parsed in (("7e-1", "0.7"), ("1.0e6", "1000000.0")):
        p.write_text(frost_yaml().read_text().replace("step_dur: 0.7", f"step_dur: {written}"))
        code, _, err = cli("gait", "convert", p, "--robot", "exo", "-o", tmp_path / "c.json")
        assert code == 2
        one_error_line(err, f"step_dur: expected a number, got a string ('{written}')", f"write {parsed}")


# ------------------------------------------------------------------------------------------- robot spec
@pytest.mark.parametrize("old, new, message", [
    ("min_base_height = 0.6", 'min_base_height = "low"', "fall.min_base_height: expected a number, got a string"),
    ("min_base_height = 0.6", "min_base_height = nan", "fall.min_base_height: must be a finite number (got nan)"),
    ('[sim]\ntimestep = 0.001\nintegrator = "implicitfast"', "", "sim: expected a table, got a string ('fast')"),
    ('integrator = "implicitfast"', 'integrator = "fast"', "sim.integrator: must be one of 'euler'"),
    ("timestep = 0.001", "timestep = 1e-9", "sim.timestep: must satisfy 0.0001 ≤ x < 0.1 s (got 1e-09)"),
    ("kp = [30000,", "kp = [true,", "joints.kp[0]: expected a number, got a boolean"),
    ("kp = [30000,", "kp = [1e12,", "joints.kp[0]: must satisfy 0 < x ≤ 1e7 N·m/rad"),
    ("[fall]", "[fal]", "fal: unknown key (known: name, mjcf"),
    ("joint_perm = [6,", "joint_perm = [6.0,", "mirror.joint_perm[0]: expected an integer, got a number (6.0)"),
    ("step_length = [0.10, 0.22, 0.02]", "step_length = [0.10, 0.22, 1e-9]",
     "action_space.step_length: the grid has"),
    ("step_length = [0.10, 0.22, 0.02]", "step_length = [0.10, 0.22]",
     "action_space.step_length: must have exactly 3 items (got 2) ([low, high, step])"),
    ("step_length = [0.10, 0.22, 0.02]", "step_length = [0.10, 2.0, 0.02]", "must lie within the bounds"),
    ("left_knee = 0.3", 'left_knee = "bent"', "posture.left_knee: expected a number, got a string ('bent')"),
    ("max_tilt = 0.8", "max_tilt = 0", "fall.max_tilt: must satisfy 0 < x ≤ π rad (got 0)"),
])
def test_bad_spec_is_one_line_exit_2(tmp_path, gait_file, old, new, message):
    assert old in EXO_SPEC
    spec = tmp_path / "spec.toml"
    text = EXO_SPEC.replace(old, new, 1)
    spec.write_text(text if new else text.replace('name = "exo"', 'name = "exo"\nsim = "fast"'))
    code, out, err = cli("walk", gait_file(), "--robot", spec, "--steps", "1")
    assert code == 2 and out == ""
    one_error_line(err, f"{spec}: ", message)


def test_spec_accepts_an_unbounded_pelvis_height(tmp_path):
    spec = tmp_path / "spec.toml"
    spec.write_text(EXO_SPEC.replace("pelvis_height = [0.80, 0.95]", "pelvis_height = [0.80, inf]"))
    assert load_robot(spec).spec.gait_quality.pelvis_height == (0.8, float("inf"))


def test_non_utf8_spec(tmp_path):
    spec = tmp_path / "spec.toml"
    spec.write_bytes(EXO_SPEC.encode().replace(b"# robustgait", b"# robust\xffgait", 1))
    with pytest.raises(RobustGaitError, match=r"spec.toml: not UTF-8 text \(byte 0xff at offset 8\)"):
        load_robot(spec)


# ------------------------------------------------------------------------------------------------- logs
def test_csv_with_one_non_numeric_cell(tmp_path):
    log = tmp_path / "w.csv"
    log.write_text("wx,wy,wz,phase\n0.1,0.2,0.3,L\n0.1,abc,0.3,R\n0.1,0.2,0.3,L\n")
    code, _, err = cli("barrier-eval", log, "--x-star", "0.1,0.2,0.3", "--r", "0.5")
    assert code == 2
    one_error_line(err, "w.csv: row 3, column 'wy': 'abc' is not a number")
    log.write_text("wx,wy,wz,phase\n0.1,0.2,0.3,L\n0.1,0.21,0.3,R\n")  # a text column is skipped
    assert load_reduced_log(log).shape == (2, 3)


def test_valid_2d_npy_and_npz_are_accepted(tmp_path):
    xs = np.array([[0.1, 0.2, 0.3], [0.11, 0.2, 0.3], [0.1, 0.21, 0.3]])
    np.save(tmp_path / "a.npy", xs)
    np.save(tmp_path / "f.npy", np.asfortranarray(xs))
    np.save(tmp_path / "i.npy", np.arange(6, dtype=np.int32).reshape(3, 2))
    np.savez_compressed(tmp_path / "c.npz", x=xs, t=np.arange(3))
    assert np.array_equal(load_reduced_log(tmp_path / "a.npy"), xs)
    assert np.array_equal(load_reduced_log(tmp_path / "f.npy"), xs)
    assert load_reduced_log(tmp_path / "i.npy").tolist() == [[0, 1], [2, 3], [4, 5]]
    assert np.array_equal(reexported(tmp_path / "c.npz"), xs)
    code, out, err = cli("barrier-eval", tmp_path / "a.npy", "--x-star", "0.1", "0.2", "0.3", "--r", "0.5", "--json")
    assert code == 0 and json.loads(out)["ok"] is True, err


@pytest.mark.parametrize("make, message", [
    (lambda p: np.save(p, np.arange(3.0)), "shape (T, n) with T, n ≥ 1, got (3,)"),
    (lambda p: np.save(p, np.ones((2, 2), complex)), "dtype complex128 is not a real number type"),
    (lambda p: np.save(p, np.array([[1, "a"]], object), allow_pickle=True), "dtype object"),
    (lambda p: np.save(p, np.array([[0.0, np.inf]])), "x[0, 1] = inf is not a finite number"),
    (lambda p: np.save(p, np.array([[0.0, 1e9]])), "is outside the limit"),
    (lambda p: p.write_bytes(b"\x93NUMPY garbage"), "not a NumPy array file"),
])
def test_bad_npy(tmp_path, make, message):
    p = tmp_path / "bad.npy"
    make(p)
    with pytest.raises(RobustGaitError, match=r"bad\.npy: ") as err:
        load_reduced_log(p)
    assert message in str(err.value) and "\n" not in str(err.value)


def test_npz_header_is_checked_before_decompressing(tmp_path):
    p = tmp_path / "big.npz"
    np.savez_compressed(p, x=np.zeros((L.MAX_LOG_ROWS + 1, 2)))  # 16 MB of zeros, a few kB compressed
    with pytest.raises(RobustGaitError, match="over the limits"):
        load_reduced_log(p)


# ------------------------------------------------------------------------------------- command line
@pytest.mark.parametrize("argv, message", [
    (["certify", "{g}", "--robot", "exo", "--seed", "-1"], "argument --seed: must satisfy 0 ≤ x ≤ 2^63 − 1"),
    (["walk", "{g}", "--robot", "exo", "--steps", "1e9"], "argument --steps: expected an integer, got '1e9'"),
    (["walk", "{g}", "--robot", "exo", "--steps", "1000000000"], "argument --steps: must satisfy 1 ≤ x ≤ 1000"),
    (["certify", "{g}", "--robot", "exo", "--samples", "1000000000"], "argument --samples: must satisfy"),
    (["certify", "{g}", "--robot", "exo", "--orbit-steps", "1000000000"], "argument --orbit-steps: must"),
    (["certify", "{g}", "--robot", "exo", "--r-max", "1e6"], "argument --r-max: must satisfy 0 < x ≤ 10000"),
    (["certify", "{g}", "--robot", "exo", "--r-max", "nan"], "argument --r-max: must be a finite number (got nan)"),
    (["certify", "{g}", "--robot", "exo", "--plot", "{t}/c.txt"], "unknown plot format '.txt'"),
    (["walk", "{g}", "--robot", "exo", "--video", "{t}/v.txt"], "unknown video format '.txt'"),
    (["certify", "{g}", "--robot", "exo", "-o", "{t}"], "is a directory"),
    (["certify", "{g}", "--robot", "exo", "-o", "/proc/x.json"], "refusing to write under /proc"),
    (["gait", "convert", "{g}", "--robot", "exo", "-o", "/missing/dir/x.json"], "output directory does not exist"),
    (["gait", "convert", "{g}", "--robot", "exo", "-o", "/dev/null"], "is a device, FIFO or socket"),
    (["barrier-eval", "{t}/w.csv", "--x-star", "0", "inf", "--r", "1"], "argument --x-star: expected finite numbers"),
    (["walk", "{g}", "--robot", "exo", "--log", "-"], "not a file name"),
])
def test_bad_arguments_are_one_line_exit_2(tmp_path, gait_file, argv, message):
    g = gait_file()
    (tmp_path / "w.csv").write_text("a,b\n0.1,0.2\n0.1,0.2\n")
    before = sorted(tmp_path.iterdir())
    code, out, err = cli(*(a.format(g=g, t=tmp_path) for a in argv))
    assert code == 2 and out == ""
    one_error_line(err, message)
    assert sorted(tmp_path.iterdir()) == before


def test_total_work_is_bounded_before_simulating(tmp_path, gait_file, no_work):
    slow = gait_file(lambda d: d["domains"][0].__setitem__("duration", 10.0))
    code, _, err = cli("walk", slow, "--robot", "exo", "--steps", "1000", "--video", tmp_path / "v.mp4")
    assert code == 2
    one_error_line(err, f"{slow}: 1000 steps (sim.step_cap) with a video: 1000 simulated steps of up to 15 s",
                   "over the limit of 2e+06")
    code, _, err = cli("certify", gait_file(), "--robot", "exo", "--override", "certify.push.horizon=100")
    assert code == 2
    one_error_line(err, "certify.orbit.max_steps 100 + certify.sequential.budget 3000 × 101 steps: 303836 simulated "
                   "steps of up to 1.05 s", "over the limit of 2.7e+08 (4 × the 6.7e+07 the defaults need here)")
    code, _, err = cli("walk", gait_file(), "--robot", "exo", "--steps", "200", "--video", tmp_path / "v.gif")
    assert code == 2
    one_error_line(err, "v.gif: this walk could last 210 s, 6300 frames at 30 fps: a .gif holds at most 3600")
    assert not (tmp_path / "v.mp4").exists()


def test_generate_checks_its_output_before_the_solve(tmp_path, no_work):
    for target in ("/missing/dir/x.json", str(tmp_path / "x.yaml"), str(tmp_path)):
        code, _, err = cli("gait", "generate", "--robot", "exo", "-o", target)
        assert code == 2  # before the problem is built (no_work)
        one_error_line(err, "argument -o/--output")


def test_outputs_never_replace_links_fifos_or_devices(tmp_path, gait_file):
    g = gait_file()
    target = tmp_path / "target.json"
    target.write_text("keep")
    link = tmp_path / "link.json"
    link.symlink_to(target)
    fifo = tmp_path / "fifo.json"
    os.mkfifo(fifo)
    for out in (link, fifo):
        code, _, err = cli("gait", "convert", g, "--robot", "exo", "-o", out)
        assert code == 2
        one_error_line(err, str(out))
    assert link.is_symlink() and target.read_text() == "keep" and stat.S_ISFIFO(os.lstat(fifo).st_mode)
    for device in ("/dev/null", "/dev/zero"):  # checked, never opened
        with pytest.raises(RobustGaitError, match="device, FIFO or socket"):
            check_output(device, "json")
    with pytest.raises(RobustGaitError, match="refusing to write under /dev"):
        check_output("/dev/robustgait-test.json", "json")
    assert not Path("/dev/robustgait-test.json").exists()


# --------------------------------------------------------------------------------------- output writer
def test_atomic_output_leaves_nothing_on_failure_or_interrupt(tmp_path):
    target = tmp_path / "a.json"
    target.write_text("old")
    for exc in (RuntimeError("disk full"), KeyboardInterrupt()):
        with pytest.raises(type(exc)), atomic_output(target, "json") as tmp:
            tmp.write_text("half")
            raise exc
        assert target.read_text() == "old" and sorted(p.name for p in tmp_path.iterdir()) == ["a.json"]
    write_text(target, "new", "json")
    assert target.read_text() == "new" and sorted(p.name for p in tmp_path.iterdir()) == ["a.json"]


def test_written_files_get_normal_permissions(tmp_path):
    new = tmp_path / "n.csv"
    write_csv(new, ["a", "b"], [[1.0, 2.5], [0.1, -3.0]])
    umask = os.umask(0)
    os.umask(umask)
    assert stat.S_IMODE(new.stat().st_mode) == 0o666 & ~umask
    assert new.read_text() == "a,b\n1.0,2.5\n0.1,-3.0\n"
    new.chmod(0o640)
    write_csv(new, ["a"], [[1.0]])
    assert stat.S_IMODE(new.stat().st_mode) == 0o640


def test_cli_outputs_are_complete_files(tmp_path, gait_file):
    g = gait_file()
    log = tmp_path / "w.csv"
    code, _, err = cli("walk", g, "--robot", "exo", "--steps", "3", "--log", log)
    assert code == 0, err
    assert log.read_text().splitlines()[0] == "wx,wy,wz" and load_reduced_log(log).shape == (3, 3)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["g.json", "w.csv"]


def test_gif_video(tmp_path, exo):
    from robustgait import walk
    from robustgait.sim import render_video

    res = walk(exo, standing_gait(exo), steps=1, keep_trajectory=True)
    gif = tmp_path / "v.gif"
    frames = render_video(exo, res.trajectory[:300], gif, fps=10, width=96, height=64)
    assert frames == 3 and gif.read_bytes()[:4] == b"GIF8"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["v.gif"]


def test_check_output_kinds():
    assert [kind_of(p) for p in ("a.JSON", "b.csv", "c.svg", "d.gif")] == ["json", "csv", "plot", "video"]
    with pytest.raises(RobustGaitError, match="unknown output format"):
        kind_of("x.txt")
    with pytest.raises(RobustGaitError, match="file name longer than 200 bytes"):
        check_output("x" * 300 + ".json", "json")


# ----------------------------------------------------------------------------------------------- docs
def test_every_file_limit_is_documented():
    from robustgait.config import Doc

    doc = (REPO / "docs" / "inputs.md").read_text()
    limits = [v for v in vars(L).values() if isinstance(v, Doc)]
    assert len(limits) >= 20
    for lim in limits:
        assert lim.text() in doc, (lim.help, lim.text())
    for name in (n for n, v in vars(L).items() if n.isupper() and isinstance(v, (int, float))):
        assert f"`{name}`" in doc, name


def test_a_certificate_file_names_its_figure_and_older_files_still_read(tmp_path):
    """A certificate's figure is ``value``; files written before it had one name (``j_star`` of a push certificate,
    ``r_star``) still read, with the same figure; an exploration alone's radius is its estimate; a file with no figure
    is refused in one line."""
    from robustgait import RobustGaitError
    from robustgait.io.certfile import certificate_radius, certificate_value, read_certificate

    base = {"status": "ok", "attained": True, "x_star": [0.0, 0.0], "map": "step", "frame": "heading",
            "reconstruction": "holonomic", "config": {"disturbance": "push"}}
    for key in ("value", "j_star", "r_star"):
        path = tmp_path / f"{key}.json"
        path.write_text(json.dumps({**base, key: 12.5}))
        assert read_certificate(path).radius == 12.5 and certificate_radius({**base, key: 12.5}) == 12.5
        assert certificate_value({**base, key: 12.5}) == 12.5
    explored = {**base, "value": 0.0, "estimate": 14.0, "verified": False}
    assert certificate_radius(explored) == 14.0 and certificate_value(explored) == 0.0
    bad = tmp_path / "none.json"
    bad.write_text(json.dumps(base))
    with pytest.raises(RobustGaitError, match="no figure"):
        read_certificate(bad)
