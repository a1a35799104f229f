"""The gait NLP's variable layout and its contact-wrench and impulse rows (:mod:`.problem`): where each domain's
Bézier coefficients, node variables, post-impact velocity and impulses sit in x, which joints double support leaves
free of the Bézier outputs, and the conditions on a contact's wrench and an impulse; the trapezoid weights of the cost
and the joint ranges less a margin."""

from __future__ import annotations

from dataclasses import dataclass

import casadi as cs
import numpy as np
from numpy.typing import NDArray

from robustgait.config import GenerationConfig
from robustgait.domains import Contact
from robustgait.errors import RobustGaitError
from robustgait.gait import BEZIER_DEGREE
from robustgait.robots import Robot
from robustgait.robots.legs import axis_kinds

FloatArray = NDArray[np.float64]


@dataclass
class DomainLayout:
    """Where one domain's variables sit in the NLP vector: its Bézier β, per-node variables (joints s, ṡ, s̈,
    base position p, roll-pitch-yaw, velocity ν_b, acceleration ν̇_b, torques u, contact wrenches λ), and the
    post-impact velocity ν⁺ and impulses Λ of the transition that ends it."""

    beta: slice
    nodes: list[dict[str, slice]]
    nu_plus: slice
    impulse: slice


@dataclass
class Layout:
    """The NLP vector x (scaled units): the domains' blocks in order. ``beta``, ``nodes``, ``nu_plus`` and
    ``impulse`` are domain 0's."""

    m: int
    domains: list[DomainLayout]
    size: int

    @property
    def beta(self) -> slice:
        return self.domains[0].beta

    @property
    def nodes(self) -> list[dict[str, slice]]:
        return self.domains[0].nodes

    @property
    def nu_plus(self) -> slice:
        return self.domains[0].nu_plus

    @property
    def impulse(self) -> slice:
        return self.domains[0].impulse


def make_layout(m: int, n_nodes: list[int], wrench_rows: list[int], impulse_rows: list[int], passive: int = 0,
                loop_rows: int = 0, roll: int = 0) -> Layout:
    """Per domain d: β (m·8), n_nodes[d] nodes with a contact wrench of wrench_rows[d] (and, for a robot with closed
    chains, ``passive`` joints' s_p, ṡ_p, s̈_p and ``loop_rows`` loop forces λ_h; on line feet, ``roll`` = 3: the
    stance foot's roll, its rate and acceleration), ν⁺ (6 + m + passive) and an impulse of impulse_rows[d] (the
    target contact set's rows) + loop_rows (the loops' impulses)."""
    k = 0

    def take(size: int) -> slice:
        nonlocal k
        s = slice(k, k + size)
        k += size
        return s

    doms = []
    for n, wr, ir in zip(n_nodes, wrench_rows, impulse_rows, strict=True):
        beta = take(m * (BEZIER_DEGREE + 1))
        nodes = [{"s": take(m), "sd": take(m), "sdd": take(m), "p": take(3), "rpy": take(3), "vb": take(6),
                  "ab": take(6), "u": take(m), "lam": take(wr), "sp": take(passive), "spd": take(passive),
                  "spdd": take(passive), "lamh": take(loop_rows), "roll": take(roll)} for _ in range(n)]
        doms.append(DomainLayout(beta, nodes, take(6 + m + passive), take(ir + loop_rows)))
    return Layout(m, doms, k)


def wrench_rows(c: Contact, lam: cs.SX, config: GenerationConfig, half_length: float, half_width: float
                ) -> list[tuple[str, cs.SX, float, float]]:
    """Contact wrench conditions (expr ≤ 0 unless noted) of one contact, world axes at its frame:

    flat (f, n) ∈ R⁶: f_z ≥ f_min, friction pyramid |f_x|, |f_y| ≤ μ f_z, centre of pressure inside the sole
    less a margin (|n_y| ≤ a f_z, |n_x| ≤ b f_z), |n_z| ≤ μ_t f_z. Line (f_x, f_y, f_z, n_x, n_z): f_z ≥
    f_line, the same pyramid, the centre of pressure along the edge inside the sole (|n_x| ≤ b f_z; the edge
    runs along world y), |n_z| ≤ μ_t f_z. A line foot (f_x, f_y, f_z, n_y, n_z): f_z ≥ f_min, the same pyramid, the
    centre of pressure along the foot (|n_y| ≤ a f_z; the line runs along world x), |n_z| ≤ μ_t f_z. Returns (name,
    expr, lower, upper) rows.
    """
    mu, mut = config.friction, config.torsional_friction
    ax, ay = half_length - config.scaled("cop_margin"), half_width - config.scaled("cop_margin")
    f = lam[:3]
    least = config.scaled("min_normal_force") if c.kind in ("flat", "line") else config.scaled("min_line_force")
    rows = [("normal_force", f[2], least, cs.inf),
            ("friction", cs.vertcat(f[0] - mu * f[2], -f[0] - mu * f[2], f[1] - mu * f[2], -f[1] - mu * f[2]),
             -cs.inf, 0.0)]
    if c.kind == "flat":
        tq = lam[3:]
        rows += [("cop", cs.vertcat(-tq[1] - ax * f[2], tq[1] - ax * f[2], tq[0] - ay * f[2], -tq[0] - ay * f[2]),
                  -cs.inf, 0.0),
                 ("yaw_moment", cs.vertcat(tq[2] - mut * f[2], -tq[2] - mut * f[2]), -cs.inf, 0.0)]
    elif c.kind == "line":
        ny, nz = lam[3], lam[4]
        rows += [("cop", cs.vertcat(-ny - ax * f[2], ny - ax * f[2]), -cs.inf, 0.0),
                 ("yaw_moment", cs.vertcat(nz - mut * f[2], -nz - mut * f[2]), -cs.inf, 0.0)]
    else:
        nx, nz = lam[3], lam[4]
        rows += [("cop", cs.vertcat(nx - ay * f[2], -nx - ay * f[2]), -cs.inf, 0.0),
                 ("yaw_moment", cs.vertcat(nz - mut * f[2], -nz - mut * f[2]), -cs.inf, 0.0)]
    return rows


def impulse_rows(contacts: tuple[Contact, ...], imp: cs.SX, mu: float) -> cs.SX:
    """Each contact's impulse pushes (Λ_z ≥ 0) inside the friction pyramid (rows ≥ 0)."""
    out, k = [], 0
    for c in contacts:
        fx, fy, fz = imp[k], imp[k + 1], imp[k + 2]
        out += [fz, mu * fz - fx, mu * fz + fx, mu * fz - fy, mu * fz + fy]
        k += c.n_rows
    return cs.vertcat(*out)


def trapezoid_weights(n: int) -> FloatArray:
    """The trapezoid rule's weights (n,) on n equally spaced nodes of [0, 1]: 1/(n − 1), halved at both ends."""
    w = np.full(n, 1.0 / (n - 1))
    w[[0, -1]] *= 0.5
    return w


def inner_range(joint_range: FloatArray, margin: float) -> FloatArray:
    """Each joint's range (m, 2) [rad] less ``margin`` at each finite end, the margin at most a quarter of the range
    (a narrow range keeps half of itself): [lo + μ, hi − μ], μ = min(margin, (hi − lo)/4); an unlimited end stays
    infinite."""
    lo, hi = joint_range[:, 0], joint_range[:, 1]
    width = np.where(np.isfinite(lo) & np.isfinite(hi), hi - lo, np.inf)
    mu = np.minimum(margin, width / 4.0)
    return np.stack([lo + mu, hi - mu], axis=1)


def ankle_roll_problem(robot: Robot, side: str) -> str | None:
    """Why the ``side`` leg cannot walk a multi-contact gait, in one clause, or None: it has no ankle roll, which rolls
    the heel's edge flat (:func:`double_support_free_joints` picks it as a free joint of double support)."""
    if robot.ankle_rolls[side] is not None:
        return None
    names = ", ".join(robot.model.joint(j).name for j in robot.leg_joints[side])
    return (f"the {side} leg ({names}) has no ankle roll: multi-contact gaits roll the heel's edge flat with it; "
            "generate flat-foot gaits (domains flat)")


def double_support_free_joints(robot: Robot, side: str, names: tuple[str, ...] | None = None) -> list[int]:
    """Joints (spec order) of the ``side`` leg that are *not* Bézier outputs in double support.

    With two line contacts (10 rows) the 18 coordinates keep 8 degrees of freedom, so only 8 joints can be
    outputs; the base and 4 joints follow from the loop closure (a square 10 × 10 system at position,
    velocity and acceleration level). The 4 must make that system regular: the front leg's hip roll (lateral
    position), hip yaw (the heel edge's yaw), knee (distance) and ankle roll (the edge's roll) do — chosen by
    the joint axes in the model's zero posture (x: roll, z: yaw, y: pitch; the knee is the second pitch joint
    from the hip, the ankle roll the last roll joint), or given by ``names``."""
    spec, m = robot.spec, robot.model
    if names is not None:
        missing = [n for n in names if n not in spec.joints]
        if len(names) != 4 or missing:
            raise RobustGaitError(f"ds_free_joints must name 4 actuated joints, got {list(names)}")
        return [spec.joints.index(n) for n in names]
    chain = list(robot.leg_joints[side])
    no_roll = ankle_roll_problem(robot, side)
    if no_roll is not None:
        raise RobustGaitError(no_roll)
    kinds = list(axis_kinds(m, tuple(chain)))
    rolls = [j for j, k in zip(chain, kinds, strict=True) if k == "x"]
    yaws = [j for j, k in zip(chain, kinds, strict=True) if k == "z"]
    pitches = [j for j, k in zip(chain, kinds, strict=True) if k == "y"]
    if len(rolls) < 2 or not yaws or len(pitches) < 2:
        raise RobustGaitError(f"cannot pick the double-support free joints of the {side} leg from its joint axes "
                              f"({', '.join(m.joint(j).name for j in chain)}): set GenerationConfig.ds_free_joints")
    picked = [rolls[0], yaws[0], pitches[1], rolls[-1]]
    ids = [m.joint(n).id for n in spec.joints]
    return [ids.index(j) for j in picked]
