"""Physics check of an optimized gait, re-evaluated with MuJoCo's own model (DESIGN §4, run on every solve).

* Dynamics residual at every node: r = M q̈ + c − B u − J_stᵀ λ in MuJoCo's coordinates, with M from
  ``mj_fullM``, c = ``qfrc_bias``, J_st from ``mj_jac`` at the stance sole frame; relative to ‖M q̈‖ + ‖c‖.
* Stance contact: sole frame pose and velocity (MuJoCo kinematics) — the foot must not move.
* Impact map: q̇⁺ = q̇⁻ + M⁻¹ J_swᵀ Λ with J_sw q̇⁺ = 0 (MuJoCo's M and J), and periodicity: the post-impact
  state, shifted so the new stance sole sits at the origin and mirrored, equals the initial state.
* Contact wrench: normal force, friction pyramid, centre of pressure, yaw moment (the problem's bounds).
* Essential constraints: landing position (step length, width), swing height at τ = ½, duration.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import mujoco
import numpy as np
from numpy.typing import NDArray

from robustgait.dynamics import Dynamics, foot_frame
from robustgait.gait import GaitParams
from robustgait.gaitgen.problem import FlatFootProblem
from robustgait.gaitgen.states import NodeStates, to_mujoco_state

FloatArray = NDArray[np.float64]
DYNAMICS_TOL = 1e-6
PERIODICITY_TOL = 1e-6
LENGTH_TOL = 1e-3
TIME_TOL = 1e-3
FORCE_TOL = 1e-6  # [N] slack on the wrench inequalities (IPOPT's bound relaxation)


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
    step_length_error: float
    step_width_error: float
    step_height_error: float
    duration_error: float
    passed: bool
    failures: tuple[str, ...]

    def to_dict(self) -> dict[str, object]:
        return asdict(self)


def _sole_jacobian(m: mujoco.MjModel, d: mujoco.MjData, geom: int, point: FloatArray) -> FloatArray:
    jp, jr = np.zeros((3, m.nv)), np.zeros((3, m.nv))
    mujoco.mj_jac(m, d, jp, jr, point, int(m.geom_bodyid[geom]))
    return np.vstack([jp, jr])


def check_solution(dyn: Dynamics, prob: FlatFootProblem, params: GaitParams, ns: NodeStates,
                   duration: float) -> PhysicsCheck:
    """Re-evaluate a solution's physics with MuJoCo (module docstring)."""
    robot = dyn.robot
    m, d = robot.model, mujoco.MjData(robot.model)
    cfg = prob.config
    st_geom, sw_geom = robot.sole_geom_id[prob.stance], robot.sole_geom_id[prob.swing]
    st_frame, sw_frame = foot_frame(prob.stance, "sole"), foot_frame(prob.swing, "sole")
    dyn_res, drift = 0.0, 0.0
    M = np.zeros((m.nv, m.nv))
    for i in range(len(ns.s)):
        qpos, qvel = to_mujoco_state(robot, ns.H[i], ns.s[i], ns.vb[i], ns.sd[i])
        qacc = dyn.velocity_map(qpos).T @ np.concatenate([ns.ab[i], ns.sdd[i]])
        d.qpos[:], d.qvel[:] = qpos, qvel
        mujoco.mj_forward(m, d)
        mujoco.mj_fullM(m, d, M)
        p_st, _ = dyn.frame_pose(st_frame, qpos)
        J = _sole_jacobian(m, d, st_geom, p_st)
        tau = np.zeros(m.nv)
        tau[robot.dof_idx] = ns.u[i]
        lhs = M @ qacc + d.qfrc_bias
        r = lhs - tau - J.T @ ns.lam[i]
        dyn_res = max(dyn_res, float(np.linalg.norm(r) / max(np.linalg.norm(M @ qacc) + np.linalg.norm(d.qfrc_bias),
                                                           1.0)))
        drift = max(drift, float(np.linalg.norm(p_st)), float(np.linalg.norm(J @ qvel)))
    # impact and periodicity, at the last node (pre-impact)
    qpos, qvel = to_mujoco_state(robot, ns.H[-1], ns.s[-1], ns.vb[-1], ns.sd[-1])
    d.qpos[:], d.qvel[:] = qpos, qvel
    mujoco.mj_forward(m, d)
    mujoco.mj_fullM(m, d, M)
    p_sw, _ = dyn.frame_pose(sw_frame, qpos)
    Jsw = _sole_jacobian(m, d, sw_geom, p_sw)
    minv_jt = np.linalg.solve(M, Jsw.T)
    qvel_plus = qvel - minv_jt @ np.linalg.solve(Jsw @ minv_jt, Jsw @ qvel)
    impact_res = float(np.linalg.norm(Jsw @ qvel_plus))
    shifted = qpos.copy()
    shifted[:3] -= p_sw
    mq, mv = robot.mirror_state(shifted, qvel_plus)
    q0, v0 = to_mujoco_state(robot, ns.H[0], ns.s[0], ns.vb[0], ns.sd[0])
    if np.dot(mq[3:7], q0[3:7]) < 0:  # q and −q are the same rotation
        mq[3:7] *= -1
    periodicity = float(max(np.abs(mq - q0).max(), np.abs(mv - v0).max()))
    f, n = ns.lam[:, :3], ns.lam[:, 3:]
    fz = f[:, 2]
    friction = float(np.max(np.abs(f[:, :2]) / fz[:, None]))
    ax, ay = prob.half_length - cfg.cop_margin, prob.half_width - cfg.cop_margin
    cop = np.column_stack([-n[:, 1] / fz, n[:, 0] / fz])
    cop_margin = float(np.min(np.column_stack([ax - np.abs(cop[:, 0]), ay - np.abs(cop[:, 1])])))
    side = 1.0 if prob.swing == "left" else -1.0
    mid = (len(ns.s) - 1) // 2
    q_mid, _ = to_mujoco_state(robot, ns.H[mid], ns.s[mid], ns.vb[mid], ns.sd[mid])
    h_mid = dyn.frame_pose(sw_frame, q_mid)[0][2]
    errs = {
        "step_length_error": abs(p_sw[0] - params.step_length),
        "step_width_error": abs(side * p_sw[1] - params.step_width),
        "step_height_error": abs(h_mid - params.step_height),
        "duration_error": abs(duration - params.step_duration),
    }
    failures = []
    if dyn_res > DYNAMICS_TOL:
        failures.append(f"dynamics residual {dyn_res:.2e} > {DYNAMICS_TOL:g}")
    if drift > 1e-6:
        failures.append(f"stance foot moves ({drift:.2e})")
    if impact_res > 1e-6 or periodicity > PERIODICITY_TOL:
        failures.append(f"periodicity {periodicity:.2e} (impact {impact_res:.2e}) > {PERIODICITY_TOL:g}")
    if fz.min() < cfg.min_normal_force - FORCE_TOL or friction > cfg.friction + 1e-6 or cop_margin < -1e-6:
        failures.append(f"contact wrench outside the cone/sole (min f_z {fz.min():.1f} N, |f_t|/f_z {friction:.3f}, "
                        f"CoP margin {cop_margin:.4f} m)")
    for key, err in errs.items():
        tol = TIME_TOL if key == "duration_error" else LENGTH_TOL
        if err > tol:
            failures.append(f"{key.replace('_', ' ')} {err:.2e} > {tol:g}")
    return PhysicsCheck(dynamics_residual=dyn_res, stance_drift=drift, impact_residual=impact_res,
                        periodicity=periodicity, min_normal_force=float(fz.min()), friction_ratio=friction,
                        cop_margin=cop_margin, **{k: float(v) for k, v in errs.items()}, passed=not failures,
                        failures=tuple(failures))
