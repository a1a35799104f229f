"""A spec drafted from a robot's model (``robustgait robot init``): discovery, mirror, posture, torque limits,
gains and scaled values, gathered in a :class:`Draft` that :mod:`.writer` renders as a commented TOML.

Every refusal is a one-line :class:`~robustgait.errors.RobustGaitError` raised before anything is written: no
free joint (a URDF gets one), one leg, no sole, a sole that is not a box or a set of spheres/capsules/cylinders/
boxes/meshes, a mirror that does not reflect the model, a leg whose joints' names say the other side. A sole that its
model tilts in the posture (a foot plate's geoms rotated 90.5°) is levelled by the leg's ankle, and a centre of mass
at the soles' edge is brought over them (:mod:`.posture`).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import mujoco
import numpy as np
from numpy.typing import NDArray

from robustgait.config import RobotConfig, RobotScale
from robustgait.errors import input_error
from robustgait.inspection.discover import (
    SIDES,
    Floor,
    Legs,
    TorqueLimit,
    find_floor,
    find_legs,
    footprint_points,
    torque_limits,
)
from robustgait.inspection.gains import (
    STABLE_RADIUS,
    JointLoad,
    PDGains,
    coupled_radius,
    estimated_torque_limits,
    joint_loads,
    pd_gains,
    servo_gains,
    servo_timestep,
)
from robustgait.inspection.mirror import Mirror, Residual, find_mirror, fk_residual, name_partner
from robustgait.inspection.model import RobotModel, open_model
from robustgait.inspection.scale import Balance, Scaled, hip_roll_angle, scale
from robustgait.robotinit.posture import centre_over_soles, level_soles, level_under_load, symmetric_angles
from robustgait.robots.model import mass_matrix
from robustgait.robots.soles import GEOM_TYPES, can_touch

if TYPE_CHECKING:
    from robustgait.robotinit.timestep import TimestepChoice

INTEGRATOR_NAMES = {int(mujoco.mjtIntegrator.mjINT_EULER): "euler",
                    int(mujoco.mjtIntegrator.mjINT_IMPLICITFAST): "implicitfast",
                    int(mujoco.mjtIntegrator.mjINT_IMPLICIT): "implicit", int(mujoco.mjtIntegrator.mjINT_RK4): "rk4"}


@dataclass
class Draft:
    """Everything a written spec says (see :func:`draft_spec`). ``planned``: the joints the gait plans, in output
    order (the left leg's from the branch down, then the right leg's, then — ``--plan all`` — the others in model
    order); ``held``: the others. ``angles``: every joint's posture angle, made left/right symmetric
    (``asymmetry``: the largest change that took [rad]) and with its soles level (``levelled``: the largest ankle
    change that took [rad], :func:`~.posture.level_soles`), its mass over the soles (``centred``: the legs' lean that
    took [rad], :func:`~.posture.centre_over_soles`). ``torque``: each joint's limit and its source (estimated
    where the model has none). ``timestep``: the spec's physics step (:func:`servo_timestep`; ``servo_frequency``
    [Hz]: the fastest servo's natural frequency on its swing inertia, before any lowering for stability).
    ``height``: the base's height above the floor standing in the posture [m]. ``balance``: the default gait's
    measured step-to-step balance, when it bounds the scaled values (a point-foot walker's step durations).
    ``radius``: the spectral radius of one physics step of all the servos together (base held; < 1: they
    contract)."""

    robot: RobotModel
    config: RobotConfig
    name: str
    legs: Legs
    floor: Floor
    mirror: Mirror
    residual: Residual
    planned: tuple[int, ...]
    held: tuple[int, ...]
    angles: dict[int, float]
    asymmetry: float
    levelled: float
    centred: float
    torque: dict[int, TorqueLimit]
    loads: dict[int, JointLoad]
    gains: dict[int, PDGains]
    size: RobotScale
    scaled: Scaled
    timestep: float
    servo_frequency: float
    integrator: str
    radius: float
    height: float
    notes: list[str] = field(default_factory=list)
    stable_pd: bool = False
    choice: TimestepChoice | None = None
    balance: Balance | None = None


def spec_name(robot: RobotModel) -> str:
    """The spec's default name: the model's name (else its file's), lower case, spaces as underscores."""
    text = str(robot.mjspec.modelname or "") or robot.path.stem
    return "_".join(text.lower().split()) or "robot"


def _check_sides(robot: RobotModel, legs: Legs, mirror: Mirror) -> None:
    """Each leg joint's partner is in the other leg, and no leg joint's name says the other side."""
    names = [robot.joint_name(j) for j in robot.joints]
    for side, other in zip(SIDES, reversed(SIDES), strict=True):
        for j in legs[side].joints:
            if mirror.partner[j] not in legs[other].joints:
                raise input_error(robot.path, f"the mirror does not reflect the model: the {side} leg's joint "
                                  f"'{robot.joint_name(j)}' maps to '{robot.joint_name(mirror.partner[j])}', not a "
                                  f"joint of the {other} leg")
            said = name_partner(robot.joint_name(j), names)
            if said is not None and said[1] != side:
                raise input_error(robot.path, f"joint '{robot.joint_name(j)}' is named for the {said[1]} side but its "
                                  f"leg stands at y {'>' if side == 'left' else '<'} 0 in the base frame of "
                                  f"'{robot.base_name}' (left is +y): is the base's x axis forward?")


def _floor_collides(robot: RobotModel, floor: Floor, legs: Legs) -> None:
    """Refuse a floor plane that no sole geom can touch (an explicit pair of the two, or MuJoCo's contype/conaffinity
    filter: :func:`robustgait.robots.soles.can_touch`)."""
    if floor.add:
        return
    m = robot.model
    g = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, floor.name) if floor.name else next(
        g for g in robot.body_geoms(0) if GEOM_TYPES[int(m.geom_type[g])] == "plane")
    for side in SIDES:
        if not any(can_touch(m, g, s) for s in legs[side].sole.geoms):
            raise input_error(robot.path, f"the floor '{floor.name or 'unnamed plane'}' does not collide with the "
                              f"{side} sole's geoms (contype/conaffinity, or a <pair>): the robot would fall "
                              "through it")


def coupled_gains(robot: RobotModel, qpos: NDArray[np.float64], gains: dict[int, PDGains], dt: float,
                  integrator: str) -> tuple[dict[int, PDGains], float]:
    """The gains with every servo acting together on the joint-space mass matrix at ``qpos`` (base held):
    all lowered by the same factor until that system contracts (:func:`coupled_radius`); and its radius."""
    m = robot.model
    dofs = [int(m.jnt_dofadr[j]) for j in robot.joints]
    _, full = mass_matrix(robot.model, qpos)
    mass = full[np.ix_(dofs, dofs)]
    kp = np.array([gains[j].kp for j in robot.joints])
    kd = np.array([gains[j].kd for j in robot.joints])
    factor = 1.0
    radius = coupled_radius(mass, kp, kd, dt, integrator)
    for _ in range(200):
        if radius < STABLE_RADIUS:
            break
        factor *= 0.8
        radius = coupled_radius(mass, factor * kp, factor * kd, dt, integrator)
    if factor == 1.0:
        return gains, radius
    return {j: dataclasses.replace(g, kp=factor * g.kp, kd=factor * g.kd, bound="stability")
            for j, g in gains.items()}, radius


def drafted_gains(robot: RobotModel, loads: dict[int, JointLoad], torque: dict[int, TorqueLimit],
                  config: RobotConfig, qpos: NDArray[np.float64], dt: float, integrator: str
                  ) -> tuple[dict[int, PDGains], float]:
    """Every joint's servo at the physics step ``dt`` [s]: :func:`pd_gains` from its loads and torque limit, then
    :func:`coupled_gains` on the mass matrix at ``qpos``; and the coupled radius."""
    gains = {j: pd_gains(loads[j], float(torque[j].value or 0.0), config.bandwidth, config.damping_ratio,
                         config.tracking_error, dt, integrator) for j in robot.joints}
    return coupled_gains(robot, qpos, gains, dt, integrator)


def draft_at_timestep(draft: Draft, dt: float, stable_pd: bool, choice: TimestepChoice | None = None) -> Draft:
    """The draft with the physics step ``dt`` [s] and its gains drafted at it (:func:`drafted_gains`: the gain rules
    depend on the step), its servos stable PD or not, and the accuracy rule's ``choice`` that set it (None: none)."""
    qpos = draft.robot.qpos(height=draft.height)
    gains, radius = drafted_gains(draft.robot, draft.loads, draft.torque, draft.config, qpos, dt, draft.integrator)
    return dataclasses.replace(draft, timestep=dt, gains=gains, radius=radius, stable_pd=stable_pd, choice=choice,
                               notes=list(draft.notes))


def lowered(draft: Draft) -> bool:
    """Whether a servo's gains were lowered to contract at the draft's step: the step is above the servos' stability
    bound."""
    return any(g.bound == "stability" for g in draft.gains.values())


def symmetric_loads(loads: dict[int, JointLoad], torque: dict[int, TorqueLimit], mirror: Mirror
                    ) -> tuple[dict[int, JointLoad], dict[int, TorqueLimit]]:
    """The loads averaged over each left/right pair and the smaller torque limit of the pair, so that partners get
    the same servo (a model's two sides may differ slightly, e.g. in a link's mass)."""
    out_loads, out_torque = {}, {}
    for j, load in loads.items():
        p = loads[mirror.partner[j]]
        out_loads[j] = JointLoad((load.swing + p.swing) / 2, (load.stance + p.stance) / 2, load.stance_side)
        mine, theirs = torque[j], torque[mirror.partner[j]]
        if (theirs.value or 0.0) < (mine.value or 0.0) * (1 - 1e-6):
            out_torque[j] = TorqueLimit(theirs.value, f"{theirs.source} of its mirror joint (the smaller of the pair)")
        else:
            out_torque[j] = mine
    return out_loads, out_torque


def draft_spec(path: str | Path, config: RobotConfig) -> Draft:
    """Read a robot's MJCF or URDF and draft its spec (module docstring)."""
    robot = open_model(path, config.keyframe)
    src = robot.path
    find_legs(robot, config.foot_level, config.sole_tolerance)  # one leg, no sole ...: said before the mirror
    mirror = find_mirror(robot, config.mirror_tolerance)
    robot.angles, asymmetry = symmetric_angles(robot, mirror)
    robot.close()  # a closed chain's passive joints solved again from the planned ones (robots.loops)
    legs = find_legs(robot, config.foot_level, config.sole_tolerance)  # in the symmetric posture
    levelled = level_soles(robot, legs, mirror)
    if levelled > 0.0:
        robot.close()
        legs = find_legs(robot, config.foot_level, config.sole_tolerance)  # in the levelled posture
    centred = centre_over_soles(robot, legs, mirror, config.stand_fraction)
    if centred > 0.0:
        robot.close()
        legs = find_legs(robot, config.foot_level, config.sole_tolerance)  # in the leaned posture
    loaded, under_load = level_under_load(robot, legs, mirror)
    if under_load > 0.0:
        legs = find_legs(robot, config.foot_level, config.sole_tolerance)  # in the posture levelled under load
    angles = robot.angles
    floor = find_floor(robot)
    _floor_collides(robot, floor, legs)
    _check_sides(robot, legs, mirror)
    residual = fk_residual(robot, mirror, config.mirror_samples, config.seed)
    if residual.position > config.mirror_tolerance or residual.angle > config.mirror_angle_tolerance:
        raise input_error(src, f"the mirror does not reflect the model: body '{robot.body_name(residual.body)}' is "
                          f"{residual.position:.3g} m and {residual.angle:.3g} rad from the reflection of its partner "
                          f"(tolerance {config.mirror_tolerance:g} m, {config.mirror_angle_tolerance:g} rad)")
    planned = legs.joints
    if config.plan == "all":
        planned = planned + tuple(j for j in robot.joints if j not in legs.joints)
    held = tuple(j for j in robot.joints if j not in planned)
    height = floor.height + legs.standing_height
    qpos = robot.qpos(height=height)
    feet = {side: legs[side].foot for side in SIDES}
    torque = torque_limits(robot)
    notes = []
    missing = [j for j, t in torque.items() if t.value is None]
    if missing:
        d = robot.kinematics(qpos)
        corners = {legs[s].foot: np.vstack([footprint_points(robot.model, d, g) for g in legs[s].sole.geoms])
                   for s in SIDES}
        estimates = estimated_torque_limits(robot, qpos, corners, missing, config.torque_limit_factor)
        for j in missing:
            torque[j] = TorqueLimit(estimates[j], f"estimated: {config.torque_limit_factor:g} × the largest static "
                                    "torque it holds (no limit in the model)")
        notes.append(f"{len(missing)} joint{'s have' if len(missing) > 1 else ' has'} no torque limit in the model: "
                     f"estimated ({config.torque_limit_factor:g} × the largest static torque it holds, the weight "
                     "at a sole's corner included): give the real limits (actuatorfrcrange) and run robot init again")
    loads, torque = symmetric_loads(joint_loads(robot, qpos, feet), torque, mirror)
    integrator = INTEGRATOR_NAMES.get(int(robot.model.opt.integrator), "euler")
    if integrator == "euler":
        integrator = "implicitfast"
        notes.append("the model integrates with Euler, whose explicit servo damping limits the gains: the spec "
                     "sets implicitfast (the servos' damping integrated implicitly)")
    servo_frequency = max(math.sqrt(servo_gains(loads[j], float(torque[j].value or 0.0), config.bandwidth,
                                                 config.damping_ratio, config.tracking_error)[0] / loads[j].swing)
                          for j in robot.joints) / (2 * math.pi)
    gravity = float(np.linalg.norm(robot.model.opt.gravity))
    timestep = servo_timestep(float(robot.model.opt.timestep), servo_frequency, config.servo_steps,
                              math.sqrt(legs.leg_length / gravity), config.scale.timestep)
    gains, radius = drafted_gains(robot, loads, torque, config, qpos, timestep, integrator)
    other = robot.model.neq - len(robot.loops)
    if other:
        notes.append(f"the model has {other} equality constraint{'s' if other > 1 else ''} "
                     + ("besides its closed chains' " if robot.loops else "")
                     + "(closed linkages?): robustgait's servos drive every joint on its own; check that they agree")
    if robot.loops:
        notes.append(f"{len(robot.loops)} closed chain{'s' if len(robot.loops) > 1 else ''} ([loops]): "
                     f"{len(robot.passive)} passive joints ({sum(1 for j in robot.passive if j not in robot.solved)} "
                     "of them springs, held at their posture angle) solved from the loops in the posture, largest "
                     f"residual {max(robot.opened.values()) * 1e3:.3g} mm at the keyframe, "
                     f"{max(robot.loop_residuals().values()) * 1e3:.2g} mm in the posture; gait generation holds them "
                     "as holonomic constraints, springs rigid (docs/robots.md, \"Closed chains, springs and line "
                     "feet\")")
    if asymmetry > 0.0:
        notes.append(f"the posture was not left/right symmetric: made symmetric (largest change {asymmetry:.3g} rad)")
    if centred > 0.0:
        notes.append(f"the centre of mass stood near the soles' edge in the posture: the legs leaned by {centred:.3g} "
                     "rad at the ankles (the hips turned back as much) to bring it over the middle of the soles")
    if levelled > 0.0:
        notes.append(f"the soles were not level in the posture: each ankle turned by up to {levelled:.3g} rad to "
                     "level them")
    if under_load > 0.0:
        bent = ", ".join(f"{robot.joint_name(j)} {a:.3g}" for j, a in loaded.items())
        notes.append(f"the springs deflect under the robot's weight standing on both feet ({bent} rad; the weight "
                     "split without internal forces): each ankle turned by up to "
                     f"{under_load:.3g} rad to level the soles as it stands (robot check settles the springs so before "
                     "it checks the soles and stands the posture; the posture's springs stay rigid, as gait generation "
                     "holds them)")
    size = RobotScale(leg_length=legs.leg_length, standing_height=legs.standing_height, mass=robot.mass,
                      gravity=gravity, hip_spacing=legs.hip_spacing,
                      sole_length=legs.left.sole.length, sole_width=legs.left.sole.width, ankle_roll=legs.ankle_roll,
                      sole_spacing=legs.sole_spacing, upper_body_height=legs.upper_body_height,
                      line_feet=legs.left.sole.foot == legs.right.sole.foot == "line",
                      roll_support=not any(legs[s].sole.foot == "line" and legs[s].sole.fill is None for s in SIDES))
    if not legs.ankle_roll and not size.roll_support:
        last = robot.joint_name(legs.left.joints[-1])
        notes.append(f"the legs have no ankle roll (the left leg ends at {last}) and stand on line feet: a line foot "
                     "takes no roll moment, so neither an ankle nor the hips move the centre of pressure sideways; "
                     "the robot balances sideways by foot placement, as a point foot does (the H-LIP's stepping, "
                     "Xiong & Ames, IEEE T-RO 38(4), 2022: the step regulator, sim.regulator), its pelvis roll "
                     "bounded as exo's; step width = the soles' spacing "
                     f"{legs.sole_spacing:.4g} m (gait generate plans legs without an ankle roll parallel), not "
                     "searched, and gaits are flat-foot (multi-contact rolls the heel with an ankle roll)")
    elif not legs.ankle_roll:
        last = robot.joint_name(legs.left.joints[-1])
        notes.append(f"the legs have no ankle roll (the left leg ends at {last}): a flat stance foot cannot move the "
                     "centre of pressure sideways by itself, so the hips balance sideways (the pelvis may roll "
                     f"{hip_roll_angle(size):.3g} rad, carrying the upper body over the stance foot), both feet land "
                     f"flat only under parallel legs (step width = the soles' spacing {legs.sole_spacing:.4g} m, not "
                     "searched), and gaits are flat-foot (multi-contact rolls the heel with an ankle roll)")
    return Draft(robot=robot, config=config, name=config.name or spec_name(robot), legs=legs, floor=floor,
                 mirror=mirror, residual=residual, planned=planned, held=held, angles=angles, asymmetry=asymmetry,
                 levelled=levelled, centred=centred,
                 torque=torque, loads=loads, gains=gains, size=size, scaled=scale(size, config.scale),
                 timestep=timestep, servo_frequency=servo_frequency, integrator=integrator, radius=radius,
                 height=height, notes=notes)
