"""The loads a robot's servos see and the PD gains made from them (``docs/robots.md``, "Your robot").

**Reflected inertia.** A servo driving joint j with every other joint held sees the inertia of what it moves:

* *swing* — I_sw = M_jj, the diagonal of the joint-space mass matrix M(q) (armature included) in the standing
  posture: joint j moves its own subtree while the rest of the robot stays put (the stance leg holds the base);
* *stance* — I_st: the foot of the leg is welded to the ground, the base is free: joint j now moves the whole
  robot about its axis. With v = (base twist, q̇_j) and the foot's Jacobian J (6 × 7), the motion is the null
  vector n of J scaled to n_j = 1, and I_st = nᵀ M n (Featherstone, *Rigid Body Dynamics Algorithms*, 2008, §3.6:
  the inertia of a constrained system along its free motion). A joint outside the welded leg gets I_st = I_sw.

**Gains.** The servo u = kp (q_d − q) − kd q̇ on an inertia I is a mass–spring–damper of natural frequency
ω = √(kp / I) and damping ratio ζ = kd / (2 √(kp I)). For a bandwidth ω = 2π f:

* kp = min(I_st ω², τ_max / e): the stiffness that gives the loaded (stance) joint the bandwidth, capped so that
  a tracking error e saturates the torque limit τ_max (beyond it more stiffness only saturates);
* kd = 2 ζ √(kp I_sw): damping ratio ζ on the swing inertia, the smaller load — where a servo rings and where
  explicit integration goes unstable (the stance leg is damped by the ground contact);
* discrete stability (:func:`spectral_radius`): the servo on I_sw integrated at the model's timestep by its
  integrator must contract (spectral radius < 1); else kp and kd are scaled down until it does.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numpy as np
from numpy.typing import NDArray

from robustgait.config.robot import SETTLE_ITERATIONS, SETTLE_TOLERANCE
from robustgait.errors import input_error
from robustgait.inspection.model import RobotModel, joint_range
from robustgait.robots.loops import joint_dofs, loop_rows
from robustgait.robots.model import mass_matrix

# the largest spectral radius accepted as a contracting servo (a slow servo's is 1 − ζ ω h, just below 1: the bound
# only refuses growth, not slowness)
STABLE_RADIUS = 1.0 - 1e-9


@dataclass(frozen=True)
class JointLoad:
    """The inertias a joint's servo sees [kg m²] (module docstring): ``swing`` M_jj, ``stance`` with the foot of
    ``stance_side`` welded (the largest over the two feet)."""

    swing: float
    stance: float
    stance_side: str


def body_jacobian(m: mujoco.MjModel, d: mujoco.MjData, body: int) -> NDArray[np.float64]:
    """The body's 6 × nv Jacobian (linear at its origin, then angular; world frame)."""
    jp, jr = np.zeros((3, m.nv)), np.zeros((3, m.nv))
    mujoco.mj_jacBody(m, d, jp, jr, body)
    return np.vstack([jp, jr])


def welded_inertia(full: NDArray[np.float64], jac: NDArray[np.float64], base: NDArray[np.int64], dof: int) -> float:
    """I_st of dof ``dof`` (module docstring): the inertia along the null motion of the welded foot's Jacobian
    over the base dofs and ``dof``; M_jj when the foot does not move with the joint."""
    cols = [*base.tolist(), dof]
    jd = jac[:, cols]
    if float(np.linalg.norm(jd[:, -1])) < 1e-12:
        return float(full[dof, dof])
    _, sv, vt = np.linalg.svd(jd)
    n = vt[-1]
    if sv[-1] <= 1e-9 * sv[0] or abs(n[-1]) < 1e-9:  # the null space is not one motion of the joint
        return float(full[dof, dof])
    n = n / n[-1]
    return float(n @ full[np.ix_(cols, cols)] @ n)


def joint_loads(robot: RobotModel, qpos: NDArray[np.float64], feet: dict[str, int]) -> dict[int, JointLoad]:
    """Every non-base joint's swing and stance inertias at ``qpos`` (``feet``: side → foot body)."""
    m = robot.model
    d, full = mass_matrix(robot.model, qpos)
    base_joint = int(m.body_jntadr[robot.base])
    base = np.arange(int(m.jnt_dofadr[base_joint]), int(m.jnt_dofadr[base_joint]) + 6)
    jacs = {side: body_jacobian(m, d, foot) for side, foot in feet.items()}
    out = {}
    for j in robot.joints:
        dof = int(m.jnt_dofadr[j])
        welded = {side: welded_inertia(full, jac, base, dof) for side, jac in jacs.items()}
        side = max(welded, key=welded.__getitem__)
        out[j] = JointLoad(float(full[dof, dof]), welded[side], side)
    return out


def step_matrix(stiffness: NDArray[np.float64], damping: NDArray[np.float64], dt: float, integrator: str
                ) -> NDArray[np.float64]:
    """One physics step of servos on a mass: q̈ = −(K q + D q̇) with K = M⁻¹ Kp, D = M⁻¹ Kd (n, n), as MuJoCo
    integrates it: ``euler`` semi-implicit (v⁺ = v + h a(q, v), q⁺ = q + h v⁺; actuator damping explicit),
    ``implicit``/``implicitfast`` with the servos' damping implicit (v⁺ = v + h a(q, v⁺)), ``rk4`` classical
    Runge–Kutta (the Taylor polynomial of e^{Ah} of degree 4). Returns the (2n, 2n) map of (q, v)."""
    n = stiffness.shape[0]
    eye, h = np.eye(n), dt
    if integrator == "euler":
        vq, vv = -h * stiffness, eye - h * damping
    elif integrator in ("implicit", "implicitfast"):
        g = np.asarray(np.linalg.inv(eye + h * damping), dtype=np.float64)
        vq, vv = -h * g @ stiffness, g
    else:
        a = np.block([[np.zeros((n, n)), eye], [-stiffness, -damping]]) * h
        a2 = a @ a
        return np.asarray(np.eye(2 * n) + a + a2 / 2 + a2 @ a / 6 + a2 @ a2 / 24)
    return np.block([[eye + h * vq, h * vv], [vq, vv]])


def spectral_radius(kp: float, kd: float, inertia: float, dt: float, integrator: str) -> float:
    """The spectral radius of one physics step of one servo on an inertia (:func:`step_matrix`)."""
    step = step_matrix(np.array([[kp / inertia]]), np.array([[kd / inertia]]), dt, integrator)
    return float(np.max(np.abs(np.linalg.eigvals(step))))


def coupled_radius(mass: NDArray[np.float64], kp: NDArray[np.float64], kd: NDArray[np.float64], dt: float,
                   integrator: str) -> float:
    """The spectral radius of one physics step of all the servos together on the joint-space mass matrix ``mass``
    (n, n) (the base held): the coupling of the joints' inertias lowers the smallest inertia a mode sees below
    every diagonal entry, so a set of servos each stable alone can be unstable together (explicit damping)."""
    inv = np.linalg.inv(mass)
    step = step_matrix(inv * kp[None, :], inv * kd[None, :], dt, integrator)
    return float(np.max(np.abs(np.linalg.eigvals(step))))


@dataclass(frozen=True)
class PDGains:
    """One joint's servo: ``kp`` [N m/rad], ``kd`` [N m s/rad]; ``bound`` what set kp (``bandwidth``, ``torque``:
    the cap τ_max / e, ``stability``: scaled down to contract at the timestep); ``radius`` the discrete servo's
    spectral radius on the swing inertia; ``frequency`` [Hz] and ``ratio`` the natural frequency and damping
    ratio on the swing inertia."""

    kp: float
    kd: float
    bound: str
    radius: float
    frequency: float
    ratio: float


def servo_gains(load: JointLoad, torque_limit: float, bandwidth: float, damping_ratio: float,
                tracking_error: float) -> tuple[float, float, str]:
    """kp = min(I_st ω², τ_max / e) and kd = 2 ζ √(kp I_sw) (module docstring) before the discrete stability
    check, and which bound set kp (``bandwidth`` or ``torque``)."""
    omega = 2.0 * np.pi * bandwidth
    kp_band = load.stance * omega**2
    kp_cap = torque_limit / tracking_error
    kp, bound = (kp_band, "bandwidth") if kp_band <= kp_cap else (kp_cap, "torque")
    return float(kp), float(2.0 * damping_ratio * np.sqrt(kp * load.swing)), bound


def pd_gains(load: JointLoad, torque_limit: float, bandwidth: float, damping_ratio: float, tracking_error: float,
             dt: float, integrator: str) -> PDGains:
    """The gain rule of the module docstring for one joint (``bandwidth`` [Hz], ``tracking_error`` [rad])."""
    kp, kd, bound = servo_gains(load, torque_limit, bandwidth, damping_ratio, tracking_error)
    radius = spectral_radius(kp, kd, load.swing, dt, integrator)
    for _ in range(200):  # 0.8^200 ≈ 1e-20: every servo contracts well before (ω h → 0)
        if radius < STABLE_RADIUS:
            break
        kp, kd, bound = kp * 0.8, kd * 0.8, "stability"
        radius = spectral_radius(kp, kd, load.swing, dt, integrator)
    return PDGains(float(kp), float(kd), bound, radius, float(np.sqrt(kp / load.swing) / (2 * np.pi)),
                   float(kd / (2 * np.sqrt(kp * load.swing))))


def nice_floor(x: float) -> float:
    """The largest of 1, 2 and 5 × 10^k not above ``x`` (> 0)."""
    k = math.floor(math.log10(x))
    return max(f * 10.0**e for e in (k - 1, k) for f in (1.0, 2.0, 5.0) if f * 10.0**e <= x * (1 + 1e-12))


def servo_timestep(model_dt: float, frequency: float, steps: float, time_scale: float, fraction: float) -> float:
    """The physics step [s]: the model's ``model_dt``, lowered to ``nice_floor`` of the smaller of

    * 1 / (``steps`` f), ``f`` [Hz] the fastest servo's natural frequency √(kp / I_sw) / 2π on its swing inertia:
      at least ``steps`` steps per period of the fastest motion the servos make (their discrete response departs
      from the continuous one by O((ω h)²));
    * ``fraction`` × √(l/g) (``time_scale``): the step at the same fraction of the robot's time scale as exo's
      1 ms of its 0.31 s. Touchdowns are found on the step grid, so an iterate of the step map is known to within
      one step of its motion, |ẋ| h; the rates x scale with √(g/l) and their changes |ẋ| with g/l (dynamic
      similarity), so the grid's resolution relative to the rates is the same for walkers at equal h / √(l/g).

    What each robot gets and what other timesteps did to its walks: docs/robots.md ("Walking the grid") and
    docs/performance.md."""
    return min(model_dt, nice_floor(min(1.0 / (steps * frequency), fraction * time_scale)))


def static_torques(robot: RobotModel, qpos: NDArray[np.float64], feet: list[int],
                   weight: NDArray[np.float64] | None = None) -> NDArray[np.float64]:
    """The joint torques that hold the robot still at ``qpos`` standing on the ``feet`` bodies (welded), (nv,) with
    the base's six entries 0: gravity g(q) = Jᵀ w + (0, τ) with the feet's wrenches w chosen to minimise
    Σ (τ_i / weight_i)² (the split of the weight between two feet is otherwise undetermined; one foot: exact).
    ``weight``: per-dof scales of the non-base dofs (torque limits), or ones.

    A robot with closed chains (``robot.loops``) also takes its loops' forces μ (MuJoCo's equality rows J_h, free
    like the feet's wrenches): g(q) = Jᵀ w + J_hᵀ μ + (0, τ), with no torque on a passive joint that is not a
    spring (a rod's ball joint, Cassie's tarsus) and the springs' torques free and not minimised (a spring deflects
    until it holds what it must; statically it is a rigid joint): without the loops' forces the knee seemed to hold
    the whole leg through its rod. The springs' entries are the torques they hold."""
    m = robot.model
    d = robot.kinematics(qpos)
    if robot.loops:
        return _static_torques_closed(robot, d, feet, weight)
    bias = d.qfrc_bias.copy()  # gravity at zero velocity
    b0 = int(m.jnt_dofadr[int(m.body_jntadr[robot.base])])
    base = np.arange(b0, b0 + 6)
    rest = np.setdiff1d(np.arange(m.nv), base)
    jac = np.vstack([body_jacobian(m, d, f) for f in feet])  # (6k, nv)
    scale = np.ones(rest.size) if weight is None else np.asarray(weight, dtype=float)
    # τ = g_r − J_rᵀ w subject to g_b = J_bᵀ w; minimise ‖τ / scale‖² (the KKT system of a constrained least squares)
    a = jac[:, rest].T / scale[:, None]
    r = bias[rest] / scale
    cb = jac[:, base].T
    kkt = np.block([[a.T @ a, cb.T], [cb, np.zeros((6, 6))]])
    sol = np.linalg.lstsq(kkt, np.concatenate([a.T @ r, bias[base]]), rcond=None)[0]
    out = np.zeros(m.nv)
    out[rest] = bias[rest] - jac[:, rest].T @ sol[: jac.shape[0]]
    return out


def _static_torques_closed(robot: RobotModel, d: mujoco.MjData, feet: list[int],
                           weight: NDArray[np.float64] | None) -> NDArray[np.float64]:
    """:func:`static_torques` of a robot with closed chains (its docstring): minimise Σ (τ_i / weight_i)² over the
    planned and held dofs R, subject to g_C = A_Cᵀ f on the base's dofs and the passive non-spring ones C, the
    unknowns f = (w, μ), A = [J (6k × nv); J_h (r × nv)]; the springs' dofs are neither."""
    m = robot.model
    b0 = int(m.jnt_dofadr[int(m.body_jntadr[robot.base])])
    base = np.arange(b0, b0 + 6)
    rest = np.setdiff1d(np.arange(m.nv), base)
    scale = np.ones(m.nv)
    scale[rest] = 1.0 if weight is None else np.asarray(weight, dtype=float)
    springs = joint_dofs(m, tuple(j for j in robot.passive if m.jnt_stiffness[j] > 0))
    zero = joint_dofs(m, tuple(j for j in robot.passive if m.jnt_stiffness[j] == 0))
    held = np.concatenate([base, np.asarray(zero, dtype=np.int64)])
    free = np.setdiff1d(rest, [*zero, *springs])
    bias = d.qfrc_bias.copy()  # gravity at zero velocity
    _, jh = loop_rows(m, d, robot.loops)
    jac = np.vstack([*(body_jacobian(m, d, f) for f in feet), jh])
    a = jac[:, free].T / scale[free, None]
    r = bias[free] / scale[free]
    cb = jac[:, held].T
    kkt = np.block([[a.T @ a, cb.T], [cb, np.zeros((held.size, held.size))]])
    sol = np.linalg.lstsq(kkt, np.concatenate([a.T @ r, bias[held]]), rcond=None)[0]
    out = bias - jac.T @ sol[: jac.shape[0]]
    out[base] = 0.0
    return out


def standing_loads(robot: RobotModel, qpos: NDArray[np.float64], feet: list[int]) -> NDArray[np.float64]:
    """The joint torques that hold the robot still at ``qpos`` standing on the ``feet`` bodies (welded), (nv,) with
    the base's six entries 0, its weight split **without internal forces**: the feet's wrenches w are the least-norm
    solution of the equilibrium of the base's dofs and of the passive joints that are not springs, g_C = A_Cᵀ f with
    f = (w, μ) (μ the loops' forces, not minimised), and every other dof holds τ = g − Jᵀ w − J_hᵀ μ.

    What each foot carries is then what the weight puts on it, neither foot pushing against the other. This is the
    split a compliant stance settles into when the stance is left/right symmetric (its two legs equally stiff, the
    weight's share and its centre of pressure the same on each foot): unlike :func:`static_torques`, which minimises
    the servos' torques over the internal forces and lets them unload the springs, it is the load the springs
    deflect under (:func:`settle_springs`)."""
    m = robot.model
    d = robot.kinematics(qpos)
    b0 = int(m.jnt_dofadr[int(m.body_jntadr[robot.base])])
    base = np.arange(b0, b0 + 6)
    zero = joint_dofs(m, tuple(j for j in robot.passive if m.jnt_stiffness[j] == 0))
    held = np.concatenate([base, np.asarray(zero, dtype=np.int64)])
    jac = np.vstack([body_jacobian(m, d, f) for f in feet])
    if robot.loops:
        jac = np.vstack([jac, loop_rows(m, d, robot.loops)[1]])
    bias = d.qfrc_bias.copy()  # gravity at zero velocity
    a = jac[:, held].T
    cost = np.zeros(jac.shape[0])
    cost[: 6 * len(feet)] = 1.0  # the feet's wrenches minimised, the loops' forces free
    kkt = np.block([[np.diag(cost), a.T], [a, np.zeros((held.size, held.size))]])
    sol = np.linalg.lstsq(kkt, np.concatenate([np.zeros(jac.shape[0]), bias[held]]), rcond=None)[0]
    out = bias - jac.T @ sol[: jac.shape[0]]
    out[base] = 0.0
    return out


def settle_springs(robot: RobotModel, feet: list[int]) -> dict[int, float]:
    """The posture (``robot.angles``, edited) with its springs at their static deflection under the robot's weight
    standing on the ``feet`` bodies: each spring at springref − τ/k, τ its :func:`standing_loads` torque, the loops
    closed again (:meth:`RobotModel.close`), repeated until no deflection changes by more than
    :data:`robustgait.config.robot.SETTLE_TOLERANCE` (the load moves with the posture). A posture whose springs are
    rigid (as gait generation holds them) is not the posture the robot stands in: its weight turns every joint below a
    spring. Returns each spring's angle (joint id → rad or m); {} for a robot without springs. Raises RobustGaitError
    (one line naming the spring, its deflection and its range) when a spring would leave its range."""
    m = robot.model
    if not robot.springs:
        return {}
    angles: dict[int, float] = {}
    for _ in range(SETTLE_ITERATIONS):
        tau = standing_loads(robot, robot.qpos(), feet)
        angles = {s.joint: s.springref - float(tau[int(m.jnt_dofadr[s.joint])]) / s.stiffness for s in robot.springs}
        for s in robot.springs:
            limits = joint_range(m, s.joint)
            if limits is not None and not limits[0] <= angles[s.joint] <= limits[1]:
                raise input_error(robot.path, f"spring '{robot.joint_name(s.joint)}' ({s.stiffness:g} N m/rad) "
                                  f"would deflect to {angles[s.joint]:.4g} under the robot's weight standing in the "
                                  f"posture ({tau[int(m.jnt_dofadr[s.joint])]:.4g} N m), outside its range "
                                  f"[{limits[0]:.4g}, {limits[1]:.4g}]")
        change = max(abs(a - robot.angles[j]) for j, a in angles.items())
        robot.angles.update(angles)
        robot.close()
        if change <= SETTLE_TOLERANCE:
            break
    return angles


def estimated_torque_limits(robot: RobotModel, qpos: NDArray[np.float64], soles: dict[int, NDArray[np.float64]],
                            joints: list[int], factor: float) -> dict[int, float]:
    """For joints whose model gives no torque limit: ``factor`` × the largest of (a) the joint's static torque
    standing on either foot alone at ``qpos``; (b) the torque that holds the robot's weight W = m |g| pressing at a
    corner of a sole, a_j · ((c − p_j) × W ẑ) over the corners c of the feet below the joint (what a stance joint
    must resist before the foot tips instead); (c) the bound m_s |g| ‖c_s − p_j‖ on the gravity torque of the
    subtree it moves (mass m_s, centre of mass c_s, anchor p_j) in any posture [N m]. ``soles``: foot body → its
    sole's corner points (k, 3), world frame at ``qpos``."""
    m = robot.model
    d = robot.kinematics(qpos)
    single = [np.abs(static_torques(robot, qpos, [f])) for f in soles]
    g = float(np.linalg.norm(m.opt.gravity))
    weight = np.array([0.0, 0.0, robot.mass * g])
    out = {}
    for j in joints:
        body, dof = int(m.jnt_bodyid[j]), int(m.jnt_dofadr[j])
        a, p = d.xaxis[j], d.xanchor[j]
        subtree = float(m.body_subtreemass[body]) * g * float(np.linalg.norm(d.subtree_com[body] - p))
        corner = max((abs(float(a @ np.cross(c - p, weight))) for f, pts in soles.items()
                      if body == f or body in robot.ancestors(f) for c in pts), default=0.0)
        out[j] = factor * max(subtree, corner, *(float(s[dof]) for s in single))
    return out


def tipping_stiffness(robot: RobotModel, qpos: NDArray[np.float64], foot: int, joints: list[int],
                      delta: float = 1e-4) -> dict[int, float]:
    """Gravity's tipping stiffness about each joint of the stance chain, standing on ``foot`` alone [N m/rad]:
    k_j = −∂τ_j/∂q_j, τ the static torque that holds the robot (:func:`static_torques`), each joint turned with
    the foot kept in place (the base moved by the inverse of the foot's displacement). k_j > 0: gravity pulls the
    robot further the way the joint turned (an inverted pendulum about the ankle: k = m g h); a servo holds the
    posture only if kp_j > k_j (the other joints held rigid)."""
    m = robot.model
    d0 = robot.kinematics(qpos)
    p0, r0 = d0.xpos[foot].copy(), d0.xmat[foot].reshape(3, 3).copy()
    adr = int(m.jnt_qposadr[int(m.body_jntadr[robot.base])])
    out = {}
    for j in joints:
        tau = []
        for step in (delta, -delta):
            q = qpos.copy()
            q[m.jnt_qposadr[j]] += step
            d = robot.kinematics(q)
            turn = r0 @ d.xmat[foot].reshape(3, 3).T  # undoes the foot's rotation
            base_r = turn @ d.xmat[robot.base].reshape(3, 3)
            q[adr:adr + 3] = p0 + turn @ (d.xpos[robot.base] - d.xpos[foot])
            quat = np.zeros(4)
            mujoco.mju_mat2Quat(quat, base_r.ravel())
            q[adr + 3:adr + 7] = quat
            tau.append(static_torques(robot, q, [foot])[int(m.jnt_dofadr[j])])
        out[j] = -(tau[0] - tau[1]) / (2 * delta)
    return out
