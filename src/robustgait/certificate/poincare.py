"""The step-to-step Poincaré map on the switching surface, in a reduced state (``docs/certificate.md``).

Section S: the switching events of the simulator (swing-foot touchdown once τ ≥ ``min_switch_tau``, the paper's
x⁻ ∈ S). A state on S starts a step of one stance. *Canonical* states are written for the gait's own stance
(``gait.stance``); a state that starts a step of the other stance is mirrored (:meth:`Robot.mirror_state`),
so a symmetric gait has a period-1 fixed point of the **step map** P: S → S (one step, then mirror). The
**stride map** is two steps, no mirroring. With a horizon k the map certified is P^k: k maps on full states, a
fall in any of them a fall.

The fixed point x* (:meth:`ReturnMap.find_fixed_point`, ``docs/certificate.md`` "Fixed point") is searched on full
states in **section coordinates** (:func:`.reduced.section_coordinates`: the canonical state
without the base's x, y and yaw, under which the map is equivariant): iterate until a window of ``fp_window`` iterates
lies within ``fp_tol``, optionally refine by damped Newton on P(x) = x, then the spectral radius ρ of the linearized map
(:mod:`.numerics`); a gait whose orbit does not settle, settles with period two, or whose ρ ≥
``fp_rho_max`` has no fixed point to certify — unless the stride map, searched when the step map has no orbit
(:func:`settle`, ``stride_fallback``: a robot whose left and right differ), settles. The certificate's reduced state
(Φ, ι and metric of ``certify.state``: :class:`.reduced.ReducedState`) is set up at x*.
Frames of the base angular velocity ω:

* ``heading`` (default): ω in the world frame rotated by the base's yaw, R_z(ψ)ᵀ ω. Equals the world frame
  for a robot heading along +x, and is invariant to the slow heading drift of a real walk — which the
  world frame is not once states are mirrored (measured on the Atalante gait, step-map iterates 50–100:
  yaw drifts from +0.007 to −0.083 rad; world-frame residual median 6.9e-3, max 1.6e-2 rad/s; heading
  frame median 2.7e-3, max 4.9e-3).
* ``world``: ω in the world frame, R ω_body.
* ``body``: ω_body, MuJoCo's ``qvel[3:6]``.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from dataclasses import dataclass

import mujoco
import numpy as np
from numpy.typing import NDArray

from robustgait.certificate.numerics import (
    BatchMap,
    Jacobian,
    OrbitReport,
    fd_jacobian,
    flow_projection,
    newton,
    orbit_status,
    search_report,
    spectral_radius,
    window_residual,
)
from robustgait.certificate.reduced import ReducedState, reduce_state, section_coordinates, section_state
from robustgait.config import CertifyConfig, Frame, MapKind, SimConfig
from robustgait.config.certify import NEWTON_DAMPING
from robustgait.domains import step_segments
from robustgait.errors import RobustGaitError
from robustgait.gait import Gait
from robustgait.robots import Robot
from robustgait.sim.factory import make_engine
from robustgait.sim.walk import SwitchEvent, WalkResult, canonical_event_states

FloatArray = NDArray[np.float64]


def canonical_reduced_events(robot: Robot, gait: Gait, events: list[SwitchEvent], frame: Frame) -> FloatArray:
    """Reduced states (len(events), 3) of a walk's switching events, each written for the gait's own stance
    (events that start a step of the other stance are mirrored) — the sequence the step map acts on."""
    qpos, qvel = canonical_event_states(robot, gait, events)
    return reduce_state(qpos, qvel, frame).reshape(-1, 3)


def walk_stability(robot: Robot, gait: Gait, result: WalkResult, certify: CertifyConfig | None = None,
                   sim: SimConfig | None = None) -> OrbitReport | None:
    """A walk's orbit (:attr:`WalkResult.orbit`) with the spectral radius ρ of its map (the step map; the stride map
    for an orbit of period 2, ``certify.stride_fallback``) at the event where it settled (:meth:`ReturnMap.stability`:
    one batch of 2d + 1 maps and one more), when it settled and ``certify.fp_rho_max`` is set; otherwise the orbit as
    it is."""
    c = certify or CertifyConfig()
    orbit = result.orbit
    if orbit is None or orbit.settled is None or c.fp_rho_max is None:
        return orbit
    qpos, qvel = canonical_event_states(robot, gait, result.events[orbit.settled - 1:orbit.settled])
    kind: MapKind = "stride" if orbit.period == 2 else "step"
    with ReturnMap(robot, gait, dataclasses.replace(c, map=kind, horizon=1), sim) as pmap:
        x = section_coordinates(qpos, qvel, gait.step_duration)[0]
        try:
            st = pmap.stability(x, qpos[0])
        except RobustGaitError:  # a neighbour within the finite-difference step falls: no linearization
            return orbit
    return dataclasses.replace(orbit, map_residual=st.map_residual, rho=st.rho, moduli=st.moduli,
                               rho_fixed_event=st.rho_fixed_event, one_sided=st.one_sided)


def settle(robot: Robot, gait: Gait, config: CertifyConfig, sim: SimConfig | None = None,
           progress: Callable[[int, float], None] | None = None
           ) -> tuple[ReturnMap, FixedPoint | FixedPointFailure]:
    """The map of ``config`` at its fixed point (:meth:`ReturnMap.find_fixed_point`), or the failure — with
    ``stride_fallback``, a step map whose iterates settle on no orbit (``no_stable_orbit``, ``period_two_orbit``) or
    fall (``fell_before_fixed_point``) is replaced by the stride map (two physical steps, unmirrored), searched from
    the gait's start: the mirrored step map of a robot whose left and right differ (T1's shanks: 60 g) steps on the
    same leg again and again, which is not the walk — it wanders, or falls, while the walk settles on a period-two
    orbit of it (``docs/certificate.md``, "Fixed point"). An orbit the step map found unstable is not searched again
    (for a symmetric robot the stride map's ρ is its square). The caller closes the map returned (the stride map
    after a fallback: ``map.kind``); a failure of both is the step map's status (the stride map's if it settled
    unstable or fell, or the step map fell), the stride map's finding appended."""
    pmap = ReturnMap(robot, gait, config, sim)
    try:
        return pmap, pmap.find_fixed_point(progress)
    except FixedPointFailure as exc:
        if config.map != "step" or not config.stride_fallback or exc.status == "unstable_orbit":
            return pmap, exc
        first = exc
    pmap.close()
    stride = ReturnMap(robot, gait, dataclasses.replace(config, map="stride"), sim)
    try:
        return stride, stride.find_fixed_point(progress)
    except FixedPointFailure as exc:
        # the stride map's finding when it is the stronger one (it settled unstable, or fell), or when the step map
        # fell (the mirrored step map of an asymmetric robot can fall where the walk does not)
        own = exc.status in ("unstable_orbit", "fell_before_fixed_point") or first.status == "fell_before_fixed_point"
        return stride, FixedPointFailure(exc.status if own else first.status, exc.steps if own else first.steps,
                                         f"{first}; the stride map: {exc}",
                                         exc.orbit if own else first.orbit,
                                         exc.fixed_point)


class FixedPointFailure(RobustGaitError):
    """The fixed-point search failed — a property of the gait, not bad input: ``status`` is
    ``fell_before_fixed_point``, ``no_stable_orbit``, ``period_two_orbit`` or ``unstable_orbit``; ``steps`` the steps
    walked (completed) before it ended; ``orbit`` what the search saw
    (:class:`.numerics.OrbitReport`, None if the gait fell before its first iterate);
    ``fixed_point`` the x* refused (``unstable_orbit``)."""

    def __init__(self, status: str, steps: int, message: str, orbit: OrbitReport | None = None,
                 fixed_point: FixedPoint | None = None):
        super().__init__(message)
        self.status = status
        self.steps = steps
        self.orbit = orbit
        self.fixed_point = fixed_point


@dataclass(frozen=True)
class FixedPoint:
    """x* of the chosen map: its full canonical state (qpos, qvel), its base angular velocity ω* (3,) in the search's
    frame, its residual (‖P(x*) − x*‖ in section coordinates when the search computed it — with Newton or ρ —, else the
    window residual of ``fp_metric``), the steps walked until the orbit settled, the successive residuals of the
    iterates, and the search's :class:`~.numerics.OrbitReport` (None for a start that is not a search's)."""

    qpos: FloatArray
    qvel: FloatArray
    omega: FloatArray
    residual: float
    steps: int
    residuals: tuple[float, ...]
    orbit: OrbitReport | None = None


@dataclass(frozen=True)
class Stability:
    """The linearized map at x* (:meth:`ReturnMap.stability`): ρ and the eigenvalue moduli (largest first) with the
    touchdown found in continuous time, ρ with it at a fixed physics step, ‖P(x*) − x*‖ (section coordinates), and
    the Jacobian columns taken one-sided."""

    rho: float
    moduli: tuple[float, ...]
    rho_fixed_event: float
    map_residual: float
    one_sided: int


class ReturnMap:
    """The batched return map P^k: (N, n) → (N, n) of a gait in its reduced state (NaN rows: the sample fell within
    the k maps), of the kind, horizon, state, frame and reconstruction of ``config`` (``map``, ``horizon``,
    ``state``, ``frame``, ``reconstruction``), simulated with ``sim``. The reduced state is set up at the fixed
    point: call :meth:`find_fixed_point` (or :meth:`set_fixed_point`) first."""

    def __init__(self, robot: Robot, gait: Gait, config: CertifyConfig | None = None, sim: SimConfig | None = None):
        config = config or CertifyConfig()
        if gait.initial_state is None:
            raise RobustGaitError("the gait has no initial state to find a fixed point from")
        self.config = config
        self.robot, self.gait, self.kind, self.frame = robot, gait, config.map, config.frame
        self.reconstruction = config.reconstruction
        self.engine = make_engine(robot, gait, sim)
        self.stance = gait.stance
        self.other = "left" if gait.stance == "right" else "right"
        self.horizon = config.horizon
        self.fixed_point: FixedPoint | None = None
        self._reduced: ReducedState | None = None
        self.physics_steps = 0
        # the reduced iterates P^1 … P^k of the last call's samples, (k, N, n); NaN from a fall on
        self.last_path: FloatArray | None = None

    def close(self) -> None:
        self.engine.close()

    def __enter__(self) -> ReturnMap:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    @property
    def period(self) -> int:
        return 1 if self.kind == "step" else 2

    def find_fixed_point(self, progress: Callable[[int, float], None] | None = None) -> FixedPoint:
        """Iterate the map on full states from the gait's initial state until its orbit settles — the first iterate
        x_k after ``fp_min_steps`` steps whose window of ``fp_window`` iterates all lie within ``fp_tol`` of it
        (:func:`.numerics.window_residual` in ``fp_metric``) —, refine x* by damped Newton on P(x) = x in
        section coordinates (``fp_newton_iterations``; x* stays x_k unless Newton converges), then take the spectral
        radius ρ of the linearized map at x* (:meth:`stability`) unless ``fp_rho_max`` is not set.

        Iterating the map itself (canonical stance, then mirror) rather than walking on alternating legs makes x* a
        fixed point of exactly the map that is certified, also for a robot whose MJCF is not perfectly left/right
        symmetric. Raises :class:`FixedPointFailure` (a RobustGaitError) — ``fell_before_fixed_point``;
        ``no_stable_orbit`` (no window within ``fp_max_steps``); ``period_two_orbit`` (none, but iterates two apart
        settled); ``unstable_orbit`` (ρ ≥ ``fp_rho_max``) — with what the search saw. ``progress(step, residual)``
        after each iterate (the successive residual in ``fp_metric``).
        """
        cfg = self.config
        qpos, qvel = self.initial_section()
        xs = [self._metric(qpos, qvel)]

        def report() -> OrbitReport:
            return search_report(xs, metric=cfg.fp_metric, window=cfg.fp_window, tol=cfg.fp_tol,
                                 min_index=math.ceil(cfg.min_steps / self.period), period=self.period)

        for k in range(self.period, cfg.fp_max_steps + 1, self.period):
            qpos, qvel, reason = self._advance(qpos, qvel)
            if reason[0] is not None:
                raise FixedPointFailure("fell_before_fixed_point", k - self.period,
                                        f"the gait fell within step {k} ({reason[0]}) before a fixed point was "
                                        "reached", report() if len(xs) > 1 else None)
            xs.append(self._metric(qpos, qvel))
            if progress is not None:
                progress(k, float(np.linalg.norm(xs[-1] - xs[-2])))
            if k >= cfg.min_steps and window_residual(xs, cfg.fp_window) <= cfg.fp_tol:
                return self.set_fixed_point(self._refine(qpos, qvel, report()))
        orbit = report()
        status = orbit_status(orbit, None)
        what = (f"the {self.kind}-map iterates settled on no window of {cfg.fp_window} within fp_tol = "
                f"{cfg.fp_tol:g} ({cfg.fp_metric} coordinates) in {orbit.steps} steps: smallest successive residual "
                f"{min(orbit.residuals):.3g}, last window {orbit.window_residual:.3g}")
        if status == "period_two_orbit":
            hint = ("; certify the stride map instead (--map stride)"
                    if self.kind == "step" and not cfg.stride_fallback else "")
            raise FixedPointFailure("period_two_orbit", orbit.steps, f"a period-two orbit: {what}, but iterates two "
                                    f"apart settled (window residual {window_residual(xs, cfg.fp_window, 2):.3g})"
                                    + hint, orbit)
        raise FixedPointFailure("no_stable_orbit", orbit.steps, f"no stable orbit: {what}", orbit)

    def _metric(self, qpos: FloatArray, qvel: FloatArray) -> FloatArray:
        """The coordinates the search's window measures (``fp_metric``) of one state (1, nq), (1, nv)."""
        if self.config.fp_metric == "omega":
            return reduce_state(qpos, qvel, self.frame)[0]
        return section_coordinates(qpos, qvel, self.gait.step_duration)[0]

    def section_map(self, reference: FloatArray) -> BatchMap:
        """P in section coordinates, x_S ↦ x_S(P(x)) (N, d) → (N, d), NaN rows for falls; the states rebuilt with the
        base's x, y and yaw of ``reference`` (a qpos: the map is equivariant under them, yaw up to the friction
        pyramid)."""
        t = self.gait.step_duration

        def F(xs: FloatArray) -> FloatArray:
            qpos, qvel = section_state(xs, reference, t)
            qpos, qvel, _ = self._advance(qpos, qvel)
            return section_coordinates(qpos, qvel, t)
        return F

    def _refine(self, qpos: FloatArray, qvel: FloatArray, orbit: OrbitReport) -> FixedPoint:
        """x* from the settled iterate (1, nq), (1, nv): Newton (if asked and it converges), then ρ (if asked)."""
        cfg = self.config
        t = self.gait.step_duration
        ref = qpos[0].copy()
        F = self.section_map(ref)
        x = section_coordinates(qpos, qvel, t)[0]
        jac: Jacobian | None = None
        if cfg.fp_newton_iterations > 0:
            nr = newton(F, x, step=cfg.fp_fd_step, jump=cfg.fp_fd_jump, tol=cfg.fp_newton_tol,
                        iterations=cfg.fp_newton_iterations, damping=NEWTON_DAMPING)
            orbit = dataclasses.replace(orbit, newton=nr.residuals, newton_converged=nr.converged)
            if nr.converged:
                x, jac = nr.x, nr.jacobian
                qpos, qvel = section_state(x[None], ref, t)
            else:
                jac = nr.first
        residual = orbit.window_residual
        if cfg.fp_rho_max is not None:
            try:
                st = self.stability(x, ref, jac)
            except RobustGaitError as exc:  # a neighbour of x* within the finite-difference step falls
                raise FixedPointFailure("unstable_orbit", orbit.steps, f"no linearization at x*: {exc}",
                                        orbit) from None
            orbit = dataclasses.replace(orbit, map_residual=st.map_residual, rho=st.rho, moduli=st.moduli,
                                        rho_fixed_event=st.rho_fixed_event, one_sided=st.one_sided)
            residual = st.map_residual
        elif orbit.newton:
            residual = orbit.newton[-1] if orbit.newton_converged else orbit.newton[0]
        fp = FixedPoint(qpos[0].copy(), qvel[0].copy(), reduce_state(qpos, qvel, self.frame)[0], residual,
                        orbit.steps, orbit.residuals, orbit)
        if orbit_status(orbit, cfg.fp_rho_max) == "unstable_orbit":
            assert orbit.rho is not None and cfg.fp_rho_max is not None
            raise FixedPointFailure("unstable_orbit", orbit.steps, f"an unstable orbit: the {self.kind} map settled at "
                                    f"step {orbit.settled}, but its linearization at x* has spectral radius ρ = "
                                    f"{orbit.rho:.3g} ≥ fp_rho_max = {cfg.fp_rho_max:g} (eigenvalue moduli "
                                    f"{' '.join(f'{m:.3g}' for m in orbit.moduli[:4])} …)", orbit, fp)
        return fp

    def stability(self, x: FloatArray, reference: FloatArray, jacobian: Jacobian | None = None) -> Stability:
        """The linearized map at x (section coordinates, states rebuilt with ``reference``'s x, y and yaw): J by
        finite differences (``jacobian`` if given, else ONE batch of 2d + 1 states, :func:`.numerics.fd_jacobian`
        with ``fp_fd_step``, ``fp_fd_jump``), then, for impact switching, Π J with the touchdown found in continuous
        time (:meth:`touchdown_projection`): ρ and the eigenvalue moduli of Π J, and ρ of J (touchdown at a fixed
        physics step). Raises :class:`RobustGaitError` if the map falls on both sides of a coordinate."""
        cfg = self.config
        j = jacobian or fd_jacobian(self.section_map(reference), x, cfg.fp_fd_step, cfg.fp_fd_jump)
        rho_fixed, _ = spectral_radius(j.matrix)
        proj = self.touchdown_projection(x, reference)
        rho, moduli = spectral_radius(j.matrix if proj is None else proj @ j.matrix)
        return Stability(rho, tuple(float(m) for m in moduli), rho_fixed, float(np.linalg.norm(j.value - x)),
                         len(j.one_sided))

    def touchdown_projection(self, x: FloatArray, reference: FloatArray) -> FloatArray | None:
        """Π (d, d) of :func:`.numerics.flow_projection` at the image of x (section coordinates): the flow f
        there by a backward difference over the last physics step, (x_S(end) − x_S(one step before)) / Δt, and the
        gradient of the guard — the signed distance of the landing sole (the gait's stance sole in canonical
        coordinates) to the floor, ``mj_geomDistance`` — by central differences in the position coordinates. None for
        time switching (the event time does not depend on the state) or a flow tangent to the guard."""
        if self.engine.config.switching != "impact":
            return None
        t = self.gait.step_duration
        qpos, qvel = section_state(x[None], reference, t)
        states = self._image_and_before(qpos, qvel)
        if states is None:
            return None
        ends = section_coordinates(*states, t)
        flow = (ends[1] - ends[0]) / self.robot.dt
        return flow_projection(flow, self._guard_gradient(ends[1], states[0][1]))

    def _image_and_before(self, qpos: FloatArray, qvel: FloatArray) -> tuple[FloatArray, FloatArray] | None:
        """The map's image of one state and the state one physics step before it, canonical: (2, nq), (2, nv); None
        if it falls."""
        phases = self._phases()
        start = self.engine.full_states(qpos, qvel)[0]
        for j, (stance, d) in enumerate(phases):
            last = j == len(phases) - 1
            if last:
                start = self.engine.full_states(qpos, qvel)[0]
            b = self.engine.step(qpos, qvel, stance, domain=d, record=last)
            self.physics_steps += b.physics_steps
            if b.fell[0]:
                return None
            qpos, qvel = b.qpos, b.qvel
        tr = b.trajectory[0]
        before = tr[-2] if len(tr) >= 2 else start
        nq, nv = self.engine.nq, self.engine.nv
        q = np.vstack([before[1:1 + nq], qpos[0]])
        v = np.vstack([before[1 + nq:1 + nq + nv], qvel[0]])
        return self.robot.mirror_state(q, v) if self.kind == "step" else (q, v)

    def _guard_gradient(self, x: FloatArray, reference: FloatArray) -> FloatArray:
        """∇g (d,) at x (section coordinates): g = the signed distance of the gait's stance sole to the floor."""
        m, t, h = self.robot.model, self.gait.step_duration, self.config.fp_fd_step
        data = mujoco.MjData(m)
        sole, floor = self.robot.sole_geom_id[self.stance], self.robot.floor_geom_id
        n_pos = self.engine.nq - 4
        e = np.eye(x.shape[0])[:n_pos] * h
        qpos, _ = section_state(np.vstack([x + e, x - e]), reference, t)
        dist = np.empty(len(qpos))
        for i, q in enumerate(qpos):
            data.qpos[:] = q
            mujoco.mj_kinematics(m, data)
            dist[i] = mujoco.mj_geomDistance(m, data, sole, floor, 1.0, None)
        grad = np.zeros(x.shape[0])
        grad[:n_pos] = (dist[:n_pos] - dist[n_pos:]) / (2 * h)
        return grad

    def initial_section(self) -> tuple[FloatArray, FloatArray]:
        """The gait's initial state as a canonical section state (1, nq), (1, nv): itself for a flat-foot gait; a
        multi-contact gait starts at the beginning of single support, so it is walked to its heel strike first and
        mirrored. Raises :class:`FixedPointFailure` if it falls on the way."""
        init = self.gait.initial_state
        if init is None:
            raise RobustGaitError("the gait has no initial state to start from")
        qpos, qvel = init.qpos[None].copy(), init.qvel[None].copy()
        if len(self.engine.graph) > 1:
            qpos, qvel, reason = self._run(qpos, qvel, [(self.stance, 0)])
            if reason[0] is not None:
                raise FixedPointFailure("fell_before_fixed_point", 0,
                                        f"the gait fell within step 1 ({reason[0]}) before a fixed point was reached")
            qpos, qvel = self.robot.mirror_state(qpos, qvel)
        return qpos, qvel

    def _run(self, qpos: FloatArray, qvel: FloatArray, phases: list[tuple[str, int]],
             progress: Callable[[int], None] | None = None) -> tuple[FloatArray, FloatArray, list[str | None]]:
        """Simulate phases in order (``progress`` on the last); a sample that falls in one is NaN afterwards."""
        reasons: list[str | None] = [None] * qpos.shape[0]
        for j, (stance, d) in enumerate(phases):
            b = self.engine.step(qpos, qvel, stance, domain=d, progress=progress if j == len(phases) - 1 else None)
            self.physics_steps += b.physics_steps
            reasons = [r0 if r0 is not None else r1 for r0, r1 in zip(reasons, b.fall_reason, strict=True)]
            qpos, qvel = b.qpos, b.qvel
        fell = np.array([r is not None for r in reasons])
        qpos, qvel = qpos.copy(), qvel.copy()
        qpos[fell] = np.nan
        qvel[fell] = np.nan
        return qpos, qvel, reasons

    def _advance(self, qpos: FloatArray, qvel: FloatArray,
                 progress: Callable[[int], None] | None = None) -> tuple[FloatArray, FloatArray, list[str | None]]:
        """The map on full canonical states (K, nq), (K, nv): one step and a mirror, or a stride. Returns the
        images (NaN rows for falls) and each sample's fall reason (None if it did not fall).

        A canonical state lies on the section at the end of a single support of the other leg, so the step
        map simulates the rest of that step (multi-contact: its double support) and the gait's own stance's
        single support, then mirrors; the stride map goes on through the other leg's step instead."""
        qpos, qvel, reasons = self._run(qpos, qvel, self._phases(), progress)
        if self.kind == "step":
            qpos, qvel = self.robot.mirror_state(qpos, qvel)
        return qpos, qvel, reasons

    def _phases(self) -> list[tuple[str, int]]:
        """(stance, domain) of one map in simulation order: a step, or a stride."""
        n = len(self.engine.graph)
        return step_segments(self.stance, n) + (step_segments(self.other, n) if self.kind == "stride" else [])

    def set_fixed_point(self, fp: FixedPoint) -> FixedPoint:
        """Use ``fp`` as x* (e.g. found earlier by this map) and set the reduced state up at it."""
        self.fixed_point = fp
        self._reduced = ReducedState.at(self.config.state, self.robot, fp.qpos, fp.qvel, self.stance, self.config)
        return fp

    @property
    def reduced(self) -> ReducedState:
        """The certificate's reduced state (Φ, ι, metric) at the fixed point."""
        if self._reduced is None:
            raise RobustGaitError("find the fixed point first (ReturnMap.find_fixed_point)")
        return self._reduced

    @property
    def dim(self) -> int:
        return self.reduced.dim

    def reconstruct(self, xbar: FloatArray) -> tuple[FloatArray, FloatArray]:
        """ι(x̄): full canonical states (N, nq), (N, nv) from reduced states (N, n)
        (:meth:`.reduced.ReducedState.iota`)."""
        return self.reduced.iota(np.atleast_2d(np.asarray(xbar, dtype=float)))

    def __call__(self, xbar: FloatArray, progress: Callable[[int], None] | None = None) -> FloatArray:
        """P^k(x̄) = Φ(Δ^k(ι(x̄))) for a batch (N, n), k = the horizon; NaN rows where the sample fell within any of
        the k steps (or strides). The iterates P^1 … P^k are kept in ``last_path`` (k, N, n)."""
        red = self.reduced
        qpos, qvel = self.reconstruct(xbar)
        path = np.full((self.horizon, qpos.shape[0], red.dim), np.nan)
        for j in range(self.horizon):
            qpos, qvel, _ = self._advance(qpos, qvel, progress=progress if j == self.horizon - 1 else None)
            ok = np.isfinite(qvel).all(axis=1)
            if ok.any():
                path[j, ok] = red.phi(qpos[ok], qvel[ok])
        self.last_path = path
        return path[-1].copy()
