"""The physics timestep by accuracy (``docs/robots.md``, "The timestep"): how far a robot's walk at a timestep h is
from its walk at h/2, and the largest candidate h that is close enough.

* **A trial** of h (:func:`run_trial`): the robot's default gait (:func:`default_gait`) walked from its start at h
  and at h/2 — the same servos, the same ``stable_pd``: only the physics step halved (:meth:`Robot.at_timestep`) —
  each until the certificate's orbit rule has its answer (:func:`robustgait.certificate.search.find_orbit`'s walk,
  without the stability probe). Its **error** is the largest difference of the two settled bands' centres, phase by
  phase, in band coordinates (:func:`band_difference`); undefined unless both walks settled.
* **The rule** (:func:`choose_timestep`): the largest candidate whose two walks settled and whose error is at most
  ``robot.timestep_tolerance``; when none is, the smallest candidate, with a one-line note. The candidates
  (:func:`candidate_timesteps`): the model's own step and ``robot.timestep_candidates``, largest first.
* ``robot check``'s ``timestep`` check (:func:`check_timestep`): the trial of the spec's own timestep.

The walks are the simulation's own and never raise for a gait that falls or does not settle: the trial says so.
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from robustgait.certificate.orbit import Status
from robustgait.certificate.search import Walking, find_orbit
from robustgait.config import Config
from robustgait.config.gait import reach_problem
from robustgait.errors import RobustGaitError
from robustgait.gait import Gait
from robustgait.gaitgen import GaitGenerator
from robustgait.inspection.check import CheckResult
from robustgait.robots import Robot

FloatArray = NDArray[np.float64]
Say = Callable[[str], None]


def ms(h: float) -> str:
    """A timestep [s] in words: ``0.5 ms``."""
    return f"{h * 1e3:.4g} ms"


@dataclass(frozen=True)
class TimestepWalk:
    """One walk of a gait until the orbit rule's answer: its ``timestep`` [s], the orbit's ``status``
    (:class:`~robustgait.certificate.orbit.Status`) and ``reason`` (empty when ok), ``steps`` walked, the
    settled band's ``period`` and ``centres`` (k, d) in band coordinates (None when it did not settle),
    ``sides_differ`` (its period was searched from 2: the robot's left and right differ), ``physics_steps`` simulated
    and the wall ``seconds``."""

    timestep: float
    status: Status
    reason: str
    steps: int
    period: int
    centres: FloatArray | None
    sides_differ: bool
    physics_steps: int
    seconds: float

    @property
    def settled(self) -> bool:
        return self.status == Status.OK and self.centres is not None

    def describe(self) -> str:
        """A clause: ``settled (period 2)``, ``fell in step 57``, ``did not settle``."""
        if self.settled:
            return f"settled (period {self.period})"
        if self.status == Status.FELL:
            return f"fell in step {self.steps + 1}"
        return "did not settle" if self.status == Status.UNSETTLED else str(self.status)


@dataclass(frozen=True)
class Trial:
    """A candidate ``timestep`` [s]: its walk at h (``coarse``) and at h/2 (``fine``), and the ``error`` (the largest
    difference of their settled band centres, band coordinates; None unless both settled)."""

    timestep: float
    coarse: TimestepWalk
    fine: TimestepWalk
    error: float | None

    @property
    def settled(self) -> bool:
        return self.coarse.settled and self.fine.settled

    def passes(self, tolerance: float) -> bool:
        """Both walks settled and the error is at most ``tolerance``."""
        return self.settled and self.error is not None and self.error <= tolerance

    def why_not(self, tolerance: float) -> str:
        """A clause saying why the trial does not pass (empty when it does)."""
        if self.passes(tolerance):
            return ""
        for w in (self.coarse, self.fine):
            if not w.settled:
                return f"its walk at {ms(w.timestep)} {w.describe()}"
        return f"{self.error:.3g} against {ms(self.fine.timestep)}, over {tolerance:g}"

    def describe(self, tolerance: float) -> str:
        """One line: the error against h/2, or why there is none."""
        if self.error is not None:
            verdict = "within" if self.passes(tolerance) else "over"
            return (f"{ms(self.timestep)} against {ms(self.fine.timestep)}: {self.error:.3g} band units ({verdict} "
                    f"{tolerance:g})")
        return f"{ms(self.timestep)}: {self.why_not(tolerance)}"


@dataclass(frozen=True)
class TimestepChoice:
    """The accuracy rule's answer (module docstring): the chosen ``timestep`` [s]; ``passed`` whether a candidate
    passed (else it is the smallest, and ``note`` says so in one line); the ``tolerance`` (band coordinates); the
    ``candidates`` [s], largest first, and the ``trials`` walked (largest first: those below the chosen one are not
    walked unless every candidate was asked for); ``excluded``: candidates not tried, above the servos' stability
    bound (their gains would be lowered to contract)."""

    timestep: float
    passed: bool
    tolerance: float
    candidates: tuple[float, ...]
    trials: tuple[Trial, ...]
    note: str = ""
    excluded: tuple[float, ...] = ()

    def trial(self, h: float) -> Trial | None:
        return next((t for t in self.trials if t.timestep == h), None)

    @property
    def chosen(self) -> Trial | None:
        return self.trial(self.timestep)

    @property
    def larger(self) -> Trial | None:
        """The trial of the next larger candidate than the chosen one (why it was not taken), None for the first."""
        before = [t for t in self.trials if t.timestep > self.timestep]
        return before[-1] if before else None


def candidate_timesteps(model_dt: float, candidates: Sequence[float]) -> tuple[float, ...]:
    """The timesteps [s] to try, largest first: the model's own ``model_dt`` and the ``candidates`` (the model's step
    counted once when it is one of them). A candidate above the model's step is tried too: the accuracy test, not the
    model file's choice, decides."""
    out = list(candidates)
    if not any(math.isclose(h, model_dt, rel_tol=1e-9) for h in out):
        out.append(model_dt)
    return tuple(sorted(out, reverse=True))


def band_difference(a: FloatArray, b: FloatArray, stride: int = 1) -> float:
    """The largest |a − b| over phases and coordinates of two bands' centres a (k_a, d), b (k_b, d) of walks from the
    same start (phase p: the states after j ≡ p steps), both tiled to the least common multiple of their periods,
    under the best cyclic shift by a multiple of ``stride`` steps (2 for a robot whose left and right differ: a
    state is only compared with one of the same stance)."""
    n = math.lcm(a.shape[0], b.shape[0])
    ta, tb = np.tile(a, (n // a.shape[0], 1)), np.tile(b, (n // b.shape[0], 1))
    return float(min(np.max(np.abs(ta - np.roll(tb, s, axis=0))) for s in range(0, n, max(1, stride))))


def trial_error(coarse: TimestepWalk, fine: TimestepWalk) -> float | None:
    """The error of a trial (:func:`band_difference` of the settled centres), None unless both walks settled."""
    if coarse.centres is None or fine.centres is None or not (coarse.settled and fine.settled):
        return None
    return band_difference(coarse.centres, fine.centres, 2 if coarse.sides_differ or fine.sides_differ else 1)


def choose_timestep(trials: Sequence[Trial], tolerance: float) -> tuple[float, bool, str]:
    """The rule on trials of candidates, largest first: (the largest passing candidate, True, ""), or (the smallest
    candidate, False, a one-line note saying that none passed). Raises RobustGaitError without trials."""
    if not trials:
        raise RobustGaitError("no timestep candidate to choose from")
    for t in trials:
        if t.passes(tolerance):
            return t.timestep, True, ""
    last = trials[-1]
    return last.timestep, False, (
        f"no timestep candidate kept the default gait's switching states within {tolerance:g} band units of those at "
        f"half the step (robot.timestep_tolerance): the smallest, {ms(last.timestep)}, {last.why_not(tolerance)}")


def default_gait(robot: Robot, config: Config) -> tuple[Gait | None, str]:
    """The robot's default gait — its spec's ``[gait]`` (:attr:`Robot.default_params`) solved with
    ``config.generate``, as ``gait generate`` solves it (without its walk check) — or (None, why) when it cannot be: a
    step beyond the robot's reach, a failed solve, or an error while the problem is built or solved. Never raises."""
    try:
        params = robot.default_params.resolved(config.generate.domains)
        problem = reach_problem(params, robot.scale, config.generate)
        if problem is not None:
            return None, problem
        res = GaitGenerator(robot, config.generate).solve(params)
    except Exception as exc:  # a model the NLP cannot be built for fails in CasADi's or adam's own exceptions
        return None, f"{type(exc).__name__}: {' '.join(str(exc).split())[:200]}"
    if res.gait is None:
        return None, f"its solve failed ({res.status}: {res.reason})"
    return res.gait, ""


def settled_walk(robot: Robot, gait: Gait, config: Config) -> TimestepWalk:
    """The gait walked from its start with ``config.sim`` until the orbit rule of ``config.certify`` has its answer
    (:func:`robustgait.certificate.search.find_orbit`, no stability probe, no linearization)."""
    c = config.certify
    certify = dataclasses.replace(c, orbit=dataclasses.replace(c.orbit, probe_impulse=0.0, linearization=False))
    t0 = time.perf_counter()
    o = find_orbit(Walking(robot, gait, config.sim), certify)
    return TimestepWalk(robot.dt, o.status, o.reason, o.steps, o.period,
                  None if o.band is None or not o.ok else np.array(o.band.centres), o.sides_differ, o.physics_steps,
                  time.perf_counter() - t0)


WalkCache = dict[tuple[float, tuple[float, ...], tuple[float, ...]], TimestepWalk]


def _walk(robot: Robot, gait: Gait, config: Config, cache: WalkCache) -> TimestepWalk:
    """:func:`settled_walk`, once per physics step and servos: the reference of one candidate is the walk of the next
    when its gains are the same."""
    key = (robot.dt, tuple(robot.servo_kp.tolist()), tuple(robot.servo_kd.tolist()))
    if key not in cache:
        cache[key] = settled_walk(robot, gait, config)
    return cache[key]


def run_trial(robot: Robot, gait: Gait, config: Config, cache: WalkCache | None = None) -> Trial:
    """The trial of the robot's own timestep h (module docstring): ``gait`` walked by ``robot`` and by
    ``robot.at_timestep(h / 2)`` with the spec's ``stable_pd``. ``cache``: walks already made of the same gait and
    spec (:func:`_walk`)."""
    walks = {} if cache is None else cache
    fine = robot.at_timestep(robot.dt / 2, robot.spec.stable_pd)
    a, b = _walk(robot, gait, config, walks), _walk(fine, gait, config, walks)
    return Trial(robot.dt, a, b, trial_error(a, b))


def select_timestep(robot_at: Callable[[float], Robot], gait: Gait, candidates: Sequence[float], config: Config, *,
                    every: bool = False, say: Say | None = None) -> TimestepChoice:
    """The accuracy rule (module docstring) over ``candidates`` [s], largest first: ``robot_at(h)`` is the robot at
    candidate h (its gains drafted at h, stable PD or not as its spec says); the trials stop at the first that passes
    unless ``every``. ``say(line)`` is told each trial as it starts and ends. Raises RobustGaitError without
    candidates."""
    tell = say or (lambda line: None)
    tol = config.robot.timestep_tolerance
    cache: WalkCache = {}
    trials = []
    for h in candidates:
        robot = robot_at(h)
        tell(f"timestep {ms(h)}: walking the default gait at {ms(h)} and {ms(h / 2)}"
             f"{' (stable PD)' if robot.spec.stable_pd else ''} until its switching states settle ...")
        t = run_trial(robot, gait, config, cache)
        trials.append(t)
        tell(f"timestep {t.describe(tol)}")
        if t.passes(tol) and not every:
            break
    h, passed, note = choose_timestep(trials, tol)
    return TimestepChoice(h, passed, tol, tuple(candidates), tuple(trials), note)


def check_timestep(robot: Robot, config: Config, say: Say | None = None) -> CheckResult:
    """``robot check``'s ``timestep``: the trial of the spec's own timestep (:func:`run_trial`, the default gait of
    :func:`default_gait`) passes ``robot.timestep_tolerance``. Fails, saying why, when the default gait cannot be
    generated."""
    tell = say or (lambda line: None)
    h, tol, spd = robot.dt, config.robot.timestep_tolerance, robot.spec.stable_pd
    how = f"{ms(h)}{' (stable PD)' if spd else ''}"
    tell(f"timestep: generating the default gait, then walking it at {how} and {ms(h / 2)} ...")
    gait, why = default_gait(robot, config)
    if gait is None:
        return CheckResult("timestep", False, f"timestep: FAIL: the default gait could not be generated ({why}): the "
                           f"spec's {ms(h)} is not checked", {"timestep": h, "tolerance": tol})
    t = run_trial(robot, gait, config)
    ok = t.passes(tol)
    values: dict[str, float] = {"timestep": h, "reference": h / 2, "tolerance": tol, "stable_pd": spd,
                                "settled": t.settled, "seconds": t.coarse.seconds + t.fine.seconds}
    verdict = f"timestep: {'ok' if ok else 'FAIL'}: the default gait's settled switching states at {how} and at "
    limit = f"(at most {tol:g}, robot.timestep_tolerance)"
    if t.error is None:
        return CheckResult("timestep", False, f"{verdict}{ms(h / 2)} cannot be compared {limit}: {t.why_not(tol)}",
                           values)
    values["error"] = t.error
    return CheckResult("timestep", ok, f"{verdict}{ms(h / 2)} differ by {t.error:.3g} band units {limit}; "
                       f"{t.coarse.describe()} at {ms(h)}", values)
