"""The spec TOML of a :class:`~robustgait.robotinit.draft.Draft` (the format of ``docs/robots.md``), every value
with a comment saying where it came from, and the summary ``robot init`` prints."""

from __future__ import annotations

import math
import os
from pathlib import Path

import mujoco
import numpy as np

from robustgait.inspection.discover import SIDES, FoundSole
from robustgait.inspection.scale import (
    GAIT_AXES,
    balance,
    capsule_line_feet,
    duration_constant,
    hips_balance,
    narrow_soles,
    sig,
)
from robustgait.robotinit.chains import loop_lines, passive_lines
from robustgait.robotinit.draft import INTEGRATOR_NAMES, Draft
from robustgait.robotinit.timestep import TimestepChoice, ms
from robustgait.robotinit.tomltext import angle, key, num, text
from robustgait.robots.sides import mass_asymmetry
from robustgait.robots.soles import GEOM_TYPES, MIN_TREAD_FILL, SOLE_PLANE_TOLERANCE, SOLE_TILT_SLOPE
from robustgait.robots.spec import FallCriteria


def _rows(items: list[tuple[str, str]], indent: str = "  ") -> list[str]:
    """Array items one per line, each with its comment, the comments aligned."""
    width = max(len(v) for v, _ in items) + 1
    return [f"{indent}{(v + ','):<{width}}  # {c}" for v, c in items]


def _range_text(draft: Draft, j: int) -> str:
    m = draft.robot.model
    if not m.jnt_limited[j]:
        return "unlimited"
    lo, hi = m.jnt_range[j]
    return f"range [{lo:.3g}, {hi:.3g}]"


def _sole_lines(draft: Draft, side: str, sole: FoundSole) -> list[str]:
    r = draft.robot
    body = r.body_name(sole.body)
    shape = f"{sole.length:.3g} × {sole.width:.3g} m"
    kinds = sorted({_geom_type(draft, g) for g in sole.geoms})
    what = f"{len(sole.geoms)} {'/'.join(kinds)} geom{'s' if len(sole.geoms) > 1 else ''} of body '{body}'"
    lines = [f"[legs.{side}]"]
    if sole.kind == "geom":
        lines.append(f"sole_geom = {text(r.geom_name(sole.geoms[0]))}  # the foot's lowest collision geom: a box, "
                     f"sole {shape}")
    elif sole.kind == "geoms":
        names = ", ".join(text(r.geom_name(g)) for g in sole.geoms)
        lines.append(f"sole_geoms = [{names}]  # the foot's lowest collision geoms ({what}): a virtual sole "
                     f"{shape}")
    else:
        lines.append(f"sole_body = {text(body)}  # the foot's lowest collision geoms are unnamed ({what}): a "
                     f"virtual sole {shape}")
        if sole.sole_class is not None:
            lines.append(f"sole_class = {text(sole.sole_class)}  # just the sole's geoms: the body's other "
                         "collision geoms are of other classes")
    if sole.foot != "flat" and sole.fill is not None:
        lines.append(f"foot = {text(sole.foot)}  # its contact polygon covers {100 * sole.fill:.0f} % of the "
                     "rectangle around it (a heel point and a toe bar cover 50 %; a flat sole at least "
                     f"{100 * MIN_TREAD_FILL:.0f} %): planned on its longest chord along the foot, "
                     f"{sole.length:.3g} m (the centre of pressure moves along the line only; lateral balance by "
                     "foot placement)")
    elif sole.foot != "flat":
        lines.append(f"foot = {text(sole.foot)}  # its ground points lie on a line {sole.length:.3g} m long: no "
                     "support width (the centre of pressure moves along the line only; lateral balance by foot "
                     "placement)")
    return lines + _tread_lines(draft, sole)


def _tread_lines(draft: Draft, sole: FoundSole) -> list[str]:
    """A comment naming a sole's meshes and how many of each one's convex-hull vertices the sole spans (none for a
    sole without meshes)."""
    if not sole.tread:
        return []
    m = draft.robot.model
    meshes = ", ".join(f"'{mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_MESH, int(m.geom_dataid[g])) or '#' + str(g)}' "
                       f"({n} vertices)" for g, n in sole.tread)
    return [f"# mesh sole: MuJoCo collides a mesh through its convex hull; the sole spans the hull vertices within "
            f"{SOLE_PLANE_TOLERANCE * 1e3:g} mm + {SOLE_TILT_SLOPE:g} × their distance of the lowest (the tread), "
            f"of {meshes}"]


def _geom_type(draft: Draft, g: int) -> str:
    return GEOM_TYPES[int(draft.robot.model.geom_type[g])]


def _header(draft: Draft, spec_path: Path) -> list[str]:
    r, legs = draft.robot, draft.legs
    rel = os.path.relpath(r.path.resolve(), spec_path.resolve().parent)
    key_text = f"keyframe '{r.keyframe}'" if r.keyframe is not None else "no keyframe: every joint at 0 (clipped)"
    lines = [
        f"# Robot spec written by `robustgait robot init {r.path.name}` (docs/robots.md, \"Your robot\").",
        "# Every value says where it came from; check the robot with `robustgait robot check` on this file.",
        f"# Model: {r.model.nbody - 1} bodies, {len(r.joints)} joints besides the base, {r.mass:.3g} kg; standing "
        f"posture: {key_text}.",
        f"# Sizes the rules scale with: leg length l = {legs.leg_length:.3g} m (first leg joint above the sole, "
        f"straight legs), standing height h = {legs.standing_height:.3g} m,",
        f"# hip spacing {legs.hip_spacing:.3g} m, sole {legs.left.sole.length:.3g} × {legs.left.sole.width:.3g} m, "
        f"g = {draft.size.gravity:.3g} m/s².",
    ]
    lines += [f"# NOTE: {n}" for n in draft.notes]
    lines += [
        f"name = {text(draft.name)}",
        f"description = {text(f'{r.mjspec.modelname or r.path.stem} ({r.path.name}), spec by robustgait robot init')}",
        f"mjcf = {text(rel)}  # the model file, relative to this spec"
        + ("; a URDF's base gets its free joint at load" if r.kind == "urdf" else ""),
        f"base_body = {text(r.base_name)}  # the body with the free joint"
        + (" (the URDF's root link)" if r.kind == "urdf" else ""),
    ]
    f = draft.floor
    if f.add:
        lines.append("add_floor = true  # the model has no plane in its world body: the loader adds robustgait_floor")
    elif f.name is not None:
        lines.append(f"floor_geom = {text(f.name)}  # the plane geom of the world body")
    else:
        lines.append("# floor: the world body's only plane, unnamed (the loader names it robustgait_floor)")
    return lines


def _joints(draft: Draft) -> list[str]:
    r, c = draft.robot, draft.config
    branch = r.body_name(draft.legs.branch)
    what = ("the two legs, from where their chains branch ('" + branch + "') down to the feet, left (y > 0) first"
            if c.plan == "legs" else "every joint: the legs first (left, then right), then the others")
    names = [(text(r.joint_name(j)), f"{_range_text(draft, j)}" + (f", {d}" if (d := _leg_of(draft, j)) else ""))
             for j in draft.planned]
    kp = [(num(draft.gains[j].kp), _kp_comment(draft, j)) for j in draft.planned]
    kd = [(num(draft.gains[j].kd), _kd_comment(draft, j)) for j in draft.planned]
    tl = [(num(draft.torque[j].value or 0.0), f"{r.joint_name(j)}: {draft.torque[j].source}") for j in draft.planned]
    return [
        "",
        "[joints]",
        f"# planned (--plan {c.plan}): {what}",
        "names = [", *_rows(names), "]",
        f"# kp = I_stance (2π × {c.bandwidth:g} Hz)², at most τ_max / {c.tracking_error:g} rad (robot.bandwidth, "
        "robot.tracking_error); I_stance: the robot's inertia about the joint with its foot welded [kg m²]",
        "kp = [", *_rows(kp), "]",
        f"# kd = 2 × {c.damping_ratio:g} × √(kp I_swing) (robot.damping_ratio); I_swing: the mass matrix's diagonal "
        f"[kg m²]; the servos contract at the {draft.timestep:g} s step ({draft.integrator}, see [sim])",
        "kd = [", *_rows(kd), "]",
        "torque_limit = [", *_rows(tl), "]",
        *passive_lines(r),
    ]


def _leg_of(draft: Draft, j: int) -> str:
    for side in SIDES:
        if j in draft.legs[side].joints:
            return f"{side} leg"
    return ""


def _kp_comment(draft: Draft, j: int) -> str:
    g, load = draft.gains[j], draft.loads[j]
    bound = {"bandwidth": "I_stance ω²", "torque": "capped: τ_max / tracking error",
             "stability": "lowered to contract at the timestep"}[g.bound]
    return f"{draft.robot.joint_name(j)}: I_stance {load.stance:.3g}, {bound}"


def _kd_comment(draft: Draft, j: int) -> str:
    g, load = draft.gains[j], draft.loads[j]
    return (f"{draft.robot.joint_name(j)}: I_swing {load.swing:.3g}, swing natural frequency {g.frequency:.3g} Hz, "
            f"ζ {g.ratio:.2g}")


def _held(draft: Draft) -> list[str]:
    if not draft.held:
        return []
    r = draft.robot
    src = f"keyframe '{r.keyframe}'" if r.keyframe is not None else "0 clipped to the range (no keyframe)"
    sym = " made left/right symmetric" if draft.asymmetry > 0 else ""
    lines = ["", "[joints.held]", f"# joints the gait does not plan, held by their servo at the posture's angle "
             f"[rad] ({src}{sym})"]
    lines += [f"{key(r.joint_name(j))} = {angle(draft.angles[j])}" for j in draft.held]
    lines += ["", "[joints.held_servo]", "# [kp, kd, torque_limit] by the rule of [joints]; the torque limit's source "
              "in the comment"]
    for j in draft.held:
        g = draft.gains[j]
        lines.append(f"{key(r.joint_name(j))} = [{num(g.kp)}, {num(g.kd)}, {num(draft.torque[j].value or 0.0)}]"
                     f"  # {draft.torque[j].source}")
    return lines


def _mirror(draft: Draft) -> list[str]:
    r, c, res = draft.robot, draft.config, draft.residual
    index = {j: i for i, j in enumerate(draft.planned)}
    perm = [index[draft.mirror.partner[j]] for j in draft.planned]
    sign = [int(draft.mirror.sign[j]) for j in draft.planned]
    lines = ["", "[mirror]",
             "# the other stance's joints: partners by left/right names and mirrored anchors, signs from the joint "
             "axes (a hinge's axis a reflects to −S a, S = diag(1, −1, 1))",
             f"# verified: forward kinematics of the relabeled configuration puts every body at its partner's "
             f"reflection over {res.samples} random configurations,",
             f"# largest residual {res.position:.2g} m and {res.angle:.2g} rad (tolerance {c.mirror_tolerance:g} m, "
             f"{c.mirror_angle_tolerance:g} rad)",
             f"joint_perm = {perm}", f"joint_sign = {sign}",
             "base_sign = [1, -1, 1, -1, 1, -1]  # (x, y, z, roll, pitch, yaw): reflection about the base's x–z plane"]
    if draft.held:
        lines += ["", "[mirror.held]", "# each held joint: [the held joint it becomes, sign] (verified as above)"]
        lines += [f"{key(r.joint_name(j))} = [{text(r.joint_name(draft.mirror.partner[j]))}, "
                  f"{int(draft.mirror.sign[j])}]" for j in draft.held]
    return lines


def _timestep_comment(draft: Draft) -> str:
    if draft.choice is not None:
        return _accuracy_comment(draft, draft.choice)
    model = float(draft.robot.model.opt.timestep)
    size, c = draft.size, draft.config
    rules = (f"at least {c.servo_steps:g} steps per period of the fastest servo ({draft.servo_frequency:.3g} Hz on "
             f"its swing inertia; robot.servo_steps) and at most {c.scale.timestep:g} × √(l/g) = "
             f"{c.scale.timestep * math.sqrt(size.leg_length / size.gravity) * 1e3:.3g} ms (robot.scale.timestep)")
    if draft.timestep >= model:
        return f"the model's <option>: {rules}"
    return f"the model's {model:g} s lowered to a nice value: {rules}"


def _accuracy_comment(draft: Draft, choice: TimestepChoice) -> str:
    """The accuracy rule's comment: the rule, the tolerance, the error at the chosen step against half of it and why
    the next larger candidate was not taken."""
    model = float(draft.robot.model.opt.timestep)
    tol = choice.tolerance
    tried = ", ".join(ms(h) for h in choice.candidates)
    text = (f"by accuracy (robot.timestep_rule): the largest of {tried} (the model's {ms(model)} and "
            f"robot.timestep_candidates) whose default gait's settled switching states, stable PD, lie "
            f"within {tol:g} band units of those at half the step (robot.timestep_tolerance)")
    chosen = choice.chosen
    if choice.passed and chosen is not None and chosen.error is not None:
        text += f": {chosen.error:.3g} against {ms(chosen.fine.timestep)}"
    else:
        text += f": NONE DOES, the smallest is written ({chosen.why_not(tol) if chosen else 'not walked'})"
    larger = choice.larger
    if larger is not None:
        text += f"; {ms(larger.timestep)} not taken: {larger.why_not(tol)}"
    if choice.excluded:
        text += (f"; not tried: {', '.join(ms(h) for h in choice.excluded)} (above the servos' stability bound: their "
                 "gains would be lowered to contract)")
    return text


def _sim(draft: Draft) -> list[str]:
    lines = [
        "", "[sim]",
        f"timestep = {num(draft.timestep)}  # " + _timestep_comment(draft),
        f"integrator = {text(draft.integrator)}  # "
        + ("the model's <option>" if INTEGRATOR_NAMES.get(int(draft.robot.model.opt.integrator)) == draft.integrator
           else "the model's is euler: implicitfast integrates the servos' damping implicitly")
        + f"; one step of all the servos on the mass matrix (base held) has spectral radius {draft.radius:.6f} "
        "(< 1: stable)",
    ]
    if draft.stable_pd:
        lines.append("stable_pd = true  # the servos' damping is kd + h kp, integrated implicitly (stable PD), as the "
                     "timestep rule walked them")
    return lines


def _scaled(draft: Draft) -> list[str]:
    s, size, rules = draft.scaled, draft.size, draft.config.scale
    rate = f"√(g/l) = {math.sqrt(size.gravity / size.leg_length):.3g}/s"

    def axis(v: tuple[float, float, float]) -> str:  # as many digits as [gait]'s: a one-value axis holds its default
        return f"[{num(v[0])}, {num(v[1])}, {num(v[2])}]"

    lines = [
        "", "[fall]",
        f"min_base_height = {num(s.fall_height, 3)}  # {rules.fall_height:g} × the standing height h (robot.scale."
        "fall_height)",
        f"max_tilt = {num(FallCriteria.max_tilt)}  # robustgait's default (an angle: no scale)",
        *_sim(draft),
        "", "[gait_quality]",
        "# angles: exo's hand-tuned bounds (an angle has no scale); rates ∝ √(g/l), heights ∝ h (robot.scale)",
        f"pelvis_roll = {num(s.pelvis_roll, 3)}  # "
        + ("exo's (robot.scale.pelvis_roll)" if size.ankle_roll else
           f"no ankle roll: atan((w/2) / h_u) = atan({size.sole_spacing / 2:.3g} / {size.upper_body_height:.3g}), the "
           "roll that carries the upper body's centre of mass over the stance foot (the hips balance sideways)"
           if hips_balance(size) else
           "exo's (robot.scale.pelvis_roll): line feet take no roll moment, so the upper body carried over the "
           "stance foot does not balance the robot sideways; the next foothold does (H-LIP stepping: Xiong & Ames, "
           "IEEE T-RO 38(4), 2022; sim.regulator)"),
        f"pelvis_yaw = {num(rules.pelvis_yaw)}  # exo's (robot.scale.pelvis_yaw)",
        f"pelvis_pitch = [{num(rules.pelvis_pitch[0])}, {num(rules.pelvis_pitch[1])}]  # exo's "
        "(robot.scale.pelvis_pitch)",
        f"pelvis_height = [{num(s.pelvis_height[0], 3)}, {num(s.pelvis_height[1], 3)}]  # "
        f"[{rules.pelvis_height[0]:g}, {rules.pelvis_height[1]:g}] × h",
        f"pelvis_angular_velocity = {num(s.angular_velocity, 3)}  # "
        + ("no ankle roll: 2π × pelvis_roll / the default step duration (the pelvis rolls over each stance foot "
           f"and back within a step), at least {rules.angular_velocity:g} × {rate}" if hips_balance(size) else
           f"{rules.angular_velocity:g} × {rate}"),
        f"swing_tilt = {num(rules.swing_tilt)}  # exo's (robot.scale.swing_tilt)",
        f"swing_yaw = {num(rules.swing_yaw)}  # exo's (robot.scale.swing_yaw)",
        f"joint_velocity = {num(s.joint_velocity, 3)}  # {rules.joint_velocity:g} × {rate}",
        "", "[action_space]",
        "# studies search this grid, [low, high, step]: [low, high] = multiples of the [gait] default, a nice step "
        "(robot.scale.action_*)" + ("; narrow soles: steps end by robot.scale.narrow_step_duration × √(l/g)"
                                    if narrow_soles(draft.size) else "")
        + ("; the default gait balances by foot placement (robot.scale.point_foot_share: its ankle does not hold "
           "the centre of mass): steps end by λT = robot.scale."
           + ("line_foot_step (capsule line feet)" if capsule_line_feet(draft.size) else "point_foot_step")
           + f", λ = √(g/z0) = {draft.balance.rate:.3g} 1/s" if draft.balance is not None else "")
        + ("; capsule line feet: swing clearances from robot.scale.line_foot_height × the default"
           if capsule_line_feet(draft.size) else "")
        + (f"; the default gait at the window's end of {' and '.join(draft.balance.ends_fail)} did not pass gait "
           "generate: that end is the default" if draft.balance is not None and draft.balance.ends_fail else ""),
        *(f"{a} = {axis(s.action_space[a])}" for a in GAIT_AXES),
    ]
    if s.multicontact_action_space is None:
        lines += ["# step_width: one value, the soles' spacing (no ankle roll); no [action_space.multicontact]: "
                  "multi-contact gaits roll the heel's edge flat with an ankle roll, which these legs lack"]
    else:
        lines += ["", "[action_space.multicontact]",
                  "# multi-contact studies (robot.scale.multicontact_*, rolling_fraction)",
                  *(f"{a} = {axis(v)}" for a, v in s.multicontact_action_space.items())]
    return lines


def _posture(draft: Draft) -> list[str]:
    r = draft.robot
    src = f"the keyframe '{r.keyframe}'" if r.keyframe is not None else "every joint at 0 clipped to its range"
    lines = ["", "[posture]", f"# cold-start posture of gait generation [rad]: {src}"
             + (" made left/right symmetric" if draft.asymmetry > 0 else "")
             + (", its ankles turned to level the soles" if draft.levelled > 0 else "")
             + (", its legs leaned at the ankles to bring the centre of mass over the soles" if draft.centred > 0
                else "")]
    lines += [f"{key(r.joint_name(j))} = {angle(draft.angles[j])}" for j in draft.planned]
    return lines


def _generation(draft: Draft) -> list[str]:
    s, size = draft.scaled, draft.size
    weight = size.mass * size.gravity
    g = s.generation
    return [
        "", "[generation]",
        "# the loader's robot-relative rules written out (config.relative_generation_defaults; docs/robots.md)",
        f"min_normal_force = {num(g['min_normal_force'], 3)}  # {g['min_normal_force'] / weight:.0%} of the weight "
        f"m g = {weight:.4g} N",
        f"min_line_force = {num(g['min_line_force'], 3)}  # {g['min_line_force'] / weight:.0%} of the weight",
        f"cop_margin = {num(g['cop_margin'], 3)}  # {_of_half_width(g['cop_margin'], size.sole_width)} the sole's "
        f"half-width {size.sole_width / 2:.3g} m",
        f"foot_gap = {num(g['foot_gap'], 3)}  # {_of_half_width(g['foot_gap'], size.sole_width)} the sole's "
        "half-width",
        *([f"joint_margin = {num(g['joint_margin'], 3)}  # narrow soles: room at each joint limit for the step "
           "regulator's corrections (robot.scale.joint_margin_narrow)"] if "joint_margin" in g else []),
    ]


def _of_half_width(value: float, width: float) -> str:
    """``k ×`` a value's multiple of a sole's half-width, or what a line foot (no width) makes of it."""
    return f"{value / (width / 2):.2g} ×" if width > 0 else "a line foot: a share of"


def _gait(draft: Draft) -> list[str]:
    s, size, rules = draft.scaled, draft.size, draft.config.scale
    t = math.sqrt(size.leg_length / size.gravity)
    c = duration_constant(size, rules)
    width_rule = (f"the hip spacing {size.hip_spacing:.3g} m" if s.gait["step_width"] == sig(size.hip_spacing)
                  else f"sole width + {rules.step_width_gap:g} × foot_gap (wider than the hips)")
    if not size.ankle_roll:
        width_rule = ("the soles' spacing in the posture: without an ankle roll both feet land flat only under "
                      "parallel legs (gait generate refuses another width)")
    return [
        "", "[gait]",
        "# the robot's default gait (what `gait generate` uses without flags), scaled with the leg length l",
        f"step_length = {num(s.gait['step_length'], 3)}  # {rules.step_length:g} × l",
        f"step_duration = {num(s.gait['step_duration'], 3)}  # {c:g} × √(l/g) = {c:g} × {t:.3g} s (flat-foot"
        + ("; line feet: robot.scale.step_duration_line" if size.line_feet
           else "; narrow soles: robot.scale.step_duration_narrow" if narrow_soles(size) else "")
        + f"; multi-contact: {rules.step_duration_multicontact:g} × √(l/g))",
        f"step_width = {num(s.gait['step_width'], 3 if size.ankle_roll else 4)}  # {width_rule}",
        f"step_height = {num(s.gait['step_height'], 3)}  # {rules.step_height:g} × l",
    ]


def render(draft: Draft, spec_path: str | Path) -> str:
    """The spec TOML (``spec_path``: where it will be written; the model's path is written relative to it)."""
    p = Path(spec_path)
    lines = [*_header(draft, p), *_joints(draft), *_held(draft)]
    for side in SIDES:
        lines += ["", *_sole_lines(draft, side, draft.legs[side].sole)]
    lines += [*_mirror(draft), *loop_lines(draft.robot, draft.robot.opened), *_scaled(draft), *_posture(draft),
              *_generation(draft), *_gait(draft)]
    return "\n".join(lines) + "\n"


def _timestep_summary(draft: Draft) -> str:
    c = draft.choice
    if c is None:
        return f"timestep {ms(draft.timestep)}: the servo rule (robot.servo_steps, robot.scale.timestep)"
    head = f"timestep {ms(draft.timestep)}, stable PD: "
    head += ("the largest candidate" if c.passed else "NO candidate") + (
        f" within {c.tolerance:g} band units of half the step (robot.timestep_tolerance); ")
    return head + "; ".join(t.describe(c.tolerance) for t in c.trials)


def summary(draft: Draft, spec_path: str | Path) -> list[str]:
    """What ``robot init`` prints: what it found and decided, one fact per line."""
    r, legs, res, c = draft.robot, draft.legs, draft.residual, draft.config
    out = [f"{r.path.name}: {len(r.joints)} joints besides the base '{r.base_name}', {r.mass:.3g} kg; posture: "
           + (f"keyframe '{r.keyframe}'" if r.keyframe else "no keyframe (joints at 0)")
           + f", standing height {legs.standing_height:.3g} m"]
    for side in SIDES:
        leg = legs[side]
        sole = leg.sole
        how = {"geom": f"box '{r.geom_name(sole.geoms[0])}'", "geoms": f"{len(sole.geoms)} named geoms",
               "body": f"{len(sole.geoms)} unnamed geoms of '{r.body_name(sole.body)}'"
               + (f" (class '{sole.sole_class}')" if sole.sole_class else "")}[sole.kind]
        out.append(f"{side} leg: {len(leg.joints)} joints {r.joint_name(leg.joints[0])} … "
                   f"{r.joint_name(leg.joints[-1])}; sole {how}, {sole.length:.3g} × {sole.width:.3g} m")
    floor = ("added (add_floor)" if draft.floor.add else f"'{draft.floor.name}'" if draft.floor.name
             else "the world's unnamed plane")
    out.append(f"floor: {floor}; planned {len(draft.planned)} joints, held {len(draft.held)}")
    sides = mass_asymmetry(r.model, r.base, draft.mirror.body_partner)
    out.append(f"mirror: verified on {res.samples} random configurations, largest residual {res.position:.2g} m, "
               f"{res.angle:.2g} rad; {sides.describe(r.model, c.side_mass_tolerance, c.side_inertia_tolerance)}")
    kp = np.array([draft.gains[j].kp for j in draft.planned])
    bounds = [draft.gains[j].bound for j in draft.planned]
    out.append(f"gains ({draft.config.bandwidth:g} Hz, ζ {draft.config.damping_ratio:g}, cap τ_max / "
               f"{draft.config.tracking_error:g} rad): kp {kp.min():.4g}–{kp.max():.4g} N m/rad; "
               f"{bounds.count('torque')} of {len(bounds)} planned joints capped by their torque limit"
               + (f", {bounds.count('stability')} lowered for stability" if "stability" in bounds else ""))
    g = draft.scaled.gait
    out.append("default gait: " + ", ".join(f"{k} {v:g}" for k, v in g.items()))
    out.append(f"balance: {balance(draft.size)[1]} for flat-foot gaits (sim.regulator)")
    out.append(_timestep_summary(draft))
    out += [f"note: {n}" for n in draft.notes]
    out.append(f"wrote {spec_path}; check it: robustgait robot check {spec_path}")
    return out
