"""The reduced state of a certificate: coordinates Φ of a full state at the Poincaré section, the reconstruction ι
of a full state from reduced coordinates, and the metric of the certified ball (``docs/certificate.md``).

The paper certifies the base angular velocity and names the full state and the centroidal dynamics as other
choices (Tucker, Li, Ames, arXiv 2310.06169, §IV). Each choice is one :class:`ReducedState`, set up at the fixed
point x* = (q*, q̇*) of the return map:

* ``omega`` — the paper's: x̄ = A(q) ω_B, the base angular velocity in a frame (heading by default), 3-D,
  Euclidean metric in rad/s; ι from ``certify.reconstruction`` (:func:`holonomic_reconstruction` or
  angular-only).
* ``centroidal`` — the whole body's centroidal momentum h = (p, L) (linear momentum, angular momentum about the
  centre of mass), 6-D, heading frame. A push of impulse J at a point r from the centre of mass changes it by
  exactly (J, r × J). Metric: twice the centroidal kinetic energy, ‖h‖²_W = ‖p‖²/m + Lᵀ I_c⁻¹ L (I_c the
  locked inertia about the centre of mass at q*).
* ``velocity`` — every generalized velocity that keeps the stance contact, J_s δq̇ = 0 (n_v − 6 dimensions for a
  flat sole), in coordinates that are orthonormal for the kinetic-energy metric ‖δq̇‖²_M = δq̇ᵀ M(q*) δq̇ (twice
  the kinetic energy).

For the energy metrics ι adds to q̇* the least-kinetic-energy change that keeps the stance contact and produces
the reduced change (for ``velocity`` that change itself), so ι(x̄*) = x* and Φ(ι(x̄)) = x̄ exactly (at q*).
Velocities enter Φ in the heading representation H(q) q̇ (the base's linear velocity rotated by −yaw; MuJoCo's
angular velocity is already in the body frame; joints as they are), so Φ is invariant to the slow heading
drift of a walk, as the ``heading`` frame of ``omega`` is.

The "stance" contact is that of the step the section state starts: the sole that is touching down (the
convention of :func:`holonomic_reconstruction`, measured in ``docs/certificate.md``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Literal

import mujoco
import numpy as np
from numpy.typing import NDArray

from robustgait.certificate.shape import Shape
from robustgait.config import CertifyConfig, Frame, Reconstruction
from robustgait.robots import Robot
from robustgait.robots.model import mass_matrix
from robustgait.rotations import quat_to_mat

StateName = Literal["omega", "centroidal", "velocity"]
FloatArray = NDArray[np.float64]


def frame_rotation(qpos: FloatArray, frame: Frame) -> FloatArray:
    """A (..., 3, 3) with Φ = A ω_body: R (world), R_z(ψ)ᵀ R (heading, ψ = yaw of the base x axis), I (body)."""
    r = quat_to_mat(np.asarray(qpos)[..., 3:7])
    if frame == "body":
        return np.broadcast_to(np.eye(3), r.shape).copy()
    if frame == "world":
        return r
    return np.asarray(heading_rotation(qpos) @ r)


def heading_rotation(qpos: FloatArray) -> FloatArray:
    """R_z(ψ)ᵀ (..., 3, 3): world vectors into the heading frame (the world frame turned by the base's yaw ψ)."""
    r = quat_to_mat(np.asarray(qpos)[..., 3:7])
    psi = np.arctan2(r[..., 1, 0], r[..., 0, 0])
    c, s = np.cos(psi), np.sin(psi)
    zero, one = np.zeros_like(c), np.ones_like(c)
    return np.stack([np.stack([c, s, zero], -1), np.stack([-s, c, zero], -1), np.stack([zero, zero, one], -1)], -2)


def reduce_state(qpos: FloatArray, qvel: FloatArray, frame: Frame) -> FloatArray:
    """Φ(x) = A(q) ω_body, the base angular velocity in ``frame``: qpos (K, nq), qvel (K, nv) → (K, 3).

    Paper: x̄ = [0 I 0] x (Tucker, Li, Ames, arXiv 2310.06169, §IV).
    """
    a = frame_rotation(qpos, frame)
    return np.einsum("kij,kj->ki", a, np.asarray(qvel)[..., 3:6])


def heading_velocity(qpos: FloatArray, qvel: FloatArray) -> FloatArray:
    """H(q) q̇ (K, nv): MuJoCo's velocities with the base's linear velocity (world axes) rotated into the heading
    frame; the body-frame angular velocity and the joints are unchanged."""
    out = np.array(qvel, dtype=float, copy=True)
    out[..., 0:3] = np.einsum("kij,kj->ki", heading_rotation(qpos), np.asarray(qvel)[..., 0:3])
    return out


def section_dimension(robot: Robot) -> int:
    """d = nq + nv − 4: the number of section coordinates (:func:`section_coordinates`) of the robot's states."""
    return int(robot.model.nq + robot.model.nv - 4)


def section_coordinates(qpos: FloatArray, qvel: FloatArray, duration: float) -> FloatArray:
    """x_S (K, nq + nv − 4) of states qpos (K, nq), qvel (K, nv): the full state without the base's x, y and yaw ψ —
    (z, φ, θ, q_j) / T, then (v_h, ω_h, q̇_j): base height, roll φ and pitch θ (R = R_z(ψ) R_y(θ) R_x(φ)) and the
    joint positions divided by the step duration T, so that every coordinate is a rate (m/s or rad/s); the base's
    linear and angular velocity in the heading frame (world axes turned by ψ); the joint velocities.

    The coordinates of the return map's fixed point (``docs/certificate.md``, "Fixed point"): the physics does not
    depend on x and y at all, and on ψ only through MuJoCo's pyramidal friction cone, whose facets are fixed in the
    world (an elliptic cone: none; measured in ``tests/certificate/test_returnmap.py``)."""
    qpos, qvel = np.atleast_2d(qpos), np.atleast_2d(qvel)
    r = quat_to_mat(qpos[:, 3:7])
    roll = np.arctan2(r[:, 2, 1], r[:, 2, 2])
    pitch = -np.arcsin(np.clip(r[:, 2, 0], -1.0, 1.0))
    rz = heading_rotation(qpos)
    lin = np.einsum("kij,kj->ki", rz, qvel[:, 0:3])
    ang = np.einsum("kij,kj->ki", rz @ r, qvel[:, 3:6])
    pos = np.column_stack([qpos[:, 2], roll, pitch, qpos[:, 7:]])
    return np.column_stack([pos / duration, lin, ang, qvel[:, 6:]])


def section_state(xs: FloatArray, reference: FloatArray, duration: float) -> tuple[FloatArray, FloatArray]:
    """The states (K, nq), (K, nv) of section coordinates xs (K, nq + nv − 4) (:func:`section_coordinates`, whose
    inverse it is), with the base's x, y and yaw of ``reference`` (a qpos (nq,) or (K, nq))."""
    xs = np.atleast_2d(np.asarray(xs, dtype=float))
    k = xs.shape[0]
    ref = np.broadcast_to(np.asarray(reference, dtype=float), (k, np.shape(reference)[-1]))
    nq = ref.shape[1]
    pos, vel = xs[:, :nq - 4] * duration, xs[:, nq - 4:]
    rz = heading_rotation(ref)  # R_z(ψ)ᵀ of the reference's yaw
    psi = np.arctan2(rz[:, 0, 1], rz[:, 0, 0])
    c, s = np.cos(0.5 * pos[:, 1]), np.sin(0.5 * pos[:, 1])  # roll
    cp, sp = np.cos(0.5 * pos[:, 2]), np.sin(0.5 * pos[:, 2])  # pitch
    cy, sy = np.cos(0.5 * psi), np.sin(0.5 * psi)
    w, x, y, z = cp * c, cp * s, sp * c, -sp * s  # q_y(θ) q_x(φ)
    quat = np.column_stack([cy * w - sy * z, cy * x - sy * y, cy * y + sy * x, cy * z + sy * w])  # q_z(ψ) q_y q_x
    qpos = np.column_stack([ref[:, 0:2], pos[:, 0], quat, pos[:, 3:]])
    r = quat_to_mat(quat)
    world = np.transpose(rz, (0, 2, 1))  # R_z(ψ): heading frame → world
    lin = np.einsum("kij,kj->ki", world, vel[:, 0:3])
    ang = np.einsum("kji,kj->ki", r, np.einsum("kij,kj->ki", world, vel[:, 3:6]))  # Rᵀ R_z(ψ) ω_h
    return qpos, np.column_stack([lin, ang, vel[:, 6:]])


def stance_jacobian(robot: Robot, qpos: FloatArray, stance: str) -> FloatArray:
    """J_s (6, nv): the stance sole geom's (translational; rotational) Jacobian in MuJoCo's velocities."""
    m = robot.model
    d = mujoco.MjData(m)
    d.qpos[:] = qpos
    mujoco.mj_kinematics(m, d)
    mujoco.mj_comPos(m, d)
    jp, jr = np.zeros((3, m.nv)), np.zeros((3, m.nv))
    mujoco.mj_jacGeom(m, d, jp, jr, robot.sole_geom_id[stance])
    return np.vstack([jp, jr])


def holonomic_reconstruction(robot: Robot, qpos: FloatArray, stance: str) -> FloatArray:
    """Linear map G (nv, 3): the velocity change δq̇ = G δω for a change δω of the base's body-frame
    angular velocity that keeps the stance sole's twist unchanged, with the least joint-velocity change.

    Solves  min ½‖δq̇_j‖²  s.t.  J_s δq̇ = 0,  δq̇ = (δv, δω, δq̇_j),  δω given,  δv free,
    via its KKT system [[I, 0, J_jᵀ], [0, 0, J_vᵀ], [J_j, J_v, 0]] [δq̇_j; δv; λ] = [0; 0; −J_ω δω], where
    J_s = [J_v J_ω J_j] (6 × nv) is the stance sole geom's (translational; rotational) Jacobian in MuJoCo's
    velocity coordinates (``mj_jacGeom``). qpos (nq,). (``docs/certificate.md``, "holonomic" reconstruction.)
    """
    js = stance_jacobian(robot, qpos, stance)
    nv = js.shape[1]
    jv, jw, jj = js[:, 0:3], js[:, 3:6], js[:, 6:]
    nj = jj.shape[1]
    kkt = np.zeros((nj + 3 + 6, nj + 3 + 6))
    kkt[:nj, :nj] = np.eye(nj)
    kkt[:nj, nj + 3:] = jj.T
    kkt[nj:nj + 3, nj + 3:] = jv.T
    kkt[nj + 3:, :nj] = jj
    kkt[nj + 3:, nj:nj + 3] = jv
    rhs = np.zeros((nj + 9, 3))
    rhs[nj + 3:] = -jw
    sol = np.linalg.lstsq(kkt, rhs, rcond=None)[0]
    g = np.zeros((nv, 3))
    g[3:6] = np.eye(3)
    g[0:3] = sol[nj:nj + 3]
    g[6:] = sol[:nj]
    return g


def least_energy_map(mass: FloatArray, constraint: FloatArray, target: FloatArray) -> FloatArray:
    """G (nv, k): δq̇ = G b is the least-kinetic-energy velocity change with ``constraint`` δq̇ = 0 and
    ``target`` δq̇ = b, i.e. argmin δq̇ᵀ M δq̇ s.t. C δq̇ = (0, b), C = [constraint; target]:
    δq̇ = M⁻¹ Cᵀ (C M⁻¹ Cᵀ)⁻¹ (0, b). Shapes: mass (nv, nv), constraint (c, nv), target (k, nv)."""
    c = np.vstack([constraint, target])
    minv_ct = np.linalg.solve(mass, c.T)
    rows = np.linalg.solve(c @ minv_ct, np.eye(c.shape[0]))
    return np.asarray(minv_ct @ rows[:, constraint.shape[0]:])


def centroidal_momentum(robot: Robot, qpos: FloatArray, qvel: FloatArray) -> FloatArray:
    """h (K, 6) = (p, L): the whole robot's linear momentum m v_com and angular momentum about its centre of
    mass, in the heading frame, of K states (MuJoCo's ``subtree_linvel`` and ``subtree_angmom`` of the base's
    subtree, computed from ``mj_kinematics``, ``mj_comPos``, ``mj_comVel``, ``mj_subtreeVel``)."""
    m = robot.model
    d = mujoco.MjData(m)
    b = robot.base_body_id
    qpos, qvel = np.atleast_2d(qpos), np.atleast_2d(qvel)
    out = np.empty((qpos.shape[0], 6))
    mass = robot.mass
    for i in range(qpos.shape[0]):
        d.qpos[:], d.qvel[:] = qpos[i], qvel[i]
        mujoco.mj_kinematics(m, d)
        mujoco.mj_comPos(m, d)
        mujoco.mj_comVel(m, d)
        mujoco.mj_subtreeVel(m, d)
        out[i, :3] = mass * d.subtree_linvel[b]
        out[i, 3:] = d.subtree_angmom[b]
    rz = heading_rotation(qpos)
    out[:, :3] = np.einsum("kij,kj->ki", rz, out[:, :3])
    out[:, 3:] = np.einsum("kij,kj->ki", rz, out[:, 3:])
    return out


def centroidal_inertia(robot: Robot, qpos: FloatArray) -> FloatArray:
    """I_c (3, 3): the locked rotational inertia of the whole robot about its centre of mass, heading frame:
    Σ_b R_b I_b R_bᵀ + m_b (‖c_b‖² I − c_b c_bᵀ), c_b = body centre of mass − robot centre of mass."""
    m = robot.model
    d = mujoco.MjData(m)
    d.qpos[:] = qpos
    mujoco.mj_kinematics(m, d)
    bodies = [i for i in range(1, m.nbody) if m.body_rootid[i] == m.body_rootid[robot.base_body_id]]
    masses = m.body_mass[bodies]
    com = (masses[:, None] * d.xipos[bodies]).sum(0) / masses.sum()
    inertia = np.zeros((3, 3))
    for i, mb in zip(bodies, masses, strict=True):
        r = d.ximat[i].reshape(3, 3)
        c = d.xipos[i] - com
        inertia += r @ np.diag(m.body_inertia[i]) @ r.T + mb * (c @ c * np.eye(3) - np.outer(c, c))
    rz = heading_rotation(qpos)
    return np.asarray(rz @ inertia @ rz.T)


@dataclass
class ReducedState:
    """Φ, ι and the metric W of one choice of reduced state, set up at a fixed point (module docstring).

    ``dim``: k; ``unit``: of the coordinates; ``energy``: ‖δ‖²_W is twice a kinetic energy [J] (then a ball of
    radius r certifies the perturbations of kinetic energy ≤ r²/2); ``metric`` (k, k) positive definite:
    ‖δ‖²_W = δᵀ W δ, distances of the certificate are in this metric.
    """

    name: StateName
    robot: Robot
    qpos: FloatArray  # q* (nq,)
    qvel: FloatArray  # q̇* (nv,)
    stance: str
    frame: Frame
    reconstruction: Reconstruction
    dim: int = 0
    unit: str = ""
    energy: bool = False
    metric: FloatArray | None = None
    _iota: FloatArray | None = None  # δq̇ = G (x̄ − x̄*) (nv, k), MuJoCo velocities
    _proj: FloatArray | None = None  # velocity: x̄ = P H(q) q̇ (k, nv)

    @classmethod
    def at(cls, name: StateName, robot: Robot, qpos: FloatArray, qvel: FloatArray, stance: str,
           config: CertifyConfig) -> ReducedState:
        """The reduced state ``name`` set up at the fixed point (qpos, qvel) of a gait whose section states start a
        step of ``stance``."""
        s = cls(name, robot, np.asarray(qpos, float), np.asarray(qvel, float), stance, config.frame,
                config.reconstruction)
        s._setup()
        return s

    def _setup(self) -> None:
        robot, q = self.robot, self.qpos
        nv = robot.model.nv
        js = stance_jacobian(robot, q, self.stance)
        if self.name == "omega":
            self.dim, self.unit, self.metric = 3, "rad/s", np.eye(3)
            a_inv = np.linalg.inv(frame_rotation(q, self.frame))  # body-frame δω of a reduced change
            if self.reconstruction == "angular-only":
                g = np.zeros((nv, 3))
                g[3:6] = np.eye(3)
            else:
                g = holonomic_reconstruction(robot, q, self.stance)
            self._iota = g @ a_inv
            return
        mass = mass_matrix(robot.model, q)[1]
        h = np.eye(nv)
        h[0:3, 0:3] = heading_rotation(q[None])[0]  # H(q*): heading representation, orthogonal
        if self.name == "centroidal":
            basis = centroidal_momentum(robot, np.tile(q, (nv, 1)), np.eye(nv))  # A (nv rows → h): linear in q̇
            a = basis.T  # (6, nv): h = A q̇ at q*
            self.dim, self.unit, self.energy = 6, "√J", True
            self.metric = np.zeros((6, 6))
            self.metric[:3, :3] = np.eye(3) / robot.mass
            self.metric[3:, 3:] = np.linalg.inv(centroidal_inertia(robot, q))
            self._iota = least_energy_map(mass, js, a)
            return
        # velocity: an M-orthonormal basis N (heading representation) of the velocities with J_s δq̇ = 0
        m_h = h @ mass @ h.T
        null = _null_space(js @ h.T)  # (nv, nv − rank): J_s Hᵀ N = 0
        chol = np.linalg.cholesky(null.T @ m_h @ null)
        n = null @ np.linalg.inv(chol).T  # Nᵀ M̂ N = I
        self.dim, self.unit, self.energy, self.metric = n.shape[1], "√J", True, np.eye(n.shape[1])
        self._proj = n.T @ m_h  # x̄ = Nᵀ M̂ H q̇
        self._iota = h.T @ n  # δq̇ = Hᵀ N δ

    @property
    def x_star(self) -> FloatArray:
        return self.phi(self.qpos[None], self.qvel[None])[0]

    def phi(self, qpos: FloatArray, qvel: FloatArray) -> FloatArray:
        """Φ: reduced coordinates (K, k) of full states qpos (K, nq), qvel (K, nv)."""
        if self.name == "omega":
            return reduce_state(qpos, qvel, self.frame)
        if self.name == "centroidal":
            return centroidal_momentum(self.robot, qpos, qvel)
        assert self._proj is not None
        return np.asarray(heading_velocity(qpos, qvel) @ self._proj.T)

    def iota(self, xbar: FloatArray) -> tuple[FloatArray, FloatArray]:
        """ι: full states (N, nq), (N, nv) of reduced ones (N, k): the configuration of x*, the velocity of x*
        plus the change of the module docstring (exactly x* at x̄*)."""
        assert self._iota is not None
        xbar = np.atleast_2d(np.asarray(xbar, dtype=float))
        n = xbar.shape[0]
        qpos = np.tile(self.qpos, (n, 1))
        qvel = np.tile(self.qvel, (n, 1)) + (xbar - self.x_star) @ self._iota.T
        return qpos, qvel

    def kinetic_energy(self, qpos: FloatArray, qvel: FloatArray) -> FloatArray:
        """½ dᵀ M̂(q*) d (K,) [J], d = H(q) q̇ − H(q*) q̇* (heading representations, each state's own yaw): the
        kinetic energy a perturbation of the velocities adds, measured with the fixed point's inertia."""
        mass = mass_matrix(self.robot.model, self.qpos)[1]
        h = np.eye(len(self.qvel))
        h[0:3, 0:3] = heading_rotation(self.qpos[None])[0]
        m_h = h @ mass @ h.T
        d = heading_velocity(np.atleast_2d(qpos), np.atleast_2d(qvel)) - heading_velocity(self.qpos[None],
                                                                                          self.qvel[None])
        return np.asarray(0.5 * np.einsum("ki,ij,kj->k", d, m_h, d))


def _null_space(a: FloatArray, rtol: float = 1e-10) -> FloatArray:
    """An orthonormal basis (n, n − rank) of the null space of a (m, n), by SVD."""
    _, s, vt = np.linalg.svd(a)
    rank = int(np.sum(s > rtol * max(s[0], 1.0)))
    return np.asarray(vt[rank:].T)


def energy_of_radius(r: float) -> float:
    """E = r²/2 [J]: the kinetic energy certified by a ball of radius r of an energy metric."""
    return 0.5 * r * r if math.isfinite(r) else math.inf


def metric_factor(metric: FloatArray) -> FloatArray:
    """Lᵀ (k, k) with W = L Lᵀ (Cholesky): ‖δ‖²_W = δᵀ W δ = ‖Lᵀ δ‖², so the ball of W is Euclidean in Lᵀ x̄."""
    return np.asarray(np.linalg.cholesky(np.asarray(metric, dtype=float)).T)


@dataclass(frozen=True)
class Coordinates:
    """The coordinates a certificate is computed in: z = T x̄ of the reduced state x̄ = Φ(x), T = Cᵀ Lᵀ, where Lᵀ makes
    the state's metric Euclidean (:func:`metric_factor`) and Cᵀ the certified set's shape a ball
    (:class:`.shape.Shape`; C = I for the ball). The certified set B(z*, r*) is then
    {x̄ : (x̄ − x̄*)ᵀ Tᵀ T (x̄ − x̄*) ≤ r*²}.

    ``space``: omega, centroidal, velocity, or push (impulses, T = I); ``unit`` of z and r*; ``energy``: ‖z − z*‖²
    is twice a kinetic energy for the ball (:meth:`energy`); ``x_bar_star`` x̄* (k,); ``metric_t`` Lᵀ; ``shape``.
    """

    space: str
    unit: str
    energy_metric: bool
    x_bar_star: FloatArray
    metric_t: FloatArray
    shape: Shape

    @staticmethod
    def of(reduced: ReducedState, shape: Shape | None = None) -> Coordinates:
        assert reduced.metric is not None
        k = reduced.dim
        return Coordinates(reduced.name, reduced.unit, reduced.energy, reduced.x_star, metric_factor(reduced.metric),
                           shape if shape is not None else Shape(np.eye(k)))

    @property
    def dim(self) -> int:
        return int(self.x_bar_star.shape[0])

    @property
    def transform(self) -> FloatArray:
        """T (k, k): z = T x̄."""
        return np.asarray(self.shape.transform @ self.metric_t)

    @property
    def x_star(self) -> FloatArray:
        return np.asarray(self.transform @ self.x_bar_star)

    def to_z(self, xbar: FloatArray) -> FloatArray:
        """z (N, k) of reduced states x̄ (N, k) (NaN rows stay NaN)."""
        return np.asarray(np.atleast_2d(xbar) @ self.transform.T)

    def to_xbar(self, z: FloatArray) -> FloatArray:
        """x̄ (N, k) of certificate coordinates z (N, k)."""
        return np.asarray(np.linalg.solve(self.transform, np.atleast_2d(z).T).T)

    def energy(self, r: float) -> float | None:
        """E* [J]: every perturbation of kinetic energy ≤ E* lies in the certified set of radius r (the ball:
        r²/2 exactly; an ellipsoid: that of the largest ball inside it); None if the metric is not an energy."""
        if not self.energy_metric:
            return None
        return energy_of_radius(self.shape.inner_radius(r))

    @staticmethod
    def from_dict(d: dict[str, Any]) -> Coordinates:
        """Back from :meth:`to_dict` (a certificate JSON's ``coordinates``)."""
        k = len(d["x_bar_star"])
        s = np.asarray(d.get("shape", {}).get("S", np.eye(k)), dtype=float)
        return Coordinates(str(d["space"]), str(d["unit"]), bool(d["energy_metric"]),
                           np.asarray(d["x_bar_star"], dtype=float), np.asarray(d["metric_factor"], dtype=float),
                           Shape(s, None, str(d.get("shape", {}).get("fallback", ""))))

    def to_dict(self) -> dict[str, object]:
        return {"space": self.space, "unit": self.unit, "energy_metric": self.energy_metric,
                "x_bar_star": self.x_bar_star.tolist(), "transform": self.transform.tolist(),
                "metric_factor": self.metric_t.tolist(), "shape": self.shape.to_dict()}
