"""The push map of a certificate in the disturbance's own units (``certify --disturbance push``,
``docs/certificate.md``, "J*").

A sample is a horizontal impulse J = (J_x, J_y) [N s] in the heading frame of the fixed point x*. The robot starts on
its periodic orbit at x* (canonical stance), is pushed at its base's centre of mass with the force J / duration for
the validation's ``push_duration``, starting at a phase φ of the step in the validation's ``push_phase`` range (as
``robustgait validate --disturbance push``), and walks on for ``push.steps`` steps. A push *fails* when the robot
falls within those steps or, at their end, is not back in its orbit's neighbourhood
(:mod:`.recovery`: the base's Froude-scaled velocity within ``push.recovery_radius`` of x*'s, or
within a multiple of the undisturbed orbit's own scatter). The map returns the fixed point (0, 0) when the push did not
fail and NaN when it failed, so the DTBF condition of :mod:`.barrier` reads "no failure" and the
largest certified ball is J*: with confidence 1 − β at most ε of the pushes uniform in the disk |J| ≤ J* (the
estimators' statement) make the robot fall or leave it off its orbit after those steps.

The phase is a function of the sample (:func:`push_phase`: a hash of J's bytes mapped into the phase range), so the
map is deterministic — the estimators' assumption — while over the disk the phases are uniform, and the pushes of
one seed (common random numbers) meet every gait at the same phases.
"""

from __future__ import annotations

import hashlib
import math
from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

from robustgait.certificate.poincare import FixedPoint
from robustgait.config import PushConfig, ValidateConfig
from robustgait.rotations import quat_to_mat
from robustgait.sim.engine import StepEngine
from robustgait.sim.trials import orbit_band, pushed_first_step, simulate_trials, wrench_window

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


NOT_RECOVERED = "not_recovered"  # the reason of a push that did not fall but ended off its orbit


class PushMap:
    """J (N, 2) → (N, 2): (0, 0) if the push did not fail — the robot did not fall within the pushed step and
    ``push.steps`` more and is back in its orbit's neighbourhood at their end — NaN if it failed (module docstring).
    ``engine``: the gait's engine; ``fp``: its fixed point (a section state that starts a step of the gait's stance).
    The walk is the validation's (:func:`robustgait.sim.trials.simulate_trials`): a multi-contact step is the previous
    leg's rolling double support then the single support, and the push's window spans the whole step, as
    ``validate --disturbance push``'s."""

    def __init__(self, engine: StepEngine, fp: FixedPoint, validate: ValidateConfig, push: PushConfig):
        self.engine, self.fp, self.steps = engine, fp, push.steps
        self.validate = validate
        r = quat_to_mat(fp.qpos[3:7])
        self.heading = float(math.atan2(r[1, 0], r[0, 0]))
        self.step_duration = next(iter(engine.gaits.values())).step_duration
        self.window = sum(engine.horizons)  # a step runs each domain once (robustgait.domains.step_segments)
        self.physics_steps = 0
        self.band = orbit_band(engine, fp.qpos, fp.qvel, push)
        self.physics_steps = 0  # the band's undisturbed steps are the fixed point's, not the samples'
        self.fall_step: list[NDArray[np.int64]] = []  # per call: the 1-based step each sample fell in (0: none)
        self.distance: list[FloatArray] = []  # per call: each sample's distance from the orbit at the end (NaN: fell)

    def walk(self, impulse: FloatArray, phase: FloatArray) -> tuple[NDArray[np.bool_], list[str | None],
                                                                   NDArray[np.int64], FloatArray]:
        """Push the robot with impulses J (N, 2) [N s, heading frame] starting at the phases φ (N,) of the step and
        walk ``steps`` more: whether each push did not fail, its failure reason (a fall reason, or
        :data:`NOT_RECOVERED`), the 1-based step it fell in (0: none) and its scaled distance from the orbit at the
        end (:meth:`OrbitBand.distance`; NaN if it fell, 0 without a band). The map (:meth:`__call__`) is this walk
        at the phases of :func:`push_phase`; an explicit φ maps a gait's failing set over direction and phase
        (``benchmarks/bench_certify.py push-sweep``)."""
        j = np.atleast_2d(np.asarray(impulse, dtype=float))
        n = j.shape[0]
        eng, cfg = self.engine, self.validate
        wrench = push_series(j, np.asarray(phase, dtype=float), self.heading, cfg.push_duration, self.step_duration,
                             eng.robot.dt, self.window)
        qpos, qvel = np.tile(self.fp.qpos, (n, 1)), np.tile(self.fp.qvel, (n, 1))
        n_steps = 1 + self.steps
        alive, reasons, fall_step, last, physics = simulate_trials(eng, qpos, qvel, n_steps, n_steps,
                                                                   pushed_first_step(eng, wrench), first_at=0)
        self.physics_steps += physics
        distance = np.full(n, np.nan)
        distance[alive] = 0.0
        if self.band is not None and alive.any():
            nq = eng.nq
            distance[alive] = self.band.distance(last[alive, :nq], last[alive, nq:])
            off = alive & (distance > self.band.radius)
            alive = alive & ~off
            reasons = [NOT_RECOVERED if o else r for o, r in zip(off, reasons, strict=True)]
        return alive, reasons, fall_step, distance

    def __call__(self, impulse: FloatArray, progress: Callable[[int], None] | None = None) -> FloatArray:
        j = np.atleast_2d(np.asarray(impulse, dtype=float))
        ok, _, fall_step, distance = self.walk(j, push_phase(j, *self.validate.push_phase))
        if progress is not None:
            progress(j.shape[0])
        self.fall_step.append(fall_step)
        self.distance.append(distance)
        out = np.zeros((j.shape[0], 2))
        out[~ok] = np.nan
        return out
