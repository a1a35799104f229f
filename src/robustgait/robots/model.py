"""A loaded robot: its spec, the MuJoCo model compiled from its MJCF with our actuators and sensors, and the
index maps the pipeline uses.

Compiling replaces the MJCF's actuators and sensors by ours:

* one ``general`` actuator per actuated joint, in output order, acting as a PD servo
  ``u = kp (ctrl − q) − kd q̇`` clamped to the torque limit. Velocity tracking and feedforward torque
  are folded into ``ctrl`` by the controller (see :mod:`robustgait.sim.controller`), so a step's controls
  are one time series shared by every sample — what lets :func:`mujoco.rollout` run batches.
* three contact sensors (count of contacts found): left sole–floor, right sole–floor, floor–anything.
  ``anything − left − right > 0`` is a non-foot ground contact, i.e. a fall. MuJoCo's contact sensor reads the
  contacts found, whether its contype/conaffinity filter or an explicit ``<pair>`` made them.

The MJCF is read by :mod:`robustgait.io.robotfile` (``load_robot``), which hands the parsed
:class:`mujoco.MjSpec` to :class:`Robot`.
"""

from __future__ import annotations

import copy
import dataclasses
import hashlib
from functools import cached_property
from pathlib import PurePath

import mujoco
import numpy as np
from numpy.typing import NDArray

from robustgait.config import GaitParams, RobotConfig, RobotScale
from robustgait.errors import RobustGaitError, input_error
from robustgait.robots.held import weld_joints
from robustgait.robots.legs import ankle_roll_joint, foot_chain
from robustgait.robots.loops import DOF_SIZE, QPOS_SIZE, check_closed_chains
from robustgait.robots.passivemirror import passive_mirror
from robustgait.robots.sides import body_partners, mass_asymmetry
from robustgait.robots.solebox import SoleBox, sole_box
from robustgait.robots.soles import ResolvedSole, resolve_floor, resolve_soles
from robustgait.robots.spec import CLOSED_CHAIN_FIELDS, SIDES, RobotSpec

INTEGRATORS = {
    "euler": mujoco.mjtIntegrator.mjINT_EULER,
    "implicitfast": mujoco.mjtIntegrator.mjINT_IMPLICITFAST,
    "implicit": mujoco.mjtIntegrator.mjINT_IMPLICIT,
    "rk4": mujoco.mjtIntegrator.mjINT_RK4,
}
# Sensor names we add to every model; the order is the layout of ``MjData.sensordata``.
CONTACT_SENSORS = ("robustgait_contact_left", "robustgait_contact_right", "robustgait_contact_floor")


def _add_contact_sensor(spec: mujoco.MjSpec, name: str, obj: tuple[mujoco.mjtObj, str], ref: str | None) -> None:
    """A sensor counting the contacts of ``obj`` (a geom, or a body's geoms) with the geom ``ref`` (any if None)."""
    sensor = spec.add_sensor(name=name, type=mujoco.mjtSensor.mjSENS_CONTACT, objtype=obj[0], objname=obj[1])
    if ref is not None:
        sensor.reftype = mujoco.mjtObj.mjOBJ_GEOM
        sensor.refname = ref
    # intprm = (data fields bitmask: "found" only, reduce: none, number of slots)
    sensor.intprm = [1 << int(mujoco.mjtConDataField.mjCONDATA_FOUND), 0, 1]


def mass_matrix(model: mujoco.MjModel, qpos: NDArray[np.float64]) -> tuple[mujoco.MjData, NDArray[np.float64]]:
    """The forward pass at ``qpos`` (nq,) — fresh data, ``mj_forward`` — and the joint-space mass matrix M(q) (nv, nv)
    there, armature included (:func:`full_inertia`)."""
    d = mujoco.MjData(model)
    d.qpos[:] = qpos
    mujoco.mj_forward(model, d)
    return d, full_inertia(model, d)


def full_inertia(model: mujoco.MjModel, data: mujoco.MjData) -> NDArray[np.float64]:
    """M(q) (nv, nv), dense: MuJoCo's joint-space inertia (armature included) at the configuration of ``data``, whose
    forward pass (``mj_forward`` or at least ``mj_crb``) has run."""
    out = np.zeros((model.nv, model.nv))
    if hasattr(data, "qM"):  # MuJoCo < 4.0 takes the sparse qM
        mujoco.mj_fullM(model, out, data.qM)
    else:
        mujoco.mj_fullM(model, data, out)
    return out


def resolve_model(spec: RobotSpec, mjs: mujoco.MjSpec) -> tuple[dict[str, ResolvedSole], str]:
    """Check the spec's names against the parsed MJCF ``mjs`` and resolve its soles and floor in it (edited in place;
    :mod:`robustgait.robots.soles`: virtual soles, an added or named floor). Returns the soles by side and the
    floor geom's name."""
    src = spec.source or spec.mjcf
    joint_names = {j.name for j in mjs.joints}
    for j in (*spec.joints, *spec.held_names):
        if j not in joint_names:
            what = "held joint" if j in spec.held_names else "joint"
            raise input_error(src, f"unknown {what} name '{j}' (not in {spec.mjcf.name})")
    if spec.base_body not in {b.name for b in mjs.bodies}:
        raise input_error(src, f"unknown body name '{spec.base_body}' for the floating base")
    try:
        model = mjs.compile()  # as parsed, to place the soles (and number the elements)
    except ValueError as exc:
        raise input_error(spec.mjcf, f"MuJoCo could not compile the model: {exc}") from None
    geoms = {g.id: g for g in mjs.geoms}
    soles = resolve_soles(spec, mjs, model)
    floor = resolve_floor(spec, mjs, [geoms[g] for s in soles.values() for g in s.geoms])
    return soles, floor


def servo_damping(kp: float | NDArray[np.float64], kd: float | NDArray[np.float64], h: float, stable: bool
                  ) -> float | NDArray[np.float64]:
    """The damping a servo realises, kd or, as stable PD, kd + h kp [N m s/rad].

    A servo u = kp (c − q) − kd q̇ in MuJoCo's actuators is integrated with its damping implicit (``implicitfast``
    takes the velocity derivative of actuator forces) and its stiffness explicit. Stable PD (Tan, Liu & Turk, "Stable
    proportional-derivative controllers", IEEE CG&A 31(4), 2011) evaluates the stiffness at the next step's position,
    kp (c − q − h q̇), so the law becomes u = kp (c − q) − (kd + h kp) q̇: the same continuous law as h → 0, with the
    stiffness's first-order term implicit too. The references' feed-forward uses the same damping
    (:func:`robustgait.sim.controller.step_controls`), so a tracked reference keeps zero error. ``h``: the physics step
    [s]."""
    return kd + h * kp if stable else kd


def build_mjspec(spec: RobotSpec, mjs: mujoco.MjSpec, soles: dict[str, ResolvedSole], floor: str) -> mujoco.MjSpec:
    """``mjs`` (resolved by :func:`resolve_model`; edited in place and returned) with our actuators — one servo per
    planned joint (output order), then per held joint — and our contact sensors, and the spec's simulation
    options; the MJCF's own actuators, sensors and keyframes are removed."""
    for act in list(mjs.actuators):
        mjs.delete(act)
    for sensor in list(mjs.sensors):
        mjs.delete(sensor)
    for key in list(mjs.keys):
        mjs.delete(key)
    servos = [*zip(spec.joints, spec.kp, spec.kd, spec.torque_limit, strict=True),
              *((h.name, h.kp, h.kd, h.torque_limit) for h in spec.held)]
    h = spec.timestep if spec.timestep is not None else float(mjs.option.timestep)
    for j, kp, kd0, tmax in servos:
        kd = servo_damping(kp, kd0, h, spec.stable_pd)
        act = mjs.add_actuator(name=f"robustgait_{j}", target=j, trntype=mujoco.mjtTrn.mjTRN_JOINT)
        act.gaintype = mujoco.mjtGain.mjGAIN_FIXED
        act.biastype = mujoco.mjtBias.mjBIAS_AFFINE
        act.gainprm[:3] = [kp, 0.0, 0.0]
        act.biasprm[:3] = [0.0, -kp, -kd]
        act.ctrllimited = mujoco.mjtLimited.mjLIMITED_FALSE
        act.forcelimited = mujoco.mjtLimited.mjLIMITED_TRUE
        act.forcerange = [-tmax, tmax]
    for name, side in zip(CONTACT_SENSORS[:2], SIDES, strict=True):
        _add_contact_sensor(mjs, name, soles[side].sensor, floor)
    _add_contact_sensor(mjs, CONTACT_SENSORS[2], (mujoco.mjtObj.mjOBJ_GEOM, floor), None)
    if spec.timestep is not None:
        mjs.option.timestep = spec.timestep
    if spec.integrator is not None:
        mjs.option.integrator = INTEGRATORS[spec.integrator]
    return mjs


class Robot:
    """A loaded robot: its spec, the compiled MuJoCo model and the index maps the pipeline uses. ``mjcf``: the
    robot's MJCF as parsed by MuJoCo (:func:`robustgait.io.robotfile.read_mjcf`); it is edited in place.

    Joints: the planned ones (``spec.joints``, output order: ``qpos_idx``, ``dof_idx``, ``kp`` …) and the held ones
    (``spec.held``: ``held_qpos_idx``, ``held_dof_idx``, ``held_angle``). Servos (``model.nu`` of them): the planned
    joints', then the held joints' (``servo_kp``, ``servo_kd``, ``servo_limit``). ``planned``: the robot with its held
    joints welded (gait generation's model); ``resolved``: the soles and floor when ``mjcf`` is already resolved
    (:func:`resolve_model`), as for ``planned``."""

    def __init__(self, spec: RobotSpec, mjcf: mujoco.MjSpec,
                 resolved: tuple[dict[str, ResolvedSole], str] | None = None):
        self.spec = spec
        self.soles, self.floor_name = resolved if resolved is not None else resolve_model(spec, mjcf)
        self._resolved = mjcf.copy()
        mjs = build_mjspec(spec, mjcf, self.soles, self.floor_name)
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
        held = [m.joint(h.name).id for h in spec.held]
        for j, i in zip((*spec.joints, *spec.held_names), ids + held, strict=True):
            if int(m.jnt_type[i]) not in (int(mujoco.mjtJoint.mjJNT_HINGE), int(mujoco.mjtJoint.mjJNT_SLIDE)):
                raise input_error(spec.source, f"joint '{j}' is not a hinge or slide joint")
        n = len(ids) + len(held)
        passive = check_closed_chains(m, spec)
        nq = 7 + n + sum(QPOS_SIZE.get(int(m.jnt_type[j]), 1) for j in passive)
        nv = 6 + n + sum(DOF_SIZE.get(int(m.jnt_type[j]), 1) for j in passive)
        if m.nq != nq or m.nv != nv:
            names = {m.joint(i).name for i in range(1, m.njnt)} - {*spec.joints, *spec.held_names, *spec.passive}
            raise input_error(spec.source, f"the model has {m.njnt - 1} joints besides the base but the spec plans "
                              f"{len(ids)} and holds {len(held)}: every non-base joint must be in joints.names or "
                              f"joints.held (missing: {', '.join(sorted(names)) or 'none'})")
        self.passive_ids: tuple[int, ...] = passive
        self._passive_mirror = (passive_mirror(m, passive, int(base.id), spec.base_mirror_sign, spec.source)
                                if passive else None)
        self.qpos_idx: NDArray[np.int64] = np.array([m.jnt_qposadr[i] for i in ids], dtype=np.int64)
        self.dof_idx: NDArray[np.int64] = np.array([m.jnt_dofadr[i] for i in ids], dtype=np.int64)
        self.held_qpos_idx: NDArray[np.int64] = np.array([m.jnt_qposadr[i] for i in held], dtype=np.int64)
        self.held_dof_idx: NDArray[np.int64] = np.array([m.jnt_dofadr[i] for i in held], dtype=np.int64)
        self.held_angle = np.array([h.angle for h in spec.held], dtype=float)
        order = {h.name: k for k, h in enumerate(spec.held)}
        self._held_perm = [order[h.mirror] for h in spec.held]
        self._held_sign = np.array([h.sign for h in spec.held], dtype=float)
        self.base_body_id = int(base.id)
        self.sole_geom_id = {side: m.geom(sole.geom).id for side, sole in self.soles.items()}
        self.floor_geom_id = m.geom(self.floor_name).id
        self.sensor_adr = {name: int(m.sensor(name).adr[0]) for name in CONTACT_SENSORS}
        self.kp = np.asarray(spec.kp)
        # the damping the servos realise (the spec's kd, or stable PD's kd + h kp: servo_damping)
        dt = float(self.model.opt.timestep)
        self.kd = np.asarray(servo_damping(self.kp, np.asarray(spec.kd), dt, spec.stable_pd))
        self.torque_limit = np.asarray(spec.torque_limit)
        self.servo_kp = np.concatenate([self.kp, [h.kp for h in spec.held]])
        self.servo_kd = np.concatenate([self.kd, [servo_damping(x.kp, x.kd, dt, spec.stable_pd) for x in spec.held]])
        self.servo_limit = np.concatenate([self.torque_limit, [h.torque_limit for h in spec.held]])
        self.joint_range = np.array([m.jnt_range[i] if m.jnt_limited[i] else (-np.inf, np.inf) for i in ids])

    @cached_property
    def planned(self) -> Robot:
        """The robot whose model has the held joints welded at their angles (:func:`robustgait.robots.held.
        weld_joints`): what gait generation plans with; the robot itself when it holds no joint."""
        if not self.spec.held:
            return self
        mjs = self._resolved.copy()
        weld_joints(mjs, mjs.compile(), self.spec.held, self.spec.source)
        return Robot(dataclasses.replace(self.spec, held=()), mjs, resolved=(self.soles, self.floor_name))

    def at_timestep(self, h: float, stable_pd: bool = True) -> Robot:
        """This robot with the physics step ``h`` [s] and its servos as stable PD or not (``stable_pd``,
        :func:`servo_damping`): a new model compiled from the same parsed MJCF, soles and floor, every other value of
        the spec (gains, limits, integrator, …) unchanged; edits made to this robot's compiled ``model`` are not
        carried over. Raises RobustGaitError for an ``h`` that is not a positive finite number."""
        if not (np.isfinite(h) and h > 0):
            raise RobustGaitError(f"{self.name}: a timestep must be a positive number of seconds, got {h!r}")
        spec = dataclasses.replace(self.spec, timestep=float(h), stable_pd=bool(stable_pd))
        return Robot(spec, self._resolved.copy(), resolved=(self.soles, self.floor_name))

    def expand_state(self, qpos: NDArray[np.float64], qvel: NDArray[np.float64]
                     ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """A state of :attr:`planned`'s model (..., 7 + m), (..., 6 + m) as this model's: the base and planned joints
        copied, the held joints at their angles and at rest."""
        plan = self.planned
        qp = np.zeros((*np.shape(qpos)[:-1], self.model.nq))
        qv = np.zeros((*np.shape(qvel)[:-1], self.model.nv))
        qp[..., :7], qv[..., :6] = np.asarray(qpos)[..., :7], np.asarray(qvel)[..., :6]
        qp[..., self.qpos_idx] = np.asarray(qpos)[..., plan.qpos_idx]
        qv[..., self.dof_idx] = np.asarray(qvel)[..., plan.dof_idx]
        qp[..., self.held_qpos_idx] = self.held_angle
        return qp, qv

    def servo_controls(self, planned: NDArray[np.float64]) -> NDArray[np.float64]:
        """Servo controls (..., nu) from the planned joints' controls (..., m): the held joints' servos get their
        angles."""
        c = np.asarray(planned, dtype=float)
        if not self.spec.held:
            return c
        return np.concatenate([c, np.broadcast_to(self.held_angle, (*c.shape[:-1], self.held_angle.size))], axis=-1)

    @cached_property
    def leg_length(self) -> float:
        """Hip-to-sole distance [m] in the zero posture: from the joint of the base's child on the right sole's
        kinematic chain to the sole box's centre."""
        m = self.model
        d = mujoco.MjData(m)
        mujoco.mj_kinematics(m, d)
        body = int(m.geom_bodyid[self.sole_geom_id["right"]])
        while int(m.body_parentid[body]) != self.base_body_id:
            body = int(m.body_parentid[body])
        hip = d.xanchor[int(m.body_jntadr[body])]
        return float(np.linalg.norm(hip - d.geom_xpos[self.sole_geom_id["right"]]))

    @property
    def default_params(self) -> GaitParams:
        """The robot's default gait parameters: the spec's ``[gait]`` over the configuration's defaults."""
        return GaitParams(**self.spec.gait)

    @cached_property
    def sole_boxes(self) -> dict[str, SoleBox]:
        """Each side's sole box as the pipeline reads it (:class:`~robustgait.robots.solebox.SoleBox`)."""
        return {side: sole_box(self.model, self.sole_geom_id[side], self.spec.source or self.spec.mjcf)
                for side in SIDES}

    @cached_property
    def leg_joints(self) -> dict[str, tuple[int, ...]]:
        """Each side's leg joints (model joint ids), hip to foot: the planned or held joints between the base and the
        sole's body (a closed chain's passive joints are not the leg's)."""
        m = self.model
        return {side: tuple(j for j in foot_chain(m, int(m.geom_bodyid[self.sole_geom_id[side]]), self.base_body_id)
                            if j not in self.passive_ids) for side in SIDES}

    @cached_property
    def ankle_rolls(self) -> dict[str, int | None]:
        """Each side's ankle roll joint (model joint id; :func:`~robustgait.robots.legs.ankle_roll_joint`), None for
        a leg without one."""
        return {side: ankle_roll_joint(self.model, joints) for side, joints in self.leg_joints.items()}

    @property
    def has_ankle_roll(self) -> bool:
        """Whether both legs have an ankle roll (``docs/robots.md``, "Legs without an ankle roll")."""
        return all(j is not None for j in self.ankle_rolls.values())

    @cached_property
    def sole_spacing(self) -> float:
        """The lateral distance [m] between the two sole boxes' bottom centres in the spec's posture, the base at the
        origin and level: where flat feet stand under a level pelvis — for legs without an ankle roll, the only
        step width at which both land flat with the pelvis level."""
        d = mujoco.MjData(self.model)
        d.qpos[self.qpos_idx] = self.spec.posture
        mujoco.mj_kinematics(self.model, d)
        left, right = (self.sole_boxes[s].bottom_centre(d) for s in SIDES)
        return float(abs(left[1] - right[1]))

    @cached_property
    def sides_differ(self) -> bool:
        """Whether the robot's left and right differ, so that its walk is certified on the stride map (two steps,
        ``certify.map`` auto): the body pairs the spec's relabeling implies (:func:`~robustgait.robots.sides.
        body_partners`) differ in mass or inertia beyond ``robot.side_mass_tolerance`` and
        ``robot.side_inertia_tolerance`` (:meth:`~robustgait.robots.sides.MassAsymmetry.differs`), or the two sole
        boxes' half sizes by more than ``robot.mirror_tolerance`` [m] (the defaults read one sole for both,
        :attr:`sole_width`). A relabeling whose bodies have no mirror image counts as differing: no mirrored map is
        trusted. The configuration's defaults (:class:`~robustgait.config.RobotConfig`)."""
        config = RobotConfig()
        m, spec = self.model, self.spec
        partner = {m.joint(j).id: m.joint(spec.joints[p]).id
                   for j, p in zip(spec.joints, spec.mirror_perm, strict=True)}
        partner |= {m.joint(h.name).id: m.joint(h.mirror).id for h in spec.held}
        d = mujoco.MjData(m)  # the model's reference with the base at the origin and every joint at 0
        d.qpos[:] = m.qpos0
        d.qpos[:7] = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0]
        d.qpos[np.concatenate([self.qpos_idx, self.held_qpos_idx])] = 0.0
        mujoco.mj_kinematics(m, d)
        try:
            pairs = body_partners(m, self.base_body_id, partner, d, config.mirror_tolerance, spec.source or spec.mjcf)
        except ValueError:
            return True
        left, right = self.sole_boxes["left"], self.sole_boxes["right"]
        soles = max(abs(left.half_length - right.half_length), abs(left.half_width - right.half_width),
                    abs(left.half_thickness - right.half_thickness))
        return (mass_asymmetry(m, self.base_body_id, pairs).differs(config.side_mass_tolerance,
                                                                    config.side_inertia_tolerance)
                or soles > config.mirror_tolerance)

    @property
    def sole_width(self) -> float:
        """The sole's width [m], the one the step regulator's rule, its foot gap and the robot-relative defaults read:
        the right sole box's (:class:`~robustgait.robots.solebox.SoleBox`; a line foot's is 2 × its nominal half
        width, :data:`robustgait.robots.soles.LINE_HALF_WIDTH`)."""
        return 2.0 * self.sole_boxes["right"].half_width

    @cached_property
    def scale(self) -> RobotScale:
        """What robot-relative defaults scale with (:class:`robustgait.config.RobotScale`): mass, |g|, the leg length
        and the right sole box's size (:attr:`sole_width`); ``robot init``'s other measurements at their defaults."""
        sole = self.sole_boxes["right"]
        return RobotScale(mass=self.mass, gravity=float(np.linalg.norm(self.model.opt.gravity)),
                          leg_length=self.leg_length, sole_length=2.0 * sole.half_length, sole_width=self.sole_width)

    @property
    def name(self) -> str:
        return self.spec.name

    @cached_property
    def digest(self) -> str:
        """SHA-256 (hex) of what the robot's walks depend on: its compiled MuJoCo model (its binary form) and its spec
        without file paths — two robots with one digest simulate alike, wherever their files lie."""
        buf = np.empty(mujoco.mj_sizeModel(self.model), dtype=np.uint8)
        mujoco.mj_saveModel(self.model, None, buf)
        spec = {k: v for k, v in dataclasses.asdict(self.spec).items() if not isinstance(v, PurePath)
                and not (k in CLOSED_CHAIN_FIELDS and not v)}  # empty closed-chain fields leave a serial digest alone
        return hashlib.sha256(buf.tobytes() + repr(spec).encode()).hexdigest()

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
        body frame alike) ω → det(S) S ω; planned and held joints permuted and signed; a closed chain's passive
        joints onto their partners' (:mod:`robustgait.robots.passivemirror`). qpos (..., nq), qvel (..., nv).
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
        if self.spec.held:
            qp[..., self.held_qpos_idx] = np.asarray(qpos)[..., self.held_qpos_idx[self._held_perm]] * self._held_sign
            qv[..., self.held_dof_idx] = np.asarray(qvel)[..., self.held_dof_idx[self._held_perm]] * self._held_sign
        if self._passive_mirror is not None:
            self._passive_mirror.apply(np.asarray(qpos, dtype=float), np.asarray(qvel, dtype=float), qp, qv)
        return qp, qv

    def __repr__(self) -> str:
        return f"Robot({self.name!r}, joints={self.n_joints}, mass={self.mass:.1f} kg)"


def actuated_model(model: mujoco.MjModel, actuation: str, damping: NDArray[np.float64] | None = None) -> mujoco.MjModel:
    """The model the feedback engine steps for a robot model: itself for ``servo`` with the spec's damping
    (``damping`` None); else a copy whose affine servos have the servo damping ``damping`` (``servo``: u =
    kp (c − q) − damping q̇) or are direct torque motors (``motor``: gain 1, bias 0). Force ranges are kept."""
    if actuation == "servo" and damping is None:
        return model
    out = copy.copy(model)
    if actuation == "motor":
        out.actuator_gainprm[:, :] = 0.0
        out.actuator_gainprm[:, 0] = 1.0
        out.actuator_biasprm[:, :] = 0.0
    else:
        assert damping is not None
        out.actuator_biasprm[:, 2] = -np.asarray(damping, dtype=float)
    return out
