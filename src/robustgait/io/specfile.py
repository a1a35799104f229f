"""Robot spec TOML: its schema and the builder of :class:`~robustgait.robots.RobotSpec` (``docs/robots.md``,
limits in ``docs/inputs.md``). Names (joints, geoms, bodies) are checked against the MJCF when the robot is
loaded (:func:`robustgait.robots.spec.build_mjspec`); everything else is checked here."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Annotated, Literal

import msgspec
from msgspec import Meta

from robustgait.io import limits as L
from robustgait.io.schema import Table, field_error, read_toml, validate
from robustgait.robots.spec import (
    ACTION_FIELDS,
    INTEGRATORS,
    FallCriteria,
    GaitQuality,
    LegSpec,
    ParamRange,
    RobotSpec,
)

Name = Annotated[str, Meta(min_length=1, max_length=200, pattern=r"^[^\x00]+$")]
Sign = Annotated[float, Meta(ge=-1.0, le=1.0)]
QualityAngle = Annotated[float, L.QUALITY_ANGLE.meta()]
BandEnd = Annotated[float, L.QUALITY_BAND.meta()]
HeightBandEnd = Annotated[float, Meta(ge=-L.QUALITY_BAND.high, extra={"unit": "m"})]  # high end may be inf
JointVelocity = Annotated[float, L.QUALITY_JOINT_VELOCITY.meta()]
ActionAxis = Annotated[tuple[float, float, float], Meta(description="[low, high, step]")]
Integrator = Literal["euler", "implicitfast", "implicit", "rk4"]
assert set(Integrator.__args__) == set(INTEGRATORS)  # type: ignore[attr-defined]


class JointsTable(Table):
    names: Annotated[list[Name], Meta(min_length=1, max_length=L.MAX_JOINTS)]
    kp: Annotated[list[Annotated[float, L.KP.meta()]], Meta(min_length=1, max_length=L.MAX_JOINTS)]
    kd: Annotated[list[Annotated[float, L.KD.meta()]], Meta(min_length=1, max_length=L.MAX_JOINTS)]
    torque_limit: Annotated[list[Annotated[float, L.TORQUE_LIMIT.meta()]], Meta(min_length=1, max_length=L.MAX_JOINTS)]


class LegTable(Table):
    sole_geom: Name


class LegsTable(Table):
    left: LegTable
    right: LegTable


class MirrorTable(Table):
    joint_perm: Annotated[list[Annotated[int, Meta(ge=0, lt=L.MAX_JOINTS)]], Meta(min_length=1,
                                                                                  max_length=L.MAX_JOINTS)]
    joint_sign: Annotated[list[Sign], Meta(min_length=1, max_length=L.MAX_JOINTS)]
    base_sign: Annotated[tuple[Sign, Sign, Sign, Sign, Sign, Sign], Meta(description="(x, y, z, roll, pitch, yaw)")] = (
        1.0, -1.0, 1.0, -1.0, 1.0, -1.0)


class FallTable(Table):
    min_base_height: Annotated[float, L.MIN_BASE_HEIGHT.meta()] = FallCriteria.min_base_height
    max_tilt: Annotated[float, L.MAX_TILT.meta()] = FallCriteria.max_tilt


class SimTable(Table):
    timestep: Annotated[float, L.TIMESTEP.meta()] | None = None
    integrator: Integrator | None = None


class GaitQualityTable(Table):
    pelvis_roll: QualityAngle = GaitQuality.pelvis_roll
    pelvis_yaw: QualityAngle = GaitQuality.pelvis_yaw
    pelvis_pitch: Annotated[tuple[BandEnd, BandEnd], Meta(description="[low, high]")] = GaitQuality.pelvis_pitch
    pelvis_height: Annotated[tuple[HeightBandEnd, HeightBandEnd], Meta(description="[low, high]")] = (
        GaitQuality.pelvis_height)
    pelvis_angular_velocity: Annotated[float, L.QUALITY_ANGULAR_VELOCITY.meta()] = GaitQuality.pelvis_angular_velocity
    swing_tilt: QualityAngle = GaitQuality.swing_tilt
    swing_yaw: QualityAngle = GaitQuality.swing_yaw
    swing_toe_down_until: Annotated[float, Meta(ge=0.0, le=1.0, extra={"unit": "phase"})] = (
        GaitQuality.swing_toe_down_until)
    pelvis_acceleration: Annotated[float, Meta(gt=0, extra={"unit": "m/s²"})] = GaitQuality.pelvis_acceleration
    joint_velocity: JointVelocity | Annotated[list[JointVelocity], Meta(max_length=L.MAX_JOINTS)] = 10.0


class ActionAxesTable(Table):
    """The axes every action space has (``ACTION_FIELDS``)."""

    step_length: ActionAxis
    step_duration: ActionAxis
    step_width: ActionAxis
    step_height: ActionAxis


class MultiContactActionSpaceTable(ActionAxesTable):
    rolling_fraction: ActionAxis | None = None


class ActionSpaceTable(ActionAxesTable):
    multicontact: MultiContactActionSpaceTable | None = None


class SpecFile(Table):
    name: Name
    mjcf: Name
    base_body: Name
    floor_geom: Name
    joints: JointsTable
    legs: LegsTable
    mirror: MirrorTable
    description: Annotated[str, Meta(max_length=2000)] = ""
    fall: FallTable = msgspec.field(default_factory=FallTable)
    sim: SimTable = msgspec.field(default_factory=SimTable)
    gait_quality: GaitQualityTable = msgspec.field(default_factory=GaitQualityTable)
    action_space: ActionSpaceTable | None = None
    posture: dict[Name, Annotated[float, L.POSTURE.meta()]] = msgspec.field(default_factory=dict)


def _band(src: Path, key: str, band: tuple[float, float]) -> tuple[float, float]:
    lo, hi = band
    if not lo < hi:
        raise field_error(src, f"gait_quality.{key}", f"must be [low, high] with low < high (got [{lo:g}, {hi:g}])")
    return lo, hi


def _action_space(t: ActionAxesTable, src: Path,
                  prefix: str = "action_space") -> dict[str, ParamRange]:
    from robustgait.gait import GaitParams

    out = {}
    keys = ACTION_FIELDS + (("rolling_fraction",) if getattr(t, "rolling_fraction", None) is not None else ())
    for key in keys:
        lo, hi, step = getattr(t, key)
        field = f"{prefix}.{key}"
        if not all(math.isfinite(v) for v in (lo, hi, step)):
            raise field_error(src, field, f"[low, high, step] must be finite numbers (got [{lo}, {hi}, {step}])")
        if not (lo <= hi and step > 0):
            raise field_error(src, field, "must be [low, high, step] with low ≤ high and step > 0 "
                              f"(got [{lo:g}, {hi:g}, {step:g}])")
        blo, bhi = GaitParams.BOUNDS[key]
        if lo < blo or hi > bhi:
            raise field_error(src, field, f"[low, high] = [{lo:g}, {hi:g}] must lie within the bounds of "
                              f"GaitParams.{key}, [{blo:g}, {bhi:g}]")
        if (hi - lo) / step + 1 > L.MAX_GRID_POINTS:
            raise field_error(src, field, f"the grid has {math.floor((hi - lo) / step) + 1} points, over the "
                              f"limit of {L.MAX_GRID_POINTS} per axis (use a larger step)")
        out[key] = ParamRange(lo, hi, step)
    return out


def spec_from_raw(raw: object, path: Path) -> RobotSpec:
    """Validate a parsed spec TOML and build the :class:`RobotSpec` (paths relative to ``path``)."""
    s = validate(raw, SpecFile, path, "toml")
    names = tuple(s.joints.names)
    n = len(names)
    if len(set(names)) != n:
        dup = next(j for j in names if names.count(j) > 1)
        raise field_error(path, "joints.names", f"joint {dup!r} is listed twice")
    for key in ("kp", "kd", "torque_limit"):
        values = getattr(s.joints, key)
        if len(values) != n:
            raise field_error(path, f"joints.{key}", f"must be a list of {n} numbers, one per joint "
                              f"(got {len(values)} items)")
    if sorted(s.mirror.joint_perm) != list(range(n)):
        raise field_error(path, "mirror.joint_perm", f"must be a permutation of 0..{n - 1}")
    if len(s.mirror.joint_sign) != n:
        raise field_error(path, "mirror.joint_sign", f"must be a list of {n} signs, one per joint "
                          f"(got {len(s.mirror.joint_sign)} items)")
    for key, signs in (("joint_sign", s.mirror.joint_sign), ("base_sign", s.mirror.base_sign)):
        if any(abs(v) != 1.0 for v in signs):
            raise field_error(path, f"mirror.{key}", "mirror signs must be +1 or -1")
    base_sign = tuple(float(v) for v in s.mirror.base_sign)
    det = base_sign[0] * base_sign[1] * base_sign[2]
    if det > 0 or tuple(det * v for v in base_sign[:3]) != base_sign[3:]:
        raise field_error(path, "mirror.base_sign", "must be a reflection: (x, y, z) signs with one or three "
                          "-1s, and (roll, pitch, yaw) signs = det · (x, y, z) signs, e.g. [1,-1,1,-1,1,-1]")
    q = s.gait_quality
    jv = q.joint_velocity
    if isinstance(jv, list):
        if len(jv) != n:
            raise field_error(path, "gait_quality.joint_velocity", f"must be one number or a list of {n} numbers, "
                              f"one per joint (got {len(jv)} items)")
        joint_velocity = tuple(float(v) for v in jv)
    else:
        joint_velocity = (float(jv),) * n
    height = _band(path, "pelvis_height", q.pelvis_height)
    if math.isinf(height[0]):
        raise field_error(path, "gait_quality.pelvis_height", "the low end must be finite")
    quality = GaitQuality(
        pelvis_roll=q.pelvis_roll, pelvis_yaw=q.pelvis_yaw, pelvis_pitch=_band(path, "pelvis_pitch", q.pelvis_pitch),
        pelvis_height=height, pelvis_angular_velocity=q.pelvis_angular_velocity, swing_tilt=q.swing_tilt,
        swing_yaw=q.swing_yaw, swing_toe_down_until=q.swing_toe_down_until, pelvis_acceleration=q.pelvis_acceleration,
        joint_velocity=joint_velocity)
    for key in s.posture:
        if key not in names:
            raise field_error(path, f"posture.{key}", "not an actuated joint (joints.names)")
    return RobotSpec(
        name=s.name,
        mjcf=(path.parent / s.mjcf).resolve(),
        base_body=s.base_body,
        floor_geom=s.floor_geom,
        joints=names,
        kp=tuple(s.joints.kp),
        kd=tuple(s.joints.kd),
        torque_limit=tuple(s.joints.torque_limit),
        legs={"left": LegSpec(s.legs.left.sole_geom), "right": LegSpec(s.legs.right.sole_geom)},
        mirror_perm=tuple(s.mirror.joint_perm),
        mirror_sign=tuple(float(v) for v in s.mirror.joint_sign),
        base_mirror_sign=base_sign,
        fall=FallCriteria(min_base_height=s.fall.min_base_height, max_tilt=s.fall.max_tilt),
        timestep=s.sim.timestep,
        integrator=s.sim.integrator,
        description=s.description,
        source=path.resolve(),
        gait_quality=quality,
        action_space=_action_space(s.action_space, path) if s.action_space is not None else None,
        multicontact_action_space=(_action_space(s.action_space.multicontact, path, "action_space.multicontact")
                                   if s.action_space is not None and s.action_space.multicontact is not None
                                   else None),
        posture=tuple(float(s.posture.get(j, 0.0)) for j in names),
    )


def read_spec(path: str | Path) -> RobotSpec:
    """Read, validate and build a robot spec from a TOML file."""
    p = Path(path)
    return spec_from_raw(read_toml(p, "robot spec file"), p)
