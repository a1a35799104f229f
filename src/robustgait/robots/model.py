"""A loaded robot: its spec, the MuJoCo model compiled from its MJCF with our actuators and sensors, and the
index maps the pipeline uses.

Compiling replaces the MJCF's actuators and sensors by ours:

* one ``general`` actuator per actuated joint, in output order, acting as a PD servo
  ``u = kp (ctrl − q) − kd q̇`` clamped to the torque limit. Velocity tracking and feedforward torque
  are folded into ``ctrl`` by the controller (see :mod:`robustgait.sim.controller`), so a step's controls
  are one time series shared by every sample — what lets :func:`mujoco.rollout` run batches.
* three contact sensors (count of contacts found): left sole–floor, right sole–floor, floor–anything.
  ``anything − left − right > 0`` is a non-foot ground contact, i.e. a fall.

The MJCF is read by :mod:`robustgait.io.robotfile` (``load_robot``), which hands the parsed
:class:`mujoco.MjSpec` to :class:`Robot`.
"""

from __future__ import annotations

from functools import cached_property

import mujoco
import numpy as np
from numpy.typing import NDArray

from robustgait.errors import input_error
from robustgait.robots.spec import RobotSpec

INTEGRATORS = {
    "euler": mujoco.mjtIntegrator.mjINT_EULER,
    "implicitfast": mujoco.mjtIntegrator.mjINT_IMPLICITFAST,
    "implicit": mujoco.mjtIntegrator.mjINT_IMPLICIT,
    "rk4": mujoco.mjtIntegrator.mjINT_RK4,
}
# Sensor names we add to every model; the order is the layout of ``MjData.sensordata``.
CONTACT_SENSORS = ("robustgait_contact_left", "robustgait_contact_right", "robustgait_contact_floor")


def _add_contact_sensor(spec: mujoco.MjSpec, name: str, geom: str, ref: str | None) -> None:
    sensor = spec.add_sensor(name=name, type=mujoco.mjtSensor.mjSENS_CONTACT,
                             objtype=mujoco.mjtObj.mjOBJ_GEOM, objname=geom)
    if ref is not None:
        sensor.reftype = mujoco.mjtObj.mjOBJ_GEOM
        sensor.refname = ref
    # intprm = (data fields bitmask: "found" only, reduce: none, number of slots)
    sensor.intprm = [1 << int(mujoco.mjtConDataField.mjCONDATA_FOUND), 0, 1]


def build_mjspec(spec: RobotSpec, mjs: mujoco.MjSpec) -> mujoco.MjSpec:
    """The robot's parsed MJCF ``mjs`` (edited in place and returned) with our actuators and sensors, after
    checking that the spec's names exist in it."""
    src = spec.source or spec.mjcf
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
    """A loaded robot: its spec, the compiled MuJoCo model and the index maps the pipeline uses. ``mjcf``: the
    robot's MJCF as parsed by MuJoCo (:func:`robustgait.io.robotfile.read_mjcf`); it is edited in place."""

    def __init__(self, spec: RobotSpec, mjcf: mujoco.MjSpec):
        self.spec = spec
        mjs = build_mjspec(spec, mjcf)
        self._mjspec = mjs.copy()
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

    def mjspec(self) -> mujoco.MjSpec:
        """A fresh copy of the robot's edited :class:`mujoco.MjSpec` (our actuators and sensors): to compile
        variants of the model (other masses, terrain) without reading the MJCF again."""
        return self._mjspec.copy()

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
