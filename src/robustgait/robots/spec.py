"""Robot specs as data (``docs/robots.md``): what the pipeline needs to know about a robot beyond its MJCF.

A spec names the floating-base body, the actuated joints in output order, each leg's sole geom, the
left/right relabeling, PD gains and torque limits, fall criteria, simulation options, the gait-quality bounds
of generation, the action space of studies and the cold-start posture. :mod:`robustgait.io.robotfile` reads
it from TOML; :class:`robustgait.robots.model.Robot` compiles the robot from it and its MJCF.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Literal

SHIPPED_DIR = Path(__file__).resolve().parent
SIDES = ("left", "right")
Integrator = Literal["euler", "implicitfast", "implicit", "rk4"]


@dataclass(frozen=True)
class LegSpec:
    """One leg's sole, named in exactly one way: ``sole_geom`` (one box geom whose bottom face is the sole),
    ``sole_geoms`` (a set of sphere, capsule or box geoms of one body) or ``sole_body`` (every colliding geom of
    that body; with ``sole_class`` only those of that default class). Names in the MJCF are not required for the
    last. A sole that is not one box is represented by a virtual box spanning its lowest points
    (:func:`robustgait.robots.soles.resolve_sole`)."""

    sole_geom: str | None = None
    sole_geoms: tuple[str, ...] = ()
    sole_body: str | None = None
    sole_class: str | None = None

    def describe(self) -> str:
        """How the sole is named, for messages: ``geom 'x'``, ``geoms 'a', 'b'``, ``body 'b' (class 'c')``."""
        if self.sole_geom is not None:
            return f"geom '{self.sole_geom}'"
        if self.sole_geoms:
            return "geoms " + ", ".join(f"'{g}'" for g in self.sole_geoms)
        cls = f" (class '{self.sole_class}')" if self.sole_class is not None else ""
        return f"body '{self.sole_body}'{cls}"


@dataclass(frozen=True)
class FallCriteria:
    """A state is a fall when the base is lower than ``min_base_height`` [m] or its z axis is tilted
    more than ``max_tilt`` [rad] from vertical (plus non-foot ground contact and a diverging simulation)."""

    min_base_height: float = 0.5
    max_tilt: float = 0.8


@dataclass(frozen=True)
class GaitQuality:
    """Bounds that a generated gait must satisfy at every node (docs/design.md §2, §4): what an exoskeleton's
    passenger needs besides the essential constraints. Angles of the pelvis are roll-pitch-yaw (ZYX)
    relative to the stance sole's frame; heights are above the stance sole.

    pelvis_roll, pelvis_yaw [rad]: |φ|, |ψ| ≤ bound. pelvis_pitch [rad]: (low, high) band.
    pelvis_height [m]: (low, high) band of the base origin above the stance sole.
    pelvis_angular_velocity [rad/s]: each component of the base's angular velocity (world axes) ≤ bound; None (not
    in the spec): relative to the robot, :data:`robustgait.config.gait.PELVIS_RATE_FROUDE` √(g / l) (1.5 rad/s on a
    leg of 0.92 m like exo's; larger on a smaller robot, whose motions are faster).
    pelvis_acceleration [m/s²]: each component of the pelvis origin's linear acceleration ≤ bound (what the
    passenger feels; unbounded by default).
    swing_tilt [rad]: swing sole roll and pitch ≤ bound (kept nearly parallel to the ground).
    swing_yaw [rad]: |yaw| of the swing sole ≤ bound (relative to the stance sole: no twisting foot).
    swing_toe_down_until: multi-contact only — the phase of single support by which the swing sole, which
    leaves toe-off pitched toe-down, must be back within swing_tilt (its toe-down bound falls linearly from
    the toe-off pitch bound at τ = 0; 0: within swing_tilt from the first node on).
    joint_velocity [rad/s]: |q̇_i| ≤ bound per actuated joint (output order).
    """

    pelvis_roll: float = 0.1
    pelvis_yaw: float = 0.1
    pelvis_pitch: tuple[float, float] = (-0.1, 0.2)
    pelvis_height: tuple[float, float] = (0.0, math.inf)
    pelvis_angular_velocity: float | None = None
    pelvis_acceleration: float = math.inf
    swing_tilt: float = 0.15
    swing_yaw: float = 0.15
    swing_toe_down_until: float = 0.0
    joint_velocity: tuple[float, ...] = ()


@dataclass(frozen=True)
class ParamRange:
    """One axis of a robot's action space for studies: ``low ≤ value ≤ high`` on a grid of ``step``."""

    low: float
    high: float
    step: float

    def grid(self) -> tuple[float, ...]:
        """The grid values low, low + step, ..., ≤ high (rounded to 1e-9 so that 0.1 + 0.02 k is exact)."""
        n = math.floor((self.high - self.low) / self.step + 1e-9)
        return tuple(round(self.low + k * self.step, 9) for k in range(n + 1))


@dataclass(frozen=True)
class PassivitySpec:
    """``[controller.passivity]``: per-joint gains (output order) of the passivity-based tracking law of
    :mod:`robustgait.sim.passivity`: ``lam`` Λ [1/s] (the key ``lambda``) and ``kd`` K_D [N m s/rad]."""

    lam: tuple[float, ...]
    kd: tuple[float, ...]


@dataclass(frozen=True)
class HeldJoint:
    """A joint the gait does not plan (``[joints.held]``): held by its servo (gains ``kp``, ``kd``, clamp
    ``torque_limit``) at ``angle`` [rad or m] in simulation, welded at that angle in the optimization's model.
    ``mirror``: the held joint it becomes under the left/right relabeling, with ``sign``."""

    name: str
    angle: float
    kp: float
    kd: float
    torque_limit: float
    mirror: str
    sign: float


@dataclass(frozen=True)
class RobotSpec:
    """Everything the pipeline needs to know about a robot beyond its MJCF.

    ``floor_geom`` None: the world's only plane geom; ``add_floor``: the MJCF has none and a plane
    (:data:`ADDED_FLOOR`) is added at load. ``held``: joints held at an angle (:class:`HeldJoint`).
    ``generation``, ``gait``: the robot's own defaults of gait-generation options and gait parameters (the spec's
    ``[generation]`` and ``[gait]`` tables; what is not there resolves as in :mod:`robustgait.config`).
    ``passive``: the joints of closed chains that are neither planned nor held (``joints.passive``; solved from the
    loops, :mod:`robustgait.robots.loops`); ``loops``: the model's loop equalities, key → (kind, end, end)
    (``[loops]``); ``springs``: joint → (stiffness, springref) (``[springs]``); ``feet``: side → ``line`` or
    ``point`` for a sole without support width (``legs.<side>.foot``; a side not in it is ``flat``)."""

    name: str
    mjcf: Path
    base_body: str
    floor_geom: str | None
    joints: tuple[str, ...]
    kp: tuple[float, ...]
    kd: tuple[float, ...]
    torque_limit: tuple[float, ...]
    legs: dict[str, LegSpec]
    mirror_perm: tuple[int, ...]
    mirror_sign: tuple[float, ...]
    base_mirror_sign: tuple[float, ...] = (1.0, -1.0, 1.0, -1.0, 1.0, -1.0)
    fall: FallCriteria = field(default_factory=FallCriteria)
    timestep: float | None = None
    integrator: str | None = None
    stable_pd: bool = False
    description: str = ""
    source: Path | None = None
    gait_quality: GaitQuality = field(default_factory=GaitQuality)
    action_space: dict[str, ParamRange] | None = None
    multicontact_action_space: dict[str, ParamRange] | None = None
    posture: tuple[float, ...] = ()
    passivity: PassivitySpec | None = None
    add_floor: bool = False
    held: tuple[HeldJoint, ...] = ()
    generation: dict[str, float] = field(default_factory=dict)
    gait: dict[str, float] = field(default_factory=dict)
    passive: tuple[str, ...] = ()
    loops: dict[str, tuple[str, str, str]] = field(default_factory=dict)
    springs: dict[str, tuple[float, float]] = field(default_factory=dict)
    feet: dict[str, str] = field(default_factory=dict)

    @property
    def n_joints(self) -> int:
        return len(self.joints)

    @property
    def held_names(self) -> tuple[str, ...]:
        return tuple(h.name for h in self.held)


CLOSED_CHAIN_FIELDS = ("passive", "loops", "springs", "feet")
"""The spec's fields of closed chains, springs and line feet: empty for a serial robot with flat soles."""

FOOT_KINDS = ("flat", "line", "point")
"""A sole's kind by its support: an area (flat), a line of contact (one capsule: no width), a point."""

ADDED_FLOOR = "robustgait_floor"
"""Name of the floor plane added at load (``add_floor = true``) or given to the MJCF's unnamed plane."""


ACTION_FIELDS = ("step_length", "step_duration", "step_width", "step_height")
