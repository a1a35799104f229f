"""HZD gait optimization (docs/design.md §4) over a domain graph (:mod:`robustgait.domains`): ``flat`` — one domain,
stance sole flat, rigid impact, mirrored period — or ``multicontact`` — single support, heel strike, rolling
double support on the stance toe and swing heel lines, foot-flat and toe-off, mirrored period.

Formulation (per domain, time-based phase τ = t/T_d on N_d nodes τ_i = i/(N_d−1); mixed velocity
coordinates of adam):

* Outputs: the actuated joints *are* the domain's Bézier polynomials (partial HZD, y ≡ 0):
  s(τ) = β_d b(τ), ṡ = β_d b'(τ)/T_d, s̈ = β_d b''(τ)/T_d², β_d ∈ R^{m×8}.
* Per node: base pose (p, roll-pitch-yaw), base velocity ν_b = (ṗ, ω) and acceleration ν̇_b, torques u and
  the contact wrenches λ (world axes, at the contact frames). Each contact is held at position, velocity and
  acceleration level — flat sole: its frame at a fixed point with fixed orientation; toe/heel line: the
  edge's midpoint fixed and its direction along world y (pitch free) — and the equations of motion
  M(q) ν̇ + h(q, ν) = B u + J_cᵀ λ hold. With flat single support and Bézier joints the state is fixed by
  kinematics, so nothing is integrated; double support closes a kinematic loop through both legs.
* Line feet (a robot whose soles are lines; flat graph): the soles stand on their lines (``line`` contacts, 5 rows,
  no roll moment), and the stance foot's roll — the one degree of freedom the joints leave — is integrated node to
  node (:mod:`.linefoot`); the swing foot lands free to roll, the next step starting from its roll mirrored.
* Contact wrenches (:func:`wrench_rows`): normal force, friction pyramid, centre of pressure inside the sole
  (or along the edge), yaw moment. Limits: joint range (on β: the convex hull property bounds the whole
  curve), torque limits, joint speeds, and the gait-quality bands on the pelvis (roll, pitch, yaw, height,
  angular velocity).
* Swing foot in single support: height h at τ = ½ and ≤ h everywhere, corners above the ground, sole tilt
  and yaw bounded, feet apart laterally; it lands flat at (L, ±W, 0) (flat graph) or strikes heel first,
  toe up by the heel-strike pitch, with its heel edge at (L − a, ±W, 0) (multi-contact); its velocity at the
  guard is bounded (touchdown margin for MuJoCo's soft contact). Double support ends with the front sole
  flat (a gentle foot-flat: bounded pitch rate) and the back sole pitched toe-down by the toe-off pitch.
* Impacts at the end of each domain (rigid, :func:`robustgait.dynamics.impact_residual`) onto the next
  domain's contacts: M (ν⁺ − ν⁻) = Jᵀ Λ, J ν⁺ = 0, Λ pushing inside the friction pyramid; a leaving contact
  lifts off (ż⁺ ≥ 0). The next domain starts from the post-impact state (continuity of joints through β,
  base pose, velocity; its contact rows at that node are then implied and not imposed again).
* Periodicity after relabeling: β_0[:, 0] = R β_last[:, 7] (positions) and ṡ_0(0) = R ṡ⁺ (velocities), R
  the spec's mirror (permutation and signs). Base pose and velocity at τ = 0 then follow from the stance
  constraint, and the landing pose from periodicity — so they are not imposed again (redundant rows break
  LICQ).
* Cost Σ_d ∫‖u‖² dt (trapezoid on the nodes). Scaling: torques /100, wrenches /1000, dynamics rows /100.

The essential constraints (L, T, W, h) and the rolling fraction ρ (double support lasts ρ T) are NLP
*parameters*: the problem is built once per robot and domain graph and reused.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any

import casadi as cs
import numpy as np
from numpy.typing import NDArray

from robustgait.bezier import bernstein_basis, bezier_derivative_coeffs
from robustgait.config import GenerationConfig
from robustgait.config.gait import PELVIS_RATE_FROUDE
from robustgait.domains import Contact, domain_graph, on_line_feet, other_side
from robustgait.dynamics import Dynamics, foot_frame, impact_residual
from robustgait.errors import RobustGaitError
from robustgait.gait import BEZIER_DEGREE
from robustgait.gaitgen.layout import (  # noqa: F401 (re-exported: the problem's layout and rows)
    DomainLayout,
    Layout,
    double_support_free_joints,
    impulse_rows,
    inner_range,
    make_layout,
    trapezoid_weights,
    wrench_rows,
)
from robustgait.gaitgen.linefoot import roll_collocation, roll_periodicity, roll_rows
from robustgait.gaitgen.springs import spring_collocation, spring_mirror
from robustgait.robots import GaitQuality, Robot

FloatArray = NDArray[np.float64]
U_SCALE = 100.0
F_SCALE = 1000.0
ROW_SCALE = 100.0


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


def swing_toe_down(swing_tilt: float, toe_off_pitch: float, until: float, tau: float) -> float:
    """Largest toe-down pitch [rad] of the swing sole at phase τ of multi-contact single support:
    max(swing_tilt, θ_off (1 − τ / τ_u)) with θ_off the toe-off pitch bound and τ_u the robot's
    ``swing_toe_down_until`` (:class:`~robustgait.robots.spec.GaitQuality`; τ_u = 0: swing_tilt throughout).
    The sole leaves toe-off toe-down; held within swing_tilt from the first node, Atalante's had to snap
    flat and its heel grazed the ground (docs/gaitgen.md)."""
    if until <= 0.0:
        return swing_tilt
    return max(swing_tilt, toe_off_pitch * (1.0 - tau / until))


def gait_quality(robot: Robot) -> GaitQuality:
    """The robot spec's gait-quality bounds, with a joint-speed bound of 10 rad/s per joint and a pelvis rate bound of
    :data:`~robustgait.config.gait.PELVIS_RATE_FROUDE` √(g / l) when it sets none."""
    q = robot.spec.gait_quality
    if not q.joint_velocity:
        q = replace(q, joint_velocity=(10.0,) * robot.n_joints)
    if q.pelvis_angular_velocity is None:
        s = robot.scale
        q = replace(q, pelvis_angular_velocity=PELVIS_RATE_FROUDE * math.sqrt(s.gravity / s.leg_length))
    return q


@dataclass(frozen=True)
class NodeSymbols:
    """One node's NLP symbols, unscaled: joints s, ṡ, s̈ (n,) [rad, rad/s, rad/s²] — the m planned ones, then a closed
    chain's passive ones; base pose H (4 × 4, from the position p [m] and roll-pitch-yaw [rad]), velocity ν_b = (ṗ, ω)
    and acceleration ν̇_b (6,); ν = (ν_b, ṡ) (6 + n,); torques u (m,) [N m]; contact wrenches λ (the domain's contact
    rows) [N, N m]; loop forces λ_h (the loops' rows) [N or N m]."""

    s: cs.SX
    sd: cs.SX
    sdd: cs.SX
    pb: cs.SX
    rpy: cs.SX
    vb: cs.SX
    ab: cs.SX
    u: cs.SX
    lam: cs.SX
    H: cs.SX
    nu: cs.SX
    lamh: cs.SX


@dataclass(frozen=True)
class NodeRows:
    """The rows [start, stop) of g that node i of domain d adds (:meth:`GaitProblem._add_node`)."""

    d: int
    i: int
    start: int
    stop: int


class GaitProblem:
    """The NLP of a domain graph (``config.domains``), built once for a robot and stance, solved for any
    essential constraints. See the module docstring for the formulation.

    g's rows run over domains, then nodes (:meth:`_add_node` gives a node's order), then position periodicity;
    the order fixes the NLP, hence the solution."""

    def __init__(self, dyn: Dynamics, config: GenerationConfig):
        # robot-scaled options resolved (idempotent: GaitGenerator passes them resolved)
        self.dyn, self.config = dyn, config.for_robot(dyn.robot.scale, dyn.robot.spec.generation)
        self._set_domains()
        self._set_model_functions()
        self._declare_variables()
        self._g: list[cs.SX] = []
        self._lbg: list[float] = []
        self._ubg: list[float] = []
        self._n_rows = 0
        self._basis_symbols: tuple[cs.SX, cs.SX, cs.SX] | None = None
        self.rows: dict[str, list[int]] = {}
        self.node_rows: list[NodeRows] = []
        for d in range(len(self.graph)):
            for i in range(len(self.domain_taus[d])):
                start = self._n_rows
                self._add_node(d, i)
                self.node_rows.append(NodeRows(d, i, start, self._n_rows))
        self._add_position_periodicity()
        if self.line_feet:
            self._add_roll_collocation()
        if self.springs:
            self._add_spring_collocation()
        self.g = cs.vertcat(*self._g)
        self.lbg, self.ubg = np.array(self._lbg), np.array(self._ubg)
        self.cost = self._cost()
        self.lbx, self.ubx = self._bounds()

    def _set_domains(self) -> None:
        """The domain graph and its node grids (``config.nodes`` in single support, ``config.ds_nodes`` in each
        further domain), the NLP layout, stance and swing legs, each domain's Bézier outputs (all m joints in
        single support, all but the 4 :func:`double_support_free_joints` in double support), the stance sole's
        half extents [m] and the mirror R (m × m: permutation and signs)."""
        dyn, config, robot = self.dyn, self.config, self.dyn.robot
        self.graph = graph = domain_graph(config.domains)
        # line feet (docs/gaitgen.md, "Line feet"): the flat graph's soles stand on their lines, free to roll
        self.line_feet = graph.name == "flat" and all(robot.spec.feet.get(s) == "line" for s in ("left", "right"))
        if self.line_feet:
            self.graph = graph = on_line_feet(graph)
        self.quality = gait_quality(robot)
        self.m = m = robot.n_joints
        counts = [config.nodes] + [config.ds_nodes] * (len(graph) - 1)
        self.domain_taus = [np.linspace(0.0, 1.0, n) for n in counts]
        self.taus = self.domain_taus[0]
        self.n = counts[0]
        # a closed chain's passive joints and loop rows (robustgait.closure): node variables and forces
        self.n_passive = dyn.n_joints - m
        if dyn.loops and graph.name != "flat":
            raise RobustGaitError(f"{robot.name}: gait generation plans a robot with closed chains on flat feet only "
                                  f"(domains flat), not {graph.name}")
        self.n_loop = int(dyn.loop_fun.size1_out(0)) if dyn.loops else 0
        # compliant springs (dyn.springs): their indices among the joints and the mirror's partner and sign of each
        self.springs = [sp.index for sp in dyn.springs]
        self.spring_mirror = spring_mirror(dyn) if dyn.springs else []
        self.layout = make_layout(
            m, counts, [sum(c.n_rows for c in dom.contacts) for dom in graph.domains],
            [sum(c.n_rows for c in graph.target_contacts(d)) for d in range(len(graph))], self.n_passive, self.n_loop,
            3 if self.line_feet else 0)
        st, sw = config.stance, other_side(config.stance)
        self.stance, self.swing = st, sw
        self.free = (double_support_free_joints(robot, sw, config.ds_free_joints) if graph.name == "multicontact"
                     else [])
        # the Bézier outputs of each domain: every joint in single support, all but the free ones in double
        self.outputs = [list(range(m)) if dom.guard == "touchdown" else [j for j in range(m) if j not in self.free]
                        for dom in graph.domains]
        sole = dyn.robot.sole_boxes[st]
        self.half_length, self.half_width = sole.half_length, sole.half_width
        self.mirror = np.zeros((m, m))
        self.mirror[np.arange(m), list(robot.spec.mirror_perm)] = robot.spec.mirror_sign

    def _set_model_functions(self) -> None:
        """CasADi functions of the model, each of (H, s) and, for J̇ and the bias, (ν_b, ṡ): the pose (4 × 4),
        Jacobian (6 × (6 + m)) and its time derivative of the sole, toe and heel frames of both feet; the mass
        matrix with armature (:meth:`~robustgait.dynamics.Dynamics.inertia`) and bias forces."""
        dyn, st, sw = self.dyn, self.stance, self.swing
        frames = {(side, kind): foot_frame(side, kind) for side in (st, sw) for kind in ("sole", "toe", "heel")}
        self._fk: dict[tuple[str, str], Any] = {key: dyn.frame_fun(f) for key, f in frames.items()}
        self._jac: dict[tuple[str, str], Any] = {key: dyn.jacobian_fun(f) for key, f in frames.items()}
        self._jdot: dict[tuple[str, str], Any] = {key: dyn.jacobian_dot_fun(f) for key, f in frames.items()}
        self._mass, self._bias = dyn.inertia, dyn.bias_force_fun

    def _declare_variables(self) -> None:
        """The decision variables x (``layout.size``; torques and impulses /100, wrenches /1000), parameters p = (L
        [m], T [s], W [m], h [m], ρ): step length, duration, width, height, rolling fraction; per domain T_d (T, or
        T (1 − ρ), T ρ), β_d (m × 8) from x, Bernstein bases (N_d × 8, × 7, × 6); maps d1 (8 × 7), d2 (8 × 6)."""
        self.x = x = cs.SX.sym("x", self.layout.size)
        self.p = p = cs.SX.sym("p", 5)  # step length, duration, width, height, rolling fraction
        self._length, T, self._width, self._height, rho = p[0], p[1], p[2], p[3], p[4]
        self._durations = [T] if len(self.graph) == 1 else [T * (1 - rho), T * rho]
        self.n_params = 5
        self._d1 = bezier_derivative_coeffs(np.eye(BEZIER_DEGREE + 1), 1)  # (8, 7): β d1 = first-derivative coeffs
        self._d2 = bezier_derivative_coeffs(np.eye(BEZIER_DEGREE + 1), 2)
        self._side_sign = 1.0 if self.swing == "left" else -1.0
        self._multi = self.graph.name == "multicontact"
        self._betas = [cs.reshape(x[dl.beta], self.m, BEZIER_DEGREE + 1) for dl in self.layout.domains]
        self._bases = [tuple(bernstein_basis(BEZIER_DEGREE - k, taus) for k in range(3)) for taus in self.domain_taus]

    def _add(self, name: str, expr: cs.SX, lo: float | list[float], hi: float | list[float]) -> None:
        """Append the rows lo ≤ vec(expr) ≤ hi to g (bounds broadcast) and record their indices under ``name``."""
        e = cs.vec(expr)
        start, self._n_rows = self._n_rows, self._n_rows + int(e.numel())
        self.rows.setdefault(name, []).extend(range(start, self._n_rows))
        self._g.append(e)
        self._lbg.extend(np.broadcast_to(lo, (int(e.numel()),)).tolist())
        self._ubg.extend(np.broadcast_to(hi, (int(e.numel()),)).tolist())

    def _node_symbols(self, d: int, i: int) -> NodeSymbols:
        """Node i of domain d's symbols (:class:`NodeSymbols`), torques and wrenches unscaled (×100, ×1000)."""
        node, x = self.layout.domains[d].nodes[i], self.x
        pb, rpy, vb = x[node["p"]], x[node["rpy"]], x[node["vb"]]
        s, sd, sdd = (cs.vertcat(x[node[k]], x[node[k.replace("s", "sp", 1)]]) if self.n_passive else x[node[k]]
                      for k in ("s", "sd", "sdd"))
        H = cs.vertcat(cs.horzcat(rpy_to_matrix(rpy), pb), cs.horzcat(cs.SX.zeros(1, 3), cs.SX.ones(1, 1)))
        return NodeSymbols(s=s, sd=sd, sdd=sdd, pb=pb, rpy=rpy, vb=vb, ab=x[node["ab"]],
                           u=U_SCALE * x[node["u"]], lam=F_SCALE * x[node["lam"]], H=H, nu=cs.vertcat(vb, sd),
                           lamh=U_SCALE * x[node["lamh"]])

    def _add_node(self, d: int, i: int) -> None:
        """All rows of node i of domain d, in this order: Bézier outputs, continuity (first node of a later domain),
        holonomic contacts, dynamics, contact wrenches, the swing foot (single support), and at the domain's last
        node foot-flat (double support), the impact and velocity periodicity (last domain)."""
        dom, n = self.graph.domains[d], len(self.domain_taus[d])
        v = self._node_symbols(d, i)
        self._add_bezier_outputs(d, i, v)
        if d > 0 and i == 0:
            self._add_continuity(d, v)
        Jc = self._add_holonomic_contacts(d, i, v)
        if self.n_loop:
            self._add_loops(d, i, v)
        if self.line_feet:
            self._add_stance_roll(d, i, v)
        M = self._add_dynamics(v, Jc)
        self._add_contact_wrenches(d, v)
        if dom.guard == "touchdown":
            self._add_swing_foot(v, i, n)
        if i == n - 1:
            if dom.guard == "foot_flat":
                self._add_foot_flat(v)
            nup = self._add_impact(d, v, M)
            if d == len(self.graph) - 1:
                self._add_velocity_periodicity(nup)
            if self.line_feet:
                Hsw = self._fk[(self.swing, "sole")](v.H, v.s)
                first = self.x[self.layout.nodes[0]["roll"]][:2]
                self._add("roll_periodicity", roll_periodicity(first, Hsw[:3, :3], self._jac[(self.swing, "sole")](
                    v.H, v.s), nup), 0.0, 0.0)

    def node_kind(self, d: int, i: int) -> tuple[int, bool, bool, bool, bool]:
        """What node i of domain d's rows depend on besides its variables and its Bézier basis values — the
        branches of :meth:`_add_node`: its domain, and whether it is the first, an inner, the middle or the last
        node. Nodes of one kind add the same rows as functions of those (:meth:`node_function`)."""
        n = len(self.domain_taus[d])
        return d, i == 0, 0 < i < n - 1, i == (n - 1) // 2, i == n - 1

    def node_function(self, d: int, i: int, columns: list[int]) -> cs.Function:
        """Node i of domain d's rows of g, and its term of the cost without the trapezoid weight, as a function
        of the variables they depend on: (z, p, c) → (g_node, T_d ‖u_i‖²), z = x[columns] (the columns in
        increasing order), p the parameters, c the node's Bézier basis values (8 × 3, :meth:`node_basis`). Every
        other variable is zero in it, so ``columns`` must hold all those the rows depend on. The rows are built
        by :meth:`_add_node` itself, on these symbols."""
        z, c = cs.SX.sym("z", len(columns)), cs.SX.sym("c", BEZIER_DEGREE + 1, 3)
        x = cs.SX.zeros(self.layout.size)
        for k, j in enumerate(columns):
            x[j] = z[k]
        kept = (self.x, self._betas, self._basis_symbols, self._g, self._lbg, self._ubg, self.rows, self._n_rows)
        self.x, self._betas = x, [cs.reshape(x[dl.beta], self.m, BEZIER_DEGREE + 1) for dl in self.layout.domains]
        self._basis_symbols = (c[:, 0], c[:, 1], c[:, 2])
        self._g, self._lbg, self._ubg, self.rows, self._n_rows = [], [], [], {}, 0
        try:
            self._add_node(d, i)
            rows = cs.vertcat(*self._g)
        finally:
            (self.x, self._betas, self._basis_symbols, self._g, self._lbg, self._ubg, self.rows,
             self._n_rows) = kept
        cost = self._durations[d] * cs.sumsqr(x[self.layout.domains[d].nodes[i]["u"]])
        return cs.Function(f"node_{d}_{i}", [z, self.p, c], [rows, cost], ["z", "p", "c"], ["g", "cost"])

    def _add_bezier_outputs(self, d: int, i: int, v: NodeSymbols) -> None:
        """The virtual constraints (3 |O_d| rows, ``bezier``): the output joints O_d of domain d follow its Bézier
        polynomial at τ_i, s_O = β_O b(τ_i) [rad], ṡ_O T_d = β_O b'(τ_i) [rad], s̈_O T_d² = β_O b''(τ_i) [rad]
        (b' = d1 b₇, b'' = d2 b₆). The joints are node variables tied to β by these linear rows: the nonlinear
        dynamics then stay local to a node and the Lagrangian's Hessian block-diagonal."""
        out, Td = self.outputs[d], self._durations[d]
        # a node function's basis values are its input (:meth:`node_function`)
        c0, c1, c2 = self._basis_symbols or tuple(cs.DM(c) for c in self.node_basis(d, i).T)
        bo = self._betas[d][out, :]
        self._add("bezier", cs.vertcat(v.s[out] - cs.mtimes(bo, c0), v.sd[out] * Td - cs.mtimes(bo, c1),
                                       v.sdd[out] * Td**2 - cs.mtimes(bo, c2)), 0.0, 0.0)

    def node_basis(self, d: int, i: int) -> FloatArray:
        """The Bézier basis values of node i of domain d (8 × 3): columns b(τ_i), d1 b₇(τ_i), d2 b₆(τ_i), so that
        s = β c₀, ṡ T_d = β c₁, s̈ T_d² = β c₂ (:meth:`_add_bezier_outputs`)."""
        b0, b1, b2 = self._bases[d]
        return np.stack([b0[i], self._d1 @ b1[i], self._d2 @ b2[i]], axis=1)

    def _add_continuity(self, d: int, v: NodeSymbols) -> None:
        """The first node of domain d > 0 starts where domain d − 1 left (2m + 12 rows, ``continuity``): joints s,
        base position [m] and roll-pitch-yaw [rad] of its last node, and its post-impact velocity ν⁺ = (ν_b, ṡ).
        The contacts' pose and velocity then hold already and are not imposed again at this node."""
        x, prev = self.x, self.layout.domains[d - 1]
        last = prev.nodes[-1]
        s_last = cs.vertcat(x[last["s"]], x[last["sp"]]) if self.n_passive else x[last["s"]]
        self._add("continuity", cs.vertcat(v.s - s_last,
                                           v.pb - x[prev.nodes[-1]["p"]], v.rpy - x[prev.nodes[-1]["rpy"]],
                                           v.vb - x[prev.nu_plus][:6], v.sd - x[prev.nu_plus][6:]), 0.0, 0.0)

    def _contact_target(self, c: Contact) -> cs.SX:
        """Where contact c's frame is held (3,) [m], in the stance sole's frame: the stance sole's centre, toe
        (+a) or heel (−a) edge; the swing foot's sole at (L, ±W, 0) or heel edge at (L − a, ±W, 0)."""
        a_len, L = self.half_length, self._length
        if c.leg == "stance":
            return cs.SX([a_len if c.kind == "toe" else -a_len if c.kind == "heel" else 0.0, 0.0, 0.0])
        return cs.vertcat(L - a_len if c.kind == "heel" else L, self._side_sign * self._width, 0.0)

    def _add_holonomic_contacts(self, d: int, i: int, v: NodeSymbols) -> cs.SX:
        """Each contact c of domain d held (``<name>_position``, ``_orientation``, ``_velocity``,
        ``_acceleration``): its frame at :meth:`_contact_target` (3 rows [m]); flat: R[1,0] = R[2,0] = R[2,1] = 0,
        toe/heel line: R[0,1] = R[2,1] = 0 (edge along world y, pitch free), line foot: R[1,0] = R[2,0] = 0 (the foot
        along world x, roll free); J_c ν = 0 (6 or 5 rows); J_c ν̇ + J̇_c ν = 0, alone
        at a later domain's first node (:meth:`_add_continuity`). Returns J_c stacked (contact rows × (6 + m))."""
        st, H, s, nu = self.stance, v.H, v.s, v.nu
        Js = []
        for c in self.graph.domains[d].contacts:
            key = (c.side(st), c.frame_kind())
            Hc = self._fk[key](H, s)
            J = self._jac[key](H, s)[list(c.rows), :]
            name = "stance" if c.leg == "stance" and c.kind in ("flat", "line") else f"{c.leg}_{c.kind}"
            if not (d > 0 and i == 0):
                self._add(f"{name}_position", Hc[:3, 3] - self._contact_target(c), 0.0, 0.0)
                orient = (cs.vertcat(Hc[1, 0], Hc[2, 0], Hc[2, 1]) if c.kind == "flat"
                          else cs.vertcat(Hc[1, 0], Hc[2, 0]) if c.kind == "line" else cs.vertcat(Hc[0, 1], Hc[2, 1]))
                self._add(f"{name}_orientation", orient, 0.0, 0.0)
                self._add(f"{name}_velocity", J @ nu, 0.0, 0.0)
            self._add(f"{name}_acceleration",
                      J @ cs.vertcat(v.ab, v.sdd) + self._jdot[key](H, s, v.vb, v.sd)[list(c.rows), :] @ nu, 0.0, 0.0)
            Js.append(J)
        return cs.vertcat(*Js)

    def _add_loops(self, d: int, i: int, v: NodeSymbols) -> None:
        """The closed chains held (k rows each, :attr:`robustgait.dynamics.Dynamics.loop_fun`): φ(s) = 0 [m or rad]
        (``loop_position``), J_h ṡ = 0 (``loop_velocity``), J_h s̈ + J̇_h ṡ = 0 (``loop_acceleration``), the first two
        not at a later domain's first node (implied by :meth:`_add_continuity`), as the contacts are."""
        phi, vel, acc, _ = self.dyn.loop_fun(v.s, v.sd, v.sdd)
        if not (d > 0 and i == 0):
            self._add("loop_position", phi, 0.0, 0.0)
            self._add("loop_velocity", vel, 0.0, 0.0)
        self._add("loop_acceleration", acc, 0.0, 0.0)

    def _add_stance_roll(self, d: int, i: int, v: NodeSymbols) -> None:
        """On line feet, the node's stance-foot roll, rate and acceleration variables tied to the model (3 rows [rad,
        rad/s, rad/s²], ``stance_roll``; :func:`~robustgait.gaitgen.linefoot.roll_rows`)."""
        key = (self.stance, "sole")
        Hc = self._fk[key](v.H, v.s)
        self._add("stance_roll", roll_rows(self.x[self.layout.domains[d].nodes[i]["roll"]], Hc[:3, :3],
                                           self._jac[key](v.H, v.s), self._jdot[key](v.H, v.s, v.vb, v.sd), v.nu,
                                           cs.vertcat(v.ab, v.sdd)), 0.0, 0.0)

    def _add_roll_collocation(self) -> None:
        """On line feet, the stance foot's roll integrated node to node (2 (N − 1) rows [rad, rad/s],
        ``roll_collocation``; :func:`~robustgait.gaitgen.linefoot.roll_collocation`, h = T / (N − 1))."""
        nodes, h = self.layout.nodes, self._durations[0] / (self.n - 1)
        for k in range(self.n - 1):
            self._add("roll_collocation", roll_collocation(self.x[nodes[k]["roll"]], self.x[nodes[k + 1]["roll"]], h),
                      0.0, 0.0)

    def _add_spring_collocation(self) -> None:
        """Compliant springs integrated node to node (2 (N − 1) rows per spring [rad, rad/s], ``spring_collocation``,
        :func:`~robustgait.gaitgen.springs.spring_collocation`), h = T / (N − 1)."""
        h = self._durations[0] / (self.n - 1)
        rows = spring_collocation(self.x, self.layout.nodes[:self.n], self.springs, self.m, h)
        self._add("spring_collocation", rows, 0.0, 0.0)

    def _loop_jacobian(self, s: cs.SX) -> cs.SX:
        """The loops' Jacobian in adam's mixed velocities, [0, J_h(s)] (k × (6 + n)): the rows do not move with the
        base."""
        return cs.horzcat(cs.SX.zeros(self.n_loop, 6), self.dyn.loop_fun(s, s, s)[3])

    def _add_dynamics(self, v: NodeSymbols, Jc: cs.SX) -> cs.SX:
        """The equations of motion (6 + n rows [N, N m] / 100, ``dynamics``): (M(q) + diag(armature)) ν̇ + h(q, ν)
        = (0, u, 0) + J_cᵀ λ + J_hᵀ λ_h (J_h: :meth:`_loop_jacobian`; the passive joints have no torque). Returns
        the mass matrix with armature ((6 + n) × (6 + n)) for the impact."""
        M = self._mass(v.H, v.s)
        tau = cs.vertcat(cs.SX.zeros(6), v.u, cs.SX.zeros(self.n_passive))
        if self.springs:  # compliant springs: their torque −k (s − springref) − d ṡ on their joints
            tau = tau + cs.vertcat(cs.SX.zeros(6), self.dyn.spring_torque(v.s, v.sd))
        dyn_res = M @ cs.vertcat(v.ab, v.sdd) + self._bias(v.H, v.s, v.vb, v.sd) - tau - Jc.T @ v.lam
        if self.n_loop:
            dyn_res = dyn_res - self._loop_jacobian(v.s).T @ v.lamh
        self._add("dynamics", dyn_res / ROW_SCALE, 0.0, 0.0)
        return M

    def _add_contact_wrenches(self, d: int, v: NodeSymbols) -> None:
        """Each contact's wrench conditions (:func:`wrench_rows`: normal force, friction pyramid, centre of
        pressure, yaw moment; [N, N m]) on its slice of λ, contacts in domain order."""
        k = 0
        for c in self.graph.domains[d].contacts:
            for rname, expr, lo, hi in wrench_rows(c, v.lam[k:k + c.n_rows], self.config, self.half_length,
                                                   self.half_width):
                self._add(rname, expr, lo, hi)
            k += c.n_rows

    def _add_swing_foot(self, v: NodeSymbols, i: int, n: int) -> None:
        """The swing sole S in single support (p_S [m], R_S). Inner nodes: 0 ≤ z_S ≤ h, corners ≥ flat_approach z_S
        (0 multi-contact), R_S[2,0], R_S[2,1] (R_S[2,0] only on line feet) within the swing tilt (multi-contact: toe
        up to the heel-strike pitch, down per :func:`swing_toe_down`), |R_S[1,0]| ≤ sin(swing_yaw), ±y_S ≥ 2b +
        foot_gap. τ = ½: z_S = h. τ = 1: flat at (L, ±W, 0), R_S[1,0] = R_S[2,0] = R_S[2,1] = 0 (flat graph; line
        feet: roll free, R_S[2,1] not held) or heel edge at (L − a, ±W, 0),
        R_S[0,1] = R_S[2,1] = 0, R_S[2,0] within the heel-strike pitch (multi-contact); touchdown velocity bounded
        (vertical, tangential [m/s], angular [rad/s])."""
        config, quality, sw, multi = self.config, self.quality, self.swing, self._multi
        H, s, nu, h, side_sign = v.H, v.s, v.nu, self._height, self._side_sign
        Hsw = self._fk[(sw, "sole")](H, s)
        psw = Hsw[:3, 3]
        if 0 < i < n - 1:
            self._add("swing_height", cs.vertcat(psw[2], psw[2] - h), [0.0, -cs.inf], [cs.inf, 0.0])
            corners = cs.vertcat(*(psw[2] + sx * self.half_length * Hsw[2, 0] + sy * self.half_width * Hsw[2, 1]
                                   for sx in (-1, 1) for sy in (-1, 1)))
            # flat graph: the nearer the ground, the flatter the foot; multi-contact: heel first, any corner ≥ 0
            self._add("swing_flat_approach", corners - (0.0 if multi else config.flat_approach) * psw[2], 0.0, cs.inf)
            tilt = math.sin(quality.swing_tilt)
            # R[2, 0] = −sin(pitch): multi-contact lets the toe come up to the heel-strike pitch and, on robots
            # that ask for it, the foot leave toe-off toe-down
            pitch_hi = math.sin(config.heel_strike_pitch[1]) if multi else tilt
            pitch_lo = -math.sin(swing_toe_down(quality.swing_tilt, config.toe_off_pitch[1],
                                                quality.swing_toe_down_until, i / (n - 1))) if multi else -tilt
            if self.line_feet:  # a line has no edge to touch the ground when it rolls: its pitch only
                self._add("swing_tilt", Hsw[2, 0], pitch_lo, pitch_hi)
            else:
                self._add("swing_tilt", cs.vertcat(Hsw[2, 0], Hsw[2, 1]), [pitch_lo, -tilt], [pitch_hi, tilt])
            self._add("swing_yaw", Hsw[1, 0], -math.sin(quality.swing_yaw), math.sin(quality.swing_yaw))
            self._add("feet_apart", side_sign * psw[1] - (2 * self.half_width + config.scaled("foot_gap")), 0.0,
                      cs.inf)
        if i == (n - 1) // 2:
            self._add("step_height", psw[2] - h, 0.0, 0.0)
        if i == n - 1:
            L, W = self._length, self._width
            if not multi:
                self._add("landing_position", psw - cs.vertcat(L, side_sign * W, 0.0), 0.0, 0.0)
                roll = [] if self.line_feet else [Hsw[2, 1]]  # a line foot lands free to roll
                self._add("landing_orientation", cs.vertcat(Hsw[1, 0], Hsw[2, 0], *roll), 0.0, 0.0)
                Jsw = self._jac[(sw, "sole")](H, s)
                ang = Jsw[3:, :] @ nu
            else:
                Hh = self._fk[(sw, "heel")](H, s)
                self._add("landing_position", Hh[:3, 3] - cs.vertcat(L - self.half_length, side_sign * W, 0.0),
                          0.0, 0.0)
                self._add("landing_orientation", cs.vertcat(Hsw[0, 1], Hsw[2, 1]), 0.0, 0.0)
                self._add("heel_strike_pitch", Hsw[2, 0], math.sin(config.heel_strike_pitch[0]),
                          math.sin(config.heel_strike_pitch[1]))
                Jsw = self._jac[(sw, "heel")](H, s)
                ang = (Jsw[3:, :] @ nu)[[0, 2]]
            vsw = Jsw[:3, :] @ nu
            self._add("impact_velocity", vsw[2], *config.scaled("impact_velocity"))
            tangential = config.scaled("max_impact_tangential")
            self._add("impact_tangential", vsw[:2], -tangential, tangential)
            self._add("impact_angular", ang, -config.max_impact_angular, config.max_impact_angular)

    def _add_foot_flat(self, v: NodeSymbols) -> None:
        """The end of double support: the front (swing) sole flat, R[2,0] = 0 (``foot_flat``); the back (stance)
        sole toe-down, −R[2,0] = sin(pitch) within sin(toe_off_pitch) (``toe_off_pitch``); the front sole's pitch
        rate within ±foot_flat_rate [rad/s] (``foot_flat_rate``)."""
        config, st, sw, H, s = self.config, self.stance, self.swing, v.H, v.s
        Hf, Hb = self._fk[(sw, "sole")](H, s), self._fk[(st, "sole")](H, s)
        self._add("foot_flat", Hf[2, 0], 0.0, 0.0)
        self._add("toe_off_pitch", -Hb[2, 0], math.sin(config.toe_off_pitch[0]), math.sin(config.toe_off_pitch[1]))
        self._add("foot_flat_rate", (self._jac[(sw, "sole")](H, s) @ v.nu)[4], -config.foot_flat_rate,
                  config.foot_flat_rate)

    def _add_impact(self, d: int, v: NodeSymbols, M: cs.SX) -> cs.SX:
        """The rigid impact at the end of domain d onto the next domain's contacts (Jacobian J, impulse Λ [N s],
        :func:`robustgait.dynamics.impact_residual`): M (ν⁺ − ν⁻) = Jᵀ Λ (6 + m rows / 100, ``impact_map``),
        J ν⁺ = 0 (``impact_contact``), Λ inside the friction pyramid (:func:`impulse_rows`, ``impact_impulse``),
        and the leaving contact lifting off, ż⁺ ≥ 0 [m/s] (``liftoff``: the stance sole on the flat graph, the
        stance toe after double support). Returns ν⁺ (6 + m,)."""
        x, dl, dom, st = self.x, self.layout.domains[d], self.graph.domains[d], self.stance
        H, s, nu = v.H, v.s, v.nu
        target = self.graph.target_contacts(d)  # J: their Jacobian rows stacked (Σ rows × (6 + m))
        Jt = cs.vertcat(*(self._jac[(c.side(st), c.frame_kind())](H, s)[list(c.rows), :] for c in target))
        nup, imp = x[dl.nu_plus], U_SCALE * x[dl.impulse]
        if self.n_loop:  # the loops hold through the impact: their rows join the target contacts'
            Jt = cs.vertcat(Jt, self._loop_jacobian(s))
        momentum, contact = impact_residual(M, Jt, nu, nup, imp)
        self._add("impact_map", momentum / ROW_SCALE, 0.0, 0.0)
        self._add("impact_contact", contact, 0.0, 0.0)
        self._add("impact_impulse", impulse_rows(target, imp, self.config.friction), 0.0, cs.inf)
        if dom.guard == "touchdown" and not self._multi:
            self._add("liftoff", (self._jac[(st, "sole")](H, s) @ nup)[2], 0.0, cs.inf)
        elif dom.guard == "foot_flat":
            self._add("liftoff", (self._jac[(st, "toe")](H, s) @ nup)[2], 0.0, cs.inf)
        return nup

    def _add_velocity_periodicity(self, nup: cs.SX) -> None:
        """Joint velocities periodic after relabeling (m rows [rad/s], ``velocity_periodicity``): ṡ_0(0) = R ṡ⁺
        with ṡ⁺ the last domain's post-impact joint velocities."""
        sd0 = self.x[self.layout.domains[0].nodes[0]["sd"]]
        self._add("velocity_periodicity", sd0 - cs.mtimes(cs.DM(self.mirror), nup[6:6 + self.m]), 0.0, 0.0)
        if self.springs:  # compliant springs: ṡ_j(0) = σ ṡ⁺ of its partner
            spd0, m = self.x[self.layout.domains[0].nodes[0]["spd"]], self.m
            self._add("spring_velocity_periodicity",
                      cs.vertcat(*(spd0[j - m] - sign * nup[6 + k] for j, k, sign in self.spring_mirror)), 0.0, 0.0)

    def _add_position_periodicity(self) -> None:
        """Joint positions periodic after relabeling (m rows [rad], ``position_periodicity``): β_0[:, 0] =
        R β_0[:, 7] with one domain; otherwise s_0(0) = R s_last(1) through the node joints (the last domain's
        free joints are not Bézier outputs)."""
        lay, R = self.layout, cs.DM(self.mirror)
        if len(self.graph) == 1:
            self._add("position_periodicity", self._betas[0][:, 0] - cs.mtimes(R, self._betas[-1][:, BEZIER_DEGREE]),
                      0.0, 0.0)
        else:
            self._add("position_periodicity", self.x[lay.domains[0].nodes[0]["s"]]
                      - cs.mtimes(R, self.x[lay.domains[-1].nodes[-1]["s"]]), 0.0, 0.0)
        if self.springs:  # compliant springs: s_j(0) = σ s_k(1) of its partner k
            first, last, m = self.x[lay.domains[0].nodes[0]["sp"]], self.x[lay.domains[-1].nodes[-1]["sp"]], self.m
            self._add("spring_position_periodicity",
                      cs.vertcat(*(first[j - m] - sign * last[k - m] for j, k, sign in self.spring_mirror)), 0.0, 0.0)

    def _cost(self) -> Any:
        """The cost Σ_d T_d Σ_i w_i ‖u_i / 100‖² (scaled torques; trapezoid weights w on the nodes of domain d)."""
        cost: Any = 0.0
        for d, (dl, taus, Td) in enumerate(zip(self.layout.domains, self.domain_taus, self._durations, strict=True)):
            wts = trapezoid_weights(len(taus))
            domain_cost: Any = 0.0
            for i, node in enumerate(dl.nodes):
                domain_cost = domain_cost + wts[i] * cs.sumsqr(self.x[node["u"]])
            cost = domain_cost * Td if d == 0 else cost + domain_cost * Td
        return cost

    def _bounds(self) -> tuple[FloatArray, FloatArray]:
        """Variable bounds: joint range on β (less ``joint_margin``: :func:`inner_range`) and on a closed chain's
        passive joints, torque limits, and the gait-quality bands on the node variables (pelvis roll-pitch-yaw and
        height relative to the stance sole, its angular velocity, joint speeds)."""
        lay, robot, q = self.layout, self.dyn.robot, self.quality
        lo, hi = np.full(lay.size, -np.inf), np.full(lay.size, np.inf)
        rng = inner_range(robot.joint_range, self.config.scaled("joint_margin"))
        rpy_lo = np.array([-q.pelvis_roll, q.pelvis_pitch[0], -q.pelvis_yaw])
        rpy_hi = np.array([q.pelvis_roll, q.pelvis_pitch[1], q.pelvis_yaw])
        jv = np.asarray(q.joint_velocity)
        m = robot.model  # a closed chain's passive joints: their ranges
        prange = np.array([m.joint(j).range if m.joint(j).limited[0] else (-np.inf, np.inf)
                           for j in self.dyn.passive]).reshape(-1, 2)
        for dl, out in zip(lay.domains, self.outputs, strict=True):
            blo = np.repeat(rng[:, :1], BEZIER_DEGREE + 1, axis=1)
            bhi = np.repeat(rng[:, 1:], BEZIER_DEGREE + 1, axis=1)
            free = [j for j in range(robot.n_joints) if j not in out]
            blo[free], bhi[free] = 0.0, 0.0  # not outputs in this domain: unused, fixed (the gait file fits them)
            lo[dl.beta], hi[dl.beta] = blo.ravel(order="F"), bhi.ravel(order="F")
            for node in dl.nodes:
                js = np.arange(node["s"].start, node["s"].stop)[free]
                lo[js], hi[js] = rng[free, 0], rng[free, 1]
                lo[node["u"]], hi[node["u"]] = -robot.torque_limit / U_SCALE, robot.torque_limit / U_SCALE
                lo[node["rpy"]], hi[node["rpy"]] = rpy_lo, rpy_hi
                z = node["p"].start + 2
                lo[z], hi[z] = q.pelvis_height
                w = slice(node["vb"].start + 3, node["vb"].stop)
                rate = q.pelvis_angular_velocity
                assert rate is not None  # gait_quality() sets it
                lo[w], hi[w] = -rate, rate
                a = slice(node["ab"].start, node["ab"].start + 3)
                lo[a], hi[a] = -q.pelvis_acceleration, q.pelvis_acceleration
                lo[node["sd"]], hi[node["sd"]] = -jv, jv
                lo[node["sp"]], hi[node["sp"]] = prange[:, 0], prange[:, 1]
        return lo, hi
