"""A point-foot walker's action space from its measured balance (robustgait.robotinit.init.with_balance, docs/robots.md,
"Narrow soles"): the narrowest step width of its window tried with gait generate, and the window starting at the
default width when that step does not pass (the balance and the try stubbed); the try itself end to end on exo
(slow: gaits generated and walked)."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import pytest

from robustgait import Config, load_robot
from robustgait.config.regulator import RegulatorConfig
from robustgait.inspection.scale import Balance, scale
from robustgait.robotinit import init as robotinit
from robustgait.robotinit.draft import draft_spec
from robustgait.robotinit.writer import render
from tests.inspection.test_inspection import biped_xml, write


def regulated() -> Config:
    """The defaults with the step regulator on whatever the soles (the test biped's are wide)."""
    cfg = Config()
    return dataclasses.replace(cfg, sim=dataclasses.replace(cfg.sim, regulator=RegulatorConfig(mode="on")))


def test_a_point_foot_walker_whose_narrowest_step_fails_starts_its_widths_at_the_default(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    config = regulated()
    draft = draft_spec(write(tmp_path, biped_xml()), config.robot)
    balance = Balance(share=1.0, rate=3.3)
    monkeypatch.setattr(robotinit, "measured_balance", lambda robot, gait, cfg: balance)
    tried: list[float] = []

    def fails(robot: object, width: float, cfg: Config) -> str:
        tried.append(width)
        return "the gait fell in step 3 under pd+hlip (stub)"

    monkeypatch.setattr(robotinit, "narrowest_step", fails)
    said: list[str] = []
    out = robotinit.with_balance(draft, lambda: None, None, config, said.append)  # type: ignore[arg-type,return-value]
    narrow = scale(draft.size, config.robot.scale, balance).action_space["step_width"][0]
    default = draft.scaled.gait["step_width"]
    assert tried == [narrow] and narrow < default and any(f"{narrow:g} m" in line for line in said)
    low, high, step = out.scaled.action_space["step_width"]
    assert abs(low - default) <= step / 2 + 1e-9 and out.balance is not None and out.balance.narrow_step_fails
    note = next(n for n in out.notes if "narrowest step width" in n)
    assert "(the gait fell in step 3 under pd+hlip (stub))" in note and f"{low:g}–{high:g} m" in note
    assert any("balances by foot placement" in n for n in out.notes)
    assert "its narrowest step did not pass gait generate" in render(out, tmp_path / "spec.toml")

    monkeypatch.setattr(robotinit, "narrowest_step", lambda robot, width, cfg: "")  # it walks: the rule's window
    walks = robotinit.with_balance(draft, lambda: None, None, config)  # type: ignore[arg-type,return-value]
    assert walks.scaled == scale(draft.size, config.robot.scale, balance)
    assert walks.balance is not None and not walks.balance.narrow_step_fails
    assert not any("narrowest step width" in n for n in walks.notes)


def test_an_ankle_that_holds_tries_no_narrow_step(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    config = regulated()
    draft = draft_spec(write(tmp_path, biped_xml()), config.robot)
    monkeypatch.setattr(robotinit, "measured_balance", lambda robot, gait, cfg: Balance(share=0.2, rate=3.3))
    monkeypatch.setattr(robotinit, "narrowest_step", lambda *a: pytest.fail("tried a narrow step"))
    assert robotinit.with_balance(draft, lambda: None, None, config) is draft  # type: ignore[arg-type,return-value]


@pytest.mark.slow
def test_the_narrowest_step_is_gait_generates_verdict_in_one_line() -> None:
    robot = load_robot("exo")
    assert robotinit.narrowest_step(robot, robot.default_params.step_width, Config()) == ""
    why = robotinit.narrowest_step(robot, 0.05, Config())
    assert "step width 0.05 m makes the feet collide" in why and "\n" not in why
