"""A sole box as the whole pipeline reads it (``docs/robots.md``, "Soles and floor").

Every resolved sole is one box geom (:mod:`robustgait.robots.soles`: a named box, or the virtual sole spanning a
foot's geoms). :class:`SoleBox` is the one reading of that box: which of its axes is the sole's normal, which runs
heel to toe, its half-sizes, and the points the pipeline places: the bottom face's centre, toe and heel (the gait
generator's foot frames). The gait problem's centre-of-pressure bounds, the
dynamics' foot frames, ``robot check``'s sole checks, the step regulator's sole frame and heading
(:mod:`robustgait.sim.regulator`), the walk check's tipping sole (:mod:`robustgait.gaitgen.walkcheck`) and the
defaults' sole width (:attr:`robustgait.robots.model.Robot.sole_width`) all read it from
:attr:`robustgait.robots.model.Robot.sole_boxes`: none of them assumes which of the geom's axes is which.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import mujoco
import numpy as np
from numpy.typing import NDArray

from robustgait.errors import input_error
from robustgait.robots.soles import GEOM_TYPES, LINE_HALF_WIDTH, article

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class SoleBox:
    """One sole box, in its geom's frame. ``normal``: the box axis (0, 1 or 2) across the sole, the axis closest to
    the world's vertical in the model's zero posture; ``up`` (±1): the sign of that axis pointing from the sole into
    the foot; ``long``: the axis heel to toe, the longer of the other two; ``forward`` (±1): the sign of that axis
    closest to the world's x in the zero posture; ``half_length``, ``half_width``, ``half_thickness`` [m]: the box's
    half sizes along ``long``, the third axis and ``normal``."""

    geom: int
    normal: int
    up: float
    long: int
    forward: float
    half_length: float
    half_width: float
    half_thickness: float

    @property
    def wide(self) -> int:
        """The box axis across the foot (neither the normal nor the long axis)."""
        return 3 - self.normal - self.long

    def point(self, along: float = 0.0) -> FloatArray:
        """The point (3,) of the bottom face on its long centre line, in the geom's frame [m]: its centre at
        ``along`` = 0, the toe at +1, the heel at −1 (a fraction of the half length)."""
        e = np.eye(3)
        return np.asarray(-self.up * self.half_thickness * e[self.normal]
                          + along * self.forward * self.half_length * e[self.long])

    def frame_rotation(self) -> FloatArray:
        """The foot frame's axes in the geom's frame (3, 3; columns): x heel to toe, z the sole's normal into the
        foot, y = z × x (the foot's left)."""
        e = np.eye(3)
        x_axis, z_axis = self.forward * e[self.long], self.up * e[self.normal]
        return np.column_stack([x_axis, np.cross(z_axis, x_axis), z_axis])

    def world_frame(self, data: mujoco.MjData) -> FloatArray:
        """The foot frame's axes in the world (3, 3; columns: x heel to toe, y the foot's left, z the sole's normal
        into the foot) at the kinematics of ``data``: the geom's rotation times :meth:`frame_rotation`. A vector's
        components in the foot frame are ``world_frame(data).T @ v``."""
        return np.asarray(data.geom_xmat[self.geom].reshape(3, 3) @ self.frame_rotation())

    def heading(self, data: mujoco.MjData) -> float:
        """ψ [rad], the yaw of the sole's heel-to-toe axis at the kinematics of ``data``: atan2 of that axis's world y
        and x components. Meaningless (whatever atan2 gives) for a sole standing on its toe or heel, whose axis is
        vertical."""
        toe = data.geom_xmat[self.geom].reshape(3, 3)[:, self.long] * self.forward
        return math.atan2(float(toe[1]), float(toe[0]))

    def bottom_centre(self, data: mujoco.MjData) -> FloatArray:
        """The bottom face's centre (3,) in the world [m], at the kinematics of ``data``."""
        rot = data.geom_xmat[self.geom].reshape(3, 3)
        return np.asarray(data.geom_xpos[self.geom] + rot @ self.point())

    def tilt(self, data: mujoco.MjData) -> float:
        """The angle [rad] between the sole's normal and the world's vertical at the kinematics of ``data``."""
        rot = data.geom_xmat[self.geom].reshape(3, 3)
        return float(np.arccos(min(1.0, abs(float(rot[2, self.normal])))))


def box_up(rot: FloatArray) -> tuple[int, float]:
    """The axis of a box whose rotation is ``rot`` (3, 3; its axes in the world, columns) closest to the world's
    vertical — the normal of the face it stands on — and the sign (±1) that turns that axis up."""
    normal = int(np.argmax(np.abs(rot[2])))
    return normal, 1.0 if rot[2, normal] > 0 else -1.0


def sole_box(model: mujoco.MjModel, geom: int, source: str | Path | None = None) -> SoleBox:
    """The :class:`SoleBox` of box geom ``geom`` of ``model``, its axes read in the model's zero posture (where
    ``robot init`` levels the soles). A geom that is not a box is an input error naming ``source`` (the robot's
    file) and the geom."""
    kind = GEOM_TYPES[int(model.geom_type[geom])]
    if kind != "box":
        raise input_error(source, f"the sole geom '{model.geom(geom).name}' is {article(kind)} {kind}: the foot "
                          "frames are placed on a box")
    d = mujoco.MjData(model)
    mujoco.mj_kinematics(model, d)
    rot = d.geom_xmat[geom].reshape(3, 3)  # the geom's axes in the world (columns)
    size = np.asarray(model.geom_size[geom], dtype=float)
    if float(size[1]) <= LINE_HALF_WIDTH < float(size[0]):
        # a line foot's virtual sole (robots.soles.resolve_sole): read as built — x the line toward the toe, y its
        # no width, z up — whatever the zero posture does to the foot (a capsule is round about its line)
        return SoleBox(geom=int(geom), normal=2, up=1.0, long=0, forward=1.0, half_length=float(size[0]),
                       half_width=float(size[1]), half_thickness=float(size[2]))
    normal, up = box_up(rot)
    long = max((k for k in range(3) if k != normal), key=lambda k: float(size[k]))
    wide = 3 - normal - long
    return SoleBox(geom=int(geom), normal=normal, up=up, long=long,
                   forward=1.0 if rot[0, long] >= 0 else -1.0, half_length=float(size[long]),
                   half_width=float(size[wide]), half_thickness=float(size[normal]))
