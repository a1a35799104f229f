"""Physics check of an optimized gait, re-evaluated with MuJoCo's own model (docs/design.md §4, run on every solve),
in every domain of its graph and at every transition:

* Dynamics residual at every node: r = M q̈ + c − B u − J_cᵀ λ in MuJoCo's coordinates, with M from
  ``mj_fullM``, c = ``qfrc_bias``, J_c the domain's contact rows of ``mj_jac`` at each contact frame (flat
  sole: 6 rows; toe or heel line: 5); relative to ‖M q̈‖ + ‖c‖. A robot with closed chains is checked in its
  planning model as MuJoCo compiles it (``Dynamics.plan_model``: rods lumped, springs rigid; :mod:`robustgait.closure`)
  with the loops' forces the solution carries: r = M q̈ + c − B u − J_cᵀ λ − J_hᵀ λ_h (J_h = [0, ∂φ/∂s], the
  loops' rows; impacts likewise with the loops' rows under the landing sole's). MuJoCo's full model, rods and all, is
  not what the problem plans: lumping the rods leaves a residual there (docs/gaitgen.md, "Closed chains"). Springs
  planned compliant (``generate.springs``) have no loop row: their torque is MuJoCo's own, ``qfrc_spring`` +
  ``qfrc_damper`` on their degrees of freedom, subtracted from r.
* Contacts: each contact frame's position and held orientation, and J_c q̇ — no contact may move.
* Impacts: the rigid impact map onto the next domain's contacts (:func:`robustgait.dynamics.impact_map`
  with MuJoCo's M and J) reproduces the solution's post-impact velocity; the next domain starts from it; and
  periodicity: the last post-impact state, shifted so the new stance sole sits at the origin and mirrored,
  equals the first state.
* Contact wrenches: normal force, friction pyramid, centre of pressure, yaw moment (the problem's bounds).
* Essential constraints: landing position (step length, width), swing height at τ = ½, duration.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import NamedTuple

import mujoco
import numpy as np
from numpy.typing import NDArray

from robustgait.config import GaitParams
from robustgait.domains import Contact
from robustgait.dynamics import Dynamics, foot_frame, impact_map, quat_to_rotation
from robustgait.gaitgen.problem import GaitProblem
from robustgait.gaitgen.states import NodeStates, to_mujoco_state
from robustgait.robots.model import full_inertia

FloatArray = NDArray[np.float64]
DYNAMICS_TOL = 1e-6
PERIODICITY_TOL = 1e-6
LENGTH_TOL = 1e-3
TIME_TOL = 1e-3
FORCE_TOL = 1e-6  # [N] slack on the wrench inequalities (IPOPT's bound relaxation)
COP_ON_BOUND = 5e-5  # [m] a centre of pressure within 0.05 mm of its bound is on it (what "0.0 mm" printed meant)


@dataclass(frozen=True)
class PhysicsCheck:
    """Figures of the check (see the module docstring) and ``passed`` / ``failures`` against the
    acceptance tolerances: dynamics ≤ 1e-6 relative, periodicity ≤ 1e-6, essential constraints within
    1 mm and 1 ms, wrench constraints satisfied."""

    dynamics_residual: float
    stance_drift: float
    impact_residual: float
    periodicity: float
    min_normal_force: float
    friction_ratio: float
    cop_margin: float
    cop_bound: float
    step_length_error: float
    step_width_error: float
    step_height_error: float
    duration_error: float
    passed: bool
    failures: tuple[str, ...]

    def to_dict(self) -> dict[str, object]:
        return asdict(self)

    @property
    def on_cop_bound(self) -> bool:
        """The centre of pressure reaches the generation's bound (``generate.cop_margin`` inside the sole edges) at
        some node: the slack ``cop_margin`` is below :data:`COP_ON_BOUND` — the gait sits on that constraint."""
        return self.cop_margin < COP_ON_BOUND

    def cop_text(self) -> str:
        """The centre of pressure's least distance to the sole edges against its bound, in mm, e.g. ``CoP ≥ 29.2 mm
        inside the sole edges (bound 16.7 mm)``, or ``… 16.7 mm …: on its bound``."""
        edge = (self.cop_bound + self.cop_margin) * 1e3
        text = f"CoP ≥ {edge:.1f} mm inside the sole edges (bound {self.cop_bound * 1e3:.1f} mm"
        return text + ("): on its bound" if self.on_cop_bound else f", slack {self.cop_margin * 1e3:.1f} mm)")


def _sole_jacobian(m: mujoco.MjModel, d: mujoco.MjData, body: int, point: FloatArray) -> FloatArray:
    jp, jr = np.zeros((3, m.nv)), np.zeros((3, m.nv))
    mujoco.mj_jac(m, d, jp, jr, point, body)
    return np.vstack([jp, jr])


class CheckModel:
    """The MuJoCo model a solution is checked in (module docstring): the robot's own, or for closed chains the
    planning model (``Dynamics.plan_model``, joints at their adam addresses, angles from 0), and its data."""

    def __init__(self, dyn: Dynamics):
        self.dyn, self.closed = dyn, bool(dyn.loops)
        self.m = dyn.plan_model if self.closed else dyn.robot.model
        self.d = mujoco.MjData(self.m)
        names = [*dyn.robot.spec.joints, *dyn.passive]
        self.qadr = np.array([self.m.joint(n).qposadr[0] for n in names], dtype=np.int64)
        self.vadr = np.array([self.m.joint(n).dofadr[0] for n in names], dtype=np.int64)

    def state(self, H: FloatArray, s: FloatArray, vb: FloatArray, sd: FloatArray) -> tuple[FloatArray, FloatArray]:
        """(qpos, qvel) of an adam state in this model (:func:`robustgait.gaitgen.states.to_mujoco_state`)."""
        if not self.closed:
            return to_mujoco_state(self.dyn.robot, H, s, vb, sd)
        qpos, qvel = np.zeros(self.m.nq), np.zeros(self.m.nv)
        qpos[:3], qvel[:3], qvel[3:6] = H[:3, 3], vb[:3], H[:3, :3].T @ vb[3:6]
        mujoco.mju_mat2Quat(qpos[3:7], H[:3, :3].ravel())
        qpos[self.qadr], qvel[self.vadr] = s, sd
        return qpos, qvel

    def velocity(self, qpos: FloatArray, nu: FloatArray) -> FloatArray:
        """MuJoCo's qvel (or q̈) of adam's mixed ν (or ν̇): the base's angular part into the base frame (the map is
        linear in ν̇ too, because Ṙᵀ ω = −Rᵀ ω × ω = 0)."""
        if not self.closed:
            return self.dyn.velocity_map(qpos).T @ nu
        out = np.zeros(self.m.nv)
        out[:3], out[3:6] = nu[:3], quat_to_rotation(qpos[3:7]).T @ nu[3:6]
        out[self.vadr] = nu[6:]
        return out

    def frame(self, side: str, kind: str, qpos: FloatArray) -> tuple[FloatArray, FloatArray, int]:
        """(position, rotation, body id) of a foot frame at ``qpos`` (after :meth:`forward`): adam's on the robot's
        model (the sole's body), MuJoCo's own on the planning model (its frame body)."""
        if not self.closed:
            point, rot = self.dyn.frame_pose(foot_frame(side, kind), qpos)
            return point, rot, int(self.m.geom_bodyid[self.dyn.robot.sole_geom_id[side]])
        b = self.m.body(foot_frame(side, kind)).id
        return self.d.xpos[b].copy(), self.d.xmat[b].reshape(3, 3).copy(), int(b)

    def forward(self, qpos: FloatArray, qvel: FloatArray) -> None:
        self.d.qpos[:], self.d.qvel[:] = qpos, qvel
        mujoco.mj_forward(self.m, self.d)

    def loop_jacobian(self, s: FloatArray) -> FloatArray:
        """The loops' rows in this model's velocities (k, nv): [0, ∂φ/∂s] at the adam joints (none without loops)."""
        J = np.zeros((self.dyn.loop_fun.size1_out(0) if self.closed else 0, self.m.nv))
        if self.closed:
            J[:, self.vadr] = np.asarray(self.dyn.loop_fun(s, s, s)[3], dtype=float)
        return J


def _contact_jacobian(ev: CheckModel, contacts: tuple[Contact, ...], stance: str, qpos: FloatArray) -> FloatArray:
    """MuJoCo's stacked contact Jacobian (mj_jac at each contact frame's point; its fixed rows)."""
    rows = []
    for c in contacts:
        point, _, body = ev.frame(c.side(stance), c.frame_kind(), qpos)
        rows.append(_sole_jacobian(ev.m, ev.d, body, point)[list(c.rows)])
    return np.vstack(rows)


def _wrench_figures(c: Contact, lam: FloatArray, prob: GaitProblem) -> tuple[float, float, float]:
    """(f_z, |f_t|/f_z, CoP margin [m]) of one contact wrench (the problem's bounds, see problem.wrench_rows)."""
    cfg = prob.config
    fz = float(lam[2])
    friction = float(np.max(np.abs(lam[:2])) / fz)
    ax, ay = prob.half_length - cfg.scaled("cop_margin"), prob.half_width - cfg.scaled("cop_margin")
    if c.kind == "flat":
        margin = min(ax - abs(-lam[4] / fz), ay - abs(lam[3] / fz))
    elif c.kind == "line":  # a line foot's (n_y, n_z): the centre of pressure along the foot
        margin = ax - abs(lam[3] / fz)
    else:
        margin = ay - abs(lam[3] / fz)
    return fz, friction, float(margin)


@dataclass
class _Worst:
    """The worst of each figure over a solution's nodes and transitions, as :func:`check_solution` gathers them
    (:class:`PhysicsCheck` for their meaning)."""

    dynamics: float = 0.0
    drift: float = 0.0
    fz_min: float = np.inf
    friction: float = 0.0
    cop_margin: float = np.inf
    force_short: float = 0.0
    impact: float = 0.0
    continuity: float = 0.0


class NodeResidual(NamedTuple):
    """A node's residual of the equations of motion (:func:`node_residual`): ``r`` (nv,) [N, N m], ``scale``
    ‖M q̈‖ + ‖c‖ it is measured against, the node's ``qpos`` and ``qvel`` in the check's model, and the contact
    Jacobian ``J`` (rows, nv) there."""

    r: FloatArray
    scale: float
    qpos: FloatArray
    qvel: FloatArray
    J: FloatArray


def node_residual(ev: CheckModel, contacts: tuple[Contact, ...], stance: str, ns: NodeStates, i: int
                  ) -> NodeResidual:
    """Node ``i``'s residual of the equations of motion in ``ev``'s model (module docstring), measured against
    ‖M q̈‖ + ‖c‖, with the node's state and contact Jacobian there (``ev`` left at that state)."""
    m, d = ev.m, ev.d
    qpos, qvel = ev.state(ns.H[i], ns.s[i], ns.vb[i], ns.sd[i])
    qacc = ev.velocity(qpos, np.concatenate([ns.ab[i], ns.sdd[i]]))
    ev.forward(qpos, qvel)
    M = full_inertia(m, d)
    J = _contact_jacobian(ev, contacts, stance, qpos)
    tau = np.zeros(m.nv)
    tau[ev.vadr[:ev.dyn.robot.n_joints]] = ns.u[i]
    r = M @ qacc + d.qfrc_bias - tau - J.T @ ns.lam[i]
    if ev.dyn.springs:  # compliant springs: MuJoCo's own spring and damper forces on their degrees of freedom
        dofs = ev.vadr[[sp.index for sp in ev.dyn.springs]]
        r[dofs] -= d.qfrc_spring[dofs] + d.qfrc_damper[dofs]
    if ev.closed:
        r -= ev.loop_jacobian(ns.s[i]).T @ ns.lamh[i]
    return NodeResidual(r, float(np.linalg.norm(M @ qacc) + np.linalg.norm(d.qfrc_bias)), qpos, qvel, J)


def _check_node(ev: CheckModel, prob: GaitProblem, params: GaitParams, contacts: tuple[Contact, ...], ns: NodeStates,
                i: int, worst: _Worst) -> None:
    """One node's equations of motion, contacts and wrenches against MuJoCo's (``worst`` updated in place)."""
    stance, cfg = prob.stance, prob.config
    r, scale, qpos, qvel, J = node_residual(ev, contacts, stance, ns, i)
    worst.dynamics = max(worst.dynamics, float(np.linalg.norm(r) / max(scale, 1.0)))
    worst.drift = max(worst.drift, float(np.linalg.norm(J @ qvel)))
    j = 0
    for c in contacts:
        point, rot, _ = ev.frame(c.side(stance), c.frame_kind(), qpos)
        orient = ((rot[1, 0], rot[2, 0], rot[2, 1]) if c.kind == "flat" else (rot[1, 0], rot[2, 0]) if c.kind == "line"
                  else (rot[0, 1], rot[2, 1]))
        worst.drift = max(worst.drift, float(np.linalg.norm(point - _target(c, prob, params))),
                          float(np.max(np.abs(orient))))
        fz, fr, cm = _wrench_figures(c, ns.lam[i][j:j + c.n_rows], prob)
        floor = cfg.scaled("min_normal_force") if c.kind in ("flat", "line") else cfg.scaled("min_line_force")
        worst.fz_min, worst.friction = min(worst.fz_min, fz), max(worst.friction, fr)
        worst.cop_margin, worst.force_short = min(worst.cop_margin, cm), max(worst.force_short, floor - fz)
        j += c.n_rows


def _check_impact(ev: CheckModel, prob: GaitProblem, states: list[NodeStates], k: int, worst: _Worst
                  ) -> tuple[FloatArray, FloatArray]:
    """The impact that ends domain ``k``, with MuJoCo's M and Jacobian (and a closed chain's loop rows under the
    landing sole's), against the solution's ν⁺, and the next domain's start against the post-impact state (same
    labels); returns the robot's (qpos, post-impact qvel) (a closed chain's rods solved from the loops)."""
    robot, ns = ev.dyn.robot, states[k]
    qpos, qvel = ev.state(ns.H[-1], ns.s[-1], ns.vb[-1], ns.sd[-1])
    ev.forward(qpos, qvel)
    Jt = np.vstack([_contact_jacobian(ev, prob.graph.target_contacts(k), prob.stance, qpos),
                    ev.loop_jacobian(ns.s[-1])])
    qvel_plus, _ = impact_map(full_inertia(ev.m, ev.d), Jt, qvel)
    worst.impact = max(worst.impact, float(np.linalg.norm(Jt @ qvel_plus)),
                       float(np.abs(ev.velocity(qpos, ns.nu_plus) - qvel_plus).max()))
    if k + 1 < len(states):
        nxt = states[k + 1]
        q1, v1 = ev.state(nxt.H[0], nxt.s[0], nxt.vb[0], nxt.sd[0])
        worst.continuity = max(worst.continuity, float(np.abs(q1 - qpos).max()),
                               float(np.abs(v1 - qvel_plus).max()))
    if ev.closed:  # the robot's own state, for the periodicity and the step's figures
        return to_mujoco_state(robot, ns.H[-1], ns.s[-1], ns.nu_plus[:6], ns.nu_plus[6:])
    return qpos, qvel_plus


def _failures(worst: _Worst, periodicity: float, errs: dict[str, float], friction: float) -> list[str]:
    """One line per tolerance a solution's figures exceed (the module's tolerances; ``friction`` the cone's μ)."""
    failures = []
    if worst.dynamics > DYNAMICS_TOL:
        failures.append(f"dynamics residual {worst.dynamics:.2e} > {DYNAMICS_TOL:g}")
    if worst.drift > 1e-6:
        failures.append(f"a contact moves ({worst.drift:.2e})")
    if worst.impact > 1e-6 or periodicity > PERIODICITY_TOL:
        failures.append(f"periodicity {periodicity:.2e} (impact {worst.impact:.2e}) > {PERIODICITY_TOL:g}")
    if worst.force_short > FORCE_TOL or worst.friction > friction + 1e-6 or worst.cop_margin < -1e-6:
        failures.append(f"contact wrench outside the cone/sole (min f_z {worst.fz_min:.1f} N, |f_t|/f_z "
                        f"{worst.friction:.3f}, CoP margin {worst.cop_margin:.4f} m)")
    for key, err in errs.items():
        tol = TIME_TOL if key == "duration_error" else LENGTH_TOL
        if err > tol:
            failures.append(f"{key.replace('_', ' ')} {err:.2e} > {tol:g}")
    return failures


def check_solution(dyn: Dynamics, prob: GaitProblem, params: GaitParams, states: list[NodeStates],
                   durations: list[float]) -> PhysicsCheck:
    """Re-evaluate a solution's physics with MuJoCo (module docstring), every domain and transition."""
    robot = dyn.robot
    ev = CheckModel(dyn)
    cfg = prob.config
    sw_frame = foot_frame(prob.swing, "sole")
    side = 1.0 if prob.swing == "left" else -1.0
    worst = _Worst()
    for k, (dom, ns) in enumerate(zip(prob.graph.domains, states, strict=True)):
        for i in range(len(ns.s)):
            _check_node(ev, prob, params, dom.contacts, ns, i, worst)
        qpos, qvel_plus = _check_impact(ev, prob, states, k, worst)
    # periodicity: the last post-impact state, shifted so the new stance sole sits at the origin and mirrored,
    # is the first state
    p_sw, _ = dyn.frame_pose(sw_frame, qpos)
    shifted = qpos.copy()
    shifted[:3] -= p_sw
    mq, mv = robot.mirror_state(shifted, qvel_plus)
    first = states[0]
    q0, v0 = to_mujoco_state(robot, first.H[0], first.s[0], first.vb[0], first.sd[0])
    if np.dot(mq[3:7], q0[3:7]) < 0:  # q and −q are the same rotation
        mq[3:7] *= -1
    periodicity = float(max(np.abs(mq - q0).max(), np.abs(mv - v0).max(), worst.continuity))
    mid = (len(first.s) - 1) // 2
    q_mid, _ = to_mujoco_state(robot, first.H[mid], first.s[mid], first.vb[mid], first.sd[mid])
    h_mid = dyn.frame_pose(sw_frame, q_mid)[0][2]
    errs = {
        "step_length_error": abs(p_sw[0] - params.step_length),
        "step_width_error": abs(side * p_sw[1] - params.step_width),
        "step_height_error": abs(h_mid - params.step_height),
        "duration_error": abs(sum(durations) - params.duration),
    }
    failures = _failures(worst, periodicity, errs, cfg.friction)
    return PhysicsCheck(dynamics_residual=worst.dynamics, stance_drift=worst.drift, impact_residual=worst.impact,
                        periodicity=periodicity, min_normal_force=float(worst.fz_min), friction_ratio=worst.friction,
                        cop_margin=worst.cop_margin, cop_bound=float(cfg.scaled("cop_margin")),
                        **{k: float(v) for k, v in errs.items()}, passed=not failures,
                        failures=tuple(failures))


def _target(c: Contact, prob: GaitProblem, params: GaitParams) -> FloatArray:
    """Where a contact's frame is held (stance sole frame coordinates; see the problem's contact rows)."""
    a, side = prob.half_length, 1.0 if prob.swing == "left" else -1.0
    if c.leg == "stance":
        return np.array([a if c.kind == "toe" else -a if c.kind == "heel" else 0.0, 0.0, 0.0])
    return np.array([params.step_length - (a if c.kind == "heel" else 0.0), side * params.step_width, 0.0])


def spring_problem(dyn: Dynamics, states: list[NodeStates]) -> str | None:
    """The first spring of a closed chain whose deflection leaves its range in a solution, as one line naming the
    joint and the figures; None when every spring stays in range (or has none, or the robot has no springs).

    The gait problem holds a spring rigid (s_j − springref = 0, :mod:`robustgait.closure`); its row's force λ [N m]
    is the torque the spring must hold, and the model's spring holds it at the deflection δ = s_j − springref = −λ / k
    (k its stiffness [N m/rad]): the deflection the simulation's spring takes under the planned load (its static part;
    a spring also rings after each impact). A limited spring whose δ over the nodes leaves its range is refused."""
    m = dyn.robot.model
    rows = 0 if not dyn.loops else int(dyn.loop_fun.size1_out(0))
    springs = [lp for lp in dyn.loops if lp.kind == "spring"]
    for k, lp in enumerate(springs):  # the springs' rows are the last, one each, in this order (closure.plan_loops)
        j = m.joint(lp.joint).id
        if not m.jnt_limited[j] or not m.jnt_stiffness[j] > 0:
            continue
        col = rows - len(springs) + k
        delta = np.concatenate([-ns.lamh[:, col] for ns in states]) / float(m.jnt_stiffness[j])
        lo, hi = float(m.jnt_range[j][0]) - lp.ref, float(m.jnt_range[j][1]) - lp.ref
        worst = float(delta[np.argmax(np.maximum(lo - delta, delta - hi))])
        if worst < lo or worst > hi:
            torque = -worst * float(m.jnt_stiffness[j])
            return (f"the spring '{lp.joint}' would deflect {worst:.3g} rad under the gait's load ({torque:.4g} N m "
                    f"over its {m.jnt_stiffness[j]:.4g} N m/rad), outside its range [{lo:.3g}, {hi:.3g}] rad from "
                    f"its rest angle: a slower or shorter step loads it less")
    return None
