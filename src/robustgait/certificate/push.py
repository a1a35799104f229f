"""The push map of a certificate in the disturbance's own units (``certify --disturbance push``,
``docs/certificate.md``, "J*").

A sample is a horizontal impulse J = (J_x, J_y) [N s] in the heading frame of x*. The robot starts on its orbit at x*
(a switching state the undisturbed walk reached, :mod:`.orbit`), is pushed at its base's centre of mass with the force
J / duration for the validation's ``push_duration``, starting at a phase φ of the step in the validation's
``push_phase`` range (as ``robustgait validate --disturbance push``), and walks on. A push **fails** when the robot
falls within the pushed step and ``push.horizon`` more. A pushed walk stops as soon as it has **recovered** — its
whole switching state back in its orbit's band (:class:`.band.Band`) for ``push.recovery_steps`` consecutive steps,
from where the orbit's own stability brings it home (a walk back in the band does not fall later:
``docs/certificate.md`` "Recovery") — so a push costs the steps it needs, and a push that neither falls nor recovers
walks the whole horizon. The map returns (0, 0) when the push did not fail and NaN when it failed, so the DTBF
condition of :mod:`.barrier` reads "no failure" and the largest certified ball is J*: with confidence 1 − β at most ε
of the pushes uniform in the disk |J| ≤ J* (the estimators' statement) make the robot fall within the horizon.

The phase is a function of the sample (:func:`push_phase`: a hash of J's bytes mapped into the phase range), so the
map is deterministic — the estimators' assumption — while over the disk the phases are uniform, and the pushes of
one seed (common random numbers) meet every gait at the same phases.
"""

from __future__ import annotations

import dataclasses
import hashlib
import math
from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

from robustgait.certificate.band import Band, advance_runs, band_coordinates
from robustgait.config import PushConfig, ValidateConfig
from robustgait.robots import Robot
from robustgait.rotations import quat_to_mat
from robustgait.sim.engine import StepEngine
from robustgait.sim.trials import Stop, pushed_first_step, simulate_trials, wrench_window

FloatArray = NDArray[np.float64]


def push_phase(impulse: FloatArray, low: float, high: float) -> FloatArray:
    """φ (N,) ∈ [low, high): the phase of the step at which push i starts, low + u_i (high − low) with u_i the first
    8 bytes of BLAKE2b(J_i as two little-endian float64) / 2⁶⁴ — uniform over the disk, a function of J alone."""
    j = np.ascontiguousarray(np.atleast_2d(impulse), dtype="<f8")
    u = np.array([int.from_bytes(hashlib.blake2b(row.tobytes(), digest_size=8).digest(), "little") / 2.0**64
                  for row in j])
    return np.asarray(low + u * (high - low))


def push_series(impulse: FloatArray, phase: FloatArray, heading: float, duration: float, period: float, dt: float,
                horizon: int) -> FloatArray:
    """Base wrench series (N, horizon, 6) [N, N m]: the force J/duration, J rotated from the heading frame into the
    world by the heading ψ, over round(duration/dt) physics steps from step round(φ·period/dt)."""
    width = max(1, round(duration / dt))
    c, s = math.cos(heading), math.sin(heading)
    world = np.stack([c * impulse[:, 0] - s * impulse[:, 1], s * impulse[:, 0] + c * impulse[:, 1]], axis=1)
    return wrench_window(world / (width * dt), np.round(phase * period / dt).astype(int), width, horizon)


def recovery_stop(band: Band, robot: Robot, steps: int, recovered: NDArray[np.int64],
                  farthest: FloatArray | None = None, trace: FloatArray | None = None) -> Stop:
    """The stop rule of recovering walks (:func:`robustgait.sim.trials.simulate_trials`): a trial is done once its
    section state has been in ``band`` for ``steps`` consecutive steps, in phase with the orbit or shifted by whole
    steps (:func:`.band.advance_runs`: the state after j steps from x* in the band of phase (j + s) mod k, the same s
    throughout the run); ``recovered`` (K,) gets the step it was done at (1-based, counted from the pushed
    step), ``farthest`` (K,), if given, the largest in-phase band distance (:meth:`.band.Band.distance`) of its
    states until then, and ``trace`` (K, H), if given, after each step its distance from the band under the nearest
    shift (NaN once it stopped or fell)."""
    run = np.zeros((recovered.shape[0], band.period), dtype=np.int64)
    nq = robot.model.nq

    def stop(k: int, idx: NDArray[np.int64], states: FloatArray) -> NDArray[np.bool_]:
        z = band_coordinates(robot, states[:, :nq], states[:, nq:])
        runs = run[idx]
        shifted = advance_runs(band, runs, z, k + 1)
        run[idx] = runs
        if farthest is not None:
            farthest[idx] = np.fmax(farthest[idx], shifted[:, 0])
        if trace is not None:
            trace[idx, k] = shifted.min(axis=1)
        done = runs.max(axis=1) >= steps
        recovered[idx[done]] = k + 1
        return np.asarray(done)
    return stop


def recovered_steps(band: Band, robot: Robot, sections: FloatArray, steps: int) -> NDArray[np.int64]:
    """The step (1-based) at which each walk had been in ``band`` for ``steps`` consecutive steps, 0 if it never was,
    from its section states after every step (K, H, nq + nv) from x* (canonical; NaN after a fall): the rule of
    :func:`recovery_stop` on recorded walks (``validate``)."""
    k, h, _ = sections.shape
    recovered = np.zeros(k, dtype=np.int64)
    stop = recovery_stop(band, robot, steps, recovered)
    live = np.ones(k, dtype=bool)
    for j in range(h):
        idx = np.flatnonzero(live & np.isfinite(sections[:, j]).all(axis=1))
        if idx.size:
            live[idx[stop(j, idx, sections[idx, j])]] = False
    return recovered


class PushMap:
    """J (N, 2) → (N, 2): (0, 0) if the push did not fail, NaN if it failed (module docstring). ``engine``: the gait's
    engine; ``qpos``, ``qvel``: x* (a section state that starts a step of the gait's stance), ``band``: its orbit's
    band, where a recovered walk stops (with ``push.recovery_radius`` as its floor; None, or ``push.recovery`` false:
    every push walks the whole horizon); ``push``: the rule of a push — the statement's, or an exploration push's
    (:meth:`~robustgait.config.PushConfig.exploring`). The walk
    is the validation's (:func:`robustgait.sim.trials.simulate_trials`): a multi-contact step is the previous leg's
    rolling double support then the single support, and the push's window spans the whole step, as ``validate
    --disturbance push``'s."""

    def __init__(self, engine: StepEngine, qpos: FloatArray, qvel: FloatArray, band: Band | None,
                 validate: ValidateConfig, push: PushConfig):
        self.engine, self.qpos, self.qvel = engine, qpos, qvel
        # the band's floor is this rule's (an exploration push's band is looser than the statement's)
        self.band = dataclasses.replace(band, radius=push.recovery_radius) if band is not None and push.recovery \
            else None
        self.horizon, self.recovery_steps = push.horizon, push.recovery_steps
        self.validate = validate
        r = quat_to_mat(qpos[3:7])
        self.heading = float(math.atan2(r[1, 0], r[0, 0]))
        self.step_duration = next(iter(engine.gaits.values())).step_duration
        self.window = sum(engine.horizons)  # a step runs each domain once (robustgait.domains.step_segments)
        self.physics_steps = 0
        self.fall_step: list[NDArray[np.int64]] = []  # per call: the 1-based step each sample fell in (0: none)
        self.recovered: list[NDArray[np.int64]] = []  # per call: the step each sample was recovered at (0: not)
        self.farthest: FloatArray | None = None  # the last walk's largest band distance per sample (with a band)
        self.trace: FloatArray | None = None  # the last walk's band distance after every step (K, 1 + horizon)

    def walk(self, impulse: FloatArray, phase: FloatArray) -> tuple[NDArray[np.bool_], list[str | None],
                                                                   NDArray[np.int64], NDArray[np.int64]]:
        """Push the robot with impulses J (N, 2) [N s, heading frame] starting at the phases φ (N,) of the step and
        walk until each push recovered, fell, or the horizon: whether each push did not fail (fall), its fall reason
        (None: none), the 1-based step it fell in (0: none) and the step it was back in the band for
        ``recovery_steps`` steps (0: it was not; without a band, 0). The map (:meth:`__call__`) is this walk at
        the phases of :func:`push_phase`; an explicit φ maps a gait's failing set over direction and phase
        (``benchmarks/experiments/push_cost/run.py push-sweep``)."""
        j = np.atleast_2d(np.asarray(impulse, dtype=float))
        n = j.shape[0]
        eng, cfg = self.engine, self.validate
        wrench = push_series(j, np.asarray(phase, dtype=float), self.heading, cfg.push_duration, self.step_duration,
                             eng.robot.dt, self.window)
        recovered = np.zeros(n, dtype=np.int64)
        n_steps = 1 + self.horizon
        self.farthest, self.trace = np.zeros(n), np.full((n, n_steps), np.nan)
        stop = (recovery_stop(self.band, eng.robot, self.recovery_steps, recovered, self.farthest, self.trace)
                if self.band is not None else None)
        alive, reasons, fall_step, _, physics = simulate_trials(
            eng, np.tile(self.qpos, (n, 1)), np.tile(self.qvel, (n, 1)), n_steps, n_steps,
            pushed_first_step(eng, wrench), first_at=0, stop=stop)
        self.physics_steps += physics
        return alive, reasons, fall_step, recovered

    def __call__(self, impulse: FloatArray, progress: Callable[[int], None] | None = None) -> FloatArray:
        j = np.atleast_2d(np.asarray(impulse, dtype=float))
        ok, _, fall_step, recovered = self.walk(j, push_phase(j, *self.validate.push_phase))
        if progress is not None:
            progress(j.shape[0])
        self.fall_step.append(fall_step)
        self.recovered.append(recovered)
        out = np.zeros((j.shape[0], 2))
        out[~ok] = np.nan
        return out
