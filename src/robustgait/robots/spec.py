"""Robot specs (DESIGN §2): an MJCF file plus a TOML spec naming what the pipeline needs.

A spec names the floating-base body, the actuated joints in output order, each leg's sole geom, the
left/right relabeling, PD gains and torque limits, fall criteria and simulation options. Loading a spec
compiles the MJCF with MuJoCo and replaces its actuators and sensors by ours:

* one ``general`` actuator per actuated joint, in output order, acting as a PD servo
  ``u = kp (ctrl − q) − kd q̇`` clamped to the torque limit. Velocity tracking and feedforward torque
  are folded into ``ctrl`` by the controller (see :mod:`robustgait.sim.controller`), so a step's controls
  are one time series shared by every sample — what lets :func:`mujoco.rollout` run batches.
* three contact sensors (count of contacts found): left sole–floor, right sole–floor, floor–anything.
  ``anything − left − right > 0`` is a non-foot ground contact, i.e. a fall.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path

import mujoco
import numpy as np
from numpy.typing import NDArray

from robustgait.errors import RobustGaitError, input_error

SHIPPED_DIR = Path(__file__).resolve().parent
SIDES = ("left", "right")
INTEGRATORS = {
    "euler": mujoco.mjtIntegrator.mjINT_EULER,
    "implicitfast": mujoco.mjtIntegrator.mjINT_IMPLICITFAST,
    "implicit": mujoco.mjtIntegrator.mjINT_IMPLICIT,
    "rk4": mujoco.mjtIntegrator.mjINT_RK4,
}
# Sensor names we add to every model; the order is the layout of ``MjData.sensordata``.
CONTACT_SENSORS = ("robustgait_contact_left", "robustgait_contact_right", "robustgait_contact_floor")


@dataclass(frozen=True)
class LegSpec:
    """One leg: the collision geom of its sole (a box whose bottom face is the sole)."""

    sole_geom: str


@dataclass(frozen=True)
class FallCriteria:
    """A state is a fall when the base is lower than ``min_base_height`` [m] or its z axis is tilted
    more than ``max_tilt`` [rad] from vertical (plus non-foot ground contact and a diverging simulation)."""

    min_base_height: float = 0.5
    max_tilt: float = 0.8


@dataclass(frozen=True)
class GaitQuality:
    """Bounds that a generated gait must satisfy at every node (DESIGN §2, §4): what an exoskeleton's
    passenger needs besides the essential constraints. Angles of the pelvis are roll-pitch-yaw (ZYX)
    relative to the stance sole's frame; heights are above the stance sole.

    pelvis_roll, pelvis_yaw [rad]: |φ|, |ψ| ≤ bound. pelvis_pitch [rad]: (low, high) band.
    pelvis_height [m]: (low, high) band of the base origin above the stance sole.
    pelvis_angular_velocity [rad/s]: each component of the base's angular velocity (world axes) ≤ bound.
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
    pelvis_angular_velocity: float = 1.5
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
class RobotSpec:
    """Everything the pipeline needs to know about a robot beyond its MJCF."""

    name: str
    mjcf: Path
    base_body: str
    floor_geom: str
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
    description: str = ""
    source: Path | None = None
    gait_quality: GaitQuality = field(default_factory=GaitQuality)
    action_space: dict[str, ParamRange] | None = None
    multicontact_action_space: dict[str, ParamRange] | None = None
    posture: tuple[float, ...] = ()

    @property
    def n_joints(self) -> int:
        return len(self.joints)


ACTION_FIELDS = ("step_length", "step_duration", "step_width", "step_height")


def parse_spec(path: Path) -> RobotSpec:
    """Read and validate a spec TOML (structure and limits; names are checked against the MJCF on load).
    The schema is :class:`robustgait.io.specfile.SpecFile`; errors read ``FILE: field: problem``."""
    from robustgait.io.specfile import read_spec

    return read_spec(path)


def _add_contact_sensor(spec: mujoco.MjSpec, name: str, geom: str, ref: str | None) -> None:
    sensor = spec.add_sensor(name=name, type=mujoco.mjtSensor.mjSENS_CONTACT,
                             objtype=mujoco.mjtObj.mjOBJ_GEOM, objname=geom)
    if ref is not None:
        sensor.reftype = mujoco.mjtObj.mjOBJ_GEOM
        sensor.refname = ref
    # intprm = (data fields bitmask: "found" only, reduce: none, number of slots)
    sensor.intprm = [1 << int(mujoco.mjtConDataField.mjCONDATA_FOUND), 0, 1]


def build_mjspec(spec: RobotSpec) -> mujoco.MjSpec:
    """The robot's MJCF as an editable :class:`mujoco.MjSpec`, with our actuators and sensors."""
    src = spec.source or spec.mjcf
    if not spec.mjcf.is_file():
        raise input_error(src, f"MJCF file not found: {spec.mjcf}")
    try:
        mjs = mujoco.MjSpec.from_file(str(spec.mjcf))
    except ValueError as exc:
        raise input_error(spec.mjcf, f"MuJoCo could not parse the MJCF: {exc}") from None
    joint_names = {j.name for j in mjs.joints}
    geom_names = {g.name for g in mjs.geoms}
    for j in spec.joints:
        if j not in joint_names:
            raise input_error(src, f"unknown joint name '{j}' (not in {spec.mjcf.name})")
    for side, leg in spec.legs.items():
        if leg.sole_geom not in geom_names:
            raise input_error(src, f"unknown geom name '{leg.sole_geom}' for the {side} sole")
    if spec.floor_geom not in geom_names:
        raise input_error(src, f"unknown geom name '{spec.floor_geom}' for the floor")
    if spec.base_body not in {b.name for b in mjs.bodies}:
        raise input_error(src, f"unknown body name '{spec.base_body}' for the floating base")
    for act in list(mjs.actuators):
        mjs.delete(act)
    for sensor in list(mjs.sensors):
        mjs.delete(sensor)
    for key in list(mjs.keys):
        mjs.delete(key)
    for j, kp, kd, tmax in zip(spec.joints, spec.kp, spec.kd, spec.torque_limit, strict=True):
        act = mjs.add_actuator(name=f"robustgait_{j}", target=j, trntype=mujoco.mjtTrn.mjTRN_JOINT)
        act.gaintype = mujoco.mjtGain.mjGAIN_FIXED
        act.biastype = mujoco.mjtBias.mjBIAS_AFFINE
        act.gainprm[:3] = [kp, 0.0, 0.0]
        act.biasprm[:3] = [0.0, -kp, -kd]
        act.ctrllimited = mujoco.mjtLimited.mjLIMITED_FALSE
        act.forcelimited = mujoco.mjtLimited.mjLIMITED_TRUE
        act.forcerange = [-tmax, tmax]
    _add_contact_sensor(mjs, CONTACT_SENSORS[0], spec.legs["left"].sole_geom, spec.floor_geom)
    _add_contact_sensor(mjs, CONTACT_SENSORS[1], spec.legs["right"].sole_geom, spec.floor_geom)
    _add_contact_sensor(mjs, CONTACT_SENSORS[2], spec.floor_geom, None)
    if spec.timestep is not None:
        mjs.option.timestep = spec.timestep
    if spec.integrator is not None:
        mjs.option.integrator = INTEGRATORS[spec.integrator]
    return mjs


class Robot:
    """A loaded robot: its spec, the compiled MuJoCo model and the index maps the pipeline uses."""

    def __init__(self, spec: RobotSpec):
        self.spec = spec
        mjs = build_mjspec(spec)
        try:
            self.model: mujoco.MjModel = mjs.compile()
        except ValueError as exc:
            raise input_error(spec.mjcf, f"MuJoCo could not compile the model: {exc}") from None
        m = self.model
        base = m.body(spec.base_body)
        jnt = int(base.jntadr[0]) if base.jntnum[0] > 0 else -1
        if jnt < 0 or int(m.jnt_type[jnt]) != int(mujoco.mjtJoint.mjJNT_FREE):
            raise input_error(spec.source, f"base body '{spec.base_body}' has no free joint")
        if jnt != 0:
            raise input_error(spec.source, "the free joint of the base must be the model's first joint")
        ids = [m.joint(j).id for j in spec.joints]
        for j, i in zip(spec.joints, ids, strict=True):
            if int(m.jnt_type[i]) not in (int(mujoco.mjtJoint.mjJNT_HINGE), int(mujoco.mjtJoint.mjJNT_SLIDE)):
                raise input_error(spec.source, f"joint '{j}' is not a hinge or slide joint")
        if m.nq != 7 + len(ids) or m.nv != 6 + len(ids):
            raise input_error(spec.source, f"the model has {m.nv - 6} joints besides the base but the spec "
                              f"actuates {len(ids)}: every non-base joint must be actuated")
        self.qpos_idx: NDArray[np.int64] = np.array([m.jnt_qposadr[i] for i in ids], dtype=np.int64)
        self.dof_idx: NDArray[np.int64] = np.array([m.jnt_dofadr[i] for i in ids], dtype=np.int64)
        self.base_body_id = int(base.id)
        self.sole_geom_id = {s: m.geom(leg.sole_geom).id for s, leg in spec.legs.items()}
        self.floor_geom_id = m.geom(spec.floor_geom).id
        self.sensor_adr = {name: int(m.sensor(name).adr[0]) for name in CONTACT_SENSORS}
        self.kp = np.asarray(spec.kp)
        self.kd = np.asarray(spec.kd)
        self.torque_limit = np.asarray(spec.torque_limit)
        self.joint_range = np.array([m.jnt_range[i] if m.jnt_limited[i] else (-np.inf, np.inf) for i in ids])

    @property
    def name(self) -> str:
        return self.spec.name

    @property
    def n_joints(self) -> int:
        return self.spec.n_joints

    @property
    def dt(self) -> float:
        return float(self.model.opt.timestep)

    @cached_property
    def mass(self) -> float:
        return float(self.model.body_subtreemass[self.base_body_id])

    def new_data(self) -> mujoco.MjData:
        return mujoco.MjData(self.model)

    def mirror_joints(self, values: NDArray[np.float64]) -> NDArray[np.float64]:
        """Relabel joint-space arrays (..., n_joints) for the other stance: permute, then sign."""
        return np.asarray(values)[..., list(self.spec.mirror_perm)] * np.asarray(self.spec.mirror_sign)

    def mirror_state(self, qpos: NDArray[np.float64], qvel: NDArray[np.float64]
                     ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """The state relabeled for the other stance: a reflection S of the base about the sagittal plane.

        Base position p → S p, orientation R → S R S, linear velocity v → S v, angular velocity (world or
        body frame alike) ω → det(S) S ω; joints permuted and signed. qpos (..., nq), qvel (..., nv).
        """
        s = np.asarray(self.spec.base_mirror_sign[:3])
        qp = np.array(qpos, dtype=float)
        qv = np.array(qvel, dtype=float)
        qp[..., 0:3] *= s
        # A reflected rotation S R(a, θ) S is R(det(S) S a, θ): the quaternion's vector part maps like ω.
        qp[..., 4:7] *= np.prod(s) * s
        qv[..., 0:3] *= s
        qv[..., 3:6] *= np.prod(s) * s
        qp[..., self.qpos_idx] = self.mirror_joints(np.asarray(qpos)[..., self.qpos_idx])
        qv[..., self.dof_idx] = self.mirror_joints(np.asarray(qvel)[..., self.dof_idx])
        return qp, qv

    def __repr__(self) -> str:
        return f"Robot({self.name!r}, joints={self.n_joints}, mass={self.mass:.1f} kg)"


def shipped_robots() -> list[str]:
    """Names of the robots that ship with the package."""
    return sorted(p.parent.name for p in SHIPPED_DIR.glob("*/spec.toml"))


def load_robot(robot: str | Path | Robot) -> Robot:
    """Load a shipped robot by name (``"exo"``) or a user robot from a spec ``.toml`` path."""
    if isinstance(robot, Robot):
        return robot
    text = str(robot)
    if text in shipped_robots():
        return Robot(parse_spec(SHIPPED_DIR / text / "spec.toml"))
    path = Path(text)
    if path.suffix == ".toml" or path.exists():
        return Robot(parse_spec(path))
    raise RobustGaitError(
        f"{text}: unknown robot (shipped: {', '.join(shipped_robots()) or 'none'}; or give a spec .toml path)")
