"""Does a generated gait walk? (``docs/gaitgen.md``, "The walk check"). A gait whose optimization converged and whose
physics check passed can still fall in MuJoCo — a joint-space tracking controller has no balance feedback of its
own, a narrow sole tips, and a walk whose corrections drive a joint to the end of its range falls tens of steps
later. ``gait generate`` walks it under the configured controller until the certificate's orbit rule has its answer
(the switching states settled and held their band, or did not settle — then on to ``generate.walk_unsettled``
steps, as a drift may be a slow fall), at least ``generate.walk_steps`` steps, before it calls it good; when it
falls, the walk's record gives the probable cause and what to try.
"""

from __future__ import annotations

import dataclasses
import math
import weakref
from collections.abc import Callable
from dataclasses import dataclass, field

import mujoco
import numpy as np
from numpy.typing import NDArray

from robustgait.certificate.orbit import Orbit, SettlingWatch, Status
from robustgait.certificate.search import Walked, find_orbit
from robustgait.config import Config, GaitParams
from robustgait.gait import Gait
from robustgait.gaitgen.check import PhysicsCheck
from robustgait.gaitgen.solve import GaitGenerator, GaitGenResult
from robustgait.robots import Robot
from robustgait.sim.controller import desired_outputs
from robustgait.sim.regulator_rules import placement_share, regulator_rule
from robustgait.sim.walk import SwitchEvent, WalkResult, walk

# a stance sole tilted more than this [rad] while the other foot is off the floor is tipping over an edge
TIP_ANGLE = 0.05
# a walk whose servos clamp their torque in more than this fraction of joint-steps is short of torque
SATURATION_FRACTION = 0.01
# a joint closer than this [rad] to an end of its range has reached it: the limit's constraint takes over
LIMIT_ROOM = 0.01


@dataclass
class WalkCheck:
    """Outcome of the walk check: ``steps`` asked at least, ``taken``, ``fell`` with ``fall_reason`` (engine codes),
    ``controller`` that ran; ``orbit``: the orbit rule's status and ``orbit_text`` its summary (empty when the walk
    was not watched); when it fell, ``cause`` (one clause), ``limit_joint`` (the joint whose range end it reached
    first, if that came before any tipping sole) and ``advice`` (what to try); ``speed_note``: when it did not fall
    but its speed is not the gait's planned one (:meth:`robustgait.sim.walk.WalkResult.speed_note`), that note —
    the check still passes: a march in place is a walk, and the user is told."""

    steps: int
    taken: int
    fell: bool
    fall_reason: str | None
    controller: str
    orbit: str = ""
    orbit_text: str = ""
    cause: str = ""
    limit_joint: str | None = None
    advice: list[str] = field(default_factory=list)
    speed_note: str = ""

    @property
    def passed(self) -> bool:
        return not self.fell

    def to_dict(self) -> dict[str, object]:
        return {"steps": self.steps, "taken": self.taken, "fell": self.fell, "fall_reason": self.fall_reason,
                "controller": self.controller, "orbit": self.orbit, "orbit_text": self.orbit_text,
                "cause": self.cause, "limit_joint": self.limit_joint, "advice": self.advice,
                "speed_note": self.speed_note}

    def text(self) -> str:
        """One line: what the walk did, and when it fell why and what to try."""
        if not self.fell:
            return (f"walked {self.taken} steps under {self.controller}" + (f"; {self.orbit_text}"
                                                                             if self.orbit_text else "")
                    + (f"; note: {self.speed_note}" if self.speed_note else ""))
        tries = "; ".join(self.advice)
        return (f"the gait fell in step {self.taken + 1} under {self.controller} ({self.fall_reason}): "
                f"{self.cause}" + (f"; try: {tries}" if tries else ""))


def orbit_summary(orbit: Orbit) -> str:
    """One clause on a walk's orbit for the walk check: settled and held (period, scatter σ in band coordinates), or
    not settled with the rule's reason and the certificate's verdict to expect."""
    if orbit.status == Status.OK:
        assert orbit.band is not None
        return (f"its switching states settled by step {orbit.settled} and held their band {orbit.held} steps "
                f"(period {orbit.period}, σ {orbit.band.sigma:.2g})")
    return f"its switching states did not settle, so robustgait certify will refuse it: {orbit.reason}"


def sole_tipping(robot: Robot, trajectory: NDArray[np.float64], every: int = 5
                 ) -> tuple[str, float, str, int] | None:
    """The first stance sole that tipped over an edge in a recorded walk (n, nstate): (side, tilt [rad], which edge:
    outer, inner, toe or heel, the trajectory's row), or None. A sole is the stance sole while the other is ≥ 1 cm
    higher; it tips when its tilt from the floor plane exceeds :data:`TIP_ANGLE` — a line foot (``feet``: line) when
    its pitch does, since it is free to roll about its line. The sole's axes are its
    :class:`~robustgait.robots.solebox.SoleBox`'s foot frame (a box whose x axis is its normal reads right)."""
    m = robot.model
    data = mujoco.MjData(m)
    nq = m.nq
    for row in range(0, len(trajectory), every):
        st = trajectory[row]
        data.qpos[:] = st[1:1 + nq]
        mujoco.mj_kinematics(m, data)
        z = {s: data.geom_xpos[g][2] for s, g in robot.sole_geom_id.items()}
        for side, other in (("left", "right"), ("right", "left")):
            if z[other] - z[side] < 0.01:
                continue
            # the foot frame's axes (x heel to toe, y left, z up) whichever of the sole geom's axes they are
            r = robot.sole_boxes[side].world_frame(data)
            roll, pitch = r[2, 1], r[2, 0]  # the world z axis in the foot frame: the sole's roll and pitch
            line = robot.spec.feet.get(side) == "line"
            # a line foot is free to roll about its line: only its pitch over the toe or the heel tips it
            tilt = math.asin(min(abs(pitch), 1.0)) if line else math.acos(min(max(r[2, 2], -1.0), 1.0))
            if tilt > TIP_ANGLE:
                if abs(roll) >= abs(pitch) and not line:
                    # the foot frame's y axis points to the robot's left, so a sole whose +y edge is down (roll < 0)
                    # rests on its left edge: the outer edge of a left sole, the inner edge of a right one
                    down_left = roll < 0
                    edge = "outer" if down_left == (side == "left") else "inner"
                else:
                    # pitch is the world z component of the heel-to-toe axis: below 0 the toes are down, the heel up
                    edge = "toe" if pitch < 0 else "heel"
                return side, tilt, edge, row
    return None


def tipping_text(robot: Robot, tip: tuple[str, float, str, int]) -> str:
    """What :func:`sole_tipping` found, in one phrase: the side, the edge (a line foot's toe or heel), the tilt [°] and
    the sole's width (a line foot's length)."""
    side, tilt, edge, _ = tip
    if robot.spec.feet.get(side) == "line":
        length = 2.0 * robot.sole_boxes[side].half_length
        return (f"the {side} stance foot tipped over its {edge} ({math.degrees(tilt):.0f}°; the line foot is "
                f"{length * 100:.1f} cm long)")
    return (f"the {side} stance sole tipped over its {edge} edge ({math.degrees(tilt):.0f}°; the sole is "
            f"{robot.sole_width * 100:.1f} cm wide)")


def planned_envelope(robot: Robot, gait: Gait, samples: int = 101) -> NDArray[np.float64]:
    """The least and largest angle (m, 2) [rad] each joint is planned at, over every domain of the gait and its
    mirror image (both stances), at ``samples`` phases per domain."""
    tau = np.linspace(0.0, 1.0, samples)
    ys = [desired_outputs(g, tau, d)[0] for g in (gait, gait.mirrored(robot)) for d in range(len(g.domains))]
    y = np.concatenate(ys)
    return np.stack([y.min(axis=0), y.max(axis=0)], axis=1)


def joint_at_limit(robot: Robot, trajectory: NDArray[np.float64], planned: NDArray[np.float64] | None = None
                   ) -> tuple[str, str, int] | None:
    """The first of the gait's joints to come within :data:`LIMIT_ROOM` of an end of its range in a recorded walk
    (n, nstate): (joint name, "lower" or "upper", the trajectory's row), or None. With ``planned`` (m, 2)
    (:func:`planned_envelope`), an end the plan itself reaches (by the same measure) is not counted: a knee planned
    straight rests on its stop by design. Held joints are not the gait's and may rest on a limit too."""
    lo, hi = robot.joint_range[:, 0], robot.joint_range[:, 1]
    q = trajectory[:, 1 + robot.qpos_idx]                                    # (n, m)
    low, high = q - lo < LIMIT_ROOM, hi - q < LIMIT_ROOM
    if planned is not None:
        low &= planned[:, 0] - lo >= LIMIT_ROOM
        high &= hi - planned[:, 1] >= LIMIT_ROOM
    hit = (low | high).any(axis=1)
    if not hit.any():
        return None
    row = int(np.argmax(hit))
    j = int(np.argmax(low[row] | high[row]))
    return robot.spec.joints[j], "lower" if low[row, j] else "upper", row


def step_of(result: WalkResult, time: float) -> int:
    """The step (1-based) in progress at ``time`` [s] of a walk: one more than the switching events before it."""
    return 1 + sum(1 for e in result.events if e.time < time)


def probable_cause(robot: Robot, gait: Gait, result: WalkResult, check: PhysicsCheck | None
                   ) -> tuple[str, str | None]:
    """The likeliest cause of the fall of ``gait``'s walk, from the walk's record, most specific first, and the joint
    that reached the end of its range when that is the cause (else None): whichever came first of a joint reaching an
    end of its range the plan keeps away from (:func:`joint_at_limit`) and a stance sole tipping over an edge; else
    the gait's centre of pressure on its bound, torque saturation, or the fall reason."""
    if result.trajectory is not None:
        tr = result.trajectory
        tip, limit = sole_tipping(robot, tr), joint_at_limit(robot, tr, planned_envelope(robot, gait))
        if limit is not None and (tip is None or limit[2] < tip[3]):
            name, end, row = limit
            return (f"{name} reached the {end} end of its range in step {step_of(result, float(tr[row, 0]))} "
                    "(the tracking and the step corrections have no room left there)"), name
        if tip is not None:
            return tipping_text(robot, tip), None
    if check is not None and check.on_cop_bound:
        return f"the gait's centre of pressure sits on its bound ({check.cop_text()})", None
    sat = result.tracking.get("saturation_fraction", 0.0)
    if sat > SATURATION_FRACTION:
        return f"the servos clamp their torque in {sat:.1%} of joint-steps", None
    return f"{result.fall_reason} without a tipping sole, a joint at its limit or saturation", None


def advice(robot: Robot, gait: Gait, config: Config, cause: str, share: float | None = None,
           limit_joint: str | None = None, whole_tried: bool = False) -> list[str]:
    """What to try after a fall, from the robot and the configuration; ``share``: the κ the walk's regulator ran with
    (it may have measured the walk and taken the whole gain), None: the sole's width rule's; ``limit_joint``: the
    joint whose range end the walk reached (:func:`probable_cause`); ``whole_tried``: the regulator's probe measured
    the whole gain too and kept the rule's share (the whole gain is then not advised)."""
    out = []
    if limit_joint is not None:
        margin = config.generate.for_robot(robot.scale, robot.spec.generation).scaled("joint_margin")
        more = max(2.0 * margin, config.generate.retry_joint_margin, 0.05)
        out.append(f"a gait planned further inside the joint ranges (--override generate.joint_margin={more:g}; "
                   f"now {margin:g} rad)")
    reg = config.sim.regulator
    width = robot.sole_width
    flat = len(gait.domains) == 1
    on = flat and regulator_rule(reg, width, robot.leg_length, 1)[0]
    if flat and not on:
        out.append(f"the H-LIP step regulator (--override sim.regulator.mode=on; sole/leg "
                   f"{width / robot.leg_length:.3f})")
    if share is None:
        share = placement_share(reg, width, robot.leg_length)
    if on and share < 1.0 and "tipped" in cause and not whole_tried:
        # a sole that tips is not holding the CoM through the ankle: the stepping may need all of the H-LIP's gain
        out.append(f"the H-LIP's whole stepping gain (--override sim.regulator.gain_scale=1; the sole's rule "
                   f"gives {share:.2f})")
    if "tipped" in cause or "centre of pressure" in cause:
        if on:  # under the stepping regulator the error grows over the single support: a long step tips the sole
            out.append(f"shorter, quicker steps (--step-length; --step-duration under this gait's "
                       f"{gait.step_duration:.3g} s)")
        else:
            out.append("shorter, slower steps (--step-length, --step-duration)")
        if robot.has_ankle_roll:  # without one the legs fix the width (docs/robots.md)
            out.append("a wider step (--step-width)")
    if "torque" in cause:
        out.append("a slower gait or lower servo gains ([controller] in the robot spec)")
    if not out:
        out.append("another step duration or length (--step-duration, --step-length)")
    return out


def walk_check(robot: Robot, gait: Gait, config: Config, check: PhysicsCheck | None = None) -> WalkCheck:
    """Walk ``gait`` with ``config.sim`` (its controller and regulator) from its initial state, at least
    ``config.generate.walk_steps`` steps and, with ``generate.walk_settle``, on until the orbit rule of
    ``config.certify`` has its answer (:class:`~robustgait.certificate.orbit.SettlingWatch`: at most
    ``orbit.max_steps`` + ``orbit.hold_steps`` steps) — and when that answer is ``unsettled``, on to
    ``generate.walk_unsettled`` steps (a drift may be a slow fall); when it falls, walk it again to its fall with its
    trajectory kept, and say why and what to try. A ``walk_steps`` of 0 skips the walk (a pass)."""
    least = config.generate.walk_steps
    if least == 0:
        return WalkCheck(0, 0, False, None, config.sim.controller)
    until = None
    steps = least
    if config.generate.walk_settle:
        orbit_cfg = config.certify.orbit
        steps = max(least, orbit_cfg.max_steps + orbit_cfg.hold_steps)
        watch = SettlingWatch(robot, gait.stance, config.certify)

        def until(events: list[SwitchEvent]) -> bool:
            done = watch(events)  # fed every event, whatever the least steps
            return done and len(events) >= least

    result = walk(robot, gait, config.sim, steps=steps, until=until)
    orbit = None if until is None else find_orbit(Walked(robot, gait, result), config.certify)
    on = config.generate.walk_unsettled
    if orbit is not None and orbit.status == Status.UNSETTLED and not result.fell and on > result.steps_taken:
        result = walk(robot, gait, config.sim, steps=on)  # the walk is deterministic: the same steps, then on
    out = WalkCheck(least, result.steps_taken, result.fell, result.fall_reason, result.controller,
                    speed_note=result.speed_note(config.sim.speed_agreement))
    if orbit is not None:
        out.orbit = orbit.status.value
        out.orbit_text = orbit_summary(orbit) if not result.fell else orbit.reason
    if result.fell:
        diagnosis = diagnose_fall(robot, gait, config, result.steps_taken + 1, check)
        assert diagnosis is not None  # the same walk: it falls again
        out.cause, out.limit_joint, out.advice = diagnosis
    return out


def diagnose_fall(robot: Robot, gait: Gait, config: Config, steps: int, check: PhysicsCheck | None = None
                  ) -> tuple[str, str | None, list[str]] | None:
    """Why ``gait``'s undisturbed walk under ``config.sim`` falls within ``steps`` steps: walked again (the walk is
    deterministic) with every physics step kept, its probable cause, the joint at its range's end when that is the
    cause (:func:`probable_cause`), and what to try (:func:`advice`); None when it walks them all."""
    record = walk(robot, gait, config.sim, steps=steps, keep_trajectory=True)
    if not record.fell:
        return None
    cause, joint = probable_cause(robot, gait, record, check)
    reg = record.regulator or {}
    ran = reg.get("share")
    return cause, joint, advice(robot, gait, config, cause, None if ran is None else float(ran), joint,
                                whole_tried="growth_whole" in reg)


def walk_plan(config: Config) -> str:
    """The walk check's length, in words: fixed, or from the least steps on until the orbit rule's answer."""
    least = config.generate.walk_steps
    if not config.generate.walk_settle:
        return f"{least} steps"
    o = config.certify.orbit
    on = config.generate.walk_unsettled
    return (f"at least {least} steps, on until its switching states settle and hold {o.hold_steps} steps: at most "
            f"{max(least, o.max_steps + o.hold_steps)}" + (f", or {on} if they do not settle" if on else ""))


def retry_margin(robot: Robot, config: Config, walked: WalkCheck) -> float | None:
    """The joint margin [rad] to solve the gait again with after a failed walk check, or None: the gait fell after one
    of its joints reached the end of its range (:func:`probable_cause`) and its joint margin is below
    ``generate.retry_joint_margin`` — planned further inside the ranges, the tracking and the step regulator's
    corrections have room there."""
    if not walked.fell:
        return None
    return margin_after(robot, config, walked.limit_joint)


def margin_after(robot: Robot, config: Config, limit_joint: str | None) -> float | None:
    """:func:`retry_margin`'s rule for a fall whose cause is known: ``generate.retry_joint_margin`` when a joint
    (``limit_joint``) reached the end of its range and the gait's joint margin is below it, else None."""
    if limit_joint is None:
        return None
    margin = config.generate.for_robot(robot.scale, robot.spec.generation).scaled("joint_margin")
    retry = config.generate.retry_joint_margin
    return retry if margin < retry else None


_MARGINED: weakref.WeakKeyDictionary[GaitGenerator, dict[float, GaitGenerator]] = weakref.WeakKeyDictionary()


def retry_generator(robot: Robot, config: Config, margin: float, base: GaitGenerator | None = None
                    ) -> tuple[Config, GaitGenerator]:
    """``config`` with ``generate.joint_margin`` = ``margin`` [rad], and a generator for it: built once per ``base``
    generator (a study worker's, the command's) and margin, since building costs seconds; a new one without
    ``base``."""
    again = dataclasses.replace(config, generate=dataclasses.replace(config.generate, joint_margin=margin))
    if base is None:
        return again, GaitGenerator(robot, again.generate)
    built = _MARGINED.setdefault(base, {})
    if margin not in built:
        built[margin] = GaitGenerator(robot, again.generate)
    return again, built[margin]


@dataclass
class CheckedGait:
    """What :func:`generate_walking` did: ``result``, the solve whose gait it stands by (the second after a retry);
    ``walked``, that gait's walk check (None when the solve failed); ``first``, the first gait's walk check and
    ``margin`` [rad] the joint margin of the second solve, when it solved again."""

    result: GaitGenResult
    walked: WalkCheck | None
    first: WalkCheck | None = None
    margin: float | None = None

    @property
    def passed(self) -> bool:
        return self.result.gait is not None and self.walked is not None and self.walked.passed


def generate_walking(robot: Robot, params: GaitParams, config: Config, generator: GaitGenerator, *,
                     warm: Gait | None = None, say: Callable[[str], None] | None = None) -> CheckedGait:
    """Solve ``params`` with ``generator`` (built for ``robot`` with ``config.generate``), walk-check the gait
    (:func:`walk_check`) and, when the walk fell after a joint reached an end of its range (:func:`retry_margin`),
    solve once more planned that much further inside the ranges and walk-check that gait. ``say(line)`` is told each
    stage as it starts. Never raises for a failed solve or walk: the result says so."""
    tell = say or (lambda line: None)
    res = generator.solve(params, warm)
    if res.gait is None:
        return CheckedGait(res, None)
    if config.generate.walk_steps:
        tell(f"solved; walking it in MuJoCo ({walk_plan(config)}) ...")
    walked = walk_check(robot, res.gait, config, res.check)
    margin = retry_margin(robot, config, walked)
    if margin is None:
        return CheckedGait(res, walked)
    tell(f"the walk check failed: {walked.text()}\nsolving again with {margin:g} rad between the planned joints and "
         "their range ends (generate.retry_joint_margin) ...")
    again, gen = retry_generator(robot, config, margin, generator)
    retry = gen.solve(params, warm)
    if retry.gait is None:
        return CheckedGait(retry, None, walked, margin)
    return CheckedGait(retry, walk_check(robot, retry.gait, again, retry.check), walked, margin)
