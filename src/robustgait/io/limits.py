"""The limits of every input *file* (gait, robot spec, reduced-state log), as data: the schemas use them, their
messages and ``docs/inputs.md`` state the same numbers (a test keeps the page in step). The limits of options
are their config fields' (:mod:`robustgait.config`), those of the work of a command :mod:`robustgait.config.work`.

A value outside its limit is refused with a one-line error, never clamped. The limits are generous for any real
legged robot or exoskeleton; they exist so that a typo (``1e6`` for ``1.0``), a NaN or an absurd file fails at
once instead of allocating memory until the process is killed.
"""

from __future__ import annotations

import math

from robustgait.config.base import Doc

MAX_INPUT_BYTES = 64 * 2**20  # any input file (gait, spec, log): a real one is < 1 MiB
MAX_NESTING = 64  # depth of nested lists/objects in free-form values (meta, solver, inputparams)
MAX_JOINTS = 64  # actuated joints of a robot (= rows of a gait's Bézier coefficients)
MAX_DOMAINS = 8  # continuous domains of one gait
MAX_FEEDFORWARD_SAMPLES = 10_000  # phase samples of a domain's feedforward torque

DOMAIN_DURATION = Doc("domain duration", unit="s", ge=0.01, le=10.0)
STEP_DURATION = Doc("step duration (sum of the domains)", unit="s", ge=0.01, le=10.0)
BEZIER_COEFFICIENT = Doc("Bézier coefficient", unit="rad or m", ge=-100.0, le=100.0)
FEEDFORWARD_PHASE = Doc("feedforward phase τ", ge=0.0, le=1.0)
FEEDFORWARD_TORQUE = Doc("feedforward torque", unit="N·m", ge=-1e5, le=1e5)
QPOS = Doc("state qpos entry", unit="m or rad", ge=-1000.0, le=1000.0)
QVEL = Doc("state qvel entry", unit="m/s or rad/s", ge=-1000.0, le=1000.0)
MIN_QUATERNION_NORM = 1e-6  # a base quaternion shorter than this cannot be normalized; others are

# robot spec (TOML)
KP = Doc("kp", unit="N·m/rad", gt=0.0, le=1e7)
KD = Doc("kd", unit="N·m·s/rad", gt=0.0, le=1e6)
TORQUE_LIMIT = Doc("torque_limit", unit="N·m", gt=0.0, le=1e5)
PASSIVITY_LAMBDA = Doc("controller.passivity.lambda", unit="1/s", gt=0.0, le=1e4)
TIMESTEP = Doc("sim.timestep", unit="s", ge=1e-4, lt=0.1)
STABLE_PD = Doc("sim.stable_pd: servo damping kd + h kp, integrated implicitly (stable PD)")
MIN_BASE_HEIGHT = Doc("fall.min_base_height", unit="m", ge=0.0, le=10.0)
MAX_TILT = Doc("fall.max_tilt", unit="rad", gt=0.0, le=math.pi)
QUALITY_ANGLE = Doc("gait_quality angle bound", unit="rad", gt=0.0, le=math.pi)
QUALITY_BAND = Doc("gait_quality band end", unit="rad or m", ge=-10.0, le=10.0)
QUALITY_ANGULAR_VELOCITY = Doc("gait_quality.pelvis_angular_velocity", unit="rad/s", gt=0.0, le=100.0)
QUALITY_JOINT_VELOCITY = Doc("gait_quality.joint_velocity", unit="rad/s", gt=0.0, le=1000.0)
POSTURE = Doc("posture angle", unit="rad or m", ge=-10.0, le=10.0)
MAX_GRID_POINTS = 1000  # grid points per action-space axis

# reduced-state logs (CSV, NPY, NPZ) and the numbers given with them to barrier-eval
LOG_VALUE = Doc("log value", ge=-1e6, le=1e6)
MAX_LOG_COLUMNS = 1000
MAX_LOG_ROWS = 1_000_000
BARRIER_R = Doc("barrier-eval --r", gt=0.0, le=1e6)
X_STAR = Doc("barrier-eval --x-star value", ge=-1e6, le=1e6)
