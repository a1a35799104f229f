"""``robustgait robot init`` end to end (``docs/robots.md``, "Your robot"): the draft of a model (:mod:`.draft`), its
timestep chosen by accuracy (:mod:`.timestep`) with the gains drafted at each candidate step, and the spec's text
(:mod:`.writer`).

With ``robot.timestep_rule`` = ``accuracy`` (the default) each candidate step h (:func:`.timestep.candidate_timesteps`;
one whose drafted gains would be lowered to contract is above the servos' stability bound and not tried) is the spec
robot init would write at h with stable PD, loaded as a robot; the default gait is generated once (the gains and the
step do not enter the gait's optimisation) and walked at each candidate (:func:`.timestep.select_timestep`). When the
default gait cannot be generated, no candidate is below the stability bound, or none is accurate enough, the timestep
is the servo rule's (:func:`.gains.servo_timestep`, without stable PD), with a note saying why. When the step
regulator runs for the robot's soles, the default gait's walk also says whether its ankle holds the centre of mass
(:func:`measured_balance`): a point-foot walker's step durations end at λT = ``robot.scale.point_foot_step``
(``line_foot_step`` on capsule line feet), and its window's narrowest and longest steps are tried: one that does not
pass ``gait generate`` moves that end of the window to the default (:func:`window_end`, :func:`with_balance`).
"""

from __future__ import annotations

import dataclasses
import functools
import sys
from collections.abc import Callable
from pathlib import Path

from robustgait.config import Config
from robustgait.errors import RobustGaitError
from robustgait.gait import Gait
from robustgait.gaitgen import GaitGenerator
from robustgait.gaitgen.walkcheck import generate_walking
from robustgait.inspection.scale import TRIED_ENDS, Balance, capsule_line_feet, scale
from robustgait.io.robotfile import read_mjcf, spec_from_raw
from robustgait.robotinit.draft import Draft, draft_at_timestep, draft_spec, lowered
from robustgait.robotinit.timestep import candidate_timesteps, default_gait, ms, select_timestep
from robustgait.robotinit.writer import render
from robustgait.robots import Robot
from robustgait.sim.engine import StepEngine
from robustgait.sim.regulator_rules import regulator_rule

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover - exercised on 3.10 only
    import tomli as tomllib


def draft_robot(draft: Draft, spec_path: str | Path) -> Robot:
    """The robot of the spec a draft renders (:func:`.writer.render`, written at ``spec_path``: the model's path is
    relative to it), loaded without writing a file. Raises RobustGaitError when that spec does not load."""
    p = Path(spec_path)
    try:
        spec = spec_from_raw(tomllib.loads(render(draft, p)), p)
        return Robot(spec, read_mjcf(spec))
    except RobustGaitError as exc:  # as write_spec says it of the spec it would write
        raise RobustGaitError(f"{p}: the written spec does not load (nothing written): {exc}") from None


def init_spec(model: str | Path, spec_path: str | Path, config: Config,
              say: Callable[[str], None] | None = None) -> Draft:
    """The draft ``robot init`` writes for ``model`` at ``spec_path`` (module docstring); ``say(line)`` is told what it
    walks as it goes. Raises RobustGaitError (one line) for a model it cannot draft; a default gait that cannot be
    generated is a note, never an error."""
    tell = say or (lambda line: None)
    draft = draft_spec(model, config.robot)
    if config.robot.timestep_rule == "servo":
        return draft
    model_dt = float(draft.robot.model.opt.timestep)
    drafts = {h: draft_at_timestep(draft, h, True) for h in candidate_timesteps(model_dt,
                                                                               config.robot.timestep_candidates)}
    excluded = tuple(h for h, d in drafts.items() if lowered(d))
    candidates = [h for h in drafts if h not in excluded]
    if not candidates:
        draft.notes.append(f"every timestep candidate ({', '.join(ms(h) for h in drafts)}) is above the servos' "
                           "stability bound (their gains would be lowered to contract): the timestep is the servo "
                           "rule's")
        return draft
    robots: dict[float, Robot] = {}

    def robot_at(h: float) -> Robot:
        if h not in robots:
            robots[h] = draft_robot(drafts[h], spec_path)
        return robots[h]

    tell(f"generating the default gait of {draft.name} to choose its timestep (robot.timestep_rule accuracy) ...")
    gait, why = default_gait(robot_at(candidates[0]), config)
    if gait is None:
        draft.notes.append(f"the default gait could not be generated ({why}): the timestep is the servo rule's, not "
                           "chosen by walking it (robot.timestep_rule)")
        return draft
    choice = dataclasses.replace(select_timestep(robot_at, gait, candidates, config, say=tell), excluded=excluded)
    if not choice.passed:  # no step is accurate enough with stable PD: the servo rule's
        draft.notes.append(f"{choice.note}: the timestep is the servo rule's, without stable PD")
        return with_balance(draft, lambda: draft_robot(draft, spec_path), gait, config, tell)
    out = draft_at_timestep(draft, choice.timestep, True, choice)
    if choice.note:
        out.notes.append(choice.note)
    return with_balance(out, lambda: robot_at(choice.timestep), gait, config, tell)


def measured_balance(robot: Robot, gait: Gait, config: Config) -> Balance | None:
    """The default gait's step-to-step balance on ``robot`` (:class:`~robustgait.inspection.scale.Balance`): the share
    κ of the H-LIP gain its step regulator settles on by measuring the walk's lateral growth
    (:func:`~robustgait.sim.regulator.lateral_growth`), and the H-LIP's rate λ; None when the regulator does not run
    (``sim.regulator``: soles wide for the robot)."""
    with StepEngine(robot, gait, config.sim) as engine:
        reg = engine.regulator
        return None if reg is None else Balance(reg.share, reg.lam)


def window_end(robot: Robot, axis: str, value: float, config: Config,
               generator: Callable[[], GaitGenerator] | None = None) -> str:
    """Why the robot's default flat-foot gait with ``axis`` (a GaitParams field) at ``value`` does not pass ``gait
    generate`` — its solve, its walk check and the one retry (:func:`~robustgait.gaitgen.walkcheck.generate_walking`)
    — in one line; "" when it passes. ``generator()``: the flat-foot generator of ``robot`` to use (one is built
    when None). Never raises for a failed solve or walk."""
    cfg = dataclasses.replace(config, generate=dataclasses.replace(config.generate, domains="flat"))
    params = dataclasses.replace(robot.default_params.resolved("flat"), **{axis: value})
    try:
        gen = generator() if generator is not None else GaitGenerator(robot, cfg.generate)
        checked = generate_walking(robot, params, cfg, gen)
    except RobustGaitError as exc:
        return str(exc)
    if checked.result.gait is None:
        return f"its solve failed ({checked.result.status}: {checked.result.reason})"
    if checked.walked is not None and not checked.walked.passed:
        return checked.walked.text()
    return ""


def with_balance(draft: Draft, robot: Callable[[], Robot], gait: Gait, config: Config,
                 say: Callable[[str], None] | None = None) -> Draft:
    """The draft with its scaled values bounded by the default gait's balance as ``robot()`` (the draft's robot)
    walks it (:func:`measured_balance`), and notes saying so: a point-foot walker's step durations end at λT =
    ``robot.scale.point_foot_step`` (:func:`~robustgait.inspection.scale.duration_rule`), and each end of
    :data:`~robustgait.inspection.scale.TRIED_ENDS` (the narrowest step, the longest) that does not pass ``gait
    generate`` with the other parameters at the default (:func:`window_end`) moves to the default
    (:func:`~robustgait.inspection.scale.tried_rule`). Unchanged when the step regulator does not run for the robot's
    soles (``sim.regulator``) or applies less than ``robot.scale.point_foot_share`` of the H-LIP's gain (the ankle
    holds the centre of mass). ``say(line)`` is told what it walks."""
    if not regulator_rule(config.sim.regulator, draft.size.sole_width, draft.size.leg_length, 1)[0]:
        return draft
    rules = config.robot.scale
    drafted = robot()
    balance = measured_balance(drafted, gait, config)
    if balance is None or not balance.point_foot(rules):
        return draft
    scaled = scale(draft.size, rules, balance)
    notes, tell = list(draft.notes), say or (lambda line: None)
    failed: dict[str, tuple[float, str]] = {}
    # one flat-foot generator for every end tried, built by the first
    generator = functools.cache(lambda: GaitGenerator(drafted, dataclasses.replace(config.generate, domains="flat")))
    for axis, end in TRIED_ENDS.items():
        value, default = scaled.action_space[axis][end], scaled.gait[axis]
        if (value - default) * (1 if end else -1) <= 0:  # the window does not reach past the default there
            continue
        tell(f"walking the window's {'longest' if end else 'narrowest'} step ({axis.replace('_', ' ')} {value:g} m)"
             " ...")
        why = window_end(drafted, axis, value, config, generator)
        if why:
            failed[axis] = (value, why)
    if failed:
        balance = dataclasses.replace(balance, ends_fail=tuple(failed))
        scaled = scale(draft.size, rules, balance)
        for axis, (value, why) in failed.items():
            low, high, _ = scaled.action_space[axis]
            notes.append(f"the default gait with {axis} {value:g} m, the window's end, does not pass gait generate "
                         f"({why}): a point-foot walker's {axis} window stops at the default "
                         f"{scaled.gait[axis]:g} m, {low:g}–{high:g} m (robot.scale.action_{axis})")
    if scaled == draft.scaled:
        return draft
    low, high, _ = scaled.action_space["step_duration"]
    step, name = ((rules.line_foot_step, "line_foot_step: capsule line feet") if capsule_line_feet(draft.size)
                  else (rules.point_foot_step, "point_foot_step"))
    notes.insert(len(draft.notes), f"the default gait balances by foot placement (the step regulator applies κ = "
                 f"{balance.share:.2g} of the H-LIP's stepping gain, at least robot.scale.point_foot_share "
                 f"{rules.point_foot_share:g}: the ankle does not hold the centre of mass): its step durations end "
                 f"at λT = {step:g} (λ = √(g/z0) = {balance.rate:.3g} 1/s), {low:g}–{high:g} s "
                 f"(robot.scale.{name})")
    return dataclasses.replace(draft, scaled=scaled, balance=balance, notes=notes)
