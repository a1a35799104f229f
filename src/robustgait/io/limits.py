"""The documented limits of every input (``docs/inputs.md`` lists them; a test keeps the two in step).

A value outside its limit is refused with a one-line error, never clamped. The limits are generous for
any real legged robot or exoskeleton; they exist so that a typo (``1e6`` for ``1.0``), a NaN or an absurd
request fails at once instead of allocating memory until the process is killed or running for days.
Where a limit bounds work (steps, samples, durations, timestep), the worst case it allows is stated.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import msgspec


@dataclass(frozen=True)
class Limit:
    """A closed or half-open interval [low, high] for one input, with its unit (for messages and docs)."""

    name: str
    low: float | None
    high: float | None
    unit: str = ""
    low_open: bool = False
    high_open: bool = False

    def meta(self) -> msgspec.Meta:
        """The msgspec constraint of this limit (NaN fails every bound, so it is refused too)."""
        kw: dict[str, Any] = {}
        if self.low is not None:
            kw["gt" if self.low_open else "ge"] = self.low
        if self.high is not None:
            kw["lt" if self.high_open else "le"] = self.high
        return msgspec.Meta(**kw, extra={"unit": self.unit})

    def contains(self, value: float) -> bool:
        if math.isnan(value):
            return False
        if self.low is not None and (value <= self.low if self.low_open else value < self.low):
            return False
        return not (self.high is not None and (value >= self.high if self.high_open else value > self.high))

    def text(self) -> str:
        """``0.01 ≤ x ≤ 10 s`` style."""
        unit = f" {self.unit}" if self.unit else ""
        lo = "" if self.low is None else f"{number_text(self.low)} {'<' if self.low_open else '≤'} "
        hi = "" if self.high is None else f" {'<' if self.high_open else '≤'} {number_text(self.high)}"
        return f"{lo}x{hi}{unit}"


def number_text(v: float) -> str:
    """A limit's number as people write it: π, 1e7, 0.01."""
    if v == math.pi:
        return "π"
    if float(v).is_integer() and v > 2**20 and (int(v) + 1).bit_count() == 1:
        return f"2^{(int(v) + 1).bit_length() - 1} − 1"
    if float(v).is_integer() and abs(v) >= 1e5:
        return f"{v:.0e}".replace("e+0", "e").replace("e+", "e")
    return f"{v:g}"


def symmetric(name: str, bound: float, unit: str = "") -> Limit:
    return Limit(name, -bound, bound, unit)


# ------------------------------------------------------------------------------------------ input files
MAX_INPUT_BYTES = 64 * 2**20  # any input file (gait, spec, log): a real one is < 1 MiB
MAX_NESTING = 64  # depth of nested lists/objects in free-form values (meta, solver, inputparams)
MAX_JOINTS = 64  # actuated joints of a robot (= rows of a gait's Bézier coefficients)
MAX_DOMAINS = 8  # continuous domains of one gait
MAX_FEEDFORWARD_SAMPLES = 10_000  # phase samples of a domain's feedforward torque

DOMAIN_DURATION = Limit("domain duration", 0.01, 10.0, "s")
STEP_DURATION = Limit("step duration (sum of the domains)", 0.01, 10.0, "s")
BEZIER_COEFFICIENT = symmetric("Bézier coefficient", 100.0, "rad or m")
FEEDFORWARD_PHASE = Limit("feedforward phase τ", 0.0, 1.0)
FEEDFORWARD_TORQUE = symmetric("feedforward torque", 1e5, "N·m")
QPOS = symmetric("state qpos entry", 1000.0, "m or rad")
QVEL = symmetric("state qvel entry", 1000.0, "m/s or rad/s")
MIN_QUATERNION_NORM = 1e-6  # a base quaternion shorter than this cannot be normalized; others are

# robot spec (TOML)
KP = Limit("kp", 0.0, 1e7, "N·m/rad", low_open=True)
KD = Limit("kd", 0.0, 1e6, "N·m·s/rad", low_open=True)
TORQUE_LIMIT = Limit("torque_limit", 0.0, 1e5, "N·m", low_open=True)
TIMESTEP = Limit("sim.timestep", 1e-4, 0.1, "s", high_open=True)
MIN_BASE_HEIGHT = Limit("fall.min_base_height", 0.0, 10.0, "m")
MAX_TILT = Limit("fall.max_tilt", 0.0, math.pi, "rad", low_open=True)
QUALITY_ANGLE = Limit("gait_quality angle bound", 0.0, math.pi, "rad", low_open=True)
QUALITY_BAND = symmetric("gait_quality band end", 10.0, "rad or m")
QUALITY_ANGULAR_VELOCITY = Limit("gait_quality.pelvis_angular_velocity", 0.0, 100.0, "rad/s", low_open=True)
QUALITY_JOINT_VELOCITY = Limit("gait_quality.joint_velocity", 0.0, 1000.0, "rad/s", low_open=True)
POSTURE = symmetric("posture angle", 10.0, "rad or m")
MAX_GRID_POINTS = 1000  # grid points per action-space axis

# reduced-state logs (CSV, NPY, NPZ)
LOG_VALUE = symmetric("log value", 1e6)
MAX_LOG_COLUMNS = 1000
MAX_LOG_ROWS = 1_000_000

# ---------------------------------------------------------------------------------- command-line arguments
STEPS = Limit("--steps", 1, 1000)
SAMPLES = Limit("--samples", 1, 10_000)
FP_MAX_STEPS = Limit("--fp-max-steps", 1, 1000)
SEED = Limit("--seed", 0, 2**63 - 1)  # fits a signed 64-bit integer (study storage)
R_MAX = Limit("--r-max", 0.0, 10.0, "rad/s", low_open=True)  # a base angular velocity perturbation
ALPHA = Limit("--alpha", 0.0, 1.0, low_open=True, high_open=True)
EPSILON = Limit("--epsilon", 0.0, 1.0, low_open=True, high_open=True)  # a volume fraction
BETA = Limit("--beta", 0.0, 1.0, low_open=True, high_open=True)  # 1 − confidence
BUDGET = Limit("--budget", 1, 10_000)  # samples of a sequential certificate, as --samples
FP_TOL = Limit("--fp-tol", 0.0, 1.0, "rad/s", low_open=True)
BARRIER_R = Limit("--r", 0.0, 1e6, low_open=True)
X_STAR = symmetric("--x-star value", 1e6)
NODES = Limit("--nodes", 5, 101)  # odd; the problem build time grows with the node count
# studies: the budget (each gait is generated, walked and certified: seconds each), workers, compare seeds
ITERATIONS = Limit("study iterations", 1, 1000)
BATCH = Limit("study batch", 2, 100)  # a batch is ranked: at least two gaits to compare
WORKERS = Limit("--workers", 1, 256)
COMPARE_SEEDS = Limit("study compare --seeds", 1, 1000)
TRIALS = Limit("--trials", 1, 10_000)  # validation trials per disturbance kind (one batch)
STEPS_AFTER = Limit("--steps-after", 1, 1000)
FRAMES = Limit("--frames", 2, 60)  # gait tiles: each frame is a 320 × 480 tile in one PNG row
WARMUP_STEPS = Limit("--warmup-steps", 0, 1000)

# The work of one command: every simulated gait step counted to its latest end (τ = 1.5 without touchdown).
# A walk or certificate within every limit above can still combine a 10 s gait, a 1e-4 s timestep and 1000
# steps (1.5e8 physics steps, hours): the product is bounded too. 2e7 physics steps are ~3–7 min batched
# (certify, 2 cores) and ~30 min for one walk; the defaults (0.7 s exo gait, 1 ms) use 1e5–1e6.
MAX_PHYSICS_STEPS = 20_000_000
# A walk with --video keeps every physics step's state (~40 floats for exo) for the renderer: 2e6 steps are
# ~0.6 GB and ~30 min of motion at 1 ms (the defaults: 50 steps, 3.5e4 physics steps).
MAX_VIDEO_PHYSICS_STEPS = 2_000_000
# An animated .gif keeps every frame in memory until written (320×240, ~77 kB each): 1800 frames are 60 s at
# 30 fps, ~140 MB; the default walk (50 steps of a 0.7 s gait) is ~1100 frames. Longer videos: .mp4.
MAX_GIF_FRAMES = 1800


def check_gif(seconds: float, path: str, fps: int = 30) -> None:
    """Raise a one-line error if a .gif of up to ``seconds`` of motion could exceed :data:`MAX_GIF_FRAMES`."""
    from robustgait.errors import input_error

    frames = math.ceil(seconds * fps)
    if frames > MAX_GIF_FRAMES:
        raise input_error(path, f"this walk could last {seconds:g} s, {frames} frames at {fps} fps: a .gif holds at "
                          f"most {MAX_GIF_FRAMES} (use .mp4, or fewer --steps)")


def check_work(gait_steps: int, longest_step: float, timestep: float, what: str,
               limit: int = MAX_PHYSICS_STEPS) -> int:
    """Raise a one-line error if ``gait_steps`` simulated steps, each at most ``longest_step`` [s] long (the
    gait's step duration × ``SimConfig.max_step_tau``), could take more than ``limit`` physics steps of
    ``timestep`` [s]; return that worst-case count."""
    from robustgait.errors import RobustGaitError

    worst = int(gait_steps * math.ceil(longest_step / timestep))
    if worst > limit:
        raise RobustGaitError(
            f"{what}: {gait_steps} simulated steps of up to {longest_step:g} s at a {timestep:g} s timestep are up "
            f"to {worst:.2g} physics steps, over the limit of {limit:.0e} (ask for fewer steps or samples, or use "
            "a larger sim.timestep)")
    return worst
