"""Robots from files, the one module that reads and writes them: the robot spec TOML (its schema and the builder of
:class:`~robustgait.robots.RobotSpec`), the MJCF it names (parsed by MuJoCo), :func:`load_robot` (``docs/robots.md``,
limits in ``docs/inputs.md``), and the files of ``robot init``: the MJCF or URDF it reads (:func:`read_model`) and the
spec it writes only once the loader accepts it (:func:`write_spec`; its text is rendered by
:mod:`robustgait.robotinit.writer`).
Names (joints, geoms, bodies) are checked against the MJCF when the robot is compiled
(:func:`robustgait.robots.model.build_mjspec`); everything else is checked here."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path
from typing import Annotated, Any, Literal

import annotated_types as at
import mujoco
from pydantic import Field, StringConstraints, ValidationError

from robustgait.config import ROBOT_SCALED, GaitParams, GenerationConfig, field_at
from robustgait.config.base import Doc, Float, Int, Str, explain, validator
from robustgait.config.gait import GAIT_PARAM_NAMES
from robustgait.errors import RobustGaitError, input_error
from robustgait.io import limits as L
from robustgait.io.output import atomic_output
from robustgait.io.schema import field_error, read_toml, table, validate
from robustgait.robots.model import INTEGRATORS, Robot
from robustgait.robots.spec import (
    ACTION_FIELDS,
    ADDED_FLOOR,
    SHIPPED_DIR,
    FallCriteria,
    GaitQuality,
    HeldJoint,
    Integrator,
    LegSpec,
    ParamRange,
    PassivitySpec,
    RobotSpec,
)

Name = Annotated[str, StringConstraints(strict=True, min_length=1, max_length=200, pattern=r"^[^\x00]+$")]
Sign = Annotated[Float, Doc(ge=-1.0, le=1.0)]
QualityAngle = Annotated[Float, L.QUALITY_ANGLE]
BandEnd = Annotated[Float, L.QUALITY_BAND]
# the high end of the pelvis height band may be inf (unbounded above)
HeightBandEnd = Annotated[float, Field(strict=True, allow_inf_nan=True), Doc(unit="m", ge=-10.0)]
JointVelocity = Annotated[Float, L.QUALITY_JOINT_VELOCITY]
ActionAxis = Annotated[tuple[Float, Float, Float], Doc("[low, high, step]")]
assert set(Integrator.__args__) == set(INTEGRATORS)  # type: ignore[attr-defined]


def _joints(item: Any) -> Any:
    """A list of one value per joint."""
    return Annotated[list[item], at.MinLen(1), at.MaxLen(L.MAX_JOINTS)]


FootKind = Literal["flat", "line", "point"]
Loop = Annotated[tuple[Literal["connect", "weld", "joint"], Name, Name], Doc("[kind, end, end]")]
SpringValues = Annotated[tuple[Annotated[Float, Doc(ge=0.0, le=1e9)], Annotated[Float, Doc(ge=-1e3, le=1e3)]],
                         Doc("[stiffness, springref]")]
HeldServo = Annotated[tuple[Annotated[Float, L.KP], Annotated[Float, L.KD], Annotated[Float, L.TORQUE_LIMIT]],
                      Doc("[kp, kd, torque_limit]")]


@table
class JointsTable:
    names: _joints(Name)  # type: ignore[valid-type]
    kp: _joints(Annotated[Float, L.KP])  # type: ignore[valid-type]
    kd: _joints(Annotated[Float, L.KD])  # type: ignore[valid-type]
    torque_limit: _joints(Annotated[Float, L.TORQUE_LIMIT])  # type: ignore[valid-type]
    held: dict[Name, Annotated[Float, L.POSTURE]] = dataclasses.field(default_factory=dict)
    held_servo: dict[Name, HeldServo] = dataclasses.field(default_factory=dict)
    passive: Annotated[list[Name], at.MaxLen(L.MAX_JOINTS), Doc(
        "closed chains' joints neither planned nor held, solved from their loops")] = dataclasses.field(
        default_factory=list)


@table
class LegTable:
    sole_geom: Name | None = None
    sole_geoms: Annotated[list[Name], at.MinLen(1), at.MaxLen(64)] | None = None
    sole_body: Name | None = None
    sole_class: Name | None = None
    foot: FootKind = "flat"


@table
class LegsTable:
    left: LegTable
    right: LegTable


@table
class MirrorTable:
    joint_perm: _joints(Annotated[Int, Doc(ge=0, lt=L.MAX_JOINTS)])  # type: ignore[valid-type]
    joint_sign: _joints(Sign)  # type: ignore[valid-type]
    base_sign: Annotated[tuple[Sign, Sign, Sign, Sign, Sign, Sign], Doc("(x, y, z, roll, pitch, yaw)")] = (
        1.0, -1.0, 1.0, -1.0, 1.0, -1.0)
    held: dict[Name, Annotated[tuple[Name, Sign], Doc("[mirror joint, sign]")]] = dataclasses.field(
        default_factory=dict)


@table
class FallTable:
    min_base_height: Annotated[Float, L.MIN_BASE_HEIGHT] = FallCriteria.min_base_height
    max_tilt: Annotated[Float, L.MAX_TILT] = FallCriteria.max_tilt


@table
class SimTable:
    timestep: Annotated[Float, L.TIMESTEP] | None = None
    integrator: Integrator | None = None
    stable_pd: Annotated[bool, L.STABLE_PD] = False


@table
class GaitQualityTable:
    pelvis_roll: QualityAngle = GaitQuality.pelvis_roll
    pelvis_yaw: QualityAngle = GaitQuality.pelvis_yaw
    pelvis_pitch: Annotated[tuple[BandEnd, BandEnd], Doc("[low, high]")] = GaitQuality.pelvis_pitch
    pelvis_height: Annotated[tuple[HeightBandEnd, HeightBandEnd], Doc("[low, high]")] = GaitQuality.pelvis_height
    pelvis_angular_velocity: Annotated[Float, L.QUALITY_ANGULAR_VELOCITY] | None = None
    swing_tilt: QualityAngle = GaitQuality.swing_tilt
    swing_yaw: QualityAngle = GaitQuality.swing_yaw
    swing_toe_down_until: Annotated[Float, Doc(unit="phase", ge=0.0, le=1.0)] = GaitQuality.swing_toe_down_until
    pelvis_acceleration: Annotated[float, Field(strict=True, allow_inf_nan=True), Doc(unit="m/s²", gt=0)] = (
        GaitQuality.pelvis_acceleration)
    joint_velocity: JointVelocity | Annotated[list[JointVelocity], at.MaxLen(L.MAX_JOINTS)] = 10.0


@table
class ActionAxesTable:
    """The axes every action space has (``ACTION_FIELDS``)."""

    step_length: ActionAxis
    step_duration: ActionAxis
    step_width: ActionAxis
    step_height: ActionAxis


@table
class MultiContactActionSpaceTable(ActionAxesTable):
    rolling_fraction: ActionAxis | None = None


@table
class ActionSpaceTable(ActionAxesTable):
    multicontact: MultiContactActionSpaceTable | None = None


@table
class PassivityTable:
    lam: Annotated[_joints(Annotated[Float, L.PASSIVITY_LAMBDA]), Field(alias="lambda")]  # type: ignore[valid-type]
    kd: _joints(Annotated[Float, L.KD])  # type: ignore[valid-type]


@table
class ControllerTable:
    passivity: PassivityTable | None = None


@table
class SpecFile:
    name: Name
    mjcf: Name
    base_body: Name
    joints: JointsTable
    legs: LegsTable
    mirror: MirrorTable
    description: Annotated[Str, at.MaxLen(2000)] = ""
    fall: FallTable = dataclasses.field(default_factory=FallTable)
    sim: SimTable = dataclasses.field(default_factory=SimTable)
    gait_quality: GaitQualityTable = dataclasses.field(default_factory=GaitQualityTable)
    action_space: ActionSpaceTable | None = None
    posture: dict[Name, Annotated[Float, L.POSTURE]] = dataclasses.field(default_factory=dict)
    controller: ControllerTable | None = None
    floor_geom: Name | None = None
    add_floor: Annotated[bool, Field(strict=True)] = False
    generation: dict[Name, Any] = dataclasses.field(default_factory=dict)
    gait: dict[Name, Any] = dataclasses.field(default_factory=dict)
    loops: dict[Name, Loop] = dataclasses.field(default_factory=dict)
    springs: dict[Name, SpringValues] = dataclasses.field(default_factory=dict)


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
        doc = field_at(GaitParams, key).doc
        if not (doc.contains(lo) and doc.contains(hi)):
            raise field_error(src, field, f"[low, high] = [{lo:g}, {hi:g}] must lie within the bounds of "
                              f"GaitParams.{key}, {doc.text()}")
        if (hi - lo) / step + 1 > L.MAX_GRID_POINTS:
            raise field_error(src, field, f"the grid has {math.floor((hi - lo) / step) + 1} points, over the "
                              f"limit of {L.MAX_GRID_POINTS} per axis (use a larger step)")
        out[key] = ParamRange(lo, hi, step)
    return out


def _section(raw: dict[str, Any], schema: type, path: Path, table_name: str,
             allowed: tuple[str, ...]) -> dict[str, Any]:
    """A spec table of config fields (``[generation]``, ``[gait]``): only the ``allowed`` keys, each validated by the
    config section ``schema`` (its limits and types); returns the given values, validated."""
    for key in raw:
        if key not in allowed:
            raise field_error(path, f"{table_name}.{key}",
                              f"not a field of [{table_name}] (one of: {', '.join(allowed)})")
    try:
        obj = validator(schema)(raw)
    except ValidationError as exc:
        raise field_error(path, table_name, explain(exc, schema, fmt="toml")) from None
    return {k: getattr(obj, k) for k in raw}


def _legs(s: SpecFile, path: Path) -> dict[str, LegSpec]:
    out = {}
    for side in ("left", "right"):
        t: LegTable = getattr(s.legs, side)
        given = [k for k in ("sole_geom", "sole_geoms", "sole_body") if getattr(t, k) is not None]
        if len(given) != 1:
            raise field_error(path, f"legs.{side}", "name the sole with exactly one of sole_geom, sole_geoms or "
                              f"sole_body (got {', '.join(given) or 'none'})")
        if t.sole_class is not None and t.sole_body is None:
            raise field_error(path, f"legs.{side}.sole_class", "selects geoms of sole_body: set sole_body too")
        out[side] = LegSpec(sole_geom=t.sole_geom, sole_geoms=tuple(t.sole_geoms or ()), sole_body=t.sole_body,
                            sole_class=t.sole_class)
    return out


def _held(s: SpecFile, path: Path, planned: tuple[str, ...]) -> tuple[HeldJoint, ...]:
    """The held joints with their servos and mirror partners; the held posture must be mirror-consistent."""
    held, servo, mirror = s.joints.held, s.joints.held_servo, s.mirror.held
    out = []
    for name, angle in held.items():
        if name in planned:
            raise field_error(path, f"joints.held.{name}", "is also in joints.names: a joint is planned or held")
        if name not in servo:
            raise field_error(path, f"joints.held_servo.{name}", "missing: each held joint needs [kp, kd, "
                              "torque_limit] for its servo")
        if name not in mirror:
            raise field_error(path, f"mirror.held.{name}", "missing: each held joint needs [mirror joint, sign]")
        partner, sign = mirror[name]
        if partner not in held:
            raise field_error(path, f"mirror.held.{name}", f"its mirror joint '{partner}' is not a held joint")
        if abs(sign) != 1.0:
            raise field_error(path, f"mirror.held.{name}", "mirror signs must be +1 or -1")
        if abs(angle - sign * held[partner]) > 1e-9:
            raise field_error(path, f"joints.held.{name}", f"the held posture is not left/right symmetric: {angle:g} "
                              f"but its mirror {partner} × {sign:+g} is {sign * held[partner]:g} (the periodic gait "
                              "relabels one step into the next)")
        kp, kd, limit = servo[name]
        out.append(HeldJoint(name, float(angle), float(kp), float(kd), float(limit), partner, float(sign)))
    for table_name, keys in (("joints.held_servo", servo), ("mirror.held", mirror)):
        for name in keys:
            if name not in held:
                raise field_error(path, f"{table_name}.{name}", "not a held joint (joints.held)")
    for h in out:
        back = mirror[h.mirror]
        if back[0] != h.name or back[1] != h.sign:
            raise field_error(path, f"mirror.held.{h.name}", f"is not an involution: {h.name} → {h.mirror} but "
                              f"{h.mirror} → {back[0]} (sign {back[1]:+g})")
    return tuple(out)


def _check_per_joint(path: Path, key: str, values: list[float], n: int) -> None:
    """A per-joint list of the spec must have one number per joint (``joints.names``)."""
    if len(values) != n:
        raise field_error(path, key, f"must be a list of {n} numbers, one per joint (got {len(values)} items)")


def _mirror(s: SpecFile, path: Path, n: int) -> tuple[float, ...]:
    """Check the ``[mirror]`` table against ``n`` joints; returns the base's signs (6,), a reflection."""
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
    return base_sign


def _quality(s: SpecFile, path: Path, n: int) -> GaitQuality:
    """The ``[gait_quality]`` bands, a per-joint velocity bound widened to ``n`` joints."""
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
    return GaitQuality(
        pelvis_roll=q.pelvis_roll, pelvis_yaw=q.pelvis_yaw, pelvis_pitch=_band(path, "pelvis_pitch", q.pelvis_pitch),
        pelvis_height=height, pelvis_angular_velocity=q.pelvis_angular_velocity, swing_tilt=q.swing_tilt,
        swing_yaw=q.swing_yaw, swing_toe_down_until=q.swing_toe_down_until, pelvis_acceleration=q.pelvis_acceleration,
        joint_velocity=joint_velocity)


def _passivity(s: SpecFile, path: Path, n: int) -> PassivitySpec | None:
    """The passivity-based controller's per-joint gains, None when the spec gives none."""
    if s.controller is None or s.controller.passivity is None:
        return None
    pt = s.controller.passivity
    for key, values in (("lambda", pt.lam), ("kd", pt.kd)):
        _check_per_joint(path, f"controller.passivity.{key}", values, n)
    return PassivitySpec(lam=tuple(float(v) for v in pt.lam), kd=tuple(float(v) for v in pt.kd))


def spec_from_raw(raw: object, path: Path) -> RobotSpec:
    """Validate a parsed spec TOML and build the :class:`RobotSpec` (paths relative to ``path``)."""
    s = validate(raw, SpecFile, path, "toml")
    names = tuple(s.joints.names)
    n = len(names)
    if len(set(names)) != n:
        dup = next(j for j in names if names.count(j) > 1)
        raise field_error(path, "joints.names", f"joint {dup!r} is listed twice")
    for key in ("kp", "kd", "torque_limit"):
        _check_per_joint(path, f"joints.{key}", getattr(s.joints, key), n)
    base_sign = _mirror(s, path, n)
    quality = _quality(s, path, n)
    for key in s.posture:
        if key not in names:
            raise field_error(path, f"posture.{key}", "not a planned joint (joints.names)")
    if s.add_floor and s.floor_geom is not None and s.floor_geom != ADDED_FLOOR:
        raise field_error(path, "add_floor", f"adds a floor named {ADDED_FLOOR}: floor_geom must be unset or that name "
                          f"(got '{s.floor_geom}')")
    passivity = _passivity(s, path, n)
    return RobotSpec(
        name=s.name,
        mjcf=(path.parent / s.mjcf).resolve(),
        base_body=s.base_body,
        floor_geom=s.floor_geom,
        joints=names,
        kp=tuple(s.joints.kp),
        kd=tuple(s.joints.kd),
        torque_limit=tuple(s.joints.torque_limit),
        legs=_legs(s, path),
        mirror_perm=tuple(s.mirror.joint_perm),
        mirror_sign=tuple(float(v) for v in s.mirror.joint_sign),
        base_mirror_sign=base_sign,
        fall=FallCriteria(min_base_height=s.fall.min_base_height, max_tilt=s.fall.max_tilt),
        timestep=s.sim.timestep,
        integrator=s.sim.integrator,
        stable_pd=s.sim.stable_pd,
        description=s.description,
        source=path.resolve(),
        gait_quality=quality,
        action_space=_action_space(s.action_space, path) if s.action_space is not None else None,
        multicontact_action_space=(_action_space(s.action_space.multicontact, path, "action_space.multicontact")
                                   if s.action_space is not None and s.action_space.multicontact is not None
                                   else None),
        posture=tuple(float(s.posture.get(j, 0.0)) for j in names),
        passivity=passivity,
        add_floor=s.add_floor,
        held=_held(s, path, names),
        generation=_section(s.generation, GenerationConfig, path, "generation", ROBOT_SCALED),
        gait=_section(s.gait, GaitParams, path, "gait", GAIT_PARAM_NAMES),
        passive=_passive(s, path, names),
        loops={k: (v[0], v[1], v[2]) for k, v in s.loops.items()},
        springs={k: (float(v[0]), float(v[1])) for k, v in s.springs.items()},
        feet={side: getattr(s.legs, side).foot for side in ("left", "right") if getattr(s.legs, side).foot != "flat"},
    )


def _passive(s: SpecFile, path: Path, planned: tuple[str, ...]) -> tuple[str, ...]:
    """The passive joints (``joints.passive``): each once, neither planned nor held; a spring is a passive joint."""
    passive = tuple(s.joints.passive)
    for name in passive:
        if passive.count(name) > 1:
            raise field_error(path, "joints.passive", f"joint {name!r} is listed twice")
        if name in planned or name in s.joints.held:
            raise field_error(path, "joints.passive", f"joint {name!r} is also planned or held: a joint is planned, "
                              "held or passive")
    for name in s.springs:
        if name not in passive:
            raise field_error(path, f"springs.{name}", "not a passive joint (joints.passive)")
    return passive


def read_spec(path: str | Path) -> RobotSpec:
    """Read, validate and build a robot spec from a TOML file."""
    p = Path(path)
    return spec_from_raw(read_toml(p, "robot spec file"), p)


def read_mjcf(spec: RobotSpec) -> mujoco.MjSpec:
    """The robot's MJCF (or URDF) file parsed by MuJoCo (one-line errors for a missing or unparsable file). A URDF
    cannot express a floating base: its base body gets a free joint (:func:`parse_model`)."""
    src = spec.source or spec.mjcf
    if not spec.mjcf.is_file():
        raise input_error(src, f"MJCF file not found: {spec.mjcf}")
    return parse_model(spec.mjcf, spec.base_body)


def parse_model(path: Path, base_body: str | None = None) -> mujoco.MjSpec:
    """An MJCF or URDF file parsed by MuJoCo. A URDF (``.urdf``) attaches its root link to the world; with
    ``base_body`` given and jointless, that body gets a free joint, the floating base URDF cannot express."""
    kind = "URDF" if path.suffix.lower() == ".urdf" else "MJCF"
    try:
        mjs = mujoco.MjSpec.from_file(str(path))
    except ValueError as exc:
        raise input_error(path, f"MuJoCo could not parse the {kind}: {' '.join(str(exc).split())}") from None
    if kind == "URDF" and base_body is not None:
        body = mjs.body(base_body)
        if body is not None and not body.joints:
            body.add_freejoint()
    return mjs


def shipped_robots() -> list[str]:
    """Names of the robots that ship with the package."""
    return sorted(p.parent.name for p in SHIPPED_DIR.glob("*/spec.toml"))


def load_robot(robot: str | Path | Robot) -> Robot:
    """Load a shipped robot by name (``"exo"``) or a user robot from a spec ``.toml`` path."""
    if isinstance(robot, Robot):
        return robot
    text = str(robot)
    if text in shipped_robots():
        path = SHIPPED_DIR / text / "spec.toml"
    elif Path(text).suffix == ".toml" or Path(text).exists():
        path = Path(text)
    else:
        raise RobustGaitError(
            f"{text}: unknown robot (shipped: {', '.join(shipped_robots()) or 'none'}; or give a spec .toml path)")
    spec = read_spec(path)
    return Robot(spec, read_mjcf(spec))


# --- the files of `robot init`: the model it reads and the spec it writes ---

ModelKind = Literal["mjcf", "urdf"]
MODEL_SUFFIXES: dict[str, ModelKind] = {".xml": "mjcf", ".mjcf": "mjcf", ".urdf": "urdf"}


def model_kind(path: str | Path) -> ModelKind:
    """``mjcf`` or ``urdf`` from the file's extension (a one-line error for any other)."""
    p = Path(path)
    kind = MODEL_SUFFIXES.get(p.suffix.lower())
    if kind is None:
        raise input_error(p, f"unknown robot model format {p.suffix or '(no extension)'!r} (robustgait reads an "
                          "MJCF .xml or a URDF .urdf)")
    return kind


def read_model(path: str | Path) -> tuple[mujoco.MjSpec, ModelKind]:
    """The model file parsed by MuJoCo (MuJoCo compiles a URDF with its own defaults: ``fusestatic`` merges every
    link attached by a fixed joint into its parent, visual geometry is discarded, a joint's ``effort`` becomes its
    ``actuatorfrcrange``). Returns the parsed spec and the file's kind."""
    p = Path(path)
    kind = model_kind(p)
    if p.is_dir():
        raise input_error(p, "is a directory: give the robot's MJCF or URDF file")
    if not p.is_file():
        raise input_error(p, "robot model file not found")
    return parse_model(p), kind


def write_spec(path: str | Path, text: str) -> Path:
    """Write a spec TOML atomically (:mod:`robustgait.io.output`), after loading it with :func:`load_robot` from
    its temporary file beside the target (so that the model's relative path resolves the same): a spec the loader
    refuses is not written."""
    target = Path(path)
    with atomic_output(target, "toml") as tmp:
        tmp.write_text(text, encoding="utf-8")
        try:
            load_robot(tmp)
        except RobustGaitError as exc:
            raise RobustGaitError(f"{target}: the written spec does not load (nothing written): "
                                  f"{str(exc).replace(str(tmp), target.name)}") from None
    return target
