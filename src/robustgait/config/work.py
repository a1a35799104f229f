"""Bounds on the work of one command: each option is within its limits, but their product can still be hours.

A walk or certificate within every option's limits can combine a 10 s gait, a 1e-4 s timestep and 1000 steps
(1.5e8 physics steps): the product is bounded too, before any work starts. 2e7 physics steps are ~3–7 min batched
(certify, 2 cores) and ~30 min for one walk; the defaults (0.7 s exo gait, 1 ms) use 1e5–1e6.
"""

from __future__ import annotations

import math

from robustgait.errors import RobustGaitError

MAX_PHYSICS_STEPS = 20_000_000
# A walk with a video keeps every physics step's state (~40 floats for exo) for the renderer: 2e6 steps are
# ~0.6 GB and ~30 min of motion at 1 ms (the defaults: 50 steps, 3.5e4 physics steps).
MAX_VIDEO_PHYSICS_STEPS = 2_000_000
# An animated .gif keeps every frame in memory until written (320×240, ~77 kB each): 1800 frames are 60 s at
# 30 fps, ~140 MB; the default walk (50 steps of a 0.7 s gait) is ~1100 frames. Longer videos: .mp4.
MAX_GIF_FRAMES = 1800


def check_work(gait_steps: int, longest_step: float, timestep: float, what: str,
               limit: int = MAX_PHYSICS_STEPS) -> int:
    """Raise a one-line error if ``gait_steps`` simulated steps, each at most ``longest_step`` [s] long (a step's
    duration × ``SimConfig.max_step_tau``), could take more than ``limit`` physics steps of ``timestep`` [s];
    return that worst-case count. ``what`` names the settings that asked for the work."""
    worst = int(gait_steps * math.ceil(longest_step / timestep))
    if worst > limit:
        raise RobustGaitError(
            f"{what}: {gait_steps} simulated steps of up to {longest_step:g} s at a {timestep:g} s timestep are up "
            f"to {worst:.2g} physics steps, over the limit of {limit:.0e} (ask for fewer steps or samples, or use "
            "a larger sim.timestep)")
    return worst


def check_gif(seconds: float, path: str, fps: int = 30) -> None:
    """Raise a one-line error if a .gif of up to ``seconds`` of motion could exceed :data:`MAX_GIF_FRAMES`."""
    frames = math.ceil(seconds * fps)
    if frames > MAX_GIF_FRAMES:
        raise RobustGaitError(f"{path}: this walk could last {seconds:g} s, {frames} frames at {fps} fps: a .gif "
                              f"holds at most {MAX_GIF_FRAMES} (use .mp4, or fewer steps)")
