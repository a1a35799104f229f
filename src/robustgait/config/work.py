"""Bounds on the work of one command, checked before any of it: each option is within its limits, but their
product can still be hours.

Work is counted as the command's worst case, :class:`Work`: the steps it may simulate (every sample surviving
every step) × the physics steps one step may take, the engine's horizons at the robot's timestep — single
support to τ = ``sim.max_step_tau`` (a later touchdown is a fall), a multi-contact step's rolling double support
to τ = 1 (:func:`robustgait.sim.engine.step_horizons`). Two bounds, in units that do not depend on how long the
robot's steps are:

* **One step** may take at most :data:`MAX_STEP_PHYSICS_STEPS` = 30 000 physics steps: a 2 s step to τ = 1.5 at
  1e-4 s (exo's and Atalante's steps need 1 050–1 800 at 1 ms). This refuses a resolution no gait needs — a
  1e-5 s timestep, a 10 s gait at 1e-4 s, ``max_step_tau`` 10 on a 5 s gait — whatever the counts.
* **The command** may take at most :data:`WORK_HEADROOM` = 4 × what its default settings take on the same robot
  and gait (the same steps, default ``max_step_tau``), or :data:`MAX_PHYSICS_STEPS` = 2e7 physics steps if that
  is more. Counted in simulated steps this hardly depends on the robot: a certificate simulates its orbit search
  (``orbit.max_steps`` + ``orbit.hold_steps`` steps of the walk and the stability probe's pushes,
  :meth:`~robustgait.config.CertifyConfig.orbit_steps`) and, per planned sample, the steps of
  :attr:`~robustgait.config.CertifyConfig.steps_per_sample` (a push: the pushed step and ``push.horizon`` more),
  every sample counted as walking to its horizon (:func:`robustgait.certificate.certify.certify_steps`); a request
  may simulate 4 × what the defaults do, so the defaults pass on every robot and domain graph, and a setting that
  multiplies the steps beyond that — ``certify.push.horizon`` 100 with the default budget, ``validate --trials
  10000 --steps-after 1000`` — is refused before any work. The 2e7 floor keeps small jobs on small robots passing.
  The defaults' worst cases: ``docs/inputs.md`` (``benchmarks/perf/work.py``).

Memory, not time, bounds a video: every state of the walk is kept for the renderer, and an animated .gif keeps
every frame until it is written; those limits are absolute.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from robustgait.errors import RobustGaitError

MAX_PHYSICS_STEPS = 20_000_000
WORK_HEADROOM = 4
MAX_STEP_PHYSICS_STEPS = 30_000
# A walk with a video keeps every physics step's state (~40 floats for exo) for the renderer: 2e6 steps are
# ~0.6 GB and ~30 min of motion at 1 ms (the defaults: 50 steps, 5e4–9e4 physics steps).
MAX_VIDEO_PHYSICS_STEPS = 2_000_000
# An animated .gif keeps every frame in memory until written (320×240 palette images, 77 kB each: 3600 frames,
# 2 min at 30 fps, are 280 MB). The default walk (50 steps, each to its worst case) is up to 1575 frames on exo's
# 0.7 s gait and 2565 on Atalante's longest multi-contact steps (1.2 s: 1710 physics steps each). Longer: .mp4.
MAX_GIF_FRAMES = 3600


@dataclass(frozen=True)
class Work:
    """A command's worst case: ``steps`` simulated steps, each of up to ``step_physics`` physics steps."""

    steps: int
    step_physics: int

    @property
    def physics_steps(self) -> int:
        return self.steps * self.step_physics


def work_limit(defaults: Work) -> int:
    """The most physics steps a command may take: :data:`WORK_HEADROOM` × its defaults' worst case on the same
    robot and gait, or :data:`MAX_PHYSICS_STEPS` if that is more (module docstring)."""
    return max(MAX_PHYSICS_STEPS, WORK_HEADROOM * defaults.physics_steps)


def check_work(work: Work, defaults: Work | None, timestep: float, what: str, limit: int | None = None) -> int:
    """Raise a one-line error if one of ``work``'s steps could take more than :data:`MAX_STEP_PHYSICS_STEPS`
    physics steps of ``timestep`` [s], or all of them more than ``limit`` (default :func:`work_limit` of the
    command's ``defaults``); return the worst-case count. ``what`` names the settings that asked for the work."""
    seconds = work.step_physics * timestep
    if work.step_physics > MAX_STEP_PHYSICS_STEPS:
        raise RobustGaitError(
            f"{what}: one simulated step may last {seconds:g} s, {work.step_physics} physics steps at a {timestep:g} "
            f"s timestep, over the limit of {MAX_STEP_PHYSICS_STEPS} per step (use a larger sim.timestep, a shorter "
            "gait or a smaller sim.max_step_tau)")
    if limit is None:
        assert defaults is not None
        limit = work_limit(defaults)
        basis = (f" ({WORK_HEADROOM} × the {defaults.physics_steps:.2g} the defaults need here)"
                 if limit > MAX_PHYSICS_STEPS else "")
    else:
        basis = ""
    worst = work.physics_steps
    if worst > limit:
        raise RobustGaitError(
            f"{what}: {work.steps} simulated steps of up to {seconds:g} s at a {timestep:g} s timestep are up to "
            f"{worst:.2g} physics steps, over the limit of {limit:.2g}{basis} (ask for fewer steps or samples, or "
            "use a larger sim.timestep)")
    return worst


def check_gif(seconds: float, path: str, fps: int = 30) -> None:
    """Raise a one-line error if a .gif of up to ``seconds`` of motion could exceed :data:`MAX_GIF_FRAMES`."""
    frames = math.ceil(seconds * fps)
    if frames > MAX_GIF_FRAMES:
        raise RobustGaitError(f"{path}: this walk could last {seconds:g} s, {frames} frames at {fps} fps: a .gif "
                              f"holds at most {MAX_GIF_FRAMES} (use .mp4, or fewer steps)")
