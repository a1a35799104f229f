"""Options of gait generation: :class:`GaitGenConfig` (problem options and gait-quality overrides)."""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

from robustgait.domains import GRAPH_NAMES
from robustgait.errors import RobustGaitError
from robustgait.gait import GaitParams
from robustgait.robots.spec import GaitQuality, Robot

# Default step duration of each domain graph [s]: multi-contact gaits of 0.7 s solve but do not walk on exo (the
# 0.14 s of rolling is too fast for the simulator's soft contacts; measured, docs/gaitgen.md), 0.8–1.1 s do.
DEFAULT_STEP_DURATION = {"flat": 0.7, "multicontact": 0.9}


def default_params(domains: str = "flat") -> GaitParams:
    """The default essential constraints of a domain graph (GaitParams' defaults, the graph's duration)."""
    if domains not in DEFAULT_STEP_DURATION:
        raise RobustGaitError(f"domains must be one of {GRAPH_NAMES}, got {domains!r}")
    return GaitParams(step_duration=DEFAULT_STEP_DURATION[domains])


@dataclass(frozen=True)
class GaitGenConfig:
    """Options of the gait-generation problem (besides the :class:`~robustgait.gait.GaitParams`).

    domains: the domain graph, ``flat`` or ``multicontact`` (:mod:`robustgait.domains`).
    nodes: collocation nodes of single support (odd, so that τ = ½ is a node); ds_nodes: of double support
    (multi-contact); stance: the leg the gait is written for;
    friction: μ of the friction pyramid (below the simulator's 1.0 for margin); torsional_friction: μ_t;
    min_normal_force [N]; cop_margin [m] inside the sole edges; impact_velocity: bounds on the swing sole's
    vertical velocity at the guard [m/s]; max_impact_tangential [m/s]; max_impact_angular [rad/s]: bound on
    each component of the swing sole's angular velocity at the guard; flat_approach: every corner of the
    swing sole stays at least this fraction of the sole centre's height above the ground (a foot near the
    ground is nearly flat, so touchdown is not a corner grazing early); foot_gap [m]: lateral clearance
    between the soles' edges; max_iter, tol: IPOPT.

    Multi-contact only: heel_strike_pitch [rad]: (min, max) toe-up pitch of the swing sole when its heel
    strikes; toe_off_pitch [rad]: (min, max) toe-down pitch of the stance sole at toe-off (the max also
    bounds the swing sole's toe-down pitch early in the next swing when the robot's gait quality sets
    ``swing_toe_down_until``); foot_flat_rate
    [rad/s]: bound on the front sole's pitch rate when it lands flat (a gentle foot-flat);
    min_line_force [N]: normal force of each line contact in double support; ds_free_joints: the 4 joints of
    the swing leg (of a ``stance`` gait) that are not Bézier outputs in double support (None: picked from
    the joint axes, see :func:`robustgait.gaitgen.problem.double_support_free_joints`).

    Gait quality (``None`` = the robot spec's ``[gait_quality]``, see
    :class:`~robustgait.robots.spec.GaitQuality`): pelvis_roll, pelvis_yaw [rad] (|·| ≤), pelvis_pitch
    [rad] (band), pelvis_height [m] (band above the stance sole), pelvis_angular_velocity [rad/s] (each
    component), pelvis_acceleration [m/s²] (each component), swing_tilt [rad] (swing sole roll/pitch),
    swing_yaw [rad], joint_velocity [rad/s] (one value for every joint or one per joint).
    """

    domains: str = "flat"
    nodes: int = 17
    ds_nodes: int = 17
    stance: str = "right"
    friction: float = 0.6
    torsional_friction: float = 0.02
    min_normal_force: float = 50.0
    cop_margin: float = 0.02
    impact_velocity: tuple[float, float] = (-0.4, -0.05)
    max_impact_tangential: float = 0.15
    max_impact_angular: float = 0.5
    flat_approach: float = 0.5
    foot_gap: float = 0.02
    heel_strike_pitch: tuple[float, float] = (0.2, 0.35)
    toe_off_pitch: tuple[float, float] = (0.2, 0.6)
    foot_flat_rate: float = 1.0
    min_line_force: float = 150.0
    ds_free_joints: tuple[str, ...] | None = None
    max_iter: int = 300
    tol: float = 1e-8
    pelvis_roll: float | None = None
    pelvis_yaw: float | None = None
    pelvis_pitch: tuple[float, float] | None = None
    pelvis_height: tuple[float, float] | None = None
    pelvis_angular_velocity: float | None = None
    pelvis_acceleration: float | None = None
    swing_tilt: float | None = None
    swing_yaw: float | None = None
    joint_velocity: float | tuple[float, ...] | None = None

    def __post_init__(self) -> None:
        if self.domains not in GRAPH_NAMES:
            raise RobustGaitError(f"domains must be one of {GRAPH_NAMES}, got {self.domains!r}")
        if self.nodes < 5 or self.nodes % 2 == 0 or self.ds_nodes < 3:
            raise RobustGaitError(f"nodes must be odd and ≥ 5 and ds_nodes ≥ 3, got {self.nodes}, {self.ds_nodes}")
        if self.stance not in ("left", "right"):
            raise RobustGaitError(f"stance must be 'left' or 'right', got {self.stance!r}")

    def quality(self, robot: Robot) -> GaitQuality:
        """The gait-quality bounds in force: the spec's, with this config's non-None fields on top."""
        base = robot.spec.gait_quality
        jv = self.joint_velocity
        if jv is not None:
            jv = (float(jv),) * robot.n_joints if isinstance(jv, (int, float)) else tuple(map(float, jv))
            if len(jv) != robot.n_joints:
                raise RobustGaitError(f"joint_velocity needs 1 or {robot.n_joints} values, got {len(jv)}")
        over: dict[str, Any] = {k: v for k, v in (("pelvis_roll", self.pelvis_roll), ("pelvis_yaw", self.pelvis_yaw),
                                  ("pelvis_pitch", self.pelvis_pitch), ("pelvis_height", self.pelvis_height),
                                  ("pelvis_angular_velocity", self.pelvis_angular_velocity),
                                  ("pelvis_acceleration", self.pelvis_acceleration),
                                  ("swing_tilt", self.swing_tilt), ("swing_yaw", self.swing_yaw),
                                  ("joint_velocity", jv)) if v is not None}
        q = replace(base, **over)
        if not q.joint_velocity:
            q = replace(q, joint_velocity=(10.0,) * robot.n_joints)
        return q
