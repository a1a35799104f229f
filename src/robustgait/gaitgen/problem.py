"""Flat-foot HZD gait optimization (DESIGN §4): one domain, stance sole flat, rigid impact, mirrored period.

Formulation (time-based phase τ = t/T on N nodes τ_i = i/(N−1); mixed velocity coordinates of adam):

* Outputs: the actuated joints *are* the Bézier polynomials (partial HZD, y ≡ 0):
  s(τ) = β b(τ), ṡ = β b'(τ)/T, s̈ = β b''(τ)/T², β ∈ R^{m×8} the shared decision variable.
* Per node: base pose (p, roll-pitch-yaw), base velocity ν_b = (ṗ, ω) and acceleration ν̇_b, torques u and
  the stance contact wrench λ = (f, n) (world axes, at the stance sole frame). Constraints:
  stance sole frame at the origin with identity orientation (position level), J_st ν = 0 (velocity level),
  J_st ν̇ + J̇_st ν = 0 (acceleration level) — with a flat foot and Bézier joints the state is fixed by
  kinematics, so nothing is integrated — and the equations of motion M(q) ν̇ + h(q, ν) = B u + J_stᵀ λ.
* Contact: f_z ≥ f_min, friction pyramid |f_x|, |f_y| ≤ μ f_z, centre of pressure inside the sole with a
  margin, |n_z| ≤ μ_t f_z. Limits: joint range (on β: the convex hull property bounds the whole curve),
  torque limits, base roll/pitch.
* Swing foot: flat landing at (L, ±W, 0) at τ = 1 (step length L, step width W), height h at τ = ½ and ≤ h
  everywhere, toe and heel above the ground, sole tilt bounded, feet apart laterally, descent velocity at
  the guard within bounds (touchdown margin for MuJoCo's soft contact).
* Impact at τ = 1 (rigid, the landing sole becomes the stance): M (ν⁺ − ν⁻) = J_swᵀ Λ, J_sw ν⁺ = 0,
  Λ_z ≥ 0 inside the friction pyramid, the old stance sole leaves the ground (its ż⁺ ≥ 0).
* Periodicity after relabeling: β[:, 0] = R β[:, 7] (positions) and ṡ(0) = R ṡ⁺ (velocities), R the spec's
  mirror (permutation and signs). Base pose and velocity at τ = 0 then follow from the stance constraint,
  and the landing pose from periodicity — so they are not imposed again (redundant rows break LICQ).
* Cost ∫‖u‖² dt (trapezoid on the nodes). Scaling: torques /100, wrenches /1000, dynamics rows /100.

The essential constraints (L, T, W, h) are NLP *parameters*: the problem is built once per robot and reused.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any

import casadi as cs
import numpy as np
from numpy.typing import NDArray

from robustgait.bezier import bernstein_basis, bezier_derivative_coeffs
from robustgait.dynamics import Dynamics, foot_frame
from robustgait.errors import RobustGaitError
from robustgait.gait import BEZIER_DEGREE
from robustgait.robots.spec import GaitQuality, Robot

FloatArray = NDArray[np.float64]
U_SCALE = 100.0
F_SCALE = 1000.0
ROW_SCALE = 100.0


@dataclass(frozen=True)
class GaitGenConfig:
    """Options of the flat-foot problem (besides the :class:`~robustgait.gait.GaitParams`).

    nodes: collocation nodes (odd, so that τ = ½ is a node); stance: the leg the gait is written for;
    friction: μ of the friction pyramid (below the simulator's 1.0 for margin); torsional_friction: μ_t;
    min_normal_force [N]; cop_margin [m] inside the sole edges; impact_velocity: bounds on the swing sole's
    vertical velocity at the guard [m/s]; max_impact_tangential [m/s]; max_impact_angular [rad/s]: bound on
    each component of the swing sole's angular velocity at the guard; flat_approach: every corner of the
    swing sole stays at least this fraction of the sole centre's height above the ground (a foot near the
    ground is nearly flat, so touchdown is not a corner grazing early); foot_gap [m]: lateral clearance
    between the soles' edges; max_iter, tol: IPOPT.

    Gait quality (``None`` = the robot spec's ``[gait_quality]``, see
    :class:`~robustgait.robots.spec.GaitQuality`): pelvis_roll, pelvis_yaw [rad] (|·| ≤), pelvis_pitch
    [rad] (band), pelvis_height [m] (band above the stance sole), pelvis_angular_velocity [rad/s] (each
    component), swing_tilt [rad] (swing sole roll/pitch), swing_yaw [rad], joint_velocity [rad/s] (one value
    for every joint or one per joint).
    """

    nodes: int = 17
    stance: str = "right"
    friction: float = 0.6
    torsional_friction: float = 0.02
    min_normal_force: float = 50.0
    cop_margin: float = 0.02
    impact_velocity: tuple[float, float] = (-0.4, -0.05)
    max_impact_tangential: float = 0.15
    max_impact_angular: float = 0.5
    flat_approach: float = 0.5
    foot_gap: float = 0.02
    max_iter: int = 300
    tol: float = 1e-8
    pelvis_roll: float | None = None
    pelvis_yaw: float | None = None
    pelvis_pitch: tuple[float, float] | None = None
    pelvis_height: tuple[float, float] | None = None
    pelvis_angular_velocity: float | None = None
    swing_tilt: float | None = None
    swing_yaw: float | None = None
    joint_velocity: float | tuple[float, ...] | None = None

    def quality(self, robot: Robot) -> GaitQuality:
        """The gait-quality bounds in force: the spec's, with this config's non-None fields on top."""
        base = robot.spec.gait_quality
        jv = self.joint_velocity
        if jv is not None:
            jv = (float(jv),) * robot.n_joints if isinstance(jv, (int, float)) else tuple(map(float, jv))
            if len(jv) != robot.n_joints:
                raise RobustGaitError(f"joint_velocity needs 1 or {robot.n_joints} values, got {len(jv)}")
        over: dict[str, Any] = {k: v for k, v in (("pelvis_roll", self.pelvis_roll), ("pelvis_yaw", self.pelvis_yaw),
                                  ("pelvis_pitch", self.pelvis_pitch), ("pelvis_height", self.pelvis_height),
                                  ("pelvis_angular_velocity", self.pelvis_angular_velocity),
                                  ("swing_tilt", self.swing_tilt), ("swing_yaw", self.swing_yaw),
                                  ("joint_velocity", jv)) if v is not None}
        q = replace(base, **over)
        if not q.joint_velocity:
            q = replace(q, joint_velocity=(10.0,) * robot.n_joints)
        return q


def rpy_to_matrix(rpy: cs.SX | cs.DM) -> cs.SX | cs.DM:
    """R = R_z(ψ) R_y(θ) R_x(φ) for rpy = (φ, θ, ψ) (roll, pitch, yaw; ZYX Euler angles)."""
    cr, sr = cs.cos(rpy[0]), cs.sin(rpy[0])
    cp, sp = cs.cos(rpy[1]), cs.sin(rpy[1])
    cy, sy = cs.cos(rpy[2]), cs.sin(rpy[2])
    return cs.vertcat(
        cs.horzcat(cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr),
        cs.horzcat(sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr),
        cs.horzcat(-sp, cp * sr, cp * cr),
    )


def matrix_to_rpy(r: FloatArray) -> FloatArray:
    """Inverse of :func:`rpy_to_matrix` (pitch in (−π/2, π/2))."""
    return np.array([math.atan2(r[2, 1], r[2, 2]), -math.asin(max(-1.0, min(1.0, r[2, 0]))),
                     math.atan2(r[1, 0], r[0, 0])])


def sole_half_extents(dyn: Dynamics, side: str) -> tuple[float, float]:
    """(half length, half width) [m] of a box sole: its largest and middle half sizes."""
    m = dyn.robot.model
    size = np.sort(m.geom_size[dyn.robot.sole_geom_id[side]])
    return float(size[2]), float(size[1])


@dataclass
class Layout:
    """Where each block of variables sits in the NLP vector x (scaled units)."""

    m: int
    n: int
    beta: slice
    nodes: list[dict[str, slice]]
    nu_plus: slice
    impulse: slice
    size: int


def make_layout(m: int, n_nodes: int) -> Layout:
    k = 0

    def take(size: int) -> slice:
        nonlocal k
        s = slice(k, k + size)
        k += size
        return s

    beta = take(m * (BEZIER_DEGREE + 1))
    nodes = [{"s": take(m), "sd": take(m), "sdd": take(m), "p": take(3), "rpy": take(3), "vb": take(6),
              "ab": take(6), "u": take(m), "lam": take(6)} for _ in range(n_nodes)]
    nu_plus = take(6 + m)
    impulse = take(6)
    return Layout(m, n_nodes, beta, nodes, nu_plus, impulse, k)


class FlatFootProblem:
    """The NLP, built once for a robot (and stance), solved for any essential constraints."""

    def __init__(self, dyn: Dynamics, config: GaitGenConfig):
        self.dyn, self.config = dyn, config
        robot = dyn.robot
        self.quality = quality = config.quality(robot)
        if config.nodes < 5 or config.nodes % 2 == 0:
            raise ValueError("nodes must be odd and ≥ 5")
        self.m = m = robot.n_joints
        self.n = n = config.nodes
        self.taus = np.linspace(0.0, 1.0, n)
        self.layout = lay = make_layout(m, n)
        st, sw = config.stance, "left" if config.stance == "right" else "right"
        self.stance, self.swing = st, sw
        self.half_length, self.half_width = sole_half_extents(dyn, st)
        self.mirror = np.zeros((m, m))
        self.mirror[np.arange(m), list(robot.spec.mirror_perm)] = robot.spec.mirror_sign
        kd = dyn.kindyn
        fk_st = dyn.frame_fun(foot_frame(st, "sole"))
        fk_sw = {"sole": dyn.frame_fun(foot_frame(sw, "sole"))}
        j_st, j_sw = kd.jacobian_fun(foot_frame(st, "sole")), kd.jacobian_fun(foot_frame(sw, "sole"))
        jd_st = kd.jacobian_dot_fun(foot_frame(st, "sole"))
        mass, bias = dyn.mass_matrix_fun, dyn.bias_force_fun
        arm = np.zeros(6 + m)
        arm[6:] = dyn.armature[robot.dof_idx]

        x = cs.SX.sym("x", lay.size)
        p = cs.SX.sym("p", 4)  # step length, duration, width, height
        L, T, W, h = p[0], p[1], p[2], p[3]
        beta = cs.reshape(x[lay.beta], m, BEZIER_DEGREE + 1)
        b0 = bernstein_basis(BEZIER_DEGREE, self.taus)  # (n, 8)
        b1 = bernstein_basis(BEZIER_DEGREE - 1, self.taus)
        b2 = bernstein_basis(BEZIER_DEGREE - 2, self.taus)
        d1 = bezier_derivative_coeffs(np.eye(BEZIER_DEGREE + 1), 1)  # (8, 7): β d1 = first-derivative coeffs
        d2 = bezier_derivative_coeffs(np.eye(BEZIER_DEGREE + 1), 2)
        side_sign = 1.0 if sw == "left" else -1.0
        g: list[cs.SX] = []
        lbg: list[float] = []
        ubg: list[float] = []
        self.rows: dict[str, list[int]] = {}

        def add(name: str, expr: cs.SX, lo: float | list[float], hi: float | list[float]) -> None:
            e = cs.vec(expr)
            start = sum(int(gi.numel()) for gi in g)
            self.rows.setdefault(name, []).extend(range(start, start + int(e.numel())))
            g.append(e)
            lbg.extend(np.broadcast_to(lo, (int(e.numel()),)).tolist())
            ubg.extend(np.broadcast_to(hi, (int(e.numel()),)).tolist())

        mu, mut = config.friction, config.torsional_friction
        ax, ay = self.half_length - config.cop_margin, self.half_width - config.cop_margin
        cost = 0.0
        wts = np.full(n, 1.0 / (n - 1))
        wts[[0, -1]] *= 0.5
        for i, node in enumerate(lay.nodes):
            # the joints are node variables tied to β by linear rows: the nonlinear dynamics then stay local
            # to a node and the Lagrangian's Hessian block-diagonal (≈ 3× faster to build and evaluate)
            s, sd, sdd = x[node["s"]], x[node["sd"]], x[node["sdd"]]
            add("bezier", cs.vertcat(s - cs.mtimes(beta, cs.DM(b0[i])), sd * T - cs.mtimes(beta, cs.DM(d1 @ b1[i])),
                                     sdd * T**2 - cs.mtimes(beta, cs.DM(d2 @ b2[i]))), 0.0, 0.0)
            pb, rpy, vb, ab = x[node["p"]], x[node["rpy"]], x[node["vb"]], x[node["ab"]]
            u, lam = U_SCALE * x[node["u"]], F_SCALE * x[node["lam"]]
            H = cs.vertcat(cs.horzcat(rpy_to_matrix(rpy), pb), cs.horzcat(cs.SX.zeros(1, 3), cs.SX.ones(1, 1)))
            nu = cs.vertcat(vb, sd)
            Hst = fk_st(H, s)
            add("stance_position", Hst[:3, 3], 0.0, 0.0)
            add("stance_orientation", cs.vertcat(Hst[1, 0], Hst[2, 0], Hst[2, 1]), 0.0, 0.0)
            J = j_st(H, s)
            add("stance_velocity", J @ nu, 0.0, 0.0)
            add("stance_acceleration", J @ cs.vertcat(ab, sdd) + jd_st(H, s, vb, sd) @ nu, 0.0, 0.0)
            M = mass(H, s) + cs.diag(arm)
            tau = cs.vertcat(cs.SX.zeros(6), u)
            dyn_res = M @ cs.vertcat(ab, sdd) + bias(H, s, vb, sd) - tau - J.T @ lam
            add("dynamics", dyn_res / ROW_SCALE, 0.0, 0.0)
            f, tq = lam[:3], lam[3:]
            add("normal_force", f[2], config.min_normal_force, cs.inf)
            add("friction", cs.vertcat(f[0] - mu * f[2], -f[0] - mu * f[2], f[1] - mu * f[2], -f[1] - mu * f[2]),
                -cs.inf, 0.0)
            add("cop", cs.vertcat(-tq[1] - ax * f[2], tq[1] - ax * f[2], tq[0] - ay * f[2], -tq[0] - ay * f[2]),
                -cs.inf, 0.0)
            add("yaw_moment", cs.vertcat(tq[2] - mut * f[2], -tq[2] - mut * f[2]), -cs.inf, 0.0)
            Hsw = fk_sw["sole"](H, s)
            psw = Hsw[:3, 3]
            if 0 < i < n - 1:
                add("swing_height", cs.vertcat(psw[2], psw[2] - h), [0.0, -cs.inf], [cs.inf, 0.0])
                corners = cs.vertcat(*(psw[2] + sx * self.half_length * Hsw[2, 0] + sy * self.half_width * Hsw[2, 1]
                                       for sx in (-1, 1) for sy in (-1, 1)))
                add("swing_flat_approach", corners - config.flat_approach * psw[2], 0.0, cs.inf)
                add("swing_tilt", cs.vertcat(Hsw[2, 0], Hsw[2, 1]), -math.sin(quality.swing_tilt),
                    math.sin(quality.swing_tilt))
                add("swing_yaw", Hsw[1, 0], -math.sin(quality.swing_yaw), math.sin(quality.swing_yaw))
                add("feet_apart", side_sign * psw[1] - (2 * self.half_width + config.foot_gap), 0.0, cs.inf)
            if i == (n - 1) // 2:
                add("step_height", psw[2] - h, 0.0, 0.0)
            if i == n - 1:
                add("landing_position", psw - cs.vertcat(L, side_sign * W, 0.0), 0.0, 0.0)
                add("landing_orientation", cs.vertcat(Hsw[1, 0], Hsw[2, 0], Hsw[2, 1]), 0.0, 0.0)
                Jsw = j_sw(H, s)
                vsw = Jsw[:3, :] @ nu
                add("impact_velocity", vsw[2], *config.impact_velocity)
                add("impact_tangential", vsw[:2], -config.max_impact_tangential, config.max_impact_tangential)
                add("impact_angular", Jsw[3:, :] @ nu, -config.max_impact_angular, config.max_impact_angular)
                nup = x[lay.nu_plus]
                imp = U_SCALE * x[lay.impulse]
                add("impact_map", (M @ (nup - nu) - Jsw.T @ imp) / ROW_SCALE, 0.0, 0.0)
                add("impact_contact", Jsw @ nup, 0.0, 0.0)
                add("impact_impulse", cs.vertcat(imp[2], mu * imp[2] - imp[0], mu * imp[2] + imp[0],
                                                  mu * imp[2] - imp[1], mu * imp[2] + imp[1]), 0.0, cs.inf)
                add("liftoff", (J @ nup)[2], 0.0, cs.inf)
                sd0 = x[lay.nodes[0]["sd"]]
                add("velocity_periodicity", sd0 - cs.mtimes(cs.DM(self.mirror), nup[6:]), 0.0, 0.0)
            cost = cost + wts[i] * cs.sumsqr(x[node["u"]])
        add("position_periodicity", beta[:, 0] - cs.mtimes(cs.DM(self.mirror), beta[:, BEZIER_DEGREE]), 0.0, 0.0)
        self.g = cs.vertcat(*g)
        self.lbg, self.ubg = np.array(lbg), np.array(ubg)
        self.x, self.p = x, p
        self.cost = cost * T
        self.lbx, self.ubx = self._bounds()

    def _bounds(self) -> tuple[FloatArray, FloatArray]:
        """Variable bounds: joint range on β, torque limits, and the gait-quality bands on the node variables
        (pelvis roll-pitch-yaw and height relative to the stance sole, its angular velocity, joint speeds)."""
        lay, robot, q = self.layout, self.dyn.robot, self.quality
        lo, hi = np.full(lay.size, -np.inf), np.full(lay.size, np.inf)
        rng = robot.joint_range
        lo[lay.beta] = np.repeat(rng[:, :1], BEZIER_DEGREE + 1, axis=1).ravel(order="F")
        hi[lay.beta] = np.repeat(rng[:, 1:], BEZIER_DEGREE + 1, axis=1).ravel(order="F")
        rpy_lo = np.array([-q.pelvis_roll, q.pelvis_pitch[0], -q.pelvis_yaw])
        rpy_hi = np.array([q.pelvis_roll, q.pelvis_pitch[1], q.pelvis_yaw])
        jv = np.asarray(q.joint_velocity)
        for node in lay.nodes:
            lo[node["u"]], hi[node["u"]] = -robot.torque_limit / U_SCALE, robot.torque_limit / U_SCALE
            lo[node["rpy"]], hi[node["rpy"]] = rpy_lo, rpy_hi
            z = node["p"].start + 2
            lo[z], hi[z] = q.pelvis_height
            w = slice(node["vb"].start + 3, node["vb"].stop)
            lo[w], hi[w] = -q.pelvis_angular_velocity, q.pelvis_angular_velocity
            lo[node["sd"]], hi[node["sd"]] = -jv, jv
        return lo, hi
