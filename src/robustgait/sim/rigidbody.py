"""Vectorized rigid-body dynamics of a MuJoCo kinematic tree for K states at once (NumPy).

The feedback engine (:mod:`robustgait.sim.feedback`) steps K simulations in lockstep; a model-based law such as
the passivity-based tracking controller (:mod:`robustgait.sim.passivity`) needs, at every physics step and for
all K states, the mass matrix M(q), the gravity vector G(q), Coriolis terms at velocities other than the
simulated one, and Jacobians and their derivatives. Calling MuJoCo per sample for those would cost a Python
round trip per sample per step; instead this module evaluates them in batched NumPy from the per-state
kinematic quantities MuJoCo already computes in its position stage, which the batch hands out:

* ``cdof`` (K, nv, 6): each dof's motion axis, a spatial motion vector [angular; linear] in MuJoCo's
  "com-based" frame (world orientation, origin at the subtree centre of mass of the tree's root body);
* ``cinert`` (K, nbody, 10): each body's spatial inertia in that frame (MuJoCo's packed layout).

With them, in Featherstone's notation (Featherstone, *Rigid Body Dynamics Algorithms*, 2008, ch. 5–6) and
following MuJoCo's own ``mj_comVel`` / ``mj_rne`` / ``mj_crb`` (engine_core_smooth.c):

* body velocity  v_b = Σ_{d ∈ anc(b)} S_d q̇_d  (S_d = cdof_d);
* dof-axis rate  Ṡ_d = v_{before d} ×ₘ S_d  (``mj_comVel``'s convention: the velocity of the parent body plus
  the dofs of the same body that precede d; zero for the translational dofs of a free joint);
* bias acceleration  a_b = Σ_{d ∈ anc(b)} Ṡ_d q̇_d  (spatial, in the fixed frame that coincides with the
  com-based frame at this instant);
* body force  f_b = I_b a_b + v_b ×_f (I_b v_b);  generalized force  c_d = S_dᵀ Σ_{b ∈ subtree(d)} f_b.

so ``velocity_terms(v)`` = c(q, v) = C(q, v) v (MuJoCo's ``qfrc_bias`` minus gravity) for any velocity v,
together with every body's bias acceleration J̇_b(q, v) v; ``gravity`` = G(q) (MuJoCo's gravity part of
``qfrc_bias``); ``mass_matrix`` = M(q) by the composite-rigid-body algorithm (plus ``dof_armature``). Each is
checked against MuJoCo (mj_rne, mj_fullM, mj_jacDot) in tests/sim/test_feedback.py.

Not modelled (the shipped robots have none): passive joint forces (springs, dampers, friction loss),
gravity compensation, fluid forces, tendons, and joints other than free / hinge / slide.
"""

from __future__ import annotations

import mujoco
import numpy as np
from numpy.typing import NDArray

from robustgait.errors import RobustGaitError

Array = NDArray[np.float64]


def _cross_map() -> Array:
    """The (6, 36) linear map from a spatial motion v = [ω; v_l] to the flattened 6 × 6 matrix v×ₘ =
    [[ω×, 0], [v_l×, ω×]]; the force cross product is v×_f = −(v×ₘ)ᵀ."""
    out = np.zeros((6, 6, 6))
    for k, (i, j) in enumerate(((2, 1), (0, 2), (1, 0))):  # ω_k: (a×)[i, j] = +ω_k, [j, i] = −ω_k
        for off in (0, 3):
            out[k, off + i, off + j] = 1.0
            out[k, off + j, off + i] = -1.0
        out[3 + k, 3 + i, j] = 1.0
        out[3 + k, 3 + j, i] = -1.0
    return out.reshape(6, 36)


_CROSS_MAP = _cross_map()


def motion_cross_matrix(v: Array) -> Array:
    """(..., 6) spatial motions → (..., 6, 6) matrices v×ₘ (MuJoCo's ``mju_crossMotion``: v×ₘ m)."""
    return (v @ _CROSS_MAP).reshape(*v.shape[:-1], 6, 6)


def cross_motion(v: Array, m: Array) -> Array:
    """v ×ₘ m for spatial motion vectors [angular; linear] (MuJoCo's ``mju_crossMotion``), broadcast."""
    return (motion_cross_matrix(v) @ m[..., None])[..., 0]


def cross_force(v: Array, f: Array) -> Array:
    """v ×_f f = −(v×ₘ)ᵀ f for a spatial motion v and a force f [torque; force] (``mju_crossForce``)."""
    return -(motion_cross_matrix(v).swapaxes(-1, -2) @ f[..., None])[..., 0]


def _inertia_map() -> Array:
    """The (10, 36) linear map from MuJoCo's packed inertia to the flattened 6 × 6 spatial inertia
    [[I, h×], [h×ᵀ, m 1]] (``mju_mulInertVec``)."""
    out = np.zeros((10, 6, 6))
    for k, (i, j) in enumerate(((0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2))):
        out[k, i, j] = out[k, j, i] = 1.0
    # h× in the upper-right block (h = m · com offset), its transpose in the lower-left: a symmetric matrix
    for k, i, j, sign in ((6, 1, 5, -1.0), (6, 2, 4, 1.0), (7, 0, 5, 1.0), (7, 2, 3, -1.0),
                          (8, 0, 4, -1.0), (8, 1, 3, 1.0)):
        out[k, i, j] = out[k, j, i] = sign
    out[9, 3, 3] = out[9, 4, 4] = out[9, 5, 5] = 1.0
    return out.reshape(10, 36)


_INERTIA_MAP = _inertia_map()


def spatial_inertia(cinert: Array) -> Array:
    """(..., 10) MuJoCo packed inertias → (..., 6, 6) matrices [[I, h×], [h×ᵀ, m 1]] (``mju_mulInertVec``)."""
    c = np.asarray(cinert)
    return (c @ _INERTIA_MAP).reshape(*c.shape[:-1], 6, 6)


class TreeDynamics:
    #: batch size K·P from which :meth:`velocity_terms` uses component formulas for the cross and inertia
    #: products (fewer flops) instead of 6 × 6 matrices (fewer NumPy calls); both give the same result
    slab_threshold = 32

    """Dynamics of one MuJoCo model's kinematic tree for batches of states (module docstring).

    Built once per model from its structure (parents, joint types); the per-state inputs are the ``cdof``
    (K, nv, 6) and ``cinert`` (K, nbody, 10) of K states, as MuJoCo computes them in its position stage,
    passed through :meth:`prepare`.
    """

    def __init__(self, model: mujoco.MjModel):
        m = model
        nv, nb = m.nv, m.nbody
        self.nv, self.nbody = nv, nb
        allowed = {int(mujoco.mjtJoint.mjJNT_FREE), int(mujoco.mjtJoint.mjJNT_HINGE),
                   int(mujoco.mjtJoint.mjJNT_SLIDE)}
        if any(int(t) not in allowed for t in m.jnt_type):
            raise RobustGaitError("TreeDynamics supports free, hinge and slide joints only")
        dof_body = np.asarray(m.dof_bodyid, dtype=np.int64)
        # anc[b, d]: dof d moves body b (d belongs to b or to an ancestor of b)
        anc = np.zeros((nb, nv))
        for b in range(1, nb):
            p = b
            while p > 0:
                anc[b, dof_body == p] = 1.0
                p = int(m.body_parentid[p])
        # before[d, e]: dof e's velocity is in the velocity that mj_comVel crosses with dof d's axis
        before = np.zeros((nv, nv))
        for b in range(1, nb):
            cur = anc[int(m.body_parentid[b])].copy()  # the parent body's velocity
            for j in range(int(m.body_jntadr[b]), int(m.body_jntadr[b]) + int(m.body_jntnum[b])):
                adr = int(m.jnt_dofadr[j])
                if int(m.jnt_type[j]) == int(mujoco.mjtJoint.mjJNT_FREE):
                    # translational dofs: Ṡ = 0 (MuJoCo zeroes them); rotational: parent + translation
                    cur[adr:adr + 3] = 1.0
                    for k in range(3):
                        before[adr + 3 + k] = cur
                    cur[adr + 3:adr + 6] = 1.0
                else:
                    before[adr] = cur
                    cur[adr] = 1.0
        self.anc = anc
        self.before = before
        self.sub = anc.T.copy()  # sub[d, b]: body b is in the subtree of dof d's body
        # above[e, d]: dof e is dof d or on its path to the root (e's body is an ancestor-or-self of d's)
        self.above = anc[dof_body].T.astype(bool)
        # dofs are numbered parents first, so "e above d" lies in the upper triangle (mutual pairs, the dofs
        # of one body, are kept once)
        self.upper = np.triu(self.above).astype(float)
        self._diag = np.arange(nv)
        self.armature = np.asarray(m.dof_armature, dtype=float).copy()
        self.gravity_acc = np.concatenate([np.zeros(3), -np.asarray(m.opt.gravity, dtype=float)])
        self.dof_body = dof_body

    def prepare(self, cdof: Array, cinert: Array) -> TreeState:
        """The per-state inputs of K states, ``cdof`` (K, nv, 6) and ``cinert`` (K, nbody, 10), laid out for the
        batched computations: component first, then the tree index, then the batch, so that sums over the tree
        and the products by spatial inertias and cross-product matrices are each a few BLAS or elementwise
        operations on whole arrays (few NumPy calls for K = 1, vectorized for K in the hundreds)."""
        kk = cdof.shape[0]
        ci = np.ascontiguousarray(cinert.transpose(2, 1, 0))  # (10, nbody, K)
        i6 = (_INERTIA_MAP.T @ ci.reshape(10, -1)).reshape(6, 6, self.nbody, kk)
        return TreeState(np.ascontiguousarray(cdof.transpose(2, 1, 0)), ci, i6, cdof)

    def mass_matrix(self, st: TreeState) -> Array:
        """M(q) (K, nv, nv) by the composite-rigid-body algorithm: M_ed = S_eᵀ I^c_{b(d)} S_d for e on d's
        path to the root, with I^c the composite inertia of d's body's subtree; plus ``dof_armature``."""
        kk = st.cd.shape[2]
        comp = self.sub @ st.ci  # (10, nv, K): packed inertias add up
        ic = (_INERTIA_MAP.T @ comp.reshape(10, -1)).reshape(6, 6, self.nv, kk)
        force = (ic * st.cd[None]).sum(axis=1)  # (6, nv, K)
        raw = (st.cdof @ force.transpose(2, 0, 1)) * self.upper  # raw[e, d] = S_e · I^c_d S_d, e above d
        full = raw + raw.transpose(0, 2, 1)
        full[:, self._diag, self._diag] = raw[:, self._diag, self._diag] + self.armature
        return full

    def gravity(self, st: TreeState) -> Array:
        """G(q) (K, nv): the gravity part of MuJoCo's ``qfrc_bias`` (every body accelerated by −g)."""
        fg = np.einsum("ijbk,j->ibk", st.i6, self.gravity_acc)  # I_b a_g, (6, nbody, K)
        return (st.cd * (self.sub @ fg)).sum(axis=0).T

    def acceleration_terms(self, st: TreeState, a: Array, *, gravity: bool = True) -> Array:
        """M(q) a (+ G(q)) (K, nv) for accelerations a (K, nv), by the RNE with zero velocity: every body's
        acceleration Σ_{d ∈ anc(b)} S_d a_d (− g), its force I_b times that, summed over subtrees and projected
        on the dofs — cheaper than forming M. ``dof_armature`` is included."""
        nb = self.nbody
        kk = a.shape[0]
        at = np.ascontiguousarray(a.T)  # (nv, K)
        acc = (self.anc @ (st.cd * at)).reshape(6, nb, kk)
        if gravity:
            acc = acc + self.gravity_acc[:, None, None]
        if kk >= self.slab_threshold:
            f = _inert_mul_slab(st.ci, acc)
        else:
            f = (st.i6 * acc[None]).sum(axis=1)
        out = (st.cd * (self.sub @ f)).sum(axis=0).T
        return out + self.armature * a

    def velocity_terms(self, st: TreeState, v: Array) -> tuple[Array, Array]:
        """c(q, v) = C(q, v) v (K, P, nv) and every body's bias acceleration J̇_b(q, v) v (K, P, nbody, 6) for P
        velocities v (K, P, nv) per state (gravity excluded). Quadratic in v."""
        nv, nb = self.nv, self.nbody
        kk, pp = v.shape[0], v.shape[1]
        vv = np.ascontiguousarray(v.transpose(2, 1, 0))  # (nv, P, K)
        cd = st.cd[:, :, None]  # (6, nv, 1, K)
        x = (cd * vv).reshape(6, nv, -1)  # S_d q̇_d, (6, nv, P·K)
        vel = (self.anc @ x).reshape(6, nb, pp, kk)
        vb = (self.before @ x).reshape(6, nv, pp, kk)
        if kk * pp >= self.slab_threshold:  # large batches: component formulas, fewer flops
            sdot = _cross_motion_slab(vb, cd)
            acc = (self.anc @ (sdot * vv).reshape(6, nv, -1)).reshape(6, nb, pp, kk)
            ci = st.ci[:, :, None]
            f = _inert_mul_slab(ci, acc) + _cross_force_slab(vel, _inert_mul_slab(ci, vel))
        else:  # small batches: 6 × 6 matrices, fewer NumPy calls
            sdot = _cross_motion(vb, cd)
            acc = (self.anc @ (sdot * vv).reshape(6, nv, -1)).reshape(6, nb, pp, kk)
            i6 = st.i6[:, :, :, None]  # (6, 6, nb, 1, K)
            f = (i6 * acc[None]).sum(axis=1) + _cross_force(vel, (i6 * vel[None]).sum(axis=1))
        c = (cd * (self.sub @ f.reshape(6, nb, -1)).reshape(6, nv, pp, kk)).sum(axis=0)
        return c.transpose(2, 1, 0), acc.transpose(3, 2, 1, 0)


class TreeState:
    """Per-state inputs of :class:`TreeDynamics` in its layout (:meth:`TreeDynamics.prepare`)."""

    def __init__(self, cd: Array, ci: Array, i6: Array, cdof: Array):
        self.cd = cd  # (6, nv, K) dof axes
        self.ci = ci  # (10, nbody, K) packed inertias
        self.i6 = i6  # (6, 6, nbody, K) spatial inertias
        self.cdof = cdof  # (K, nv, 6)


def _cross_matrices(v: Array) -> Array:
    """(6, ...) motions → (6, 6, ...) matrices v×ₘ (component axes first)."""
    return (_CROSS_MAP.T @ v.reshape(6, -1)).reshape(6, 6, *v.shape[1:])


def _cross_motion(v: Array, m: Array) -> Array:
    """v ×ₘ m with the 6 components on axis 0 (``mju_crossMotion``), m broadcast against v."""
    return (_cross_matrices(v) * m[None]).sum(axis=1)


def _cross_force(v: Array, f: Array) -> Array:
    """v ×_f f = −(v×ₘ)ᵀ f with the 6 components on axis 0 (``mju_crossForce``)."""
    return -(_cross_matrices(v) * f[:, None]).sum(axis=0)


def _cross3(a: Array, b: Array) -> Array:
    """a × b with the 3 components on axis 0."""
    return np.stack([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])


def _cross_motion_slab(v: Array, m: Array) -> Array:
    """:func:`_cross_motion` by components: [ω × m_a; ω × m_l + v_l × m_a]."""
    w, vl = v[:3], v[3:]
    return np.concatenate([_cross3(w, m[:3]), _cross3(w, m[3:]) + _cross3(vl, m[:3])])


def _cross_force_slab(v: Array, f: Array) -> Array:
    """:func:`_cross_force` by components: [ω × f_t + v_l × f_f; ω × f_f]."""
    w, vl = v[:3], v[3:]
    return np.concatenate([_cross3(w, f[:3]) + _cross3(vl, f[3:]), _cross3(w, f[3:])])


def _inert_mul_slab(i: Array, v: Array) -> Array:
    """I v for MuJoCo packed inertias i (10, ...) and motions v (6, ...) (``mju_mulInertVec``):
    [I ω + h × v_l; m v_l − h × ω], I the rotational inertia, h = m · com offset, m the mass."""
    w0, w1, w2, l0, l1, l2 = v
    i0, i1, i2, i3, i4, i5, h0, h1, h2, mass = i
    return np.stack([
        i0 * w0 + i3 * w1 + i4 * w2 + h1 * l2 - h2 * l1,
        i3 * w0 + i1 * w1 + i5 * w2 + h2 * l0 - h0 * l2,
        i4 * w0 + i5 * w1 + i2 * w2 + h0 * l1 - h1 * l0,
        mass * l0 - h1 * w2 + h2 * w1,
        mass * l1 - h2 * w0 + h0 * w2,
        mass * l2 - h0 * w1 + h1 * w0,
    ])


class NominalKinematics:
    """MuJoCo's position-stage kinematic quantities ``cdof`` and ``cinert`` of K configurations, computed on a
    scratch ``MjData`` of a fixed (nominal) model with ``mj_kinematics`` + ``mj_comPos`` (no collision
    detection), sample by sample.

    The feedback engine's passivity law evaluates its model with this rather than with the simulator's own
    position stage at the new state: the batched physics step then stays a plain ``mj_step`` (a persistent batch
    that also computes the next position stage, or a NumPy forward kinematics over the tree's levels, is slower:
    docs/feedback.md), and the controller keeps the *nominal* model when the simulated plants are perturbed
    (per-sample masses, friction, terrain), as a real controller would.
    """

    def __init__(self, model: mujoco.MjModel):
        self.model = model
        self.data = mujoco.MjData(model)

    def __call__(self, qpos: Array) -> tuple[Array, Array]:
        """``cdof`` (K, nv, 6) and ``cinert`` (K, nbody, 10) at configurations ``qpos`` (K, nq)."""
        m, d = self.model, self.data
        kk = qpos.shape[0]
        cdof = np.empty((kk, m.nv, 6))
        cinert = np.empty((kk, m.nbody, 10))
        kin, com = mujoco.mj_kinematics, mujoco.mj_comPos
        for i in range(kk):
            d.qpos[:] = qpos[i]
            kin(m, d)
            com(m, d)
            cdof[i] = d.cdof
            cinert[i] = d.cinert
        return cdof, cinert
