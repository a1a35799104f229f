"""``robustgait robot check``: a loaded robot's spec checked against its model, one function per check, each with
its thresholds in :class:`robustgait.config.RobotCheckConfig` (``docs/robots.md``, "Your robot").

* :func:`check_mirror` — the spec's relabeling reflects the model (forward kinematics, :mod:`.mirror`);
* :func:`check_soles` — in the posture (its springs deflected by the weight, :func:`loaded`) both soles are flat
  (normal vs vertical) and at one height;
* :func:`check_torques` — the torque limits hold the posture: the static torques of double support (the weight
  split to need the least of each limit) within a margin of the limits;
* :func:`check_stiffness` — on one foot, each servo of the stance chain is stiffer than gravity's tipping stiffness
  about its joint (an inverted pendulum about the ankle: m g h) by a margin;
* :func:`check_stand` — the posture stands under the servos: free base on the floor for a while, from the posture as
  it stands (:func:`loaded`: a robot whose springs start undeflected drops onto them); the base's
  drop, tilt and the soles' slide, no fall (the spec's fall criteria), both soles in contact at the end;
* :func:`check_tracking` — the gains track: the robot hanging (base fixed, contacts off), every planned joint
  follows a sinusoid about the posture with the walker's servo law (c = q_d + kd q̇_d / kp, no feedforward);
  each joint's error RMS and its time at the torque limit.

The ``timestep`` check, which walks the default gait, is :func:`robustgait.robotinit.timestep.check_timestep`
(the certificate's orbit rule it walks with reads :attr:`robustgait.robots.model.Robot.sides_differ`); ``robot
check`` runs it after these.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import mujoco
import numpy as np
from numpy.typing import NDArray

from robustgait.config import RobotCheckConfig, RobotConfig
from robustgait.inspection.gains import settle_springs, static_torques, tipping_stiffness
from robustgait.inspection.mirror import Mirror, fk_residual, mirror_from_names
from robustgait.inspection.model import RobotModel, geom_bottom, with_closed_chains
from robustgait.robots import Robot
from robustgait.robots.sides import mass_asymmetry
from robustgait.robots.spec import SIDES


@dataclass(frozen=True)
class CheckResult:
    """One check: its ``name``, whether it ``passed``, one line saying what was measured against what, and the
    measured ``values``."""

    name: str
    passed: bool
    line: str
    values: dict[str, float] = field(default_factory=dict)


def inspected(robot: Robot) -> RobotModel:
    """The loaded robot seen by the inspection functions, its posture the spec's (planned and held angles)."""
    m = robot.model
    angles = {m.joint(j).id: a for j, a in zip(robot.spec.joints, robot.spec.posture, strict=True)}
    angles |= {m.joint(h.name).id: h.angle for h in robot.spec.held}
    return with_closed_chains(RobotModel(robot.spec.source or Path(robot.spec.mjcf), "mjcf", robot.mjspec(), m,
                                         robot.base_body_id, None, angles))


def loaded(robot: Robot) -> RobotModel:
    """The inspected robot (:func:`inspected`) as it stands on both feet: its springs at their static deflection under
    its weight (:func:`robustgait.inspection.gains.settle_springs`; the spec's posture holds them rigid), so that the
    soles, torques, stiffness and stand checks see the posture the robot stands in; :func:`inspected` for a robot
    without springs."""
    rm = inspected(robot)
    settle_springs(rm, [int(robot.model.geom_bodyid[robot.sole_geom_id[s]]) for s in SIDES])
    return rm


def standing_qpos(robot: Robot, rm: RobotModel) -> NDArray[np.float64]:
    """The posture with the base level, at the height that puts the lower sole on the floor."""
    floor = float(robot.model.geom_pos[robot.floor_geom_id][2])
    d = rm.kinematics(rm.qpos())
    low = min(geom_bottom(robot.model, d, robot.sole_geom_id[s]) for s in SIDES)
    return rm.qpos(height=floor - low)


def spec_mirror(robot: Robot, config: RobotConfig) -> tuple[RobotModel, Mirror]:
    """The spec's left/right relabeling as a :class:`~robustgait.inspection.mirror.Mirror` of the inspected model
    (raises ValueError when the spec's pairs do not match the model)."""
    spec = robot.spec
    pairs = {j: (spec.joints[p], s) for j, p, s in zip(spec.joints, spec.mirror_perm, spec.mirror_sign, strict=True)}
    pairs |= {h.name: (h.mirror, h.sign) for h in spec.held}
    rm = inspected(robot)
    return rm, mirror_from_names(rm, pairs, config.mirror_tolerance)


def check_mirror(robot: Robot, config: RobotConfig) -> CheckResult:
    """The spec's mirror reflects the model (:func:`robustgait.inspection.mirror.fk_residual`)."""
    try:
        rm, mirror = spec_mirror(robot, config)
    except ValueError as exc:
        return CheckResult("mirror", False, f"mirror: FAIL: {exc}")
    res = fk_residual(rm, mirror, config.mirror_samples, config.seed)
    asym = mass_asymmetry(rm.model, rm.base, mirror.body_partner)
    ok = res.position <= config.mirror_tolerance and res.angle <= config.mirror_angle_tolerance
    where = "" if ok else f" (worst body '{rm.body_name(res.body)}')"
    return CheckResult("mirror", bool(ok), f"mirror: {'ok' if ok else 'FAIL'}: forward kinematics of the relabeled "
                       f"configuration vs the reflected one over {res.samples} random configurations: largest residual "
                       f"{res.position:.2g} m, {res.angle:.2g} rad (tolerance {config.mirror_tolerance:g} m, "
                       f"{config.mirror_angle_tolerance:g} rad){where}; "
                       f"{asym.describe(rm.model, config.side_mass_tolerance, config.side_inertia_tolerance)}",
                       {"position": res.position, "angle": res.angle, "mass_asymmetry": asym.mass,
                        "inertia_asymmetry": asym.inertia,
                        "sides_differ": asym.differs(config.side_mass_tolerance, config.side_inertia_tolerance)})


def check_soles(robot: Robot, config: RobotCheckConfig) -> CheckResult:
    """Both soles flat and level with each other in the posture."""
    rm = loaded(robot)
    d = rm.kinematics(standing_qpos(robot, rm))
    soles = robot.sole_boxes
    tilt = {s: soles[s].tilt(d) for s in SIDES}
    gap = abs(float(soles["left"].bottom_centre(d)[2] - soles["right"].bottom_centre(d)[2]))
    ok = max(tilt.values()) <= config.sole_tilt and gap <= config.sole_gap
    return CheckResult("soles", bool(ok), f"soles: {'ok' if ok else 'FAIL'}: in the posture the soles tilt "
                       f"{tilt['left']:.3g} (left) and {tilt['right']:.3g} rad (right) from level (at most "
                       f"{config.sole_tilt:g}), their heights differ by {1e3 * gap:.3g} mm (at most "
                       f"{1e3 * config.sole_gap:g})", {"tilt": max(tilt.values()), "gap": gap})


def check_torques(robot: Robot, config: RobotCheckConfig) -> CheckResult:
    """The torque limits hold the posture in double support, with a margin."""
    rm = loaded(robot)
    m = robot.model
    q = standing_qpos(robot, rm)
    feet = [int(m.geom_bodyid[robot.sole_geom_id[s]]) for s in SIDES]
    names = [*robot.spec.joints, *robot.spec.held_names]
    dofs = [int(m.jnt_dofadr[m.joint(n).id]) for n in names]
    limit = np.zeros(m.nv)
    limit[dofs] = robot.servo_limit
    base = np.arange(6)
    weight = np.delete(limit, base)
    tau = static_torques(rm, q, feet, np.where(weight > 0, weight, 1.0))
    ratio = np.abs(tau[dofs]) / robot.servo_limit
    k = int(np.argmax(ratio))
    ok = float(ratio[k]) <= config.torque_margin
    return CheckResult("torques", bool(ok),
                       f"torques: {'ok' if ok else 'FAIL'}: holding the posture on both feet needs "
                       f"at most {100 * ratio[k]:.3g} % of a torque limit ({names[k]}: {abs(tau[dofs[k]]):.3g} of "
                       f"{robot.servo_limit[k]:.3g} N m; at most {100 * config.torque_margin:g} %)",
                       {"ratio": float(ratio[k])})


def check_stiffness(robot: Robot, config: RobotCheckConfig) -> CheckResult:
    """On either foot alone, every servo of the stance chain (the joints from the base down to that foot, planned or
    held) is stiffer than gravity's tipping stiffness about its joint by ``stance_stiffness``
    (:func:`robustgait.inspection.gains.tipping_stiffness`): else single support yields and tips over."""
    rm = loaded(robot)
    m = robot.model
    q = standing_qpos(robot, rm)
    kp = dict(zip([*robot.spec.joints, *robot.spec.held_names], robot.servo_kp, strict=True))
    worst = (np.inf, "", 0.0, 0.0)
    for side in SIDES:
        foot = int(m.geom_bodyid[robot.sole_geom_id[side]])
        chain = [j for b in [foot, *rm.ancestors(foot)] for j in rm.body_joints(b) if j in rm.joints]
        for j, k in tipping_stiffness(rm, q, foot, chain).items():
            name = rm.joint_name(j)
            if k > 0 and kp[name] / k < worst[0]:
                worst = (kp[name] / k, name, kp[name], k)
    ratio, name, gain, k = worst
    ok = ratio >= config.stance_stiffness
    what = (f"at least {ratio:.3g} × gravity's tipping stiffness about their joints ({name}: kp {gain:.4g} vs "
            f"{k:.4g} N m/rad" if name else "unopposed by gravity (no joint tips the robot over")
    return CheckResult("stiffness", bool(ok),
                       f"stiffness: {'ok' if ok else 'FAIL'}: on one foot the servos are {what}; "
                       f"at least {config.stance_stiffness:g} ×)", {"ratio": float(ratio)})


def check_stand(robot: Robot, config: RobotCheckConfig) -> CheckResult:
    """The posture stands for ``stand_time`` under its servos on the floor."""
    rm = loaded(robot)
    m = robot.model
    d = mujoco.MjData(m)
    d.qpos[:] = standing_qpos(robot, rm)
    d.ctrl[:] = robot.servo_controls(np.asarray(robot.spec.posture))
    mujoco.mj_forward(m, d)
    h0 = float(d.qpos[2])
    soles0 = {s: d.geom_xpos[robot.sole_geom_id[s]][:2].copy() for s in SIDES}
    length = 2.0 * min(robot.sole_boxes[s].half_length for s in SIDES)
    fall = robot.spec.fall
    low, tilt, slip, fell = h0, 0.0, 0.0, ""
    adr = robot.sensor_adr
    keys = ("robustgait_contact_left", "robustgait_contact_right", "robustgait_contact_floor")
    for _ in range(max(1, round(config.stand_time / robot.dt))):
        mujoco.mj_step(m, d)
        z = float(d.qpos[2])
        qx, qy = d.qpos[4:6]
        cos_tilt = 1.0 - 2.0 * (qx * qx + qy * qy)
        low, tilt = min(low, z), max(tilt, float(np.arccos(np.clip(cos_tilt, -1, 1))))
        slip = max(slip, *(float(np.linalg.norm(d.geom_xpos[robot.sole_geom_id[s]][:2] - soles0[s])) for s in SIDES))
        left, right, floor = (float(d.sensordata[adr[k]]) for k in keys)
        if not np.isfinite(d.qpos).all():
            fell = "diverged"
        elif z < fall.min_base_height:
            fell = f"base below {fall.min_base_height:g} m"
        elif cos_tilt < np.cos(fall.max_tilt):
            fell = f"tilted over {fall.max_tilt:g} rad"
        elif floor - left - right > 0:
            fell = "a body other than the soles touched the floor"
        if fell:
            break
    touching = left > 0 and right > 0
    drop = (h0 - low) / h0
    ok = (not fell and touching and drop <= config.stand_drop and tilt <= config.stand_tilt
          and slip <= config.stand_slip * length)
    what = (f"FELL ({fell})" if fell else ("ok" if ok else "FAIL"))
    return CheckResult("stand", bool(ok),
                       f"stand: {what}: {config.stand_time:g} s on the floor under the servos: the base "
                       f"dropped {100 * drop:.3g} % of its height (at most {100 * config.stand_drop:g} %), tilted "
                       f"{tilt:.3g} rad (at most {config.stand_tilt:g}), a sole slid {1e3 * slip:.3g} mm (at most "
                       f"{1e3 * config.stand_slip * length:.3g}); soles touching at the end: "
                       f"{'both' if touching else 'left' if left > 0 else 'right' if right > 0 else 'neither'}",
                       {"drop": drop, "tilt": tilt, "slip": slip})


def hanging_model(robot: Robot) -> mujoco.MjModel:
    """The robot with its base fixed in the air and contacts off (the tracking test)."""
    mjs = robot.mjspec()
    base = mjs.body(robot.spec.base_body)
    mjs.delete(base.first_joint())
    base.pos = [0.0, 0.0, 1.0]
    base.alt.type = mujoco.mjtOrientation.mjORIENTATION_QUAT
    base.quat = [1.0, 0.0, 0.0, 0.0]
    mjs.option.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONTACT)
    return mjs.compile()


def check_tracking(robot: Robot, config: RobotCheckConfig) -> CheckResult:
    """Every planned joint tracks a sinusoid, the robot hanging (module docstring)."""
    m = hanging_model(robot)
    d = mujoco.MjData(m)
    names = robot.spec.joints
    qadr = np.array([m.jnt_qposadr[m.joint(n).id] for n in names])
    vadr = np.array([m.jnt_dofadr[m.joint(n).id] for n in names])
    for h in robot.spec.held:
        d.qpos[m.jnt_qposadr[m.joint(h.name).id]] = h.angle
    lo, hi = robot.joint_range[:, 0], robot.joint_range[:, 1]
    a = config.track_amplitude
    centre = np.clip(np.asarray(robot.spec.posture), lo + a, hi - a)
    narrow = hi - lo < 2 * a  # a range narrower than the sinusoid: its middle (an unlimited joint is never narrow)
    centre[narrow] = (lo[narrow] + hi[narrow]) / 2
    amp = np.minimum(a, (hi - lo) / 2)
    phase = 2 * np.pi * np.arange(len(names)) / len(names)
    w = 2 * np.pi * config.track_frequency
    d.qpos[qadr] = centre + amp * np.sin(phase)
    d.qvel[vadr] = amp * w * np.cos(phase)
    kp, kd, limit = robot.kp, robot.kd, robot.torque_limit
    n = max(1, round(config.track_time / robot.dt))
    skip = min(n - 1, round(1.0 / config.track_frequency / robot.dt))
    err2 = np.zeros(len(names))
    sat = np.zeros(len(names))
    for k in range(n):
        t = d.time
        qd = centre + amp * np.sin(w * t + phase)
        vd = amp * w * np.cos(w * t + phase)
        planned = qd + kd * vd / kp
        d.ctrl[:] = robot.servo_controls(planned)
        u = kp * (planned - d.qpos[qadr]) - kd * d.qvel[vadr]
        mujoco.mj_step(m, d)
        if k >= skip:
            qd_next = centre + amp * np.sin(w * d.time + phase)
            err2 += (d.qpos[qadr] - qd_next) ** 2
            sat += np.abs(u) > limit
    scored = n - skip
    rms = np.sqrt(err2 / scored) / amp
    frac = sat / scored
    k = int(np.argmax(rms))
    s = int(np.argmax(frac))
    ok = float(rms[k]) <= config.track_rms and float(frac[s]) <= config.track_saturation
    return CheckResult("tracking", bool(ok), f"tracking: {'ok' if ok else 'FAIL'}: hanging, each planned joint follows "
                       f"{a:g} rad at {config.track_frequency:g} Hz (PD, no feedforward): error RMS at most "
                       f"{100 * rms[k]:.3g} % of the amplitude ({names[k]}; at most {100 * config.track_rms:g} %), "
                       f"at its torque limit at most {100 * frac[s]:.3g} % of the time ({names[s]}; at most "
                       f"{100 * config.track_saturation:g} %)", {"rms": float(rms[k]), "saturation": float(frac[s])})


def run_checks(robot: Robot, config: RobotConfig) -> list[CheckResult]:
    """Every check of the module docstring, in order."""
    c = config.check
    return [check_mirror(robot, config), check_soles(robot, c), check_torques(robot, c), check_stiffness(robot, c),
            check_stand(robot, c), check_tracking(robot, c)]
