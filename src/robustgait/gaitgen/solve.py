"""Solving the flat-foot problem: initial guess from kinematics, IPOPT, and the resulting :class:`Gait`."""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any

import casadi as cs
import mujoco
import numpy as np
from numpy.typing import NDArray

from robustgait.bezier import bezier, bezier_derivative
from robustgait.dynamics import Dynamics, foot_frame
from robustgait.errors import RobustGaitError
from robustgait.gait import BEZIER_DEGREE, Domain, Gait, GaitParams, State
from robustgait.gaitgen.check import PhysicsCheck, check_solution
from robustgait.gaitgen.problem import (
    F_SCALE,
    U_SCALE,
    FlatFootProblem,
    GaitGenConfig,
    matrix_to_rpy,
    rpy_to_matrix,
)
from robustgait.gaitgen.states import NodeStates, to_mujoco_state
from robustgait.robots import Robot

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
    nodes: NodeStates | None = None
    check: PhysicsCheck | None = None

    def summary(self) -> dict[str, Any]:
        """JSON-ready outcome (without the gait itself)."""
        return {"success": self.success, "status": self.status, "reason": self.reason,
                "params": self.params.to_dict() if self.params else None, "iterations": self.iterations,
                "solve_seconds": self.solve_seconds,
                "objective": self.objective if np.isfinite(self.objective) else None,
                "check": self.check.to_dict() if self.check else None}


def joint_trajectories(beta: FloatArray, taus: FloatArray, duration: float
                       ) -> tuple[FloatArray, FloatArray, FloatArray]:
    """s, ṡ, s̈ (n, m) of Bézier outputs β (m, 8) at phases τ (n,) for a domain of duration T."""
    return (bezier(beta, taus), bezier_derivative(beta, taus, 1) / duration,
            bezier_derivative(beta, taus, 2) / duration**2)


def kinematic_states(dyn: Dynamics, prob: FlatFootProblem, beta: FloatArray, duration: float) -> NodeStates:
    """Every node variable implied by β and T: the base from the stance-foot constraint (pose, velocity,
    acceleration), u and λ from the 6 + m equations of motion (a square system for a flat foot), and the
    rigid impact map at τ = 1 (:meth:`Dynamics.impact_map`). The initial guess: any β gives a consistent x₀."""
    kd = dyn.kindyn
    st = foot_frame(prob.stance, "sole")
    fk, jac, jdot = dyn.frame_fun(st), kd.jacobian_fun(st), kd.jacobian_dot_fun(st)
    m = prob.m
    arm = np.zeros(6 + m)
    arm[6:] = dyn.armature[dyn.robot.dof_idx]
    s, sd, sdd = joint_trajectories(beta, prob.taus, duration)
    n = len(prob.taus)
    out = {k: np.zeros((n, d)) for k, d in (("vb", 6), ("ab", 6), ("u", m), ("lam", 6))}
    Hs = np.zeros((n, 4, 4))
    for i in range(n):
        H = np.linalg.inv(np.asarray(fk(np.eye(4), s[i])))  # stance sole at the origin, identity orientation
        Hs[i] = H
        J = np.asarray(jac(H, s[i]))
        vb = -np.linalg.solve(J[:, :6], J[:, 6:] @ sd[i])
        nu = np.concatenate([vb, sd[i]])
        ab = -np.linalg.solve(J[:, :6], J[:, 6:] @ sdd[i] + np.asarray(jdot(H, s[i], vb, sd[i])) @ nu)
        M = np.asarray(dyn.mass_matrix_fun(H, s[i])) + np.diag(arm)
        rhs = M @ np.concatenate([ab, sdd[i]]) + np.asarray(dyn.bias_force_fun(H, s[i], vb, sd[i])).ravel()
        lam = np.linalg.solve(J[:, :6].T, rhs[:6])
        out["vb"][i], out["ab"][i], out["lam"][i], out["u"][i] = vb, ab, lam, rhs[6:] - J[:, 6:].T @ lam
    qpos, qvel = to_mujoco_state(dyn.robot, Hs[-1], s[-1], out["vb"][-1], sd[-1])
    qvel_plus, impulse = dyn.impact_map(qpos, qvel, prob.swing)
    return NodeStates(Hs, s, sd, sdd, out["vb"], out["ab"], out["u"], out["lam"], dyn.to_mixed(qpos, qvel_plus),
                      impulse)


def pack(prob: FlatFootProblem, beta: FloatArray, ns: NodeStates) -> FloatArray:
    """The NLP vector x (scaled units) of a trajectory."""
    lay = prob.layout
    x = np.zeros(lay.size)
    x[lay.beta] = beta.ravel(order="F")
    for i, node in enumerate(lay.nodes):
        x[node["s"]], x[node["sd"]], x[node["sdd"]] = ns.s[i], ns.sd[i], ns.sdd[i]
        x[node["p"]] = ns.H[i, :3, 3]
        x[node["rpy"]] = matrix_to_rpy(ns.H[i, :3, :3])
        x[node["vb"]], x[node["ab"]] = ns.vb[i], ns.ab[i]
        x[node["u"]], x[node["lam"]] = ns.u[i] / U_SCALE, ns.lam[i] / F_SCALE
    x[lay.nu_plus], x[lay.impulse] = ns.nu_plus, ns.impulse / U_SCALE
    return x


def unpack(prob: FlatFootProblem, x: FloatArray, duration: float) -> tuple[FloatArray, NodeStates]:
    """β (m, 8) and the node states of an NLP vector (inverse of :func:`pack`)."""
    lay = prob.layout
    beta = x[lay.beta].reshape(prob.m, BEZIER_DEGREE + 1, order="F")
    s, sd, sdd = joint_trajectories(beta, prob.taus, duration)
    n = len(lay.nodes)
    H = np.tile(np.eye(4), (n, 1, 1))
    for i, node in enumerate(lay.nodes):
        r = cs.DM(x[node["rpy"]])
        H[i, :3, :3] = np.asarray(cs.evalf(rpy_to_matrix(r)))
        H[i, :3, 3] = x[node["p"]]
    get = lambda key, scale=1.0: np.array([x[nd[key]] * scale for nd in lay.nodes])  # noqa: E731
    return beta, NodeStates(H, s, sd, sdd, get("vb"), get("ab"), get("u", U_SCALE), get("lam", F_SCALE),
                            x[lay.nu_plus].copy(), x[lay.impulse] * U_SCALE)


class GaitGenerator:
    """Builds the flat-foot NLP once for a robot (≈ 6 s for exo, 10 s for Atalante) and solves it for any
    :class:`GaitParams`."""

    def __init__(self, robot: Robot, config: GaitGenConfig | None = None, *, verbose: bool = False):
        self.robot = robot
        self.config = cfg = config or GaitGenConfig()
        t0 = time.perf_counter()
        self.dyn = Dynamics(robot)
        self.problem = prob = FlatFootProblem(self.dyn, cfg)
        nlp = {"x": prob.x, "p": prob.p, "f": prob.cost, "g": prob.g}
        opts = {"ipopt.max_iter": cfg.max_iter, "ipopt.tol": cfg.tol, "ipopt.constr_viol_tol": 1e-9,
                "ipopt.print_level": 5 if verbose else 0, "print_time": False, "ipopt.sb": "yes",
                "ipopt.linear_solver": "mumps", "ipopt.mu_strategy": "adaptive"}
        self.solver = cs.nlpsol("robustgait_flat", "ipopt", nlp, opts)
        self.build_seconds = time.perf_counter() - t0
        self.n_variables, self.n_constraints = int(prob.x.numel()), int(prob.g.numel())

    def initial_guess(self, params: GaitParams, warm_start: Gait | None = None) -> FloatArray:
        """x₀ from a warm-start gait's β (relabeled to this stance if needed) or a standing-like posture."""
        prob, robot = self.problem, self.robot
        if warm_start is not None:
            g = warm_start if warm_start.stance == prob.stance else warm_start.mirrored(robot)
            beta = g.domains[0].beta.copy()
        else:
            beta = np.repeat(self.standing_posture()[:, None], BEZIER_DEGREE + 1, axis=1)
        return pack(prob, beta, kinematic_states(self.dyn, prob, beta, params.step_duration))

    def standing_posture(self) -> FloatArray:
        """The cold-start posture (spec order): the spec's ``[posture]`` clipped to the joint ranges."""
        q = np.asarray(self.robot.spec.posture or np.zeros(self.robot.n_joints), dtype=float)
        lo, hi = self.robot.joint_range[:, 0], self.robot.joint_range[:, 1]
        return np.clip(q, np.where(np.isfinite(lo), lo, -1e9), np.where(np.isfinite(hi), hi, 1e9))

    def precheck(self, params: GaitParams) -> str | None:
        """A readable reason why ``params`` cannot be walked by this robot, or None (IPOPT decides the rest)."""
        prob, cfg = self.problem, self.config
        min_width = 2 * prob.half_width + cfg.foot_gap
        if params.step_width < min_width:
            return (f"step width {params.step_width:g} m makes the feet collide: the soles are "
                    f"{2 * prob.half_width:.3f} m wide and need a {cfg.foot_gap:g} m gap (width ≥ {min_width:.3f} m)")
        reach = self.leg_length()
        if np.hypot(params.step_length, params.step_width) > 1.2 * reach:
            return (f"a step of {params.step_length:g} m × {params.step_width:g} m is beyond the leg reach "
                    f"(leg length {reach:.3f} m)")
        if params.step_height > 0.5 * reach:
            return f"swing height {params.step_height:g} m is beyond half the leg length ({reach:.3f} m)"
        return None

    def leg_length(self) -> float:
        """Hip-to-sole distance [m] in the zero posture: from the joint of the base's child on the stance
        sole's kinematic chain to the sole geom's centre."""
        m, robot = self.robot.model, self.robot
        d = mujoco.MjData(m)
        mujoco.mj_kinematics(m, d)
        body = int(m.geom_bodyid[robot.sole_geom_id[self.problem.stance]])
        while int(m.body_parentid[body]) != robot.base_body_id:
            body = int(m.body_parentid[body])
        hip = d.xanchor[int(m.body_jntadr[body])]
        return float(np.linalg.norm(hip - d.geom_xpos[robot.sole_geom_id[self.problem.stance]]))

    def solve(self, params: GaitParams, warm_start: Gait | None = None) -> GaitGenResult:
        """Solve for one set of essential constraints; never raises on infeasible input or solver failure:
        a failed result carries the pre-check's reason, IPOPT's status or the physics check's failures."""
        prob = self.problem
        reason = self.precheck(params)
        if reason is not None:
            return GaitGenResult(success=False, status="Infeasible_Parameters", reason=reason, params=params)
        x0 = self.initial_guess(params, warm_start)
        p = np.array([params.step_length, params.step_duration, params.step_width, params.step_height])
        t0 = time.perf_counter()
        sol = self.solver(x0=x0, p=p, lbx=prob.lbx, ubx=prob.ubx, lbg=prob.lbg, ubg=prob.ubg)
        secs = time.perf_counter() - t0
        stats = self.solver.stats()
        status = str(stats.get("return_status", "unknown"))
        iters = int(stats.get("iter_count", 0))
        ok = bool(stats.get("success", False))
        x = np.asarray(sol["x"]).ravel()
        beta, ns = unpack(prob, x, params.step_duration)
        res = GaitGenResult(success=ok, status=status, reason="" if ok else f"IPOPT: {status}", params=params,
                            iterations=iters, solve_seconds=secs, objective=float(sol["f"]), nodes=ns)
        if ok:
            res.check = check = check_solution(self.dyn, prob, params, ns, params.step_duration)
            if check.passed:
                res.gait = self._gait(params, beta, ns, res)
            else:
                res.success, res.status = False, "Physics_Check_Failed"
                res.reason = "physics check failed: " + "; ".join(check.failures)
        return res

    def _gait(self, params: GaitParams, beta: FloatArray, ns: NodeStates, res: GaitGenResult) -> Gait:
        robot = self.robot
        q0, v0 = to_mujoco_state(robot, ns.H[0], ns.s[0], ns.vb[0], ns.sd[0])
        q1, v1 = to_mujoco_state(robot, ns.H[-1], ns.s[-1], ns.vb[-1], ns.sd[-1])
        solver = {"status": res.status, "iterations": res.iterations, "solve_seconds": res.solve_seconds,
                  "build_seconds": self.build_seconds, "objective": res.objective, "nodes": len(ns.s),
                  "variables": self.n_variables, "constraints": self.n_constraints,
                  "physics_check": res.check.to_dict() if res.check else None}
        return Gait(robot=robot.name, domain_graph="flat", stance=self.problem.stance, joints=robot.spec.joints,
                    domains=(Domain("single_support", params.step_duration, beta, self.problem.taus.copy(),
                                    ns.u.copy()),),
                    initial_state=State(q0, v0), pre_impact_state=State(q1, v1), params=params, solver=solver,
                    meta={"source": "robustgait gaitgen (flat-foot HZD)"})


def generate_gait(robot: Robot, step_length: float = 0.15, step_duration: float = 0.7, step_width: float = 0.25,
                  step_height: float = 0.07, *, warm_start: Gait | None = None, generator: GaitGenerator | None = None,
                  config: GaitGenConfig | None = None, verbose: bool = False) -> GaitGenResult:
    """One gait from raw essential constraints: parameters out of bounds give a failed result (never an
    exception). Pass a ``generator`` to reuse its built problem across calls."""
    try:
        params = GaitParams(step_length, step_duration, step_width, step_height)
    except RobustGaitError as exc:
        return GaitGenResult(success=False, status="Infeasible_Parameters", reason=str(exc), params=None)
    gen = generator or GaitGenerator(robot, config, verbose=verbose)
    return gen.solve(params, warm_start)
