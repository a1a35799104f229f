"""A robot's closed chains in the planning model (``docs/robots.md``, "Closed chains, springs and line feet"; the
gait problem's loop rows, ``docs/gaitgen.md``, "Closed chains").

The gait problem holds each loop of the robot's model (:func:`robustgait.robots.loops.closed_chains`) as a holonomic
constraint φ(s) = 0 on the joints s = (planned, passive hinges) of adam's model — FROST's way — with its force J_hᵀ λ_h
in the equations of motion. φ depends on the joints only: each row is a relative position or distance inside the leg,
so it does not move with the base, and its force has no base component.

* **A rod on a ball joint** (a leaf body whose one ball joint lies in a ``connect`` loop: Cassie's achilles rod) is a
  two-force member: the planning model drops it and keeps a *distance* row (|p_a − p_b|² − L²) / (2 L) = 0 between the
  ball's centre p_a (on the rod's parent) and the connect's anchor p_b on the other end, L the rod's length from its
  ball to its anchor. Its mass is lumped onto the two ends in the ratio that keeps its centre of mass (a point mass at
  each end); its rotational inertia is dropped. adam-robotics cannot take the ball joint (its MuJoCo factory skips ball
  joints and then finds the rod a second root), and the rod's spin about its own axis moves nothing.
* **Any other connect** (Cassie's plantar rod on its foot crank): the anchors' offset in the frame of the loop's lowest
  common ancestor body, R_ancᵀ (p_a − p_b), its independent directions only (the left singular vectors of its
  Jacobian at the posture: a planar loop keeps 2 of 3). In that frame the directions do not change with the motion.
* **A spring** (a passive joint with a stiffness) is rigid: s_j − springref = 0. The row's force is the spring's
  torque a compliant model would need (its deflection λ / k).

``weld`` and ``joint`` equalities with passive joints are not planned (one-line error naming the equality).
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np
from numpy.typing import NDArray

from robustgait.errors import RobustGaitError
from robustgait.robots.loops import BALL, Loop, closed_chains, find_springs

FloatArray = NDArray[np.float64]
POINT_INERTIA = 1e-9  # [kg m²] the diagonal inertia given to a lumped point mass (MuJoCo needs one)


@dataclass(frozen=True)
class PlanLoop:
    """One holonomic row set of the planning model: ``kind`` ``distance`` (a rod on a ball joint, 1 row), ``connect``
    (the independent directions of an anchor offset, up to 3 rows) or ``spring`` (1 row). ``frames``: the adam frames
    of its two anchors; ``ancestor``: the body in whose frame a connect's offset is taken; ``length``: a distance
    row's L [m]; ``joint``, ``ref``: a spring's joint name and springref [rad or m]."""

    key: str
    kind: str
    frames: tuple[str, str] = ("", "")
    ancestor: str = ""
    length: float = 0.0
    joint: str = ""
    ref: float = 0.0


def anchor_frame(key: str, end: str) -> str:
    """The adam frame (a massless body) at an anchor of loop ``key``: ``robustgait_loop_<key>_<end>``."""
    return f"robustgait_loop_{key}_{end}"


def _name(model: mujoco.MjModel, body: int) -> str:
    return str(model.body(body).name)


def _anchors(model: mujoco.MjModel, e: int) -> tuple[tuple[int, FloatArray], tuple[int, FloatArray]]:
    """The two anchors of connect equality ``e``: (body id, point in the body's frame) each (MuJoCo's ``eq_data``:
    the anchor on body 1, then on body 2; a site's own position for a connect of two sites)."""
    a, b = int(model.eq_obj1id[e]), int(model.eq_obj2id[e])
    if int(model.eq_objtype[e]) == int(mujoco.mjtObj.mjOBJ_SITE):
        return ((int(model.site_bodyid[a]), model.site_pos[a].copy()),
                (int(model.site_bodyid[b]), model.site_pos[b].copy()))
    return (a, np.array(model.eq_data[e][0:3])), (b, np.array(model.eq_data[e][3:6]))


def _lowest_common_ancestor(model: mujoco.MjModel, a: int, b: int) -> int:
    up = [a]
    while up[-1] != 0:
        up.append(int(model.body_parentid[up[-1]]))
    x = b
    while x not in up:
        x = int(model.body_parentid[x])
    return x


def _rod(model: mujoco.MjModel, loop: Loop) -> tuple[int, int] | None:
    """(index 0 or 1 of the rod end, the rod body) when one end of a connect loop is a leaf body on one ball joint of
    the loop; None otherwise."""
    if loop.kind != "connect":
        return None
    ends = _anchors(model, loop.equality)
    parents = {int(model.body_parentid[x]) for x in range(1, model.nbody)}
    for k, (body, _) in enumerate(ends):
        j = int(model.body_jntadr[body])
        if (int(model.body_jntnum[body]) == 1 and int(model.jnt_type[j]) == BALL and j in loop.joints
                and body not in parents):
            return k, body
    return None


def _add_point(mjs: mujoco.MjSpec, parent: str, name: str, pos: FloatArray, mass: float) -> None:
    """A jointless child body of ``parent`` at ``pos`` (its frame): a frame for adam when massless, else a point
    mass welded to the parent."""
    body = mjs.body(parent).add_body(name=name, pos=pos)
    if mass > 0.0:
        body.mass = mass
        body.inertia = [POINT_INERTIA] * 3
        body.explicitinertial = True


def plan_loops(mjs: mujoco.MjSpec, model: mujoco.MjModel, source: object) -> tuple[list[PlanLoop], tuple[int, ...]]:
    """Edit ``mjs`` (the robot's spec, compiled as ``model``) into the planning model of the module docstring — rods on
    ball joints and their equalities removed, their masses lumped, a frame body at every anchor — and return the loops'
    rows (:class:`PlanLoop`, model order, springs last) and the passive joints (ids in ``model``) that stay coordinates
    (the hinges and slides). Raises RobustGaitError (naming ``source``) for an equality the planning model cannot
    hold."""
    loops, passive = closed_chains(model)
    out, removed = [], []
    for loop in loops:
        ends = _anchors(model, loop.equality) if loop.kind == "connect" else None
        if ends is None:
            raise RobustGaitError(f"{source}: {loop.describe()}: gait generation plans connect equalities only, not "
                                  f"{loop.kind} (docs/robots.md, \"Closed chains, springs and line feet\")")
        rod = _rod(model, loop)
        if rod is not None:
            k, body = rod
            (_, rod_anchor), (other, other_anchor) = ends[k], ends[1 - k]
            parent = int(model.body_parentid[body])
            j = int(model.body_jntadr[body])
            centre_rod = model.jnt_pos[j]
            R = np.zeros(9)
            mujoco.mju_quat2Mat(R, model.body_quat[body])
            centre = model.body_pos[body] + R.reshape(3, 3) @ centre_rod  # the ball's centre in the parent's frame
            axis = rod_anchor - centre_rod
            length = float(np.linalg.norm(axis))
            share = float(np.clip(np.dot(model.body_ipos[body] - centre_rod, axis) / length**2, 0.0, 1.0))
            mass = float(model.body_mass[body])
            names = (anchor_frame(loop.key, "a"), anchor_frame(loop.key, "b"))
            _add_point(mjs, _name(model, parent), names[0], centre, 0.0)
            _add_point(mjs, _name(model, other), names[1], other_anchor, 0.0)
            _add_point(mjs, _name(model, parent), names[0] + "_mass", centre, (1.0 - share) * mass)
            _add_point(mjs, _name(model, other), names[1] + "_mass", other_anchor, share * mass)
            removed.append((loop.equality, _name(model, body)))
            out.append(PlanLoop(loop.key, "distance", names, length=length))
            continue
        (a, pa), (b, pb) = ends
        names = (anchor_frame(loop.key, "a"), anchor_frame(loop.key, "b"))
        _add_point(mjs, _name(model, a), names[0], pa, 0.0)
        _add_point(mjs, _name(model, b), names[1], pb, 0.0)
        out.append(PlanLoop(loop.key, "connect", names, ancestor=_name(model, _lowest_common_ancestor(model, a, b))))
    equalities = list(mjs.equalities)
    for e, rod_name in removed:
        mjs.delete(equalities[e])
        mjs.delete(mjs.body(rod_name))
    for sp in find_springs(model, passive):
        out.append(PlanLoop(str(model.joint(sp.joint).name), "spring", joint=str(model.joint(sp.joint).name),
                            ref=sp.springref))
    hinges = tuple(j for j in passive if int(model.jnt_type[j]) != BALL)
    return out, hinges
