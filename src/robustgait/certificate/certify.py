"""Certify a gait: fixed point of its return map (:mod:`.poincare`) → its reduced state
(:mod:`.reduced`) → the certified set's coordinates (:mod:`.shape`) →
sampled images → r* and a confidence statement (:mod:`.estimators`,
:mod:`.barrier`); or, for ``disturbance = push``, sampled pushes → J*
(:mod:`.push`). ``docs/certificate.md``; ``robustgait certify`` calls this.

A gait that falls before reaching a fixed point, has none, or falls from its own fixed point is a result,
not an error: the certificate has a ``status`` other than ``ok`` and r* = 0 (in a study it is a data point).
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from tqdm import tqdm

from robustgait.certificate.barrier import Certificate, certify_map, evaluate_map, sample_ball
from robustgait.certificate.estimators import certify_map_sequential
from robustgait.certificate.numerics import OrbitReport
from robustgait.certificate.poincare import FixedPoint, FixedPointFailure, ReturnMap, settle
from robustgait.certificate.push import PushMap
from robustgait.certificate.reduced import Coordinates, section_dimension
from robustgait.certificate.shape import Shape, fit_linearization, shape_from_fit, volume_ratio
from robustgait.config import CertifyConfig, SimConfig, ValidateConfig, to_dict
from robustgait.config.work import Work, check_work
from robustgait.gait import Gait
from robustgait.robots import Robot
from robustgait.sim.engine import step_physics_steps

STATUSES = ("ok", "fell_before_fixed_point", "no_stable_orbit", "period_two_orbit", "unstable_orbit",
            "unstable_fixed_point")


@dataclass
class GaitCertificate:
    """A gait's certificate.

    status: one of :data:`STATUSES` — ``ok``; ``fell_before_fixed_point`` (the gait fell while its fixed point
    was searched); ``no_stable_orbit`` (no window of ``fp_window`` iterates settled within ``fp_tol`` in
    ``fp_max_steps``); ``period_two_orbit`` (none did, but iterates two apart settled: certify the stride map);
    ``unstable_orbit`` (the orbit settled, but the linearized map at x* has spectral radius ρ ≥ ``fp_rho_max``);
    ``unstable_fixed_point`` (the reduced map falls from x̄* itself within the horizon: through the reconstruction x̄*
    is not on a walking orbit). reason: one line (empty if ok). steps_walked: steps of the fixed-point search
    (completed before a fall). orbit: what the fixed-point search saw (:class:`.numerics.OrbitReport`: the
    window, ρ and the eigenvalue moduli, Newton's residuals; None if the gait fell before its first iterate).
    certificate (the barrier :class:`Certificate` in the certificate's coordinates: r*, samples, images, margins,
    rounds, statement), coordinates (z = T x̄ of the reduced state, the shape of the set; :class:`Coordinates`),
    fixed_point and map_residual ‖P(x̄*) − x̄*‖ (certificate coordinates, one map) are None where the search did not
    get that far. r_star is 0 unless ok. ball: for an ellipsoid certified with ``ellipsoid.compare_ball``, the ball
    certified beside it (its volume ratio: :attr:`volume_ratio`). excursion: horizon k ≥ 2, per j = 1 … k the
    largest ‖P^j(z) − z*‖ over the samples in the certified set.
    """

    status: str
    certificate: Certificate | None
    fixed_point: FixedPoint | None
    map_residual: float | None
    config: CertifyConfig
    sim: SimConfig
    robot: str
    seconds: dict[str, float]
    physics_steps: int
    steps_walked: int
    reason: str = ""
    coordinates: Coordinates | None = None
    ball: Certificate | None = None
    excursion: list[float] | None = None
    validate: ValidateConfig | None = None  # push certificates: the push duration and phases used
    controller: str = "pd"  # the tracking law that ran (sim.controller, unless the note says why not)
    controller_note: str = ""
    orbit: OrbitReport | None = None
    fixed_point_physics_steps: int = 0  # simulated by the fixed-point search (its iterates, Newton, ρ)

    @property
    def ok(self) -> bool:
        return self.status == "ok"

    @property
    def r_star(self) -> float:
        return self.certificate.r_star if self.certificate is not None else 0.0

    @property
    def vacuous(self) -> bool:
        """True when nothing is certified: a failed status, or no sample inside B(r*)."""
        return self.certificate is None or self.certificate.vacuous

    @property
    def energy(self) -> float | None:
        """E* [J] of an energy state: every perturbation adding at most E* of kinetic energy is in the set."""
        if self.coordinates is None or self.certificate is None:
            return None
        return self.coordinates.energy(self.certificate.r_star)

    @property
    def volume_ratio(self) -> float | None:
        """vol(certified ellipsoid) / vol(certified ball), when both were certified."""
        if self.ball is None or self.certificate is None or self.coordinates is None:
            return None
        return volume_ratio(self.certificate.r_star, self.ball.r_star, self.coordinates.dim)

    def statement(self) -> str:
        if self.certificate is None:
            return f"No certificate ({self.status}): {self.reason}; r* = 0 after {self.steps_walked} steps."
        c, cfg = self.certificate, self.config
        if cfg.disturbance != "push" or c.vacuous or c.budget_exhausted:
            return c.statement()
        v = self.validate or ValidateConfig()
        inside = "≤" if c.attained else "<"
        if c.method == "sequential":
            verify = [r for r in c.rounds if r.kind == "verify"]
            n_a, attempt = verify[-1].n_samples, len(verify)
            basis = (f"a batch of {n_a} fresh pushes drawn uniformly in the disk after J* was fixed all recovered "
                     f"(verification attempt {attempt}: (1 − ε)^{n_a} ≤ β/2^{attempt}), and none of the "
                     f"{c.n_samples} pushes of its {len(c.rounds)} rounds with |J| {inside} J* failed")
        else:
            basis = (f"of {c.n_samples} pushes uniform in the disk |J| ≤ r_max = {c.r_max:g} N s, the {c.n_inside} "
                     f"with |J| {inside} J* all recovered (union bound over the {c.n_samples + 1} possible choices of "
                     "J*)")
        p = cfg.push
        fail = ("make the robot fall within that step and {k} more" if not p.recovery else
                "make the robot fall within that step and {k} more, or leave it off its orbit at their end (base "
                f"velocity farther than {p.recovery_radius:g} in Froude units, or {p.recovery_scatter:g}× its "
                "undisturbed scatter, from x*'s)").format(k=p.steps)
        return (f"With confidence {100.0 * c.confidence:g}%, at most {100.0 * c.violation_bound:.3g}% of the pushes "
                f"with impulse |J| {inside} J* = {c.r_star:.4g} N s (uniform in that disk; {v.push_duration:g} s long, "
                f"starting at a phase in [{v.push_phase[0]:g}, {v.push_phase[1]:g}] of the step) {fail}: {basis}.")

    def to_dict(self, *, samples: bool = True) -> dict[str, Any]:
        """JSON-ready; everything but ``seconds`` is deterministic for a given seed."""
        fp, cfg = self.fixed_point, self.config
        out: dict[str, Any] = {
            "robot": self.robot,
            "status": self.status,
            "reason": self.reason,
            "r_star": 0.0,
            "vacuous": True,
            "steps_walked": self.steps_walked,
            "state": cfg.state,
            "set": cfg.set,
            "horizon": cfg.horizon,
            "disturbance": cfg.disturbance,
            "unit": cfg.unit,
            "x_star": None,
            "omega_star": None if fp is None else [float(v) for v in fp.omega],
            "fixed_point_residual": None if fp is None else fp.residual,
            "fixed_point_steps": None if fp is None else fp.steps,
            "map_residual": self.map_residual,
            "orbit": None if self.orbit is None else self.orbit.to_dict(),
            "map": cfg.map,
            "reconstruction": cfg.reconstruction,
            "frame": cfg.frame,
            "method": cfg.method,
            "barrier": cfg.barrier,
            "energy": self.energy,
            "controller": self.controller,
            "controller_note": self.controller_note,
            "statement": self.statement(),
        }
        if self.certificate is not None:
            c = self.certificate.to_dict()
            if not samples:
                for key in ("samples", "images", "fell", "margins", "sample_round"):
                    c.pop(key)
            c["statement"] = self.statement()
            out.update(c)
        if self.coordinates is not None:
            out["coordinates"] = self.coordinates.to_dict()
        if self.ball is not None:
            out["ball"] = {"r_star": self.ball.r_star, "attained": self.ball.attained,
                           "n_samples": self.ball.n_samples, "violation_bound": self.ball.violation_bound,
                           "statement": self.ball.statement(), "volume_ratio": self.volume_ratio}
        if self.excursion is not None:
            out["excursion"] = self.excursion
        out.update({"physics_steps": self.physics_steps, "fixed_point_physics_steps": self.fixed_point_physics_steps,
                    "config": to_dict(cfg), "sim": to_dict(self.sim),
                    "seconds": self.seconds})
        if self.validate is not None:
            out["push"] = {"duration": self.validate.push_duration, "phase": list(self.validate.push_phase)}
        return out


Progress = Callable[[int], None]
BatchMap = Callable[[np.ndarray, "Progress | None"], np.ndarray]


def _estimate(P: BatchMap, x_star: np.ndarray, cfg: CertifyConfig, progress: bool, desc: str) -> Certificate:
    """Run the configured estimator on a map in certificate coordinates (progress bar: samples, stderr; the map is
    called with the bar's update, per sample that reaches its end)."""
    total = cfg.n_samples if cfg.method == "uniform" else cfg.estimator.budget
    with tqdm(total=total, desc=desc, unit="sample", disable=not progress, leave=False) as bar:
        def counted(x: np.ndarray) -> np.ndarray:
            return P(x, bar.update)
        if cfg.method == "uniform":
            return certify_map(counted, x_star, cfg)
        return certify_map_sequential(counted, x_star, cfg)


def certify_steps(config: CertifyConfig, graph: str, dim: int) -> int:
    """The most steps a certificate simulates: a multi-contact gait's walk to its first heel strike (one step at
    most), the fixed-point search on a section of ``dim`` coordinates (:meth:`CertifyConfig.fixed_point_steps`: up to
    ``fp_max_steps`` steps of the map, its Newton iterations and ρ), the map at x* (``horizon`` steps, × 2 for the
    stride map), and :attr:`~CertifyConfig.steps_per_sample` for each of :attr:`~CertifyConfig.samples_planned`
    (a push: the pushed step and ``push.steps`` more; with recovery, the undisturbed walk that measures the orbit's
    scatter first)."""
    start = 0 if graph == "flat" else 1
    band = config.push.recovery_band_steps if config.disturbance == "push" and config.push.recovery else 0
    return (start + config.fixed_point_steps(dim) + config.horizon * config.period + band
            + config.samples_planned * config.steps_per_sample)


def check_certify_work(robot: Robot, gait: Gait, config: CertifyConfig, sim: SimConfig) -> int:
    """Bound a certificate's simulation before it starts (:mod:`robustgait.config.work`): :func:`certify_steps`,
    each of up to the gait's :func:`~robustgait.sim.engine.step_horizons`, against what the default certificate
    needs on this robot and gait."""
    graph, samples = gait.domain_graph, "sequential.budget" if config.method == "sequential" else "n_samples"
    dim = section_dimension(robot)
    return check_work(Work(certify_steps(config, graph, dim), step_physics_steps(gait, robot.dt, sim)),
                      Work(certify_steps(CertifyConfig(), graph, dim), step_physics_steps(gait, robot.dt, SimConfig())),
                      robot.dt, f"certify.fp_max_steps {config.fp_max_steps} + certify.{samples} "
                      f"{config.samples_planned} × {config.steps_per_sample} steps")


class _Paths:
    """The reduced iterates P^1 … P^k of every sample the estimator evaluated, in its order (k, N, n)."""

    def __init__(self) -> None:
        self.parts: list[np.ndarray] = []

    def excursion(self, cert: Certificate, coords: Coordinates) -> list[float]:
        """Per j: the largest ‖P^j − z*‖ over the samples in the certified set (the set's own coordinates)."""
        path = coords.to_z(np.concatenate(self.parts, axis=1).reshape(-1, coords.dim)).reshape(
            len(self.parts[0]), -1, coords.dim)
        d = np.linalg.norm(np.asarray(cert.samples) - cert.x_star, axis=1)
        inside = d <= cert.r_star if cert.attained else d < cert.r_star
        if not inside.any():
            return [0.0] * path.shape[0]
        dist = np.linalg.norm(path[:, inside] - coords.x_star, axis=2)
        return [float(v) for v in np.max(np.where(np.isfinite(dist), dist, np.inf), axis=1)]


def _in_coordinates(pmap: ReturnMap, coords: Coordinates, paths: _Paths | None = None) -> BatchMap:
    """P^k in the certificate's coordinates: z ↦ T P^k(T⁻¹ z)."""
    def P(z: np.ndarray, progress: Progress | None = None) -> np.ndarray:
        out = coords.to_z(pmap(coords.to_xbar(z), progress=progress))
        if paths is not None and pmap.last_path is not None:
            paths.parts.append(pmap.last_path)
        return out
    return P


def fit_shape(pmap: ReturnMap, ball: Coordinates, cfg: CertifyConfig) -> Shape:
    """The ellipsoid's shape S in the state's metric coordinates: P^k on ``ellipsoid.fit_samples`` samples uniform in
    the ball of radius ``fit_radius`` × r_max (seed stream ``[seed, 3]``: common random numbers), a least-squares
    linearization and its Lyapunov ellipsoid (:func:`.shape.shape_from_fit`)."""
    e = cfg.ellipsoid
    rng = np.random.default_rng([cfg.seed, 3])
    z0 = sample_ball(e.fit_samples, ball.dim, e.fit_radius * cfg.radius, ball.x_star, rng)
    P = _in_coordinates(pmap, ball)
    z1 = evaluate_map(lambda z: P(z, None), z0)
    try:
        fit = fit_linearization(z0, z1, ball.x_star)
    except Exception as exc:  # too many falls to fit: no ellipsoid
        return Shape(np.eye(ball.dim), None, fallback=str(exc))
    return shape_from_fit(fit)


def certify_gait(robot: Robot, gait: Gait, config: CertifyConfig | None = None, sim: SimConfig | None = None, *,
                 validate: ValidateConfig | None = None, progress: bool = False) -> GaitCertificate:
    """Find x* by iterating the map, then certify the set of ``config`` around it with the configured estimator
    (``uniform``: :func:`.barrier.certify_map`; ``sequential``:
    :func:`.estimators.certify_map_sequential`), in the state, set and horizon of the config; or, with
    ``disturbance = push``, the impulse disk J* (pushes as ``validate``'s: duration and phases of ``validate``).

    With ``ellipsoid.compare_ball`` an ellipsoid's certificate also certifies the ball of the same state (its r* and
    the volume ratio are reported). A gait that falls, has no fixed point or falls from it returns a certificate with
    that ``status`` and r* = 0 (no exception); too much work for the limits raises :class:`RobustGaitError` before any
    simulation.
    ``progress``: bars on stderr.
    """
    cfg = config or CertifyConfig()
    sim = sim or SimConfig()
    push = cfg.disturbance == "push"
    vcfg = (validate or ValidateConfig()) if push else None
    check_certify_work(robot, gait, cfg, sim)
    t0 = time.perf_counter()

    def failed(status: str, reason: str, steps: int, fp: FixedPoint | None = None,
               map_residual: float | None = None, orbit: OrbitReport | None = None) -> GaitCertificate:
        t = time.perf_counter() - t0
        return GaitCertificate(status=status, certificate=None, fixed_point=fp, map_residual=map_residual,
                               config=cfg, sim=sim, robot=robot.name, physics_steps=0, steps_walked=steps,
                               reason=reason, validate=vcfg, controller=pmap.engine.controller_name,
                               controller_note=pmap.engine.controller_note,
                               orbit=orbit if orbit is not None or fp is None else fp.orbit,
                               fixed_point_physics_steps=pmap.physics_steps,
                               seconds={"fixed_point": t, "sampling": 0.0, "total": t, "sim_steps_per_s": 0.0})

    with tqdm(total=cfg.fp_max_steps, desc="fixed point", unit="step", disable=not progress, leave=False) as bar:
        def on_step(k: int, residual: float) -> None:
            if k < bar.n:  # the stride map's search after the step map's
                bar.reset()
                bar.set_description("fixed point (stride map)")
            bar.update(k - bar.n)
            bar.set_postfix(residual=f"{residual:.2e}")
        pmap, found = settle(robot, gait, cfg, sim, on_step)
    with pmap:
        if isinstance(found, FixedPointFailure):
            return failed(found.status, str(found), found.steps, found.fixed_point, orbit=found.orbit)
        fp, cfg = found, pmap.config  # the stride map's after a fallback (stride_fallback)
        t1 = time.perf_counter()
        fp_steps = pmap.physics_steps
        coords = Coordinates.of(pmap.reduced)
        image = coords.to_z(pmap(pmap.reduced.x_star[None]))[0]
        first = coords.to_z(pmap.last_path[0])[0] if pmap.last_path is not None else image
        map_residual = float(np.linalg.norm(first - coords.x_star))
        if not np.all(np.isfinite(image)):
            return failed("unstable_fixed_point", f"the return map falls from its own fixed point within "
                          f"{cfg.horizon} step(s) (through the {cfg.reconstruction} reconstruction x̄* is not on a "
                          "walking orbit)", fp.steps, fp)
        pmap.physics_steps = 0
        t2 = time.perf_counter()
        ball: Certificate | None = None
        excursion: list[float] | None = None
        if push:
            assert vcfg is not None
            coords = Coordinates("push", "N s", False, np.zeros(2), np.eye(2), Shape(np.eye(2)))
            pushes = PushMap(pmap.engine, fp, vcfg, cfg.push)
            cert = _estimate(pushes, np.zeros(2), cfg, progress, f"pushes, {cfg.method}")
            steps = pushes.physics_steps
        else:
            if cfg.set == "ellipsoid":
                shape = fit_shape(pmap, coords, cfg)
                if cfg.ellipsoid.compare_ball:
                    ball = _estimate(_in_coordinates(pmap, coords), coords.x_star, cfg, progress,
                                     f"{cfg.state} ball, {cfg.method}")
                coords = dataclasses.replace(coords, shape=shape)
            paths = _Paths()
            desc = f"{cfg.state} {cfg.set}{'' if cfg.horizon == 1 else f', P^{cfg.horizon}'}, {cfg.method}"
            cert = _estimate(_in_coordinates(pmap, coords, paths), coords.x_star, cfg, progress, desc)
            if cfg.horizon > 1:
                excursion = paths.excursion(cert, coords)
            steps = pmap.physics_steps
        t3 = time.perf_counter()
    return GaitCertificate(status="ok", certificate=cert, fixed_point=fp, map_residual=map_residual, config=cfg,
                           sim=sim, robot=robot.name, physics_steps=steps, steps_walked=fp.steps,
                           coordinates=coords, ball=ball, excursion=excursion, validate=vcfg,
                           controller=pmap.engine.controller_name, controller_note=pmap.engine.controller_note,
                           orbit=fp.orbit, fixed_point_physics_steps=fp_steps,
                           seconds={"fixed_point": t1 - t0, "sampling": t3 - t2, "total": t3 - t0,
                                    "sim_steps_per_s": steps / max(t3 - t2, 1e-9)})
