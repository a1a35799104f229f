"""Does a generated gait walk? (``docs/gaitgen.md``, "The walk check"). A gait whose optimization converged and whose
physics check passed can still fall within a few steps in MuJoCo — a joint-space tracking controller has no balance
feedback of its own, and a narrow sole tips. ``gait generate`` walks it ``generate.walk_steps`` steps under the
configured controller before it calls it good; when it falls, the walk's record gives the probable cause and what
to try.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import mujoco
import numpy as np
from numpy.typing import NDArray

from robustgait.config import Config
from robustgait.config.regulator import placement_share, regulator_rule
from robustgait.gait import Gait
from robustgait.gaitgen.check import PhysicsCheck
from robustgait.robots import Robot
from robustgait.sim.walk import WalkResult, walk

# a stance sole tilted more than this [rad] while the other foot is off the floor is tipping over an edge
TIP_ANGLE = 0.05
# a walk whose servos clamp their torque in more than this fraction of joint-steps is short of torque
SATURATION_FRACTION = 0.01


@dataclass
class WalkCheck:
    """Outcome of the walk check: ``steps`` asked, ``taken``, ``fell`` with ``fall_reason`` (engine codes),
    ``controller`` that ran; when it fell, ``cause`` (one clause) and ``advice`` (what to try)."""

    steps: int
    taken: int
    fell: bool
    fall_reason: str | None
    controller: str
    cause: str = ""
    advice: list[str] = field(default_factory=list)

    @property
    def passed(self) -> bool:
        return not self.fell

    def to_dict(self) -> dict[str, object]:
        return {"steps": self.steps, "taken": self.taken, "fell": self.fell, "fall_reason": self.fall_reason,
                "controller": self.controller, "cause": self.cause, "advice": self.advice}

    def text(self) -> str:
        """One line: what the walk did, and when it fell why and what to try."""
        if not self.fell:
            return f"walked {self.taken} steps under {self.controller}"
        tries = "; ".join(self.advice)
        return (f"the gait fell in step {self.taken + 1} of {self.steps} under {self.controller} ({self.fall_reason}): "
                f"{self.cause}" + (f"; try: {tries}" if tries else ""))


def sole_tipping(robot: Robot, trajectory: NDArray[np.float64], every: int = 5
                 ) -> tuple[str, float, str] | None:
    """The first stance sole that tipped over an edge in a recorded walk (n, nstate): (side, tilt [rad], which edge:
    outer, inner, toe or heel), or None. A sole is the stance sole while the other is ≥ 1 cm higher; it tips when its
    tilt from the floor plane exceeds :data:`TIP_ANGLE`."""
    m = robot.model
    data = mujoco.MjData(m)
    nq = m.nq
    for st in trajectory[::every]:
        data.qpos[:] = st[1:1 + nq]
        mujoco.mj_kinematics(m, data)
        z = {s: data.geom_xpos[g][2] for s, g in robot.sole_geom_id.items()}
        for side, other in (("left", "right"), ("right", "left")):
            if z[other] - z[side] < 0.01:
                continue
            r = data.geom_xmat[robot.sole_geom_id[side]].reshape(3, 3)
            tilt = math.acos(min(max(r[2, 2], -1.0), 1.0))
            if tilt > TIP_ANGLE:
                roll, pitch = r[2, 1], r[2, 0]  # the world z axis in the sole frame: the sole's roll and pitch
                if abs(roll) >= abs(pitch):
                    # the sole's y axis points to the robot's left: a left sole rolling onto its +y edge is inward
                    down_left = roll < 0
                    edge = "inner" if down_left == (side == "left") else "outer"
                else:
                    edge = "toe" if pitch > 0 else "heel"
                return side, tilt, edge
    return None


def probable_cause(robot: Robot, result: WalkResult, check: PhysicsCheck | None) -> str:
    """The likeliest cause of a fall, from the walk's record, most specific first: a stance sole tipping over an
    edge, the gait's centre of pressure on its bound, torque saturation, else the fall reason."""
    if result.trajectory is not None:
        tip = sole_tipping(robot, result.trajectory)
        if tip is not None:
            side, tilt, edge = tip
            width = 2.0 * robot.scale.sole_half_width
            return (f"the {side} stance sole tipped over its {edge} edge ({math.degrees(tilt):.0f}°; the sole is "
                    f"{width * 100:.1f} cm wide)")
    if check is not None and check.on_cop_bound:
        return f"the gait's centre of pressure sits on its bound ({check.cop_text()})"
    sat = result.tracking.get("saturation_fraction", 0.0)
    if sat > SATURATION_FRACTION:
        return f"the servos clamp their torque in {sat:.1%} of joint-steps"
    return f"{result.fall_reason} without a tipping sole or saturation"


def advice(robot: Robot, gait: Gait, config: Config, cause: str, share: float | None = None) -> list[str]:
    """What to try after a fall, from the robot and the configuration; ``share``: the κ the walk's regulator ran with
    (it may have measured the walk and taken the whole gain), None: the sole's width rule's."""
    out = []
    reg = config.sim.regulator
    width = 2.0 * robot.scale.sole_half_width
    flat = len(gait.domains) == 1
    on = flat and regulator_rule(reg, width, robot.leg_length, 1)[0]
    if flat and not on:
        out.append(f"the H-LIP step regulator (--override sim.regulator.mode=on; sole/leg "
                   f"{width / robot.leg_length:.3f})")
    if share is None:
        share = placement_share(reg, width, robot.leg_length)
    if on and share < 1.0 and "tipped" in cause:
        # a sole that tips is not holding the CoM through the ankle: the stepping may need all of the H-LIP's gain
        out.append(f"the H-LIP's whole stepping gain (--override sim.regulator.gain_scale=1; the sole's rule "
                   f"gives {share:.2f})")
    if "tipped" in cause or "centre of pressure" in cause:
        out.append("shorter, slower steps (--step-length, --step-duration)")
        out.append("a wider step (--step-width)")
    if "torque" in cause:
        out.append("a slower gait or lower servo gains ([controller] in the robot spec)")
    if not out:
        out.append("another step duration or length (--step-duration, --step-length)")
    return out


def walk_check(robot: Robot, gait: Gait, config: Config, check: PhysicsCheck | None = None) -> WalkCheck:
    """Walk ``gait`` ``config.generate.walk_steps`` steps with ``config.sim`` (its controller and regulator) from
    its initial state; when it falls, say why and what to try. A ``walk_steps`` of 0 skips the walk (a pass)."""
    steps = config.generate.walk_steps
    if steps == 0:
        return WalkCheck(0, 0, False, None, config.sim.controller)
    result = walk(robot, gait, config.sim, steps=steps, keep_trajectory=True)
    out = WalkCheck(steps, result.steps_taken, result.fell, result.fall_reason, result.controller)
    if result.fell:
        out.cause = probable_cause(robot, result, check)
        ran = result.regulator.get("share") if result.regulator is not None else None
        out.advice = advice(robot, gait, config, out.cause, None if ran is None else float(ran))
    return out
