"""The timestep by accuracy (robustgait.robotinit.timestep, robot init's and robot check's; docs/robots.md, "The
timestep"): the candidates, the error of two settled bands, the rule on synthetic trials, the walks it stops after
(walks stubbed), robot init's spec with the gains drafted at the chosen step and its fallback (generation stubbed);
end to end on exo and Booster T1 (slow: the default gait generated and walked)."""

from __future__ import annotations

import json
import sys
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest

from robustgait import load_robot
from robustgait.certificate.orbit import Status
from robustgait.cli import main
from robustgait.config import CertifyConfig, Config, RobotConfig
from robustgait.config.base import ConfigError
from robustgait.errors import RobustGaitError
from robustgait.robotinit import init as robotinit
from robustgait.robotinit import timestep
from robustgait.robotinit.timestep import (
    TimestepChoice,
    TimestepWalk,
    Trial,
    band_difference,
    candidate_timesteps,
    check_timestep,
    choose_timestep,
    select_timestep,
    trial_error,
)
from tests.inspection.biped import EXO_XML, biped_xml, write

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover - exercised on 3.10 only
    import tomli as tomllib

CANDIDATES = RobotConfig().timestep_candidates


def walked(h: float, centres: list[list[float]] | None, status: str = "ok", steps: int = 96,
           sides_differ: bool = False) -> TimestepWalk:
    c = None if centres is None else np.array(centres, dtype=float)
    return TimestepWalk(h, Status(status), "" if status == "ok" else "why", steps, 1 if c is None else len(c), c,
                        sides_differ, 1000, 0.1)


def trial(h: float, error: float | None, *, fell: bool = False) -> Trial:
    """A trial of h whose bands' centres differ by ``error`` (None: the walk at h/2 did not settle)."""
    a = walked(h, [[0.0, 0.0]])
    b = walked(h / 2, None, "unsettled") if error is None else walked(h / 2, [[error, 0.0]])
    if fell:
        a = walked(h, None, "fell", steps=25)
    return Trial(h, a, b, trial_error(a, b))


# ----------------------------------------------------------------------------------------------- the rule
def test_candidates_are_the_models_step_and_the_configured_ones_largest_first() -> None:
    assert candidate_timesteps(0.002, CANDIDATES) == (0.002, 0.001, 0.0005, 0.00025)
    assert candidate_timesteps(0.001, CANDIDATES) == (0.002, 0.001, 0.0005, 0.00025)  # 2 ms tried above exo's 1 ms
    assert candidate_timesteps(0.005, CANDIDATES) == (0.005, 0.002, 0.001, 0.0005, 0.00025)
    assert candidate_timesteps(0.0015, CANDIDATES) == (0.002, 0.0015, 0.001, 0.0005, 0.00025)
    assert candidate_timesteps(0.0001, CANDIDATES) == (0.002, 0.001, 0.0005, 0.00025, 0.0001)
    assert len(candidate_timesteps(0.002 * (1 + 1e-12), CANDIDATES)) == 4  # a model file's rounding: counted once


def test_band_difference_compares_phase_by_phase_and_the_same_stance() -> None:
    one = np.array([[0.0, 1.0]])
    two = np.array([[0.01, 1.0], [-0.03, 1.0]])
    assert band_difference(one, one) == 0.0
    assert band_difference(one, two) == pytest.approx(0.03)  # period 1 against 2: tiled
    swapped = two[::-1]
    assert band_difference(two, swapped) == 0.0  # one step out of phase: the same orbit of a symmetric robot
    assert band_difference(two, swapped, stride=2) == pytest.approx(0.04)  # ... but not when the stances differ
    assert trial_error(walked(0.001, [[0.0]]), walked(0.0005, None, "fell")) is None


def test_the_largest_passing_candidate_is_chosen() -> None:
    tol = 0.02
    trials = [trial(0.002, 0.03), trial(0.001, 0.014), trial(0.0005, 0.006)]
    assert choose_timestep(trials, tol) == (0.001, True, "")
    assert trials[0].why_not(tol) == "0.03 against 1 ms, over 0.02" and trials[1].why_not(tol) == ""
    # settled walks are required: an error within the tolerance after a fall does not count
    fell = [trial(0.002, 0.0, fell=True), trial(0.001, None), trial(0.0005, 0.01)]
    assert choose_timestep(fell, tol) == (0.0005, True, "")
    assert fell[0].why_not(tol) == "its walk at 2 ms fell in step 26"
    assert fell[1].why_not(tol) == "its walk at 0.5 ms did not settle"
    h, passed, note = choose_timestep([trial(0.001, 0.05), trial(0.0005, 0.03)], tol)
    assert (h, passed) == (0.0005, False) and "\n" not in note and "the smallest, 0.5 ms" in note
    with pytest.raises(RobustGaitError, match="no timestep candidate"):
        choose_timestep([], tol)


def test_the_tolerance_is_two_thirds_of_the_recovery_bands_floor() -> None:
    assert RobotConfig().timestep_tolerance == pytest.approx(2 / 3 * CertifyConfig().push.recovery_radius, rel=0.01)
    with pytest.raises(ConfigError, match="largest first"):
        RobotConfig(timestep_candidates=(0.001, 0.002))


class FakeRobot:
    """What the rule reads of a robot: its step, servos, stable PD and the robot at another step."""

    def __init__(self, h: float, stable_pd: bool = True):
        self.dt = h
        self.spec = SimpleNamespace(stable_pd=stable_pd)
        self.servo_kp = np.array([100.0])
        self.servo_kd = np.array([1.0 + h * 100.0 if stable_pd else 1.0])

    def at_timestep(self, h: float, stable_pd: bool = True) -> FakeRobot:
        return FakeRobot(h, stable_pd)


def fake_walks(monkeypatch: pytest.MonkeyPatch, slope: float = 30.0) -> list[float]:
    """Walks stubbed: a settled band whose centre is ``slope`` × h (an error of slope h / 2 at h); returns the steps
    walked, in order."""
    made: list[float] = []

    def settled_walk(robot: Any, gait: Any, config: Config) -> TimestepWalk:
        made.append(robot.dt)
        return walked(robot.dt, [[slope * robot.dt]])

    monkeypatch.setattr(timestep, "settled_walk", settled_walk)
    return made


def test_the_walks_stop_at_the_first_passing_candidate_and_are_made_once(monkeypatch: pytest.MonkeyPatch) -> None:
    made = fake_walks(monkeypatch)
    said: list[str] = []
    choice = select_timestep(FakeRobot, None, (0.002, 0.001, 0.0005, 0.00025), Config(),  # type: ignore[arg-type]
                             say=said.append)
    # 2 ms: 0.03 against 1 ms; 1 ms: 0.015 against 0.5 ms; the reference of 2 ms is the walk of 1 ms
    assert choice.timestep == 0.001 and choice.passed and made == [0.002, 0.001, 0.0005]
    assert [t.timestep for t in choice.trials] == [0.002, 0.001] and choice.larger is choice.trials[0]
    assert choice.chosen is choice.trials[1] and choice.chosen.error == pytest.approx(0.015)
    assert any("0.03 band units (over 0.02)" in line for line in said)
    every = select_timestep(FakeRobot, None, (0.002, 0.001, 0.0005), Config(), every=True)  # type: ignore[arg-type]
    assert [t.timestep for t in every.trials] == [0.002, 0.001, 0.0005] and every.timestep == 0.001


def test_a_check_whose_gait_does_not_solve_fails_in_one_line(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(timestep, "default_gait", lambda robot, config: (None, "its solve failed (stub)"))
    result = check_timestep(load_robot("exo"), Config())
    assert not result.passed and result.name == "timestep" and "\n" not in result.line
    assert "could not be generated (its solve failed (stub))" in result.line


def test_the_check_passes_within_the_tolerance(monkeypatch: pytest.MonkeyPatch) -> None:
    fake_walks(monkeypatch, slope=10.0)
    monkeypatch.setattr(timestep, "default_gait", lambda robot, config: (object(), ""))
    exo = load_robot("exo")  # 1 ms, no stable PD: 0.005 against 0.5 ms
    result = check_timestep(exo, Config())
    assert result.passed and result.values["error"] == pytest.approx(0.005) and not result.values["stable_pd"]
    assert "at 1 ms and at 0.5 ms differ by 0.005 band units (at most 0.02" in result.line
    strict = Config(robot=RobotConfig(timestep_tolerance=0.001))
    assert not check_timestep(exo, strict).passed
    monkeypatch.setattr(timestep, "settled_walk", lambda robot, gait, config: walked(robot.dt, None, "fell", 56))
    fell = check_timestep(exo, Config())
    assert not fell.passed and "error" not in fell.values and not fell.values["settled"]
    assert fell.line.endswith("cannot be compared (at most 0.02, robot.timestep_tolerance): its walk at 1 ms fell "
                              "in step 57")


def test_at_timestep_changes_the_step_and_the_servos_damping_only() -> None:
    exo = load_robot("exo")
    fine = exo.at_timestep(0.0005)
    assert fine.dt == 0.0005 and fine.spec.stable_pd and exo.dt == 0.001 and not exo.spec.stable_pd
    assert np.array_equal(fine.kp, exo.kp) and np.allclose(fine.kd, exo.kd + 0.0005 * exo.kp)
    assert np.allclose(exo.at_timestep(0.002, stable_pd=False).kd, exo.kd)
    assert fine.model.nq == exo.model.nq and fine.soles == exo.soles
    for bad in (0.0, -1e-3, float("nan")):
        with pytest.raises(RobustGaitError, match="positive number of seconds"):
            exo.at_timestep(bad)


# ----------------------------------------------------------------------------------------------- robot init
def test_init_writes_the_chosen_step_with_its_own_gains(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                                        capsys: pytest.CaptureFixture[str]) -> None:
    """Generation and walks stubbed: the spec written is the candidate's (its gains drafted at its step, stable PD),
    and its comment names the rule, the tolerance, the error at the step and why the larger one was not taken."""
    seen: dict[float, Any] = {}
    monkeypatch.setattr(robotinit, "default_gait", lambda robot, config: (object(), ""))
    monkeypatch.setattr(robotinit, "lowered", lambda draft: draft.timestep > 0.0015)  # 2 ms above the bound

    def select(robot_at: Any, gait: Any, candidates: Any, config: Config, **kw: Any) -> TimestepChoice:
        for h in candidates:
            seen[h] = robot_at(h)
        trials = (trial(0.001, 0.05), trial(0.0005, 0.0123))
        return TimestepChoice(0.0005, True, 0.02, tuple(candidates), trials)

    monkeypatch.setattr(robotinit, "select_timestep", select)
    spec = tmp_path / "biped.toml"
    code, out, err = run(capsys, "robot", "init", write(tmp_path, biped_xml()), "-o", spec)
    assert code == 0 and "generating the default gait" in err
    assert sorted(seen) == [0.00025, 0.0005, 0.001]  # the model's 2 ms is not tried
    assert all(r.dt == h and r.spec.stable_pd for h, r in seen.items())
    raw = tomllib.loads(spec.read_text())
    assert raw["sim"]["timestep"] == 0.0005 and raw["sim"]["stable_pd"] is True
    assert raw["joints"]["kp"] == pytest.approx(list(seen[0.0005].spec.kp))
    line = next(x for x in spec.read_text().splitlines() if x.startswith("timestep ="))
    assert "by accuracy" in line and "within 0.02 band units" in line and "0.0123 against 0.25 ms" in line
    assert "1 ms not taken: 0.05 against 0.5 ms, over 0.02" in line and "not tried: 2 ms" in line
    assert "stable_pd = true  # " in spec.read_text()
    assert "timestep 0.5 ms, stable PD" in out
    robot = load_robot(spec)
    assert robot.dt == 0.0005 and robot.spec.stable_pd


def test_init_falls_back_to_the_servo_rule_when_the_gait_does_not_solve(tmp_path: Path,
                                                                         monkeypatch: pytest.MonkeyPatch,
                                                                         capsys: pytest.CaptureFixture[str]) -> None:
    monkeypatch.setattr(robotinit, "default_gait", lambda robot, config: (None, "its solve failed (stub)"))
    spec, servo = tmp_path / "biped.toml", tmp_path / "servo.toml"
    model = write(tmp_path, biped_xml())
    code, out, _ = run(capsys, "robot", "init", model, "-o", spec)
    assert code == 0 and "note: the default gait could not be generated (its solve failed (stub))" in out
    assert run(capsys, "robot", "init", model, "-o", servo, "--timestep-rule", "servo")[0] == 0
    raw, ruled = tomllib.loads(spec.read_text()), tomllib.loads(servo.read_text())
    assert raw["sim"] == ruled["sim"] and "stable_pd" not in raw["sim"] and raw["joints"] == ruled["joints"]
    assert "# NOTE: the default gait could not be generated" in spec.read_text()


def test_check_without_its_timestep_check(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = run(capsys, "robot", "check", "exo", "--no-timestep", "--json")
    assert code == 0 and "timestep" not in [c["name"] for c in json.loads(out)["checks"]]


def run(capsys: pytest.CaptureFixture[str], *argv: str | Path) -> tuple[int, str, str]:
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


# ----------------------------------------------------------------------------------------------- end to end
@pytest.mark.slow  # the default gait generated and walked at two or three steps by init, then by check: ~1 min each
@pytest.mark.parametrize("model", ["exo", "t1"])
def test_init_chooses_a_step_that_check_passes(tmp_path: Path, capsys: pytest.CaptureFixture[str], model: str,
                                               request: pytest.FixtureRequest) -> None:
    if model == "exo":
        spec = tmp_path / "exo.toml"
        code, out, err = run(capsys, "robot", "init", EXO_XML, "-o", spec)
        assert code == 0 and "walking the default gait" in err
    else:  # the spec the session's T1 fixture made with the same command (tests/conftest.py)
        spec = request.getfixturevalue("t1_spec")
        capsys.readouterr()  # what the fixture printed when this test is the first to need it
    raw = tomllib.loads(spec.read_text())
    assert raw["sim"]["stable_pd"] is True and raw["sim"]["timestep"] in CANDIDATES
    assert raw["sim"]["timestep"] <= 0.002  # exo's flat gait passes at 2 ms, T1's at 1 ms (docs/robots.md)
    assert "by accuracy" in spec.read_text() and "NONE DOES" not in spec.read_text()
    code, out, _ = run(capsys, "robot", "check", spec, "--json")
    report = json.loads(out)
    checks = {c["name"]: c for c in report["checks"]}
    assert code == 0 and report["passed"] and checks["timestep"]["passed"], checks["timestep"]["line"]
    assert checks["timestep"]["timestep"] == raw["sim"]["timestep"] and checks["timestep"]["stable_pd"]
    assert checks["timestep"]["error"] <= RobotConfig().timestep_tolerance
