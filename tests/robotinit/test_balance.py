"""A point-foot walker's action space from its measured balance (robustgait.robotinit.init.with_balance, docs/robots.md,
"Narrow soles"): the narrowest and the longest step of its window tried with gait generate, and that end of the window
moved to the default when the step does not pass (the balance and the tries stubbed); the try itself end to end on
exo (slow: gaits generated and walked)."""

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
from tests.inspection.biped import biped_xml, write


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
    tried: list[tuple[str, float]] = []

    def narrow_fails(robot: object, axis: str, value: float, cfg: Config, generator: object = None) -> str:
        tried.append((axis, value))
        return "the gait fell in step 3 under pd+hlip (stub)" if axis == "step_width" else ""

    monkeypatch.setattr(robotinit, "window_end", narrow_fails)
    said: list[str] = []
    out = robotinit.with_balance(draft, lambda: None, None, config, said.append)  # type: ignore[arg-type,return-value]
    rule = scale(draft.size, config.robot.scale, balance).action_space
    narrow, longest = rule["step_width"][0], rule["step_length"][1]
    default = draft.scaled.gait["step_width"]
    assert tried == [("step_width", narrow), ("step_length", longest)] and narrow < default
    assert any(f"step width {narrow:g} m" in line for line in said)
    low, high, step = out.scaled.action_space["step_width"]
    assert abs(low - default) <= step / 2 + 1e-9 and out.balance is not None
    assert out.balance.ends_fail == ("step_width",)
    assert out.scaled.action_space["step_length"] == rule["step_length"]  # the longest step passed: kept
    note = next(n for n in out.notes if "the window's end" in n)
    assert "(the gait fell in step 3 under pd+hlip (stub))" in note and f"{low:g}–{high:g} m" in note
    assert any("balances by foot placement" in n for n in out.notes)
    assert "the window's end of step_width did not pass gait generate" in render(out, tmp_path / "spec.toml")

    # both walk: the rule's window
    monkeypatch.setattr(robotinit, "window_end", lambda robot, axis, value, cfg, generator=None: "")
    walks = robotinit.with_balance(draft, lambda: None, None, config)  # type: ignore[arg-type,return-value]
    assert walks.scaled == scale(draft.size, config.robot.scale, balance)
    assert walks.balance is not None and walks.balance.ends_fail == ()
    assert not any("the window's end" in n for n in walks.notes)

    monkeypatch.setattr(robotinit, "window_end", lambda robot, axis, value, cfg, generator=None: "fell (stub)")
    both = robotinit.with_balance(draft, lambda: None, None, config)  # type: ignore[arg-type,return-value]
    assert both.balance is not None and both.balance.ends_fail == ("step_width", "step_length")
    high_l, step_l = both.scaled.action_space["step_length"][1:]
    assert high_l <= draft.scaled.gait["step_length"] + step_l / 2 + 1e-9 < rule["step_length"][1]  # not past it


def test_an_ankle_that_holds_tries_no_narrow_step(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    config = regulated()
    draft = draft_spec(write(tmp_path, biped_xml()), config.robot)
    monkeypatch.setattr(robotinit, "measured_balance", lambda robot, gait, cfg: Balance(share=0.2, rate=3.3))
    monkeypatch.setattr(robotinit, "window_end", lambda *a: pytest.fail("tried a window's end"))
    assert robotinit.with_balance(draft, lambda: None, None, config) is draft  # type: ignore[arg-type,return-value]


@pytest.mark.slow
def test_a_window_end_is_gait_generates_verdict_in_one_line() -> None:
    robot = load_robot("exo")
    assert robotinit.window_end(robot, "step_width", robot.default_params.step_width, Config()) == ""
    why = robotinit.window_end(robot, "step_width", 0.05, Config())
    assert "step width 0.05 m makes the feet collide" in why and "\n" not in why
