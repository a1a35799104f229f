"""The orbit search: walk the gait until its switching states settle in a band, then check that states perturbed from
the band come back to it (``docs/certificate.md``, "The orbit the gait walks").

1. **Settled** — the gait is walked (:func:`robustgait.sim.walk.walk`, the walk every command runs) until its
   switching states settle (by ``orbit.max_steps``) and their band has held ``orbit.hold_steps`` more steps
   (:class:`.orbit.SettlingWatch`); the orbit, its period, band and x* are :func:`.orbit.walk_orbit`'s, so any walk
   of the same gait classified by it gives the same orbit once it has walked as far.
2. **Stable** — ``orbit.probe_pushes`` pushes of ``orbit.probe_impulse`` × m √(g l) at evenly spaced directions
   start from x*, each walked until it has come back to the band for ``push.recovery_steps`` steps, within
   ``orbit.probe_horizon`` steps (the push map's own walk, :class:`.push.PushMap`). ``unstable`` when a probe does
   not come back and keeps moving away from the band (:func:`.orbit.diverging`), or every probe falls; a probe that
   falls is a push beyond the gait's basin in its direction, which J* measures (:class:`.orbit.Probe`).
3. **ρ** — with ``orbit.linearization``, the linearized map at x* as a diagnostic (:mod:`.linearization`).

:func:`find_orbit` is the one way in: a gait walked here (:class:`Walking`, the three steps above), a walk the caller
already made (:class:`Walked`: step 1's classification alone) or a batched map instead of a walk (:class:`Iterated`,
maps whose answer is known, :mod:`.synthetic`).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from robustgait.certificate.band import advance_runs
from robustgait.certificate.linearization import linearize
from robustgait.certificate.orbit import (
    Orbit,
    Probe,
    SettlingWatch,
    Status,
    Watch,
    probe_of,
    unstable_reason,
    walk_orbit,
)
from robustgait.certificate.push import PushMap, push_phase
from robustgait.certificate.returnmap import FullStateMap
from robustgait.config import CertifyConfig, SimConfig, ValidateConfig
from robustgait.errors import RobustGaitError
from robustgait.gait import Gait
from robustgait.robots import Robot
from robustgait.sim.engine import StepEngine
from robustgait.sim.factory import make_engine
from robustgait.sim.walk import SwitchEvent, WalkResult, planned_speed, speed_note, walk

FloatArray = NDArray[np.float64]


def probe_impulse(robot: Robot, fraction: float) -> float:
    """J [N s] = fraction × m √(g l): an impulse relative to the robot's momentum at its pendulum speed."""
    return fraction * robot.mass * robot.scale.speed


def probe_stability(engine: StepEngine, orbit: Orbit, config: CertifyConfig, validate: ValidateConfig
                    ) -> tuple[Probe, int]:
    """The stability probe of step 2 (module docstring) from the settled ``orbit``'s x* and band, and the physics
    steps it simulated: ``orbit.probe_pushes`` pushes at evenly spaced directions, their impulse doubled (at most
    ``orbit.probe_doublings`` times) while none of them takes the walk out of its band — a probe that never leaves
    the band tests nothing."""
    assert orbit.qpos is not None and orbit.qvel is not None and orbit.band is not None
    o, robot = config.orbit, engine.robot
    angles = 2.0 * math.pi * np.arange(o.probe_pushes) / o.probe_pushes
    push = dataclasses.replace(config.push, recovery=True, horizon=o.probe_horizon)
    pm = PushMap(engine, orbit.qpos, orbit.qvel, orbit.band, validate, push)
    size = probe_impulse(robot, o.probe_impulse)
    for doubling in range(o.probe_doublings + 1):
        impulse = size * np.column_stack([np.cos(angles), np.sin(angles)])
        _, _, fall_step, recovered = pm.walk(impulse, push_phase(impulse, *validate.push_phase))
        assert pm.farthest is not None
        left = pm.farthest > 1.0
        if left.any() or (fall_step > 0).any() or doubling == o.probe_doublings:
            break
        size *= 2.0
    assert pm.trace is not None
    return probe_of(size, o.probe_horizon, recovered, fall_step, left, pm.trace, o.probe_growth), pm.physics_steps


@dataclass(frozen=True)
class Walking:
    """Switching states from walking ``gait`` on ``robot`` here (module docstring, steps 1–3): the walk stops where
    the rule has its answer, then the orbit's stability is probed. ``sim``: the simulation options (an ``engine``
    given is used as it is and left open; otherwise one is built from ``sim`` and closed); ``validate``: the push
    duration and phases of the probe; ``progress(step)`` after each step of the walk."""

    robot: Robot
    gait: Gait
    sim: SimConfig | None = None
    validate: ValidateConfig | None = None
    engine: StepEngine | None = None
    progress: Callable[[int], None] | None = None


@dataclass(frozen=True)
class Walked:
    """Switching states of a walk the caller already made (``result``, :func:`robustgait.sim.walk.walk` of ``gait``
    on ``robot``): classified as they are (:func:`.orbit.walk_orbit`) — no simulation, no stability probe; the same
    orbit :class:`Walking` finds once the walk went as far."""

    robot: Robot
    gait: Gait
    result: WalkResult


@dataclass(frozen=True)
class Iterated:
    """Switching states from iterating a batched map ``F``: (N, d) → (N, d) of band coordinates (NaN rows: the sample
    fell) from ``x0`` (d,), probed with states perturbed by ``perturbation`` (u uniform on the unit L∞ sphere,
    ``seed``); ``min_period`` the shortest period searched: maps whose answer is known (:mod:`.synthetic`)."""

    F: Callable[[FloatArray], FloatArray]
    x0: FloatArray
    perturbation: float
    min_period: int = 1
    seed: int = 0


def find_orbit(source: Walking | Walked | Iterated, config: CertifyConfig | None = None) -> Orbit:
    """The orbit of a source of switching states, by the one rule (:class:`.orbit.Watch`) and the one probe verdict
    (:func:`.orbit.probe_of`) with the options of ``config`` (``orbit``, ``map``, ``push``): a gait walked here
    (:class:`Walking`: settled, stable, with ``orbit.linearization`` ρ), a walk already made (:class:`Walked`:
    settled, not probed) or a batched map (:class:`Iterated`). Never raises for a gait that falls or does not
    settle: the orbit's status says so (:class:`.orbit.Status`)."""
    cfg = config or CertifyConfig()
    if isinstance(source, Walked):
        return walk_orbit(source.robot, source.gait, source.result, cfg)
    if isinstance(source, Iterated):
        return _iterate(source, cfg)
    return _walk_and_probe(source, cfg)


def _walk_and_probe(source: Walking, cfg: CertifyConfig) -> Orbit:
    """:func:`find_orbit` of a gait walked here (module docstring, steps 1–3)."""
    robot, gait, progress = source.robot, source.gait, source.progress
    v = source.validate or ValidateConfig()
    own = source.engine is None
    eng = source.engine or make_engine(robot, gait, source.sim)
    try:
        watch = SettlingWatch(robot, gait.stance, cfg)

        def until(events: list[SwitchEvent]) -> bool:
            if progress is not None:
                progress(len(events))
            return watch(events)

        result = walk(robot, gait, eng.config, steps=cfg.orbit.max_steps + cfg.orbit.hold_steps, engine=eng,
                      until=until)
        orbit = walk_orbit(robot, gait, result, cfg)
        physics = result.physics_steps
        if orbit.ok and cfg.orbit.probe_impulse > 0:
            probe, steps = probe_stability(eng, orbit, cfg, v)
            physics += steps
            orbit = dataclasses.replace(orbit, probe=probe)
            if not probe.ok:
                orbit = dataclasses.replace(orbit, status=Status.UNSTABLE, reason=unstable_reason(
                    probe, "the walk", f"pushes of {probe.impulse:.3g} N s", "steps"))
        if orbit.ok and cfg.orbit.linearization:
            assert orbit.qpos is not None and orbit.qvel is not None
            with FullStateMap(robot, gait, orbit.period, engine=eng) as fmap:
                orbit = dataclasses.replace(orbit, linearization=linearize(fmap, orbit.qpos, orbit.qvel, cfg.orbit))
                physics += fmap.physics_steps
        return dataclasses.replace(orbit, physics_steps=physics)
    finally:
        if own:
            eng.close()


def orbit_speed_note(orbit: Orbit, gait: Gait, sim: SimConfig) -> str:
    """:func:`robustgait.sim.walk.speed_note` of the orbit search's walk (its ``walk_speed`` and ``sole_turn``)
    against the gait's planned speed with ``sim.speed_agreement``: "" when that walk fell, was not recorded (an orbit
    from an older record) or the gait has no planned speed (a FROST import)."""
    plan = planned_speed(gait)
    if orbit.status == Status.FELL or orbit.walk_speed is None or plan is None:
        return ""
    return speed_note(orbit.walk_speed, plan, sim.speed_agreement, orbit.sole_turn)


def initial_section(robot: Robot, gait: Gait, engine: StepEngine) -> tuple[FloatArray, FloatArray]:
    """The gait's initial state as a canonical section state (1, nq), (1, nv): itself for a flat-foot gait; a
    multi-contact gait starts at the beginning of single support, so it is walked to its heel strike first and
    mirrored. Raises :class:`RobustGaitError` if it falls on the way."""
    init = gait.initial_state
    if init is None:
        raise RobustGaitError("the gait has no initial state to start from")
    qpos, qvel = init.qpos[None].copy(), init.qvel[None].copy()
    if len(engine.graph) > 1:
        b = engine.step(qpos, qvel, gait.stance, domain=0)
        if b.fell[0]:
            raise RobustGaitError(f"the gait fell within step 1 ({b.fall_reason[0]}) before its first switching event")
        qpos, qvel = robot.mirror_state(b.qpos, b.qvel)
    return qpos, qvel


def _iterate(source: Iterated, config: CertifyConfig) -> Orbit:
    """:func:`find_orbit` of a batched map (:class:`Iterated`): iterate F from x0 until the iterates settle (at most
    ``orbit.max_steps`` maps) and their band held, then probe stability with ``orbit.probe_pushes`` states x* +
    perturbation u, each iterated until it has been back in the band for ``push.recovery_steps`` consecutive maps
    within ``orbit.probe_horizon`` maps: the verdict of a robot's search, on a map whose answer is known."""
    F, perturbation = source.F, source.perturbation
    o, p = config.orbit, config.push
    watch = Watch(o, source.min_period, p.recovery_radius, p.recovery_scatter)
    x = np.asarray(source.x0, dtype=float)
    fell: str | None = None
    while not watch.done:
        x = np.asarray(F(x[None]), dtype=float)[0]
        if not np.all(np.isfinite(x)):
            fell = "the map's image is not finite"
            break
        watch.add(x)
    orbit, i = watch.orbit(fell)
    z = np.array(watch.z)
    if i is None or orbit.band is None:
        return orbit
    rng = np.random.default_rng(source.seed)
    u = rng.uniform(-1.0, 1.0, (o.probe_pushes, z.shape[1]))
    u /= np.abs(u).max(axis=1, keepdims=True)
    states = z[i] + perturbation * u
    run = np.zeros((o.probe_pushes, orbit.band.period), dtype=np.int64)
    back = np.zeros(o.probe_pushes, dtype=np.int64)
    trace = np.full((o.probe_pushes, o.probe_horizon), np.nan)
    left = np.zeros(o.probe_pushes, dtype=bool)
    fallen = np.zeros(o.probe_pushes, dtype=bool)
    for j in range(1, o.probe_horizon + 1):
        live = (back == 0) & ~fallen
        if not live.any():
            break
        states[live] = np.asarray(F(states[live]), dtype=float)
        fallen |= live & ~np.isfinite(states).all(axis=1)
        shifted = advance_runs(orbit.band, run, np.where(live[:, None], states, np.nan), j)
        with np.errstate(invalid="ignore"):
            left |= live & (shifted[:, 0] > 1.0)
        trace[live, j - 1] = shifted[live].min(axis=1)
        back[live & (run.max(axis=1) >= p.recovery_steps)] = j
    probe = probe_of(perturbation, o.probe_horizon, back, fallen, left, trace, o.probe_growth)
    orbit = dataclasses.replace(orbit, probe=probe)
    if not probe.ok:
        orbit = dataclasses.replace(orbit, status=Status.UNSTABLE, reason=unstable_reason(
            probe, "the iterates", f"states perturbed by {perturbation:g}", "maps"))
    return orbit
