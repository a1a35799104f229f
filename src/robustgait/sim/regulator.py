"""Step-to-step balance for an HZD gait (``docs/simulation.md``, "Step-to-step balance"): the H-LIP foot-placement
regulator (:mod:`robustgait.sim.hlip`) on top of the joint tracking controller.

A joint-space tracking controller on an HZD gait has no balance feedback: a sole too narrow to hold the base
through the ankle tips, and nothing brings the walk back. The regulator closes that loop where a walking robot
does, at the next foothold:

1. At every chunk boundary of a step (each ``update_interval`` seconds, before τ = ``freeze_tau``) it
   measures each sample's CoM state x = [p, v] per horizontal axis, relative to the stance sole's centre in the
   sole's heading frame, and compares it with the gait's own x*(τ) at the same phase — computed by kinematics from
   the gait's outputs with the stance sole flat, so the comparison carries no model bias.
2. It sets the landing change Δu = κ K (x − x*) (:func:`~robustgait.sim.hlip.step_correction` with no time left:
   the error measured now is the estimate of the error at touchdown; with ``predict`` the H-LIP's prediction
   e^{A_S (T_S − t)} (x − x*) instead), κ the share of the H-LIP gain the sole's width leaves to the foot
   (:func:`~robustgait.sim.regulator_rules.placement_share`), clipped per axis to ``max_step_change`` leg lengths and,
   inward, to keep ``foot_gap`` between the soles.
3. The landing change becomes a swing-leg joint offset g = G Δu, G the least-squares inverse of the swing sole's
   5 × n Jacobian (horizontal position and orientation, stance sole frame, base fixed) at the gait's pre-impact
   posture with the orientation rows held at zero — the foot still lands flat. The offset is blended
   in with a quintic in phase, reaching its target at ``land_tau``; it is continuous across updates.
4. At the step start the joints differ from the references by e0 (the previous landing correction, now in the
   stance leg, and any tracking error); e0 is blended out of the references by τ_c = ``carry_tau`` + ``carry_share`` κ
   (:func:`~robustgait.sim.regulator_rules.carry_phase`) instead of being a
   step in the servos' error (Morris & Grizzle, IEEE TAC 54(8), 2009: hybrid-invariant deformation of the outputs).

The servos then track y_d + o with controls c = y_d + o + (kd (ẏ_d + ȯ) + u_ff) / kp; each sample gets its own
control series per chunk, so ``mujoco.rollout`` still runs the step with no Python call per physics step. The
correction is a function of the state at the step start and at boundaries fixed relative to it: the closed-loop
step map stays a function of the section state, as the certificate assumes.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Protocol

import mujoco
import numpy as np
from numpy.typing import NDArray

from robustgait.config.regulator import RegulatorConfig
from robustgait.gait import Gait
from robustgait.robots import Robot
from robustgait.robots.loops import closed_posture, closed_velocity, passive_addresses
from robustgait.robots.solebox import SoleBox
from robustgait.sim import hlip
from robustgait.sim.controller import desired_outputs
from robustgait.sim.regulator_rules import carry_phase, placement_share, regulator_rule

Array = NDArray[np.float64]


def quintic_blend(s: Array) -> tuple[Array, Array]:
    """S(s) = 10 s³ − 15 s⁴ + 6 s⁵ and S′(s) on s clipped to [0, 1] (…): rises from 0 to 1 with zero slope and
    curvature at both ends."""
    s = np.clip(s, 0.0, 1.0)
    return s**3 * (10.0 - 15.0 * s + 6.0 * s**2), 30.0 * s**2 * (1.0 - s) ** 2


def sole_frame(data: mujoco.MjData, sole: SoleBox) -> tuple[Array, Array]:
    """Centre (3,) and heading rotation R_z(ψ)ᵀ (2, 2) of a sole box: world horizontal vectors into the sole's
    heading frame (x heel to toe, y to its left), ψ the yaw of its heel-to-toe axis (:meth:`SoleBox.heading`,
    whichever of the geom's axes that is). The centre is the box's, on the sole's normal through its bottom face's
    centre: the same point for the gait's x* (:func:`nominal_com`) and the walk's x, so a flat sole's horizontal
    offset is the bottom face's."""
    psi = sole.heading(data)
    c, s = math.cos(psi), math.sin(psi)
    return data.geom_xpos[sole.geom].copy(), np.array([[c, s], [-s, c]])


def com_state(robot: Robot, data: mujoco.MjData, states: Array, stance: str) -> Array:
    """x = [p, v] per axis (K, 2, 2) — axis 0 forward, 1 lateral — of the CoM relative to the stance sole's centre
    in its heading frame [m, m/s], from full-physics states (K, nstate)."""
    m = robot.model
    nq, nv = m.nq, m.nv
    sole = robot.sole_boxes[stance]
    out = np.empty((states.shape[0], 2, 2))
    for i, st in enumerate(states):
        data.qpos[:] = st[1:1 + nq]
        data.qvel[:] = st[1 + nq:1 + nq + nv]
        mujoco.mj_kinematics(m, data)
        mujoco.mj_comPos(m, data)
        mujoco.mj_comVel(m, data)
        mujoco.mj_subtreeVel(m, data)
        centre, rot = sole_frame(data, sole)
        out[i, :, 0] = rot @ (data.subtree_com[0, :2] - centre[:2])
        out[i, :, 1] = rot @ data.subtree_linvel[0, :2]
    return out


def _posture(robot: Robot, gait: Gait, tau: Array) -> Array:
    """qpos (K, nq) with the base at the origin, the planned joints at y_d(τ) and the held ones at their angles; a
    closed chain's passive joints solved from its loops, springs at rest (:func:`robustgait.robots.loops.
    closed_posture`: where the knee puts Cassie's tarsus, and with it the foot)."""
    q = np.zeros((tau.size, robot.model.nq))
    q[:, 3] = 1.0
    q[:, robot.qpos_idx] = desired_outputs(gait, tau)[0]
    q[:, robot.held_qpos_idx] = robot.held_angle
    if robot.passive_ids:
        qadr, _ = passive_addresses(robot.model, robot.passive_ids)
        q[:, qadr] = robot.model.qpos0[qadr]
        q = np.array([closed_posture(robot.model, robot.passive_ids, row) for row in q])
    return q


def _com_in_sole(robot: Robot, data: mujoco.MjData, qpos: Array, sole: SoleBox) -> Array:
    """The CoM relative to a sole box's centre, in its foot frame (3,) [m] (x heel to toe, y left, z up:
    :meth:`SoleBox.world_frame`), at configuration ``qpos``."""
    data.qpos[:] = qpos
    mujoco.mj_kinematics(robot.model, data)
    mujoco.mj_comPos(robot.model, data)
    return np.asarray(sole.world_frame(data).T @ (data.subtree_com[0] - data.geom_xpos[sole.geom]))


def nominal_com(robot: Robot, gait: Gait, tau: Array, dtau: float = 1e-4) -> tuple[Array, float]:
    """The gait's own CoM state x*(τ) (K, 2, 2) at phases τ (K,), and its mean CoM height over the stance sole [m].

    By kinematics from the outputs y_d(τ) with the stance sole flat on the floor (what the HZD gait was solved
    for): p* is the CoM relative to the sole's centre in the sole frame — the same for any base pose — and
    v* = dp*/dτ / T by central differences in τ."""
    data = mujoco.MjData(robot.model)
    sole = robot.sole_boxes[gait.stance]

    def rel(t: Array) -> Array:
        return np.array([_com_in_sole(robot, data, q, sole) for q in _posture(robot, gait, t)])

    p = rel(tau)
    lo, hi = np.maximum(tau - dtau, 0.0), tau + dtau   # one-sided at τ = 0 (the outputs start there)
    dp = (rel(hi) - rel(lo)) / ((hi - lo) * gait.domains[0].duration)[:, None]
    x = np.stack([p[:, :2], dp[:, :2]], axis=-1)
    return x, float(np.mean(p[:, 2]))


def com_jacobian(robot: Robot, gait: Gait, tau: Array, joints: NDArray[np.int64], dq: float = 1e-5) -> Array:
    """∂p*/∂q_j (K, 2, n): how the CoM's horizontal position relative to the stance sole (sole frame) moves with the
    planned joints ``joints`` (n,) at the gait's postures y_d(τ) (K,), by central differences."""
    data = mujoco.MjData(robot.model)
    sole = robot.sole_boxes[gait.stance]
    out = np.empty((tau.size, 2, joints.size))
    for i, q in enumerate(_posture(robot, gait, tau)):
        for c, j in enumerate(joints):
            side = []
            for sign in (1.0, -1.0):
                moved = q.copy()
                moved[robot.qpos_idx[j]] += sign * dq
                moved = closed_posture(robot.model, robot.passive_ids, moved)  # the loops move with the joint
                side.append(_com_in_sole(robot, data, moved, sole))
            out[i, :, c] = (side[0] - side[1])[:2] / (2.0 * dq)
    return out


def swing_dofs(robot: Robot, side: str) -> NDArray[np.int64]:
    """Indices into the planned joints (m) of the swing leg's: the planned joints on the chain from the base to
    ``side``'s sole."""
    m = robot.model
    body = int(m.geom_bodyid[robot.sole_geom_id[side]])
    chain: set[int] = set()
    while body > 0:
        chain.update(range(int(m.body_dofadr[body]), int(m.body_dofadr[body] + m.body_dofnum[body])))
        body = int(m.body_parentid[body])
    return np.array([j for j, d in enumerate(robot.dof_idx) if int(d) in chain], dtype=np.int64)


def landing_map(robot: Robot, gait: Gait) -> tuple[Array, Array]:
    """G (m, 2): the planned-joint offset that moves the swing sole by (Δx, Δy) [m] in the stance sole's frame at
    the gait's pre-impact posture (τ = 1), keeping its orientation (minimum-norm solution on the 5 × n Jacobian of
    the swing sole's horizontal position and orientation, base fixed: near a straight landing leg, holding the
    height too would take large knee motions for a millimetre of height); and the swing sole's position relative to
    the stance sole there (2,) [m]. A line foot keeps its pitch and yaw only (4 × n): it lands on its line at any
    roll, and a leg without an ankle roll cannot move its foot sideways at a fixed roll (the least-squares inverse
    then asks near-singular hip-pitch and knee offsets). A closed chain's passive joints move with the planned ones
    through its loops (:func:`robustgait.robots.loops.closed_velocity`)."""
    m = robot.model
    data = mujoco.MjData(m)
    data.qpos[:] = _posture(robot, gait, np.array([1.0]))[0]
    mujoco.mj_kinematics(m, data)
    mujoco.mj_comPos(m, data)
    stance = gait.stance
    swing = "left" if stance == "right" else "right"
    rot = robot.sole_boxes[stance].world_frame(data).T  # world vectors into the stance sole's foot frame
    jacp, jacr = np.zeros((3, m.nv)), np.zeros((3, m.nv))
    mujoco.mj_jacGeom(m, data, jacp, jacr, robot.sole_geom_id[swing])
    dofs = swing_dofs(robot, swing)
    # unit rates of the swing leg's planned joints, with a closed chain's passive joints moving as its loops require
    rates = np.zeros((m.nv, dofs.size))
    rates[robot.dof_idx[dofs], np.arange(dofs.size)] = 1.0
    rates = closed_velocity(m, robot.passive_ids, data.qpos, rates)
    turn = rot @ jacr @ rates
    if robot.spec.feet.get(swing) == "line":  # a line lands on its line at any roll: the sole's pitch and yaw held
        turn = turn[1:]
    jac = np.vstack([(rot @ jacp @ rates)[:2], turn])  # (5 or 4, n)
    g = np.zeros((robot.n_joints, 2))
    g[dofs] = np.linalg.pinv(jac)[:, :2]
    rel = rot @ (data.geom_xpos[robot.sole_geom_id[swing]] - data.geom_xpos[robot.sole_geom_id[stance]])
    return g, rel[:2]


@dataclass
class _Stance:
    """What the regulator knows of one stance: x* at the chunk boundaries (B, 2, 2), how the CoM moves with the
    swing leg's joints there (B, 2, m: zero columns for the other joints), the landing map G (m, 2), and the lateral
    landing change inward that keeps the soles apart [m] with its sign (+1: inward is +y)."""

    nominal: Array
    swing_com: Array
    landing: Array
    inward_room: float
    inward_sign: float


class StepRegulator:
    """The H-LIP foot-placement regulator of one gait on one robot (module docstring), for an engine that rolls
    a domain out in chunks of ``chunk`` physics steps. Call :meth:`begin` at each step start with its K start
    states, then :meth:`offsets` at each chunk boundary."""

    name = "hlip"

    def __init__(self, robot: Robot, gaits: dict[str, Gait], config: RegulatorConfig, chunk: int, horizon: int,
                 reason: str = ""):
        self.robot = robot
        self.config = config
        self.reason = reason
        self._gaits = gaits
        self.chunk = chunk
        gait = next(iter(gaits.values()))
        self.period = gait.domains[0].duration
        self.steps_per_period = self.period / robot.dt
        bounds = np.arange(0, horizon, chunk)
        self.stances: dict[str, _Stance] = {}
        heights = []
        leg = robot.leg_length
        half_width = robot.sole_width / 2.0
        for stance, g in gaits.items():
            nominal, z0 = nominal_com(robot, g, bounds / self.steps_per_period)
            heights.append(z0)
            landing, rel = landing_map(robot, g)
            room = max(abs(float(rel[1])) - 2.0 * half_width - config.foot_gap * leg, 0.0)
            swing = swing_dofs(robot, "left" if stance == "right" else "right")
            swing_com = np.zeros((bounds.size, 2, robot.n_joints))
            swing_com[:, :, swing] = com_jacobian(robot, g, bounds / self.steps_per_period, swing)
            self.stances[stance] = _Stance(nominal, swing_com, landing, room, -math.copysign(1.0, float(rel[1])))
        self.z0 = float(np.mean(heights))
        self.lam = hlip.pendulum_rate(self.z0, float(np.linalg.norm(robot.model.opt.gravity)))
        a, b = hlip.s2s_matrices(self.lam, self.period, 0.0)
        self.hlip_gain = (hlip.deadbeat_gain(self.lam, self.period, 0.0) if config.gain == "deadbeat"
                          else hlip.lqr_gain(a, b, self.z0, self.lam))
        self.rho = hlip.closed_loop_radius(a, b, self.hlip_gain)
        self.share = placement_share(config, robot.sole_width, robot.leg_length)
        self.gain = self.share * self.hlip_gain
        self.growth: float | None = None        # the walk's lateral growth per step under the rule's κ, if measured
        self.growth_whole: float | None = None  # and under κ = 1, when the first was above the limit
        self.max_change = config.max_step_change * leg
        self._data = mujoco.MjData(robot.model)
        self._ratio = robot.kd / robot.kp
        self._stance = ""
        self._o0 = np.zeros((0, robot.n_joints))   # offset at the start of the current blend segment
        self._goal = np.zeros((0, robot.n_joints))
        self._s0 = np.zeros(0)                     # S at the start of the segment
        self._e0 = np.zeros((0, robot.n_joints))   # joint error at the step start (carried out)
        self.updates = 0
        self.clipped = 0
        self.largest = 0.0

    @property
    def needs_growth(self) -> bool:
        """Whether κ depends on the walk's measured lateral growth (:meth:`settle_share`): no ``gain_scale`` given and
        the sole's width rule leaves part of the gain out."""
        return self.config.gain_scale is None and self.share < 1.0

    @property
    def carry_tau(self) -> float:
        """τ_c, the phase by which the step-start error is blended out under the current share κ
        (:func:`~robustgait.sim.regulator_rules.carry_phase`)."""
        return carry_phase(self.config, self.share)

    def set_share(self, share: float) -> None:
        """Apply ``share`` κ of the H-LIP gain from now on (and the step-start blend that goes with it,
        :attr:`carry_tau`)."""
        self.share = share
        self.gain = share * self.hlip_gain

    def settle_share(self, measure: Callable[[float], float]) -> None:
        """κ from the walk itself, ``measure(κ)`` its lateral growth per step under κ (:func:`lateral_growth`): the
        width rule's share if the error grows at most ``growth_limit`` under it; otherwise the H-LIP's whole gain
        (κ = 1) if the error grows less under that — the ankle does not hold the CoM, the point-foot case the
        H-LIP's gain is for — else still the rule's (more gain would not help)."""
        rule = self.share
        self.growth = measure(rule)
        if self.growth > self.config.growth_limit:
            self.growth_whole = measure(1.0)
            if self.growth_whole < self.growth:
                self.set_share(1.0)
                return
        self.set_share(rule)

    def summary(self) -> dict[str, float | int | str]:
        """What the regulator did so far: corrections computed, how many were clipped, the largest |Δu| [m], and its
        model (z0 [m], λ [1/s], T_S [s], the share κ of the H-LIP gain and the gain applied, the spectral radius of
        the H-LIP closed loop with the H-LIP's own gain, and the measured lateral growth when κ depended on it: under
        the width rule's κ, and under κ = 1 when that was measured)."""
        out: dict[str, float | int | str] = {
            "regulator": self.name, "updates": self.updates, "clipped": self.clipped,
            "largest_step_change": round(self.largest, 4), "z0": round(self.z0, 4), "lambda": round(self.lam, 3),
            "t_ssp": self.period, "share": round(self.share, 3), "gain": f"[{self.gain[0]:.3f}, {self.gain[1]:.3f}]",
            "hlip_rho": round(self.rho, 3)}
        for key, g in (("growth", self.growth), ("growth_whole", self.growth_whole)):
            if g is not None:
                out[key] = round(g, 3) if math.isfinite(g) else "fell"
        return out

    def begin(self, stance: str, states: Array) -> None:
        """Start a step of ``stance`` for K samples from their full-physics start states (K, nstate)."""
        kk = states.shape[0]
        m = self.robot.n_joints
        self._stance = stance
        self._o0 = np.zeros((kk, m))
        self._goal = np.zeros((kk, m))
        self._s0 = np.zeros(kk)
        q = states[:, 1:1 + self.robot.model.nq][:, self.robot.qpos_idx]
        y0 = desired_outputs(self._gaits[stance], np.zeros(1))[0][0]
        self._e0 = np.nan_to_num(q - y0) if self.carry_tau > 0 else np.zeros((kk, m))

    def _blend(self, tau: Array) -> tuple[Array, Array]:
        """S and dS/dτ of the landing blend at phases τ (…)."""
        s, ds = quintic_blend(tau / self.config.land_tau)
        return s, ds / self.config.land_tau

    def offsets(self, active: NDArray[np.int64], states: Array, k0: int, n: int) -> Array:
        """Servo control offsets (A, n, nu) for physics steps k0..k0+n−1 of the samples ``active`` from their states
        (A, nstate) at step k0: the landing correction, updated from these states before ``freeze_tau``, and the
        step-start carry, each with its rate through kd/kp."""
        cfg = self.config
        st = self.stances[self._stance]
        tau_b = k0 / self.steps_per_period
        tau = (k0 + np.arange(n)) / self.steps_per_period
        s_tau, ds_tau = self._blend(tau)
        s_arr, ds_arr = self._blend(np.array([tau_b]))
        s_b, ds_b = float(s_arr[0]), float(ds_arr[0])
        o0, goal, s0 = self._o0[active], self._goal[active], self._s0[active]
        if tau_b < min(cfg.freeze_tau, cfg.land_tau) and states.shape[0]:
            # the offset reached at this boundary and its rate, then a new segment from it towards the new goal
            span = np.maximum(1.0 - s0, 1e-12)
            o_b = o0 + ((s_b - s0) / span)[:, None] * (goal - o0)
            do_b = (ds_b / span / self.period)[:, None] * (goal - o0)
            b = k0 // self.chunk
            error = com_state(self.robot, self._data, states, self._stance) - st.nominal[b]
            # the CoM shift the correction itself makes (the swing leg's own offset) is not an error: left in, it
            # would feed back within the step through the swing leg's mass
            jac = st.swing_com[b]
            error[:, :, 0] -= (o_b[:, None, :] * jac[None]).sum(axis=-1)
            error[:, :, 1] -= (do_b[:, None, :] * jac[None]).sum(axis=-1)
            t_left = self.period - k0 * self.robot.dt if cfg.predict else 0.0
            du = hlip.step_correction(self.gain, self.lam, error, t_left)
            lim = np.array([self.max_change, self.max_change])
            clipped = np.abs(du) > lim
            du = np.clip(du, -lim, lim)
            inward = du[:, 1] * st.inward_sign
            clipped[:, 1] |= inward > st.inward_room
            du[:, 1] = np.where(inward > st.inward_room, st.inward_sign * st.inward_room, du[:, 1])
            self.updates += du.shape[0]
            self.clipped += int(clipped.any(axis=1).sum())
            self.largest = max(self.largest, float(np.abs(du).max(initial=0.0)))
            goal = du[:, :1] * st.landing[:, 0] + du[:, 1:] * st.landing[:, 1]  # G Δu, elementwise (exact per row)
            o0, s0 = o_b, np.full(active.size, s_b)
            self._o0[active], self._goal[active], self._s0[active] = o0, goal, s0
        frac = (s_tau[None, :] - s0[:, None]) / np.maximum(1.0 - s0[:, None], 1e-12)       # (A, n)
        dfrac = ds_tau[None, :] / np.maximum(1.0 - s0[:, None], 1e-12)
        diff = (goal - o0)[:, None, :]
        off = o0[:, None, :] + frac[..., None] * diff                                       # (A, n, m)
        rate = dfrac[..., None] * diff / self.period
        carry = self.carry_tau
        if carry > 0:
            c, dc = quintic_blend(tau / carry)
            e0 = self._e0[active][:, None, :]
            off = off + (1.0 - c)[None, :, None] * e0
            rate = rate - (dc / (carry * self.period))[None, :, None] * e0
        servo = off + self._ratio * rate
        nu = self.robot.model.nu
        if servo.shape[2] == nu:
            return servo
        out = np.zeros((servo.shape[0], n, nu))
        out[:, :, :servo.shape[2]] = servo
        return out


def regulator_for(robot: Robot, gaits: dict[str, Gait], config: RegulatorConfig, chunk: int, horizon: int
                  ) -> StepRegulator | None:
    """The regulator a gait's engine runs (:func:`~robustgait.sim.regulator_rules.regulator_rule`), or None."""
    gait = next(iter(gaits.values()))
    on, reason = regulator_rule(config, robot.sole_width, robot.leg_length, len(gait.domains))
    if not on:
        return None
    return StepRegulator(robot, gaits, config, chunk, horizon, reason)


class _Walker(Protocol):
    """What :func:`lateral_growth` needs of an engine (:class:`robustgait.sim.engine.StepEngine`)."""

    robot: Robot
    gaits: dict[str, Gait]
    regulator: StepRegulator | None

    def step(self, qpos: Array, qvel: Array, stance: str) -> Any: ...

    def full_states(self, qpos: Array, qvel: Array) -> Array: ...


# measured growths, one per robot, gait and simulation options: an engine is built many times for one gait
_GROWTH: dict[tuple[str, ...], float] = {}
GROWTH_STEPS = 6        # steps walked: the growth is the mean ratio from the first to the last
GROWTH_VELOCITY = 0.01  # the lateral velocity change, × √(g l)


def lateral_growth(engine: _Walker, options: str, share: float) -> float:
    """μ, how much a lateral error of the CoM grows per step under ``share`` κ of the H-LIP gain (the step-start blend
    on): the gait's initial state with its base's lateral velocity changed by ±δ
    (δ = ``GROWTH_VELOCITY`` √(g l)), walked ``GROWTH_STEPS`` steps on ``engine``; e_k (2,) = half the difference of
    the two walks' CoM states [λ p, v] (lateral, stance sole frame, λ = the H-LIP's rate) at the k-th switching event
    — the response to the change, the gait's own offsets cancelled — and μ = (‖e_K‖ / ‖e_1‖)^(1/(K − 1)); ∞ if either
    walk falls. An ankle that holds the CoM with that share's help keeps μ near 1 or below; a point foot's grows like
    e^(λT) (6.5 for λT = 1.9) without foot placement. Measured once per robot, gait, share and ``options`` (the
    simulation options' text) in a process, then reused."""
    reg = engine.regulator
    if reg is None:
        raise ValueError("lateral_growth needs an engine whose step regulator runs")
    robot = engine.robot
    gait = engine.gaits[next(iter(engine.gaits))]
    key = (robot.digest, gait.digest(), options, repr(share))
    if key in _GROWTH:
        return _GROWTH[key]
    kept = reg.share
    reg.set_share(share)
    try:
        st = gait.initial_state
        if st is None:
            raise ValueError("the gait has no initial state to walk from")
        dv = GROWTH_VELOCITY * math.sqrt(float(np.linalg.norm(robot.model.opt.gravity)) * robot.leg_length)
        qpos, qvel = np.repeat(st.qpos[None], 2, axis=0), np.repeat(st.qvel[None], 2, axis=0)
        qvel[:, 1] += [dv, -dv]
        stance, norms, data = gait.stance, [], mujoco.MjData(robot.model)
        for _ in range(GROWTH_STEPS):
            b = engine.step(qpos, qvel, stance)
            if np.any(b.fell):
                _GROWTH[key] = math.inf
                return math.inf
            qpos, qvel = b.qpos, b.qvel
            x = com_state(robot, data, engine.full_states(qpos, qvel), stance)[:, 1]  # (2, [p, v]) lateral
            e = (x[0] - x[1]) / 2.0
            norms.append(math.hypot(reg.lam * e[0], e[1]))
            stance = "left" if stance == "right" else "right"
        growth = (norms[-1] / max(norms[0], 1e-12)) ** (1.0 / (GROWTH_STEPS - 1))
    finally:
        reg.set_share(kept)
        reg.updates, reg.clipped, reg.largest = 0, 0, 0.0  # the probe's steps are not the walk's
    _GROWTH[key] = growth
    return growth
