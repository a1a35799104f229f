"""Closed kinematic chains and compliant joints of a robot's model (``docs/robots.md``, "Closed chains, springs and
line feet").

A *loop* is an active equality constraint of the model — ``connect`` (a point of one body on a point of another),
``weld`` (a body's pose on another's) or ``joint`` (a joint's angle a polynomial of another's) — that closes a cycle
through the kinematic tree: Cassie's achilles rod (a ball joint on the thigh) connected to the heel spring on the
tarsus, its plantar rod connected to the foot. The loop's joints are those of the bodies between each end and the two
ends' lowest common ancestor (for a ``joint`` equality, its two joints).

A joint of a loop is *passive* — neither planned nor held, its coordinate solved from the loop — when it is a ball
joint, or no actuator of the model drives it while one drives another joint of the loop (Cassie's tarsus, shin and
heel springs, foot crank and plantar rod), or no actuator drives it and nothing below it collides (a rod or crank of
a linkage). A spring (a joint with stiffness) is passive by the same rule; the posture holds it at its angle (rigid)
and simulation runs it as the model does.

:func:`close_loops` solves the passive joints (springs held) so that MuJoCo's own equality residuals vanish;
:func:`undriven_motion` says whether the planned joints fix the passive ones, up to a rod spinning about its own axis
on its ball joint (a motion that moves no other body).
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np
from numpy.typing import NDArray

from robustgait.errors import input_error
from robustgait.robots.legs import subtree
from robustgait.robots.soles import collides
from robustgait.robots.spec import RobotSpec

FloatArray = NDArray[np.float64]
BALL = int(mujoco.mjtJoint.mjJNT_BALL)
FREE = int(mujoco.mjtJoint.mjJNT_FREE)
HINGE = int(mujoco.mjtJoint.mjJNT_HINGE)
QPOS_SIZE, DOF_SIZE = {FREE: 7, BALL: 4}, {FREE: 6, BALL: 3}  # other joints: 1
LOOP_KINDS = {int(mujoco.mjtEq.mjEQ_CONNECT): "connect", int(mujoco.mjtEq.mjEQ_WELD): "weld",
              int(mujoco.mjtEq.mjEQ_JOINT): "joint"}
# Gauss-Newton iterations of :func:`close_loops`; a singular value below this fraction of the largest is a null motion
CLOSE_ITERATIONS, NULL_FRACTION = 200, 1e-8
LOOP_CLOSE_TOLERANCE = 1e-8  # [m] the residual to which :func:`complete_rods` closes the rods' loops (/100 inside)
MAX_STEP = 0.2  # [rad or m]: the largest change of a degree of freedom in one Gauss-Newton step of close_loops


@dataclass(frozen=True)
class Loop:
    """A closed chain: equality ``equality`` of the model (``key``: its name, or ``equality_{id}`` when unnamed),
    of ``kind`` connect, weld or joint, tying ``ends`` (two body names, or joint names for ``joint``); ``joints``: the
    joint ids on its cycle."""

    equality: int
    key: str
    kind: str
    ends: tuple[str, str]
    joints: tuple[int, ...]

    def describe(self) -> str:
        """``equality 'key' (connect of 'a' to 'b')``, for messages and comments."""
        return f"equality '{self.key}' ({self.kind} of '{self.ends[0]}' to '{self.ends[1]}')"


@dataclass(frozen=True)
class Spring:
    """A compliant joint: ``joint`` (id) with ``stiffness`` [N m/rad or N/m] about ``springref`` [rad or m], the
    model's ``stiffness`` and ``springref``."""

    joint: int
    stiffness: float
    springref: float


def _name(model: mujoco.MjModel, obj: mujoco.mjtObj, i: int, what: str) -> str:
    return str(mujoco.mj_id2name(model, obj, i) or f"{what} {i}")


def _path_up(model: mujoco.MjModel, body: int) -> list[int]:
    """``body`` and its ancestors, nearest first, down to the world body (0) included."""
    out = [body]
    while out[-1] != 0:
        out.append(int(model.body_parentid[out[-1]]))
    return out


def cycle_joints(model: mujoco.MjModel, a: int, b: int) -> tuple[int, ...]:
    """The joints (ids, ascending) of the bodies on the tree's path from body ``a`` to body ``b`` (3,), their lowest
    common ancestor's own joints excluded: the joints that move ``a`` relative to ``b``."""
    up_a, up_b = _path_up(model, a), _path_up(model, b)
    common = next(x for x in up_a if x in up_b)
    bodies = up_a[:up_a.index(common)] + up_b[:up_b.index(common)]
    return tuple(sorted(int(model.body_jntadr[x]) + k for x in bodies for k in range(int(model.body_jntnum[x]))))


def find_loops(model: mujoco.MjModel) -> tuple[Loop, ...]:
    """Every active connect, weld and joint equality of ``model`` that closes a cycle (module docstring), in model
    order. Other kinds (tendon, flex, distance) are not read."""
    out = []
    for e in range(model.neq):
        kind = LOOP_KINDS.get(int(model.eq_type[e]))
        if kind is None or not model.eq_active0[e]:
            continue
        a, b = int(model.eq_obj1id[e]), int(model.eq_obj2id[e])
        if int(model.eq_objtype[e]) == int(mujoco.mjtObj.mjOBJ_SITE):  # a connect or weld of two sites: their bodies
            a, b = int(model.site_bodyid[a]), int(model.site_bodyid[b])
        key = str(mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_EQUALITY, e) or f"equality_{e}")
        if kind == "joint":
            joints = tuple(sorted(x for x in (a, b) if x >= 0))
            ends = tuple(_name(model, mujoco.mjtObj.mjOBJ_JOINT, x, "joint") for x in (a, b) if x >= 0)
            ends = (ends[0], ends[-1])
        else:
            joints = cycle_joints(model, a, b)
            body = mujoco.mjtObj.mjOBJ_BODY
            ends = (_name(model, body, a, "body"), _name(model, body, b, "body"))
        joints = tuple(j for j in joints if int(model.jnt_type[j]) != FREE)
        if joints:
            out.append(Loop(e, key, kind, (ends[0], ends[1]), joints))
    return tuple(out)


def driven_joints(model: mujoco.MjModel) -> frozenset[int]:
    """The joints an actuator of ``model`` drives directly (transmission ``joint``)."""
    return frozenset(int(model.actuator_trnid[a][0]) for a in range(model.nu)
                     if int(model.actuator_trntype[a]) == int(mujoco.mjtTrn.mjTRN_JOINT))


def _collides_below(model: mujoco.MjModel, joint: int) -> bool:
    """Whether a geom of the joint's body or of any body below it takes part in contacts."""
    bodies = set(subtree(model, int(model.jnt_bodyid[joint])))
    return any(collides(model, g) for g in range(model.ngeom) if int(model.geom_bodyid[g]) in bodies)


def passive_joints(model: mujoco.MjModel, loops: tuple[Loop, ...]) -> tuple[int, ...]:
    """The joints of ``loops`` that are neither planned nor held (module docstring), ascending."""
    driven = driven_joints(model)
    out = set()
    for loop in loops:
        loop_driven = any(j in driven for j in loop.joints)
        for j in loop.joints:
            if int(model.jnt_type[j]) == BALL or (j not in driven and (loop_driven or not _collides_below(model, j))):
                out.add(j)
    return tuple(sorted(out))


def find_springs(model: mujoco.MjModel, joints: tuple[int, ...] | None = None) -> tuple[Spring, ...]:
    """The hinge and slide joints of ``model`` (of ``joints`` when given) with a stiffness: the model's
    ``stiffness`` and ``springref`` (``qpos_spring``)."""
    ids = range(model.njnt) if joints is None else joints
    return tuple(Spring(j, float(model.jnt_stiffness[j]), float(model.qpos_spring[model.jnt_qposadr[j]]))
                 for j in ids if int(model.jnt_type[j]) not in (BALL, FREE) and model.jnt_stiffness[j] > 0)


def joint_dofs(model: mujoco.MjModel, joints: tuple[int, ...]) -> tuple[int, ...]:
    """The degrees of freedom (ids, in joint order) of ``joints``: 3 for a ball joint, 1 for a hinge or slide."""
    return tuple(int(model.jnt_dofadr[j]) + k for j in joints for k in range(DOF_SIZE.get(int(model.jnt_type[j]), 1)))


def closed_chains(model: mujoco.MjModel) -> tuple[tuple[Loop, ...], tuple[int, ...]]:
    """The loops of ``model`` that have a passive joint (:func:`find_loops`, :func:`passive_joints`) and those
    passive joints. An equality between joints that are all planned or held (two elbows coupled) is not one: the
    servos drive each of its joints and MuJoCo keeps it."""
    loops = find_loops(model)
    passive = passive_joints(model, loops)
    return tuple(lp for lp in loops if any(j in passive for j in lp.joints)), passive


def check_closed_chains(model: mujoco.MjModel, spec: RobotSpec) -> tuple[int, ...]:
    """The passive joints (ids) of ``model`` (:func:`closed_chains`), once the spec's ``joints.passive``, ``[loops]``
    and ``[springs]`` say what the model has: the same passive joints, loops (kind and ends) and springs (stiffness and
    springref within 1e-9). Raises RobustGaitError naming the first difference."""
    src = spec.source or spec.mjcf
    loops, passive = closed_chains(model)

    def name(j: int) -> str:
        return str(mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_JOINT, j) or f"joint {j}")

    found = {name(j) for j in passive}
    if found != set(spec.passive):
        missing, extra = sorted(found - set(spec.passive)), sorted(set(spec.passive) - found)
        raise input_error(src, "joints.passive: " + "; ".join(
            ([f"the model's closed chains leave {', '.join(repr(x) for x in missing)} passive (neither planned nor "
              "held): list them"] if missing else [])
            + ([f"{', '.join(repr(x) for x in extra)} not a passive joint of a closed chain of the model"]
               if extra else [])))
    have = {lp.key: (lp.kind, *lp.ends) for lp in loops}
    for key, value in spec.loops.items():
        if have.get(key) != tuple(value):
            raise input_error(src, f"loops.{key}: the model has {have.get(key) or 'no such closed chain'}, the spec "
                              f"says {list(value)}")
    if set(have) - set(spec.loops):
        raise input_error(src, f"loops: the model's closed chain {sorted(set(have) - set(spec.loops))[0]!r} is not in "
                          "the spec")
    springs = {name(sp.joint): (sp.stiffness, sp.springref) for sp in find_springs(model, passive)}
    for joint, (k, ref) in {**{j: (np.nan, np.nan) for j in springs}, **spec.springs}.items():
        if joint not in springs or not np.allclose((k, ref), springs[joint], rtol=1e-9, atol=1e-12):
            raise input_error(src, f"springs.{joint}: the model's passive spring is {springs.get(joint) or 'none'}, "
                              f"the spec says {[k, ref]} ([stiffness, springref])")
    return passive


def loop_rows(model: mujoco.MjModel, data: mujoco.MjData, loops: tuple[Loop, ...]
              ) -> tuple[FloatArray, FloatArray]:
    """MuJoCo's own residual r (k,) and Jacobian ∂r/∂v (k, nv) of the equality constraints of ``loops`` at the
    configuration of ``data``, after ``mj_fwdPosition``: connect r = p₁ − p₂ (the two anchors, world, 3 rows), weld
    the pose error (6 rows), joint q₁ − Σ cᵢ q₂ⁱ (1 row) (MuJoCo documentation, "Equality")."""
    mujoco.mj_fwdPosition(model, data)
    ids = {loop.equality for loop in loops}
    rows = [i for i in range(data.nefc) if int(data.efc_type[i]) == int(mujoco.mjtConstraint.mjCNSTR_EQUALITY)
            and int(data.efc_id[i]) in ids]
    if mujoco.mj_isSparse(model):
        dense = np.zeros((data.nefc, model.nv))
        mujoco.mju_sparse2dense(dense, data.efc_J, data.efc_J_rownnz, data.efc_J_rowadr, data.efc_J_colind)
    else:
        dense = np.asarray(data.efc_J).reshape(data.nefc, model.nv)
    return np.asarray(data.efc_pos[rows], dtype=float), np.asarray(dense[rows], dtype=float)


def loop_residuals(model: mujoco.MjModel, qpos: FloatArray, loops: tuple[Loop, ...]) -> dict[str, float]:
    """Each loop's residual at ``qpos`` (nq,): the norm of its rows of :func:`loop_rows` [m, or rad for a joint
    equality], by loop key."""
    data = mujoco.MjData(model)
    data.qpos[:] = qpos
    out = {}
    for loop in loops:
        r, _ = loop_rows(model, data, (loop,))
        out[loop.key] = float(np.linalg.norm(r))
    return out


def close_loops(model: mujoco.MjModel, qpos: FloatArray, loops: tuple[Loop, ...], solved: tuple[int, ...],
                tolerance: float) -> FloatArray:
    """``qpos`` (nq,) with the joints ``solved`` moved so that the loops close: Gauss-Newton on r(q) of
    :func:`loop_rows`, Δv = −J_s⁺ r over the solved degrees of freedom s (the least-norm step: a rod's spin about its
    own axis, a null motion, stays as it is), integrated on the configuration manifold (``mj_integratePos``: a ball
    joint's quaternion stays unit). Stops when ‖r‖∞ ≤ ``tolerance`` / 100 [m] or after :data:`CLOSE_ITERATIONS`;
    the caller reads what is left (:func:`loop_residuals`)."""
    data = mujoco.MjData(model)
    q = np.array(qpos, dtype=float)
    dofs = list(joint_dofs(model, solved))
    if not loops or not dofs:
        return q
    for _ in range(CLOSE_ITERATIONS):
        data.qpos[:] = q
        r, jac = loop_rows(model, data, loops)
        if r.size == 0 or float(np.abs(r).max()) <= tolerance / 100.0:
            break
        step = np.zeros(model.nv)
        step[dofs] = -np.linalg.lstsq(jac[:, dofs], r, rcond=None)[0]
        largest = float(np.abs(step).max())
        if largest > MAX_STEP:  # far from closing (a start at qpos0): damped, so that it stays on the nearest branch
            step *= MAX_STEP / largest
        mujoco.mj_integratePos(model, q, step, 1.0)
    for j in solved:  # an unlimited hinge's angle, which may have wound round, back in (−π, π]
        if int(model.jnt_type[j]) == HINGE and not model.jnt_limited[j]:
            adr = int(model.jnt_qposadr[j])
            q[adr] = float(np.angle(np.exp(1j * q[adr])))
    return q


def _leaf_ball_spins(model: mujoco.MjModel, jac: FloatArray, solved: tuple[int, ...]) -> int:
    """How many null motions of the solved joints are a leaf body (no child) spinning on its ball joint: per such
    ball joint, the nullity of the loop Jacobian ``jac`` (k, nv) restricted to its three degrees of freedom."""
    count = 0
    children = {int(model.body_parentid[b]) for b in range(1, model.nbody)}
    for j in solved:
        if int(model.jnt_type[j]) != BALL or int(model.jnt_bodyid[j]) in children:
            continue
        sub = jac[:, list(joint_dofs(model, (j,)))]
        sv = np.linalg.svd(sub, compute_uv=False)
        count += int(3 - np.sum(sv > NULL_FRACTION * max(float(sv.max(initial=0.0)), 1e-12)))
    return count


def undriven_motion(model: mujoco.MjModel, qpos: FloatArray, loops: tuple[Loop, ...], solved: tuple[int, ...]
                    ) -> int | None:
    """A joint (id) of ``solved`` that the loops leave free to move with every other joint fixed — the null space of
    the loop Jacobian over the solved degrees of freedom is larger than the leaf rods' spins on their ball joints
    (:func:`_leaf_ball_spins`) — the joint with the largest share of such a motion; None when the loops fix them."""
    if not loops or not solved:
        return None
    data = mujoco.MjData(model)
    data.qpos[:] = qpos
    _, jac = loop_rows(model, data, loops)
    dofs = list(joint_dofs(model, solved))
    sub = jac[:, dofs]
    _, sv, vt = np.linalg.svd(sub, full_matrices=True)
    rank = int(np.sum(sv > NULL_FRACTION * max(float(sv.max(initial=0.0)), 1e-12)))
    null = vt[rank:]
    if len(null) <= _leaf_ball_spins(model, jac, solved):
        return None
    # the null motion least like a spin: the one with the largest share outside the leaf balls' degrees of freedom
    owner = [int(model.dof_jntid[d]) for d in dofs]
    leaf = [i for i, j in enumerate(owner) if int(model.jnt_type[j]) == BALL]
    weight = null.copy()
    weight[:, leaf] = 0.0
    k = int(np.argmax(np.abs(weight).max(axis=1)))
    return owner[int(np.argmax(np.abs(weight[k])))]


def complete_rods(model: mujoco.MjModel, qpos: FloatArray, qvel: FloatArray) -> tuple[FloatArray, FloatArray]:
    """``qpos`` (nq,), ``qvel`` (nv,) with the ball joints of the model's closed chains solved from every other joint:
    positions by :func:`close_loops` from the model's ``qpos0`` quaternion (springs and hinges as given), velocities
    the least-norm v_b with J_b v_b = −J_rest v_rest on the loops' rows (:func:`loop_rows`; a rod's spin stays 0). A
    model without ball joints in loops is returned as given."""
    loops, passive = closed_chains(model)
    balls = tuple(j for j in passive if int(model.jnt_type[j]) == BALL)
    if not balls:
        return qpos, qvel
    q, v = np.array(qpos, dtype=float), np.array(qvel, dtype=float)
    for j in balls:
        adr = int(model.jnt_qposadr[j])
        q[adr:adr + 4] = model.qpos0[adr:adr + 4]
    q = close_loops(model, q, loops, balls, LOOP_CLOSE_TOLERANCE)
    data = mujoco.MjData(model)
    data.qpos[:] = q
    _, jac = loop_rows(model, data, loops)
    dofs = list(joint_dofs(model, balls))
    v[dofs] = 0.0
    v[dofs] = -np.linalg.lstsq(jac[:, dofs], jac @ v, rcond=None)[0]
    return q, v


def passive_addresses(model: mujoco.MjModel, passive: tuple[int, ...]) -> tuple[list[int], list[int]]:
    """The qpos and qvel addresses of the joints ``passive`` (4 and 3 for a ball joint, 1 and 1 for a hinge)."""
    qadr = [int(model.jnt_qposadr[j]) + k for j in passive for k in range(4 if int(model.jnt_type[j]) == BALL else 1)]
    return qadr, list(joint_dofs(model, passive))


def reduced_state(model: mujoco.MjModel, passive: tuple[int, ...], qpos: FloatArray, qvel: FloatArray
                  ) -> tuple[FloatArray, FloatArray]:
    """A state of ``model`` (..., nq), (..., nv) without the coordinates of its ``passive`` joints: the base, planned
    and held joints in model order (a gait file's state). A model without passive joints is returned as given."""
    qadr, vadr = passive_addresses(model, passive)
    return (np.delete(np.asarray(qpos, dtype=float), qadr, axis=-1),
            np.delete(np.asarray(qvel, dtype=float), vadr, axis=-1))


def padded_state(model: mujoco.MjModel, passive: tuple[int, ...], qpos: FloatArray, qvel: FloatArray
                 ) -> tuple[FloatArray, FloatArray]:
    """A :func:`reduced_state` (..., nq − p_q), (..., nv − p_v) in the model's size (..., nq), (..., nv): the passive
    joints at the model's ``qpos0`` and at rest, the loops not closed (:func:`closed_state` closes them)."""
    qadr, vadr = passive_addresses(model, passive)
    qpos, qvel = np.asarray(qpos, dtype=float), np.asarray(qvel, dtype=float)
    q = np.broadcast_to(model.qpos0, (*qpos.shape[:-1], model.nq)).copy()
    v = np.zeros((*qvel.shape[:-1], model.nv))
    q[..., np.setdiff1d(np.arange(model.nq), qadr)] = qpos
    v[..., np.setdiff1d(np.arange(model.nv), vadr)] = qvel
    return q, v


def closed_state(model: mujoco.MjModel, passive: tuple[int, ...], qpos: FloatArray, qvel: FloatArray
                 ) -> tuple[FloatArray, FloatArray]:
    """The full state (nq,), (nv,) of a :func:`reduced_state` (qpos, qvel): each passive spring at its springref and
    at rest, every other passive joint solved from the loops — positions by :func:`close_loops` from the model's
    ``qpos0``, velocities the least-norm v_p with J_p v_p = −J_rest v_rest on the loops' rows (:func:`loop_rows`)."""
    q, v = padded_state(model, passive, qpos, qvel)
    q = closed_posture(model, passive, q)
    return q, closed_velocity(model, passive, q, v)


def closed_posture(model: mujoco.MjModel, passive: tuple[int, ...], qpos: FloatArray) -> FloatArray:
    """``qpos`` (nq,) with each passive spring at its springref and every other passive joint solved from the loops
    (:func:`close_loops`, from the passive values given: a closed posture nearby stays on its branch); the planned,
    held and base coordinates as given. A model without passive joints gets ``qpos`` as it is."""
    if not passive:
        return np.asarray(qpos, dtype=float)
    q = np.array(qpos, dtype=float)
    springs = {sp.joint: sp.springref for sp in find_springs(model, passive)}
    for j, ref in springs.items():
        q[int(model.jnt_qposadr[j])] = ref
    loops, _ = closed_chains(model)
    return close_loops(model, q, loops, tuple(j for j in passive if j not in springs), LOOP_CLOSE_TOLERANCE)


def closed_velocity(model: mujoco.MjModel, passive: tuple[int, ...], qpos: FloatArray, qvel: FloatArray
                    ) -> FloatArray:
    """``qvel`` (nv,) (or (nv, c): columns of velocities) with the passive joints other than springs moving as the
    loops at the closed configuration ``qpos`` require: the least-norm v_p with J_p v_p = −J_rest v_rest on the loops'
    rows (:func:`loop_rows`; a rod's spin 0), the springs at rest (rigid). Without passive joints: ``qvel``."""
    v = np.array(qvel, dtype=float)
    if not passive:
        return v
    springs = {sp.joint for sp in find_springs(model, passive)}
    loops, _ = closed_chains(model)
    data = mujoco.MjData(model)
    data.qpos[:] = qpos
    _, jac = loop_rows(model, data, loops)
    v[list(joint_dofs(model, tuple(springs)))] = 0.0
    dofs = list(joint_dofs(model, tuple(j for j in passive if j not in springs)))
    v[dofs] = 0.0
    v[dofs] = -np.linalg.lstsq(jac[:, dofs], jac @ v, rcond=None)[0]
    return v
