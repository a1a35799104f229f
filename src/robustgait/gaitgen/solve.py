"""Solving the gait problem of a domain graph: initial guess from kinematics, IPOPT, the resulting :class:`Gait`."""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any

import casadi as cs
import numpy as np
from numpy.typing import NDArray
from scipy.optimize import least_squares

from robustgait.bezier import bernstein_basis, bezier, bezier_derivative, bezier_derivative_coeffs
from robustgait.config import GaitParams, GenerationConfig
from robustgait.config.gait import PARALLEL_LEGS_WIDTH_TOLERANCE, least_step_width, reach_problem
from robustgait.domains import Contact
from robustgait.dynamics import Dynamics, foot_frame, impact_map
from robustgait.gait import BEZIER_DEGREE, Domain, Gait, State
from robustgait.gaitgen.check import PhysicsCheck, check_solution, spring_problem
from robustgait.gaitgen.derivatives import derivative_functions
from robustgait.gaitgen.layout import ankle_roll_problem
from robustgait.gaitgen.problem import (
    F_SCALE,
    U_SCALE,
    GaitProblem,
    matrix_to_rpy,
    rpy_to_matrix,
)
from robustgait.gaitgen.states import NodeStates, to_mujoco_state
from robustgait.robots import Robot
from robustgait.robots.loops import reduced_state
from robustgait.robots.spec import SIDES

FloatArray = NDArray[np.float64]


@dataclass
class GaitGenResult:
    """Outcome of one solve: ``gait`` when IPOPT succeeded (with the physics check in its solver report),
    else None with ``status`` (IPOPT's return status or a pre-check) and a readable ``reason``."""

    success: bool
    status: str
    reason: str
    params: GaitParams | None
    gait: Gait | None = None
    iterations: int = 0
    solve_seconds: float = 0.0
    objective: float = float("nan")
    nodes: list[NodeStates] | None = None
    check: PhysicsCheck | None = None
    continued: str = ""

    def summary(self) -> dict[str, Any]:
        """JSON-ready outcome (without the gait itself); ``continued`` only when the solve was continued from the
        robot's default gait (:meth:`GaitGenerator.solve`): the cold solve's status."""
        out = {"success": self.success, "status": self.status, "reason": self.reason,
               "params": self.params.to_dict() if self.params else None, "iterations": self.iterations,
               "solve_seconds": self.solve_seconds,
               "objective": self.objective if np.isfinite(self.objective) else None,
               "check": self.check.to_dict() if self.check else None}
        return out | ({"continued": self.continued} if self.continued else {})


# IPOPT's statuses of a solve that did not converge from its start (another start may): continued from the default gait
NOT_CONVERGED = frozenset({"Maximum_Iterations_Exceeded", "Restoration_Failed", "Infeasible_Problem_Detected",
                           "Search_Direction_Becomes_Too_Small", "Diverging_Iterates", "Error_In_Step_Computation"})


def joint_trajectories(beta: FloatArray, taus: FloatArray, duration: float
                       ) -> tuple[FloatArray, FloatArray, FloatArray]:
    """s, ṡ, s̈ (n, m) of Bézier outputs β (m, 8) at phases τ (n,) for a domain of duration T."""
    return (bezier(beta, taus), bezier_derivative(beta, taus, 1) / duration,
            bezier_derivative(beta, taus, 2) / duration**2)


def domain_durations(prob: GaitProblem, params: GaitParams) -> list[float]:
    """Duration of each domain of the problem's graph (:meth:`GaitParams.domain_durations`)."""
    return params.domain_durations(prob.graph.name)


def _contact_targets(prob: GaitProblem, params: GaitParams, d: int) -> list[tuple[Contact, FloatArray]]:
    """Each contact of domain d with the position its frame is held at (stance sole frame coordinates)."""
    a, side = prob.half_length, 1.0 if prob.swing == "left" else -1.0
    out = []
    for c in prob.graph.domains[d].contacts:
        if c.leg == "stance":
            t = np.array([a if c.kind == "toe" else -a if c.kind == "heel" else 0.0, 0.0, 0.0])
        else:
            t = np.array([params.step_length - (a if c.kind == "heel" else 0.0), side * params.step_width, 0.0])
        out.append((c, t))
    return out


def _closure_pose(dyn: Dynamics, prob: GaitProblem, targets: list[tuple[Contact, FloatArray]], s: FloatArray,
                  free: list[int], guess: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Base pose H (4, 4) and joints s (free joints changed) that hold a domain's contacts: least squares over
    the base's position and roll-pitch-yaw and the free joints (exact when the contacts allow it; a
    compromise for a cold start, whose joints may not close the loop)."""
    fks = [(c, t, dyn.frame_fun(foot_frame(c.side(prob.stance), c.frame_kind()))) for c, t in targets]

    def unpack_z(z: FloatArray) -> tuple[FloatArray, FloatArray]:
        H = np.eye(4)
        H[:3, :3] = np.asarray(cs.evalf(rpy_to_matrix(cs.DM(z[3:6]))))
        H[:3, 3] = z[:3]
        q = s.copy()
        q[free] = z[6:]
        return H, q

    def residual(z: FloatArray) -> FloatArray:
        H, q = unpack_z(z)
        out: list[Any] = []
        for c, t, f in fks:
            Hc = np.asarray(f(H, q))
            out.append(Hc[:3, 3] - t)
            out.append(np.array([Hc[1, 0], Hc[2, 0], Hc[2, 1]] if c.kind == "flat" else [Hc[0, 1], Hc[2, 1]]))
        return np.concatenate([np.ravel(o) for o in out])

    z0 = np.concatenate([guess[:3, 3], matrix_to_rpy(guess[:3, :3]), s[free]])
    return unpack_z(least_squares(residual, z0, xtol=1e-12, ftol=1e-12).x)


def kinematic_states(dyn: Dynamics, prob: GaitProblem, beta: FloatArray, duration: float, *, domain: int = 0,
                     params: GaitParams | None = None, base: FloatArray | None = None,
                     torques: FloatArray | None = None) -> NodeStates:
    """Every node variable of a domain implied by β and its duration: the base from the contacts (pose,
    velocity, acceleration), u and λ from the 6 + m equations of motion, and the rigid impact map at τ = 1
    onto the next domain's contacts (:meth:`Dynamics.impact_map`).

    Single support (one flat sole) determines the base exactly and the equations of motion are square, so
    any β gives a consistent x₀. Double support (two line contacts, 10 rows) determines the base and the 4
    free joints (:func:`~robustgait.gaitgen.problem.double_support_free_joints`) from the 8 outputs: solved
    by least squares from ``base`` (the previous domain's last pose; exact when the loop can close), then
    square velocity and acceleration systems. Its wrench is not determined by the motion (two contacts share
    the load): λ is the one that gives the node ``torques`` (n, m) when they are known (a warm start's
    stored torques: then x₀ is that gait's solution), else the least-norm wrench."""
    m = prob.m
    taus = prob.domain_taus[domain]
    dom = prob.graph.domains[domain]
    s, sd, sdd = joint_trajectories(beta, taus, duration)
    if prob.n_loop:
        return closed_chain_states(dyn, prob, s, sd, sdd)
    n = len(taus)
    keys = [foot_frame(c.side(prob.stance), c.frame_kind()) for c in dom.contacts]
    # one stance foot (flat or on its line) held flat: its whole frame fixes the base; λ keeps the contact's rows
    single = len(dom.contacts) == 1 and dom.contacts[0].kind in ("flat", "line") and dom.contacts[0].leg == "stance"
    rows = [list(range(6)) if single else list(c.rows) for c in dom.contacts]
    nl = sum(len(r) for r in rows)
    out = {k: np.zeros((n, d)) for k, d in (("vb", 6), ("ab", 6), ("u", m), ("lam", nl))}
    Hs = np.zeros((n, 4, 4))
    free = [j for j in range(m) if j not in prob.outputs[domain]]
    cols = list(range(6)) + [6 + j for j in free]  # the unknown velocities: base and free joints
    known = [6 + j for j in prob.outputs[domain]]
    targets = None if single else _contact_targets(prob, params or GaitParams().resolved(prob.graph.name), domain)
    prev = np.eye(4) if base is None else base
    for i in range(n):
        if single:  # stance sole at the origin, identity orientation
            H = np.linalg.inv(np.asarray(dyn.frame_fun(keys[0])(np.eye(4), s[i])))
        else:
            assert targets is not None
            H, s[i] = _closure_pose(dyn, prob, targets, s[i], free, prev)
        Hs[i], prev = H, H
        J = np.vstack([np.asarray(dyn.jacobian_fun(k)(H, s[i]))[r] for k, r in zip(keys, rows, strict=True)])
        if single:
            vb = -np.linalg.solve(J[:, :6], J[:, 6:] @ sd[i])
        else:
            v = -np.linalg.lstsq(J[:, cols], J[:, known] @ sd[i][prob.outputs[domain]], rcond=None)[0]
            vb, sd[i][free] = v[:6], v[6:]
        nu = np.concatenate([vb, sd[i]])
        jd = np.vstack([np.asarray(dyn.jacobian_dot_fun(k)(H, s[i], vb, sd[i]))[r]
                        for k, r in zip(keys, rows, strict=True)])
        if single:
            ab = -np.linalg.solve(J[:, :6], J[:, 6:] @ sdd[i] + jd @ nu)
        else:
            a = -np.linalg.lstsq(J[:, cols], J[:, known] @ sdd[i][prob.outputs[domain]] + jd @ nu, rcond=None)[0]
            ab, sdd[i][free] = a[:6], a[6:]
        M = np.asarray(dyn.inertia(H, s[i]))
        rhs = M @ np.concatenate([ab, sdd[i]]) + np.asarray(dyn.bias_force_fun(H, s[i], vb, sd[i])).ravel()
        if single:
            lam = np.linalg.solve(J[:, :6].T, rhs[:6])
        elif torques is not None:
            lam = np.linalg.lstsq(J.T, rhs - np.concatenate([np.zeros(6), torques[i]]), rcond=None)[0]
        else:
            lam = np.linalg.lstsq(J[:, :6].T, rhs[:6], rcond=None)[0]
        out["vb"][i], out["ab"][i], out["lam"][i], out["u"][i] = vb, ab, lam, rhs[6:] - J[:, 6:].T @ lam
    qpos, qvel = to_mujoco_state(dyn.robot, Hs[-1], s[-1], out["vb"][-1], sd[-1])
    target = prob.graph.target_contacts(domain)
    if len(target) == 1 and target[0].kind == "flat":  # one sole lands flat (the flat graph, foot-flat)
        qvel_plus, impulse = dyn.impact_map(qpos, qvel, target[0].side(prob.stance))
    else:
        qvel_plus, impulse = dyn.impact_map(qpos, qvel, target, prob.stance)
    lam = out["lam"][:, list(dom.contacts[0].rows)] if single else out["lam"]
    return NodeStates(Hs, s, sd, sdd, out["vb"], out["ab"], out["u"], lam, dyn.to_mixed(qpos, qvel_plus), impulse)


def passive_motion(dyn: Dynamics, s: FloatArray, sd: FloatArray, sdd: FloatArray
                   ) -> tuple[FloatArray, FloatArray, FloatArray]:
    """The joints s, ṡ, s̈ (n, m + p) of a robot with closed chains from the planned ones (n, m): each node's passive
    joints solved from φ(s) = 0 (:meth:`Dynamics.close_passive`, from the previous node's, the first from the closed
    posture's), ṡ_p = −J_p⁻¹ J_a ṡ_a and s̈_p = −J_p⁻¹ (J_a s̈_a + J̇_h ṡ) (J_h = [J_a, J_p],
    :attr:`Dynamics.loop_fun`)."""
    m, n_all, cols = s.shape[1], dyn.n_joints, list(dyn.solved)  # compliant springs: at springref, at rest
    out = [np.zeros((len(s), n_all)) for _ in range(3)]
    guess = dyn.closed_posture[m:]
    for i in range(len(s)):
        q = dyn.close_passive(np.concatenate([s[i], guess]))
        guess = q[m:]
        v = np.concatenate([sd[i], np.zeros(n_all - m)])
        _, _, _, J = (np.asarray(x, dtype=float) for x in dyn.loop_fun(q, v, v))
        v[cols] = -np.linalg.solve(J[:, cols], J[:, :m] @ sd[i])
        a = np.concatenate([sdd[i], np.zeros(n_all - m)])
        acc = np.asarray(dyn.loop_fun(q, v, a)[2], dtype=float).ravel()
        a[cols] = -np.linalg.solve(J[:, cols], acc)
        out[0][i], out[1][i], out[2][i] = q, v, a
    return out[0], out[1], out[2]


def closed_chain_states(dyn: Dynamics, prob: GaitProblem, s: FloatArray, sd: FloatArray, sdd: FloatArray
                        ) -> NodeStates:
    """:func:`kinematic_states` of single support on a flat stance sole for a robot with closed chains: the passive
    joints from the loops (:func:`passive_motion`), the base from the stance sole, and from the 6 + m + p equations
    of motion — square in (λ, u, λ_h) — the stance wrench λ (base rows), the loop forces λ_h (passive rows: the
    passive joints have no torque) and the torques u; the rigid impact onto the swing sole with the loops held
    (:func:`robustgait.dynamics.impact_map` on [J_sw; 0, J_h], adam's mixed coordinates)."""
    m = prob.m
    s, sd, sdd = passive_motion(dyn, s, sd, sdd)
    n = len(s)
    key = foot_frame(prob.stance, "sole")
    Hs = np.zeros((n, 4, 4))
    vb, ab, lam, u, lamh = np.zeros((n, 6)), np.zeros((n, 6)), np.zeros((n, 6)), np.zeros((n, m)), []
    for i in range(n):
        H = Hs[i] = np.linalg.inv(np.asarray(dyn.frame_fun(key)(np.eye(4), s[i])))
        J = np.asarray(dyn.jacobian_fun(key)(H, s[i]))
        vb[i] = -np.linalg.solve(J[:, :6], J[:, 6:] @ sd[i])
        nu = np.concatenate([vb[i], sd[i]])
        jd = np.asarray(dyn.jacobian_dot_fun(key)(H, s[i], vb[i], sd[i]))
        ab[i] = -np.linalg.solve(J[:, :6], J[:, 6:] @ sdd[i] + jd @ nu)
        M = np.asarray(dyn.inertia(H, s[i]))
        rhs = M @ np.concatenate([ab[i], sdd[i]]) + np.asarray(dyn.bias_force_fun(H, s[i], vb[i], sd[i])).ravel()
        Jh = np.asarray(dyn.loop_fun(s[i], sd[i], sdd[i])[3], dtype=float)
        lam[i] = np.linalg.solve(J[:, :6].T, rhs[:6])
        # least squares when compliant springs leave their rows over (the guess's springs carry no torque)
        lamh.append(np.linalg.lstsq(Jh[:, m:].T, rhs[6 + m:] - J[:, 6 + m:].T @ lam[i], rcond=None)[0])
        u[i] = rhs[6:6 + m] - J[:, 6:6 + m].T @ lam[i] - Jh[:, :m].T @ lamh[-1]
    H, nu = Hs[-1], np.concatenate([vb[-1], sd[-1]])
    target = list(prob.graph.target_contacts(0)[0].rows)  # the swing sole's rows: flat, or its line
    Jt = np.asarray(dyn.jacobian_fun(foot_frame(prob.swing, "sole"))(H, s[-1]))[target]
    Jh = np.asarray(dyn.loop_fun(s[-1], sd[-1], sdd[-1])[3], dtype=float)
    Jall = np.vstack([Jt, np.hstack([np.zeros((len(Jh), 6)), Jh])])
    nu_plus, impulse = impact_map(np.asarray(dyn.inertia(H, s[-1])), Jall, nu)
    stance = list(prob.graph.domains[0].contacts[0].rows)  # the sole held flat; λ keeps the contact's rows
    return NodeStates(Hs, s, sd, sdd, vb, ab, u, lam[:, stance], nu_plus, impulse, np.array(lamh))


def fit_bezier(taus: FloatArray, s: FloatArray, sd: FloatArray, sdd: FloatArray, duration: float) -> FloatArray:
    """Least-squares Bézier coefficients (k, 8) of joints that are not outputs (their node values s, ṡ, s̈
    (n, k)): the trajectory the simulator's PD tracks for them."""
    b0 = bernstein_basis(BEZIER_DEGREE, taus)
    b1 = bernstein_basis(BEZIER_DEGREE - 1, taus) @ bezier_derivative_coeffs(np.eye(BEZIER_DEGREE + 1), 1).T
    b2 = bernstein_basis(BEZIER_DEGREE - 2, taus) @ bezier_derivative_coeffs(np.eye(BEZIER_DEGREE + 1), 2).T
    a = np.vstack([b0, b1 / duration, b2 / duration**2])
    return np.linalg.lstsq(a, np.vstack([s, sd, sdd]), rcond=None)[0].T


def pack(prob: GaitProblem, betas: list[FloatArray], states: list[NodeStates]) -> FloatArray:
    """The NLP vector x (scaled units) of a trajectory: per domain its β (m, 8) and node states."""
    lay = prob.layout
    x = np.zeros(lay.size)
    for dl, beta, ns, out in zip(lay.domains, betas, states, prob.outputs, strict=True):
        b = np.zeros_like(beta)
        b[out] = beta[out]  # a domain's non-output rows are unused and fixed at 0
        x[dl.beta] = b.ravel(order="F")
        for i, node in enumerate(dl.nodes):
            m = prob.m  # the planned joints; a closed chain's passive ones after them
            x[node["s"]], x[node["sd"]], x[node["sdd"]] = ns.s[i][:m], ns.sd[i][:m], ns.sdd[i][:m]
            if prob.n_passive:
                x[node["sp"]], x[node["spd"]], x[node["spdd"]] = ns.s[i][m:], ns.sd[i][m:], ns.sdd[i][m:]
                x[node["lamh"]] = ns.lamh[i] / U_SCALE
            x[node["p"]] = ns.H[i, :3, 3]
            x[node["rpy"]] = matrix_to_rpy(ns.H[i, :3, :3])
            x[node["vb"]], x[node["ab"]] = ns.vb[i], ns.ab[i]
            x[node["u"]], x[node["lam"]] = ns.u[i] / U_SCALE, ns.lam[i] / F_SCALE
        x[dl.nu_plus], x[dl.impulse] = ns.nu_plus, ns.impulse / U_SCALE
    return x


def unpack(prob: GaitProblem, x: FloatArray, durations: list[float]) -> tuple[list[FloatArray], list[NodeStates]]:
    """Per domain: β (m, 8) and the node states of an NLP vector (inverse of :func:`pack`)."""
    betas, states = [], []
    for dl, taus, duration, out in zip(prob.layout.domains, prob.domain_taus, durations, prob.outputs, strict=True):
        beta = x[dl.beta].reshape(prob.m, BEZIER_DEGREE + 1, order="F")
        n = len(dl.nodes)
        # the joints at the nodes: the Bézier outputs' values, and the free joints' node variables
        s, sd, sdd = joint_trajectories(beta, taus, duration)
        free = [j for j in range(prob.m) if j not in out]
        for arr, key in ((s, "s"), (sd, "sd"), (sdd, "sdd")):
            arr[:, free] = np.array([x[nd[key]] for nd in dl.nodes])[:, free]
        H = np.tile(np.eye(4), (n, 1, 1))
        for i, node in enumerate(dl.nodes):
            r = cs.DM(x[node["rpy"]])
            H[i, :3, :3] = np.asarray(cs.evalf(rpy_to_matrix(r)))
            H[i, :3, 3] = x[node["p"]]
        get = lambda key, scale=1.0, nodes=dl.nodes: np.array([x[nd[key]] * scale for nd in nodes])  # noqa: E731
        if prob.n_passive:  # a closed chain's passive joints follow the planned ones
            s, sd, sdd = (np.hstack([a, get(k)]) for a, k in ((s, "sp"), (sd, "spd"), (sdd, "spdd")))
        betas.append(beta)
        states.append(NodeStates(H, s, sd, sdd, get("vb"), get("ab"), get("u", U_SCALE), get("lam", F_SCALE),
                                 x[dl.nu_plus].copy(), x[dl.impulse] * U_SCALE,
                                 *((get("lamh", U_SCALE),) if prob.n_loop else ())))
    return betas, states


def params_problem(robot: Robot, params: GaitParams, config: GenerationConfig) -> str | None:
    """Why ``robot`` cannot be asked for resolved ``params`` under ``config``, in one clause, or None (IPOPT decides the
    rest). ``config`` is a generator's own, its robot-scaled options set (:meth:`GenerationConfig.for_robot`). In turn:
    a step width that makes the soles collide (narrower than :func:`~robustgait.config.gait.least_step_width`), legs
    without an ankle roll asked for another width than the soles' spacing (both feet are flat only under parallel legs)
    or for a multi-contact gait (:func:`~robustgait.gaitgen.layout.ankle_roll_problem`), a step beyond the leg's reach
    (:func:`~robustgait.config.gait.reach_problem`). Needs no gait problem, so a refusal costs no build."""
    sole_width = 2 * robot.sole_boxes[config.stance].half_width
    min_width = least_step_width(sole_width, config.scaled("foot_gap"))
    if params.step_width < min_width:
        return (f"step width {params.step_width:g} m makes the feet collide: the soles are {sole_width:.3f} m wide and "
                f"need a {config.scaled('foot_gap'):g} m gap (width ≥ {min_width:.3f} m)")
    if not robot.has_ankle_roll and abs(params.step_width - robot.sole_spacing) > PARALLEL_LEGS_WIDTH_TOLERANCE:
        return (f"step width {params.step_width:g} m: the legs have no ankle roll, so both feet are flat only under "
                f"parallel legs, {robot.sole_spacing:.4g} m apart (the posture's sole spacing): set step_width to it")
    if config.domains == "multicontact":
        for side in SIDES:
            missing = ankle_roll_problem(robot, side)
            if missing is not None:
                return missing
    return reach_problem(params, robot.scale, config)


class GaitGenerator:
    """Builds the NLP of a domain graph once for a robot — its derivatives node kind by node kind
    (:mod:`.derivatives`) — and solves it for any :class:`GaitParams`."""

    def __init__(self, robot: Robot, config: GenerationConfig | None = None, *, verbose: bool = False):
        self.robot = robot
        # the options that scale with the robot: set in config, else the spec's [generation], else relative
        self.config = cfg = (config or GenerationConfig()).for_robot(robot.scale, robot.spec.generation)
        t0 = time.perf_counter()
        # the NLP plans the planned joints only: held joints are welded at their angles (Robot.planned)
        self.dyn = Dynamics(robot.planned, cfg.springs)
        self.problem = prob = GaitProblem(self.dyn, cfg)
        nlp = {"x": prob.x, "p": prob.p, "f": prob.cost, "g": prob.g}
        opts: dict[str, Any] = {"ipopt.max_iter": cfg.max_iter, "ipopt.tol": cfg.tol, "ipopt.constr_viol_tol": 1e-9,
                "ipopt.print_level": 5 if verbose else 0, "print_time": False, "ipopt.sb": "yes",
                "ipopt.linear_solver": "mumps", "ipopt.mu_strategy": "adaptive"}
        # the derivatives node kind by node kind: nlpsol's own would derive them over the whole problem
        opts["jac_g"], opts["hess_lag"] = derivative_functions(prob)
        self.solver = cs.nlpsol(f"robustgait_{cfg.domains}", "ipopt", nlp, opts)
        self.build_seconds = time.perf_counter() - t0
        self.n_variables, self.n_constraints = int(prob.x.numel()), int(prob.g.numel())
        self._default: tuple[Gait | None] | None = None  # the default gait once solved (default_gait)

    def initial_guess(self, params: GaitParams, warm_start: Gait | None = None) -> FloatArray:
        """x₀ from a warm-start gait's β (relabeled to this stance if needed; a flat gait seeds the single
        support of a multi-contact problem) or a standing-like posture held in every domain.

        A warm start of this domain graph is rebuilt with its own durations, contact targets and stored
        torques, not with ``params``: its β describes its own step, so x₀ is then that gait's solution (the
        new essential constraints are IPOPT's to meet). Rebuilt with the new step length instead, a
        multi-contact warm start's double support no longer closes and IPOPT needs several times the iterations
        (docs/gaitgen.md)."""
        prob, robot = self.problem, self.robot
        n_dom = len(prob.graph)
        durations = domain_durations(prob, params)
        ref = params
        torques: list[FloatArray | None] = [None] * n_dom
        if warm_start is not None:
            g = warm_start if warm_start.stance == prob.stance else warm_start.mirrored(robot)
            betas = [d.beta.copy() for d in g.domains[:n_dom]]
            if g.domain_graph == prob.graph.name and len(g.domains) == n_dom and g.params is not None:
                ref, durations = g.params, [d.duration for d in g.domains]
                torques = [self._node_torques(d, taus) for d, taus in zip(g.domains, prob.domain_taus, strict=True)]
        else:
            betas = [np.repeat(self.standing_posture()[:, None], BEZIER_DEGREE + 1, axis=1)]
        while len(betas) < n_dom:  # hold the last posture through the missing domains
            betas.append(np.repeat(betas[-1][:, -1:], BEZIER_DEGREE + 1, axis=1))
        states: list[NodeStates] = []
        for d, (beta, duration) in enumerate(zip(betas, durations, strict=True)):
            states.append(kinematic_states(self.dyn, prob, beta, duration, domain=d, params=ref,
                                           base=states[-1].H[-1] if states else None, torques=torques[d]))
        return pack(prob, betas, states)

    @staticmethod
    def _node_torques(domain: Domain, taus: FloatArray) -> FloatArray | None:
        """A domain's stored torques (n, m) at this problem's nodes, or None when they are not stored there."""
        if domain.ff_tau is None or domain.ff_torque is None or domain.ff_tau.shape != taus.shape:
            return None
        return domain.ff_torque if np.allclose(domain.ff_tau, taus) else None

    def standing_posture(self) -> FloatArray:
        """The cold-start posture (spec order): the spec's ``[posture]`` clipped to the joint ranges."""
        q = np.asarray(self.robot.spec.posture or np.zeros(self.robot.n_joints), dtype=float)
        lo, hi = self.robot.joint_range[:, 0], self.robot.joint_range[:, 1]
        return np.clip(q, np.where(np.isfinite(lo), lo, -1e9), np.where(np.isfinite(hi), hi, 1e9))

    def precheck(self, params: GaitParams) -> str | None:
        """A readable reason why ``params`` cannot be walked by this robot, or None (IPOPT decides the rest):
        :func:`params_problem` under this generator's options."""
        return params_problem(self.robot, params, self.config)

    def solve(self, params: GaitParams, warm_start: Gait | None = None) -> GaitGenResult:
        """Solve for one set of essential constraints; never raises on infeasible input or solver failure:
        a failed result carries the pre-check's reason, IPOPT's status or the physics check's failures. A step
        duration that is not set is the domain graph's default.

        Continuation (``generate.continuation``): when the cold start (no ``warm_start``) does not converge
        (:data:`NOT_CONVERGED`), the problem is solved again from the robot's default gait (:meth:`default_gait`); the
        result then says so (``continued``: the cold solve's status; its iterations and seconds are counted) and its
        gait's solver report names the start (``continued_from``)."""
        res = self._solve(params, warm_start)
        default = self.robot.default_params.resolved(self.problem.graph.name)
        if warm_start is None and res.params == default and self._default is None:
            self._default = (res.gait,)  # this was the default gait's own cold solve: kept, never solved again
        if warm_start is not None or res.success or res.status not in NOT_CONVERGED or not self.config.continuation:
            return res
        base = self.default_gait()
        if base is None or res.params == default:
            return res
        again = self._solve(params, base, continued=res.status)
        again.iterations += res.iterations
        again.solve_seconds += res.solve_seconds
        return again

    def default_gait(self) -> Gait | None:
        """The robot's default gait (its spec's ``[gait]``, the domain graph's duration when unset) solved from the cold
        start, once per generator; None when it does not solve."""
        if self._default is None:
            self._default = (self._solve(self.robot.default_params, None).gait,)
        return self._default[0]

    def _solve(self, params: GaitParams, warm_start: Gait | None, continued: str = "") -> GaitGenResult:
        """One IPOPT solve from ``warm_start`` (the cold start when None) and the physics check (:meth:`solve`)."""
        prob = self.problem
        params = params.resolved(prob.graph.name)
        reason = self.precheck(params)
        if reason is not None:
            return GaitGenResult(success=False, status="Infeasible_Parameters", reason=reason, params=params)
        x0 = self.initial_guess(params, warm_start)
        p = np.array([params.step_length, params.step_duration, params.step_width, params.step_height,
                      params.rolling_fraction])
        t0 = time.perf_counter()
        sol = self.solver(x0=x0, p=p, lbx=prob.lbx, ubx=prob.ubx, lbg=prob.lbg, ubg=prob.ubg)
        secs = time.perf_counter() - t0
        stats = self.solver.stats()
        status = str(stats.get("return_status", "unknown"))
        iters = int(stats.get("iter_count", 0))
        ok = bool(stats.get("success", False))
        x = np.asarray(sol["x"]).ravel()
        durations = domain_durations(prob, params)
        betas, states = unpack(prob, x, durations)
        res = GaitGenResult(success=ok, status=status, reason="" if ok else f"IPOPT: {status}", params=params,
                            iterations=iters, solve_seconds=secs, objective=float(sol["f"]), nodes=states,
                            continued=continued)
        if ok:
            res.check = check = check_solution(self.dyn, prob, params, states, durations)
            springs = spring_problem(self.dyn, states) if check.passed else None
            if check.passed and springs is None:
                res.gait = self._gait(params, betas, states, durations, res)
            elif springs is not None:
                res.success, res.status, res.reason = False, "Spring_Out_Of_Range", springs
            else:
                res.success, res.status = False, "Physics_Check_Failed"
                res.reason = "physics check failed: " + "; ".join(check.failures)
        return res

    def _gait(self, params: GaitParams, betas: list[FloatArray], states: list[NodeStates], durations: list[float],
              res: GaitGenResult) -> Gait:
        robot, prob = self.robot, self.problem
        first, section = states[0], states[0]
        # states of the planned model, written for the robot's (held joints at their angles, at rest)
        q0, v0 = robot.expand_state(*to_mujoco_state(robot.planned, first.H[0], first.s[0], first.vb[0], first.sd[0]))
        q1, v1 = robot.expand_state(*to_mujoco_state(robot.planned, section.H[-1], section.s[-1], section.vb[-1],
                                                     section.sd[-1]))
        if robot.passive_ids:  # a gait file holds the base, planned and held joints only (the loops close the rest)
            (q0, v0), (q1, v1) = (reduced_state(robot.model, robot.passive_ids, q, v) for q, v in ((q0, v0), (q1, v1)))
        solver = {"status": res.status, "iterations": res.iterations, "solve_seconds": res.solve_seconds,
                  "build_seconds": self.build_seconds, "objective": res.objective,
                  "nodes": sum(len(ns.s) for ns in states), "variables": self.n_variables,
                  "constraints": self.n_constraints, "physics_check": res.check.to_dict() if res.check else None}
        margin = float(prob.config.scaled("joint_margin"))
        if margin > 0:  # provenance of a gait planned inside its joint ranges (without one, the file is unchanged)
            solver["joint_margin"] = margin
        if res.continued:  # provenance of a solve continued from the default gait (solve)
            solver["continued_from"] = f"the robot's default gait (the cold start: {res.continued})"
        fitted = []
        for beta, out, taus, ns, duration in zip(betas, prob.outputs, prob.domain_taus, states, durations, strict=True):
            b = beta.copy()
            free = [j for j in range(prob.m) if j not in out]
            if free:
                b[free] = fit_bezier(taus, ns.s[:, free], ns.sd[:, free], ns.sdd[:, free], duration)
            fitted.append(b)
        domains = tuple(Domain(spec.name, duration, beta, taus.copy(), ns.u.copy())
                        for spec, duration, beta, taus, ns in zip(prob.graph.domains, durations, fitted,
                                                                  prob.domain_taus, states, strict=True))
        return Gait(robot=robot.name, domain_graph=prob.graph.name, stance=prob.stance, joints=robot.spec.joints,
                    domains=domains, initial_state=State(q0, v0), pre_impact_state=State(q1, v1), params=params,
                    solver=solver, meta={"source": f"robustgait gaitgen ({prob.graph.name} HZD)"},
                    held=tuple((h.name, h.angle) for h in robot.spec.held))


def generate_gait(robot: Robot, params: GaitParams | None = None, config: GenerationConfig | None = None, *,
                  warm_start: Gait | None = None, generator: GaitGenerator | None = None,
                  verbose: bool = False) -> GaitGenResult:
    """One gait: ``params`` (default :class:`GaitParams`, its step duration the domain graph's default) solved with
    ``config`` (or ``generator``, built for it once, to reuse across calls). A failed solve is a result, never an
    exception."""
    gen = generator or GaitGenerator(robot, config, verbose=verbose)
    return gen.solve(params or GaitParams(), warm_start)
