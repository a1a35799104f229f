"""The spec lines of a robot's closed chains, springs and line feet (``docs/robots.md``, "Closed chains, springs and
line feet"): ``joints.passive``, ``[loops]`` and ``[springs]``, each value commented with where it came from — the
model's equality constraints and joint stiffnesses (:mod:`robustgait.robots.loops`) and the residual of MuJoCo's
equality constraints at the keyframe and at the written posture. A serial robot gets no line of them."""

from __future__ import annotations

import mujoco

from robustgait.config.robot import LOOP_TOLERANCE
from robustgait.inspection.model import RobotModel
from robustgait.robotinit.tomltext import key as _key
from robustgait.robotinit.tomltext import text as _text
from robustgait.robots.loops import BALL


def _role(robot: RobotModel, j: int) -> str:
    """What a passive joint is: its kind, the loops it closes, its spring."""
    kind = "ball joint" if int(robot.model.jnt_type[j]) == BALL else "hinge"
    loops = [lp.key for lp in robot.loops if j in lp.joints]
    spring = next((s for s in robot.springs if s.joint == j), None)
    what = f"{kind} of loop {', '.join(loops)}"
    if spring is not None:
        return what + f"; a spring ({spring.stiffness:g} N m/rad): held at {robot.angles[j]:.4g} rad in the posture"
    if kind == "hinge":
        return what + f": solved, {robot.angles[j]:.4g} rad in the posture"
    return what + ": solved (its spin about the rod is free)"


def passive_lines(robot: RobotModel) -> list[str]:
    """``passive = [...]`` of ``[joints]``: the closed chains' joints neither planned nor held; none for a serial
    robot."""
    if not robot.passive:
        return []
    width = max(len(_text(robot.joint_name(j))) for j in robot.passive) + 1
    rows = [f"  {(_text(robot.joint_name(j)) + ','):<{width}}  # {_role(robot, j)}" for j in robot.passive]
    return ["# passive: joints of closed chains neither planned nor held (no motor drives them; a ball joint, a "
            "spring): solved from the loops (robots.loops)", "passive = [", *rows, "]"]


def loop_lines(robot: RobotModel, opened: dict[str, float]) -> list[str]:
    """``[loops]`` and ``[springs]``: each loop's equality [kind, end, end] with its joints and its residual at the
    keyframe (``opened``) and at the written posture; each passive spring's [stiffness, springref]."""
    if not robot.loops:
        return []
    now = robot.loop_residuals()
    where = f"the keyframe '{robot.keyframe}'" if robot.keyframe is not None else "the posture's first guess"
    lines = ["", "[loops]",
             "# closed kinematic chains: the model's equality constraints (MuJoCo keeps them in simulation; gait "
             "generation holds them as holonomic constraints, not converged yet); [kind, end, end]",
             f"# residual: MuJoCo's equality residual ‖r‖ at {where}, then with the passive joints solved "
             f"(springs held; tolerance {LOOP_TOLERANCE * 1e3:g} mm: robustgait.config.robot.LOOP_TOLERANCE)"]
    for lp in robot.loops:
        joints = ", ".join(robot.joint_name(j) + ("*" if j in robot.passive else "") for j in lp.joints)
        lines.append(f"{_key(lp.key)} = [{_text(lp.kind)}, {_text(lp.ends[0])}, {_text(lp.ends[1])}]  # joints "
                     f"{joints} (* passive); residual {opened[lp.key] * 1e3:.3g} mm at the keyframe, "
                     f"{now[lp.key] * 1e3:.2g} mm in the posture")
    if robot.springs:
        lines += ["", "[springs]",
                  "# passive springs, [stiffness, springref] [N m/rad, rad]: the model's joint stiffness and "
                  "springref; simulation runs them as the model does"]
        for s in robot.springs:
            lines.append(f"{_key(robot.joint_name(s.joint))} = [{s.stiffness!r}, {s.springref!r}]  # "
                         f"{_source(robot, s.joint)}")
    return lines


def _source(robot: RobotModel, j: int) -> str:
    """Where a spring's values came from: the joint's MJCF attributes."""
    m = robot.model
    name = mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_JOINT, j)
    return f"joint '{name}': stiffness, springref of the model"
