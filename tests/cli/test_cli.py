import json
import math
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from robustgait.cli import main
from tests.conftest import ATALANTE_DIR, ATALANTE_GAIT, ATALANTE_SPEC, EXO_GAIT

# (gait, robot) of each robot the command line is tried on: exo always, Atalante when ../shared is beside the repo
ROBOTS = {"exo": (EXO_GAIT, "exo"), "atalante": (ATALANTE_GAIT, ATALANTE_SPEC)}


@pytest.fixture(params=sorted(ROBOTS))
def gait_robot(request):  # type: ignore[no-untyped-def]
    if request.param == "atalante" and not (ATALANTE_DIR / "loadedExo.xml").is_file():
        pytest.skip("../shared/atalante (AMBER lab model) is not beside the repository")
    gait, robot = ROBOTS[request.param]
    return str(gait), str(robot), request.param


def run(capsys, *argv):
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def test_robots_lists_shipped(capsys):
    code, out, _ = run(capsys, "robots", "--json")
    rows = json.loads(out)
    exo = next(r for r in rows if r["name"] == "exo")
    assert code == 0 and exo["joints"] == 12 and 100 <= exo["mass_kg"] <= 135


@pytest.mark.slow  # seconds of its own: plain pytest stays ≤ 60 s; CI runs it
def test_walk_json(capsys, gait_robot):
    gait, robot, name = gait_robot
    code, out, _ = run(capsys, "walk", gait, "--robot", robot, "--steps", "5", "--json")
    res = json.loads(out)
    assert code == 0
    assert res["steps_taken"] == 5 and res["fell"] is False and res["fall_reason"] is None
    assert (0.08 < res["mean_speed"] < 0.2 if name == "atalante" else abs(res["mean_speed"] - 0.15 / 0.7) < 0.01)
    assert len(res["events"]) == 5
    assert res["orbit"]["status"] == "undecided" and res["orbit"]["steps"] == 5  # 5 events: too few to tell
    assert abs(math.degrees(res["sole_turn"])) < 0.5  # a flat sole on the floor ends single support as the plan: flat
    if name == "atalante":  # a FROST gait carries no parameters: no planned speed, no note
        assert res["planned_speed"] is None
    else:
        assert res["planned_speed"] == pytest.approx(0.15 / 0.7, rel=1e-9)
        code, out, _ = run(capsys, "walk", gait, "--robot", robot, "--steps", "5")
        assert code == 0 and "(planned 0.214)" in out and "note: the walk advances" not in out
        code, out, _ = run(capsys, "walk", gait, "--robot", robot, "--steps", "5", "--override",
                           "sim.speed_agreement=0")  # any difference at all is noted
        assert code == 0 and "of the gait's planned 0.214 m/s" in out and "backwards" not in out
    assert res["comfort"] is None  # 5 steps end before the first measured one (comfort.skip_steps = 5)
    code, out, _ = run(capsys, "walk", gait, "--robot", robot, "--steps", "5", "--json", "--override",
                       "comfort.skip_steps=2")
    c = json.loads(out)["comfort"]
    assert code == 0 and c["first_step"] == 3 and c["steps"] == 3 and c["speed"] > 0 and c["impact_force_ratio"] > 1
    code, out, _ = run(capsys, "walk", gait, "--robot", robot, "--steps", "4", "--override", "comfort.skip_steps=1")
    assert code == 0 and "comfort over steps 2–4" in out and "pelvis acceleration RMS/peak" in out


@pytest.mark.slow  # seconds of its own: plain pytest stays ≤ 60 s; CI runs it
def test_walk_reports_the_orbit_of_its_switching_events(capsys):
    code, out, _ = run(capsys, "walk", str(EXO_GAIT), "--robot", "exo", "--steps", "120")
    assert code == 0 and "orbit of the switching events: settled at step" in out and "period-1 orbit" in out
    assert "held 64 more steps" in out and "(stability: robustgait certify)" in out
    code, out, _ = run(capsys, "walk", str(EXO_GAIT), "--robot", "exo", "--steps", "50")
    assert code == 0 and "64 are needed to see the band hold (walk at least" in out


@pytest.mark.slow  # seconds of its own: plain pytest stays ≤ 60 s; CI runs it
def test_gait_convert_round_trip(tmp_path, capsys, gait_robot):
    gait, robot, _ = gait_robot
    out = tmp_path / "g.json"
    assert run(capsys, "gait", "convert", gait, "--robot", robot, "-o", str(out), "--mirror")[0] == 0
    code, stdout, _ = run(capsys, "walk", str(out), "--robot", robot, "--steps", "3", "--json")
    assert code == 0 and json.loads(stdout)["steps_taken"] == 3


@pytest.fixture(scope="module")
def bad_files(tmp_path_factory, exo_gait):
    """{name: (argv, file name)} of bad inputs on exo, each a file in a temporary directory."""
    from tests.robots.test_spec import spec_text

    tmp_path = tmp_path_factory.mktemp("bad")
    good = exo_gait.to_dict()  # a JSON gait to corrupt
    cases = {}

    def gait_case(name, mutate):
        d = json.loads(json.dumps(good))
        mutate(d)
        p = tmp_path / f"{name}.json"
        p.write_text(json.dumps(d))
        cases[name] = (["walk", str(p), "--robot", "exo"], p.name)

    gait_case("wrong_count", lambda d: d["domains"][0]["beta"][0].pop())
    gait_case("nan_coefficient", lambda d: d["domains"][0]["beta"][0].__setitem__(0, float("nan")))
    gait_case("unknown_joint", lambda d: d["joints"].__setitem__(3, "Elbow"))
    p = tmp_path / "malformed.json"
    p.write_text('{"schema_version": 1, "robot": ')
    cases["malformed_json"] = (["walk", str(p), "--robot", "exo"], p.name)
    p = tmp_path / "malformed.yaml"
    p.write_text("coeff_jt: [0.1, 0.2\nstep_dur: [")
    cases["malformed_yaml"] = (["walk", str(p), "--robot", "exo"], p.name)
    spec = spec_text("exo")
    for name, old, new in [("malformed_toml", "[legs.left]", "[legs.left"),
                           ("unknown_geom", '"right_sole"', '"right_shoe"'),
                           ("unknown_spec_joint", '"right_ankle_roll"', '"right_ankle"')]:
        p = tmp_path / f"{name}.toml"
        p.write_text(spec.replace(old, new))
        cases[name] = (["walk", str(EXO_GAIT), "--robot", str(p)], p.name)
    cases["missing_gait"] = (["walk", str(tmp_path / "nope.json"), "--robot", "exo"], "nope.json")
    cases["missing_robot"] = (["walk", str(EXO_GAIT), "--robot", str(tmp_path / "nope.toml")], "nope.toml")
    bad_config = tmp_path / "bad_config.toml"
    bad_config.write_text("[sim]\nstep_cap = 0\n")
    cases["bad_config"] = (["walk", str(EXO_GAIT), "--robot", "exo", "--config", str(bad_config)], bad_config.name)
    return cases


BAD = ["wrong_count", "nan_coefficient", "unknown_joint", "malformed_json", "malformed_yaml", "malformed_toml",
       "unknown_geom", "unknown_spec_joint", "missing_gait", "missing_robot", "bad_config"]


@pytest.mark.parametrize("case", BAD)
def test_bad_input_one_line_exit_2(bad_files, capsys, case):
    argv, filename = bad_files[case]
    code, out, err = run(capsys, *argv)
    assert code == 2 and out == ""
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("robustgait: error: ") and filename in lines[0]


@pytest.mark.slow  # seconds of its own: plain pytest stays ≤ 60 s; CI runs it
def test_console_script_no_traceback(tmp_path):
    p = tmp_path / "bad.json"
    p.write_text("[")
    # the installed console script beside this interpreter (whether or not its environment is on PATH)
    script = shutil.which("robustgait", path=str(Path(sys.executable).parent)) or shutil.which("robustgait")
    if script is None:
        pytest.skip("the robustgait console script is not installed (pip install -e .)")
    proc = subprocess.run([script, "walk", str(p), "--robot", "exo"], capture_output=True, text=True)
    assert proc.returncode == 2 and "Traceback" not in proc.stderr
    assert proc.stderr.count("\n") == 1 and "bad.json" in proc.stderr


def test_argparse_errors_are_one_line(capsys):
    assert main(["walk"]) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and "required" in err
    assert main(["--help"]) == 0 and "certify" in capsys.readouterr().out


def test_barrier_eval_accepts_negative_x_star(tmp_path, capsys):
    log = tmp_path / "x.csv"
    log.write_text("a,b\n-0.1,0.2\n-0.11,0.21\n-0.1,0.2\n")
    for argv in (["--x-star", "-0.1", "0.2"], ["--x-star=-0.1,0.2"]):
        code, out, _ = run(capsys, "barrier-eval", str(log), *argv, "--r", "0.5", "--json")
        assert code == 0 and json.loads(out)["ok"] is True


def test_interrupt_and_closed_stdout_are_one_line_or_silent(monkeypatch, capsys):
    import robustgait.cli.info as info

    def interrupted(args):
        raise KeyboardInterrupt

    def closed(args):
        raise BrokenPipeError

    monkeypatch.setattr(info, "_robots", interrupted)
    assert main(["robots"]) == 130
    assert capsys.readouterr().err == "robustgait: interrupted\n"
    monkeypatch.setattr(info, "_robots", closed)
    assert main(["robots"]) == 1
    assert capsys.readouterr().err == ""


# ---- every option comes from the configuration -------------------------------------------------------------
# Options that are inputs or outputs of a command, not configuration: file paths, printing, the robot.
IO_OPTIONS = {"-h", "--help", "--json", "--plot", "-o", "--output", "--video", "--log", "--config", "--override",
              "--robot", "--certificate", "--warm-start", "--verbose", "--quiet", "--mirror", "--check", "--columns",
              "--x-star", "--r", "--dir", "--preset", "--markdown", "--to"}


def _subparsers(parser, path=()):  # type: ignore[no-untyped-def]
    """(command path, parser) of every leaf command."""
    import argparse

    subs = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    if not subs:
        yield path, parser
    for a in subs:
        for name, p in a.choices.items():
            yield from _subparsers(p, (*path, name))


def test_every_option_default_and_choice_is_its_config_field():
    import argparse

    from robustgait.cli import build_parser
    from robustgait.cli.options import default_text
    from robustgait.config import Config, field_at

    seen = 0
    for path, parser in _subparsers(build_parser()):
        for action in parser._actions:
            flags = [o for o in action.option_strings if o not in IO_OPTIONS and not o.startswith("--no-")]
            if not flags or isinstance(action, argparse._HelpAction):
                continue
            fields = getattr(action, "robustgait_paths", None)
            assert fields, f"{' '.join(path)} {flags}: an option that is no config field"
            info = field_at(Config, fields[0])
            assert action.default is argparse.SUPPRESS, (path, flags)  # the value in force comes from the config
            if info.choices:
                assert tuple(action.choices) == info.choices, (path, flags)
            if default_text(info):
                assert f"default {default_text(info)}" in action.help, (path, flags, action.help)
            for other in fields[1:]:  # one flag for several fields: they must agree on default and type
                assert field_at(Config, other).default == info.default, (path, flags)
            seen += 1
    assert seen >= 60


def test_no_literal_default_or_choice_in_the_cli():
    """cli/ restates no default and no choice: add_argument calls take neither a literal default (other than the
    'not given' markers) nor a literal tuple or list of choices."""
    import ast
    from pathlib import Path

    import robustgait.cli

    root = Path(robustgait.cli.__file__).parent
    bad = []
    for file in sorted(root.glob("*.py")):
        for node in ast.walk(ast.parse(file.read_text())):
            if not (isinstance(node, ast.Call) and getattr(node.func, "attr", "") == "add_argument"):
                continue
            for kw in node.keywords:
                v = kw.value
                if kw.arg == "default" and isinstance(v, ast.Constant) and v.value not in (None, False):
                    bad.append(f"{file.name}:{node.lineno} default={v.value!r}")
                if kw.arg == "default" and isinstance(v, (ast.List, ast.Tuple)) and v.elts:
                    bad.append(f"{file.name}:{node.lineno} default literal")
                if kw.arg == "choices" and isinstance(v, (ast.List, ast.Tuple, ast.Set)):
                    bad.append(f"{file.name}:{node.lineno} choices literal")
    assert not bad, bad


def test_library_and_cli_resolve_the_same_multicontact_gait():
    """The multi-contact default step duration is the config's: `gait generate --domains multicontact` and the
    library's GaitParams().resolved("multicontact") (what GaitGenerator.solve uses) agree."""
    from robustgait.cli import build_parser
    from robustgait.cli.options import config_from
    from robustgait.config import GaitParams

    argv = ["gait", "generate", "--robot", "exo", "--domains", "multicontact", "-o", "g.json"]
    args = build_parser().parse_args(argv)
    assert config_from(args).params == GaitParams().resolved("multicontact")
    assert config_from(args).params.step_duration == 0.9
