"""Certify a gait: the orbit it walks (:mod:`.search`: settled in a band, stable under small pushes) → x* → its
reduced state (:mod:`.reduced`) → the certified set's coordinates (:mod:`.shape`) → sampled images of the map of the
orbit's period (:mod:`.reducedmap`) → r* and a confidence statement (:mod:`.estimators`, :mod:`.barrier`); or, for
``disturbance = push``, sampled pushes from x* that must come back to the orbit's band → J* (:mod:`.push`).
``docs/certificate.md``; ``robustgait certify`` calls this.

A gait that falls, settles on no band, does not come back from small pushes, or whose reduced map falls from x̄* is a
result, not an error: the certificate has a ``status`` other than ``ok`` (:class:`.orbit.Status`) and r* = 0 (in a
study it is a data point).
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from tqdm import tqdm

from robustgait.certificate.barrier import Certificate, Round, certify_map, evaluate_map, sample_ball
from robustgait.certificate.estimators import Replay, certify_map_sequential
from robustgait.certificate.orbit import FixedPoint, Orbit, Status, orbit_from_dict, orbit_state
from robustgait.certificate.push import PushMap
from robustgait.certificate.reduced import Coordinates, ReducedState, section_dimension
from robustgait.certificate.reducedmap import ReducedMap
from robustgait.certificate.returnmap import FullStateMap
from robustgait.certificate.search import Walking, find_orbit, orbit_speed_note, probe_impulse
from robustgait.certificate.shape import Shape, fit_linearization, shape_from_fit, volume_ratio
from robustgait.certificate.verification import attempt_beta, check_budget
from robustgait.config import CertifyConfig, SimConfig, ValidateConfig, radius_name, to_dict
from robustgait.config.certify import R_MAX_LIMIT
from robustgait.config.work import Work, check_work
from robustgait.errors import RobustGaitError
from robustgait.gait import Gait
from robustgait.io.certfile import certificate_radius
from robustgait.robots import Robot
from robustgait.sim.engine import StepEngine, step_physics_steps
from robustgait.sim.factory import make_engine


def push_basis(c: Certificate, config: CertifyConfig) -> str:
    """Why a push certificate's bound holds, in pushes and J* (the estimator words it in samples and r*): the
    verification batch, drawn in the disk the fitted fall curve placed (sequential; its β_a from ``config``), or the
    union bound over the samples (uniform)."""
    inside = "≤" if c.attained else "<"
    if c.method == "sequential":
        verify = [r for r in c.rounds if r.kind == "verify"]
        n_a, attempt = verify[-1].n_samples, len(verify)
        beta_a = attempt_beta(config, attempt)
        n_explore = c.n_samples - sum(r.n_samples for r in verify)
        estimate = "" if c.estimate is None else f"; the estimate Ĵ = {c.estimate:.4g} N s"
        earlier = c.n_samples - n_a
        pushes = f"{earlier}" if earlier == n_explore else f"{earlier} ({n_explore} of exploration)"
        return (f"a batch of {n_a} fresh pushes drawn uniformly in the disk after J* was fixed (the largest disk whose "
                f"batch the fall curve fitted to the {pushes} earlier pushes predicted to pass with probability "
                f"{config.push.pass_probability:g}{estimate}): none fell "
                f"(verification attempt {attempt}: (1 − ε)^{n_a} ≤ β_{attempt} = {100.0 * beta_a:.3g}%)")
    return (f"of {c.n_samples} pushes uniform in the disk |J| ≤ r_max = {c.r_max:g} N s, the {c.n_inside} "
            f"with |J| {inside} J* did not fall (union bound over the {c.n_samples + 1} possible choices of J*)")


@dataclass
class GaitCertificate:
    """A gait's certificate.

    status: :class:`.orbit.Status` — ``ok``; ``fell``, ``unsettled``, ``unstable`` (the orbit search's verdict,
    :mod:`.search`); ``unstable_fixed_point`` (the reduced map falls from x̄* itself within the horizon: through the
    reconstruction x̄* is not on a walking orbit). reason: one line (empty if ok). steps_walked: steps of the orbit
    search's walk (completed before a fall). orbit: what the search found (:class:`.orbit.Orbit`: the band, its period
    and scatter σ, the probe, ρ when asked). certificate (the barrier :class:`Certificate` in the certificate's
    coordinates: r*, samples, images, margins, rounds, statement), coordinates (z = T x̄ of the reduced state, the
    shape of the set; :class:`Coordinates`), fixed_point (x*: a switching state of the settled walk) and map_residual
    ‖P(x̄*) − x̄*‖ (certificate coordinates, one map) are None where the certificate did not get that far. :attr:`value`
    is 0 unless ok and verified. sigma: a state certificate's σ, the orbit's own scatter about x̄* in the certificate's
    coordinates (the last window's switching states of x*'s phase): an r* not above it certifies nothing the walk
    does not already do. ball: for an ellipsoid certified with ``ellipsoid.compare_ball``, the ball certified beside
    it (its volume ratio: :attr:`volume_ratio`). excursion: horizon k ≥ 2, per j = 1 … k the largest ‖P^j(z) − z*‖
    over the samples in the certified set. speed_note: when the orbit search's walk did not go at the gait's planned
    speed (:func:`robustgait.sim.walk.speed_note`), that note: the figure certifies that walk, not the planned one.
    """

    status: Status
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
    orbit: Orbit | None = None
    orbit_physics_steps: int = 0  # simulated by the orbit search (its walk, the probe, ρ)
    verify_physics_steps: int = 0  # of physics_steps, simulated by a push certificate's verification batches
    sigma: float | None = None
    replayed_samples: int = 0  # exploration samples answered from an earlier run's (certify_gait's ``explored``)
    replayed_orbit: bool = False  # the orbit was the earlier run's, not searched again
    gait_digest: str = ""  # Gait.digest() of the gait certified
    robot_digest: str = ""  # Robot.digest of the robot it was certified on
    speed_note: str = ""

    @property
    def ok(self) -> bool:
        return self.status == Status.OK

    @property
    def value(self) -> float:
        """The certified figure, in :attr:`unit`: J* [N s] of a push certificate, r* of a state certificate
        (:attr:`j_star` or :attr:`r_star` by name) — 0 unless certified and verified (an exploration alone certifies
        nothing: its figure is :attr:`estimate`)."""
        c = self.certificate
        return float(c.radius) if c is not None and c.verified else 0.0

    @property
    def verified(self) -> bool:
        """Whether :attr:`value` is a verified figure (a certificate whose estimator verified its radius)."""
        return self.certificate is not None and self.certificate.verified

    @property
    def figure(self) -> str:
        """The figure's name: ``J*`` (push) or ``r*`` (state), :func:`~robustgait.config.radius_name`."""
        return radius_name(self.config.space)

    @property
    def unit(self) -> str:
        """The figure's unit (``N s`` for J*; r*'s is the state's)."""
        return self.config.unit

    @property
    def estimate(self) -> float | None:
        """The exploration's estimate of the figure (Ĵ or r̂), or the figure itself when the estimator made no
        exploration (the uniform one); None without a certificate."""
        c = self.certificate
        if c is None:
            return None
        return float(c.estimate if c.estimate is not None else c.radius)

    @property
    def j_star(self) -> float:
        """J* [N s] of a push certificate; raises :class:`RobustGaitError` for a state certificate (its figure is
        :attr:`r_star`)."""
        if self.config.disturbance != "push":
            raise RobustGaitError(f"a {self.config.space} certificate's figure is r_star, not j_star")
        return self.value

    @property
    def r_star(self) -> float:
        """r* of a state certificate, in ``config.unit``; raises :class:`RobustGaitError` for a push certificate (its
        figure is :attr:`j_star`)."""
        if self.config.disturbance == "push":
            raise RobustGaitError("a push certificate's figure is j_star, not r_star")
        return self.value

    @property
    def below_scatter(self) -> bool:
        """A state certificate whose r* is not above the orbit's own scatter σ: vacuous."""
        return self.certificate is not None and self.sigma is not None and self.certificate.radius <= self.sigma

    @property
    def vacuous(self) -> bool:
        """True when nothing is certified: a failed status, no sample inside B(r*), or r* ≤ σ."""
        return self.certificate is None or self.certificate.vacuous or self.below_scatter

    @property
    def energy(self) -> float | None:
        """E* [J] of an energy state: every perturbation adding at most E* of kinetic energy is in the set."""
        if self.coordinates is None or self.certificate is None:
            return None
        return self.coordinates.energy(self.certificate.radius)

    @property
    def volume_ratio(self) -> float | None:
        """vol(certified ellipsoid) / vol(certified ball), when both were certified."""
        if self.ball is None or self.certificate is None or self.coordinates is None:
            return None
        return volume_ratio(self.certificate.radius, self.ball.radius, self.coordinates.dim)

    def statement(self) -> str:
        """The certificate in words: what it promises, with its confidence, its horizon and its basis."""
        if self.certificate is None:
            return (f"No certificate ({self.status}): {self.reason}; {radius_name(self.config.space)} = 0 after "
                    f"{self.steps_walked} steps.")
        c, cfg = self.certificate, self.config
        if not c.verified:
            name = radius_name(cfg.space)
            unit = "N s" if cfg.disturbance == "push" else cfg.unit
            return (f"{name} ≈ {c.radius:.4g} {unit} is an estimate from {c.n_samples} exploration "
                    f"{'pushes' if cfg.disturbance == 'push' else 'samples'}, not verified: no confidence statement "
                    f"(robustgait certify verifies it).")
        if cfg.disturbance != "push":
            return c.statement() + self._scatter_clause()
        if c.vacuous or c.budget_exhausted:
            return c.statement()
        v = self.validate or ValidateConfig()
        inside = "≤" if c.attained else "<"
        basis = push_basis(c, cfg)
        p = cfg.push
        fail = f"make the robot fall within that step and {p.horizon} more"
        if p.recovery:
            fail += (f" (a pushed walk stops once recovered: {p.recovery_steps} consecutive steps with every "
                     f"coordinate of the switching state within {p.recovery_radius:g} of its orbit's band in band "
                     f"coordinates, or {p.recovery_scatter:g}× the orbit's own scatter)")
        return (f"With confidence {100.0 * c.confidence:g}%, at most {100.0 * c.violation_bound:.3g}% of the pushes "
                f"with impulse |J| {inside} J* = {c.radius:.4g} N s (uniform in that disk; {v.push_duration:g} s long, "
                f"starting at a phase in [{v.push_phase[0]:g}, {v.push_phase[1]:g}] of the step) {fail}: {basis}.")

    def _scatter_clause(self) -> str:
        """A state certificate's σ, and what it means for r*."""
        if self.sigma is None:
            return ""
        unit = self.config.unit
        if self.below_scatter:
            return (f" The orbit's own switching states scatter σ = {self.sigma:.3g} {unit} about x̄*: r* is not above "
                    "it, so the certificate is vacuous (it certifies no perturbation the undisturbed walk does not "
                    "make itself).")
        return f" The orbit's own switching states scatter σ = {self.sigma:.3g} {unit} about x̄*."

    def to_dict(self, *, samples: bool = True) -> dict[str, Any]:
        """JSON-ready; everything but ``seconds`` is deterministic for a given seed. The figure: ``figure`` (``J*`` or
        ``r*``), ``value`` (the certified figure, 0 unless verified), ``estimate`` (the exploration's, None without a
        certificate), ``verified`` and ``unit``."""
        fp, cfg = self.fixed_point, self.config
        out: dict[str, Any] = {
            "robot": self.robot,
            "status": str(self.status),
            "reason": self.reason,
            "figure": self.figure,
            "value": 0.0,
            "estimate": None,
            "verified": False,
            "vacuous": True,
            "steps_walked": self.steps_walked,
            "state": cfg.state,
            "set": cfg.set,
            "horizon": cfg.horizon,
            "disturbance": cfg.disturbance,
            "unit": self.unit,
            "x_star": None,
            "omega_star": None if fp is None else [float(v) for v in fp.omega],
            "fixed_point_step": None if fp is None else fp.step,
            "map_residual": self.map_residual,
            "orbit": None if self.orbit is None else self.orbit.to_dict(),
            "map": cfg.map,
            "period": None if self.orbit is None else self.orbit.period,
            "sigma": self.sigma,
            "reconstruction": cfg.reconstruction,
            "frame": cfg.frame,
            "method": cfg.method,
            "barrier": cfg.barrier,
            "energy": self.energy,
            "controller": self.controller,
            "controller_note": self.controller_note,
            "speed_note": self.speed_note,
            "statement": self.statement(),
        }
        if self.certificate is not None:
            c = self.certificate.to_dict()
            if not samples:
                for key in ("samples", "images", "fell", "margins", "sample_round"):
                    c.pop(key)
            c["statement"] = self.statement()
            out.update(c)
            out["estimate"] = self.estimate  # the uniform estimator's is its radius
            out["vacuous"] = self.vacuous
        if self.coordinates is not None:
            out["coordinates"] = self.coordinates.to_dict()
        if self.ball is not None:
            out["ball"] = {"value": self.ball.radius, "attained": self.ball.attained,
                           "n_samples": self.ball.n_samples, "violation_bound": self.ball.violation_bound,
                           "statement": self.ball.statement(), "volume_ratio": self.volume_ratio}
        if self.excursion is not None:
            out["excursion"] = self.excursion
        if self.orbit is not None and (state := orbit_state(self.orbit)) is not None:
            out["orbit_state"] = state
        out.update({"physics_steps": self.physics_steps, "orbit_physics_steps": self.orbit_physics_steps,
                    "verify_physics_steps": self.verify_physics_steps,
                    "replayed_samples": self.replayed_samples, "replayed_orbit": self.replayed_orbit,
                    "gait_digest": self.gait_digest, "robot_digest": self.robot_digest, "config": to_dict(cfg),
                    "sim": to_dict(self.sim), "seconds": self.seconds})
        if self.validate is not None:
            out["push"] = {"duration": self.validate.push_duration, "phase": list(self.validate.push_phase)}
        return out


Progress = Callable[[int], None]
BatchMap = Callable[[np.ndarray, "Progress | None"], np.ndarray]


def _estimate(P: BatchMap, x_star: np.ndarray, cfg: CertifyConfig, progress: bool, desc: str, *,
              explore: BatchMap | None = None, verify: bool | Callable[[float], bool] = True) -> Certificate:
    """Run the configured estimator on a map in certificate coordinates (progress bar: samples, stderr; the map is
    called with the bar's update, per sample that reaches its end). ``explore``: the sequential estimator's map of
    exploration (default P); ``verify`` false: its exploration alone (an estimate)."""
    total = cfg.n_samples if cfg.method == "uniform" else cfg.estimator.budget
    with tqdm(total=total, desc=desc, unit="sample", disable=not progress, leave=False) as bar:
        def counted(x: np.ndarray) -> np.ndarray:
            return P(x, bar.update)

        def counted_explore(x: np.ndarray) -> np.ndarray:
            return (explore or P)(x, bar.update)
        if cfg.method == "uniform":
            return certify_map(counted, x_star, cfg)
        return certify_map_sequential(counted, x_star, cfg, explore=counted_explore, verify=verify)


def certificate_from_record(d: Mapping[str, Any]) -> Certificate:
    """A :class:`Certificate` from its JSON (:meth:`GaitCertificate.to_dict` with samples): null image rows
    back to NaN, null margins back to −inf; its radius the certified figure, or the estimate of an exploration alone
    (:func:`~robustgait.io.certfile.certificate_radius`: files of every version)."""
    d = {**d, "radius": certificate_radius(d)}
    fell = np.asarray(d["fell"], dtype=bool)
    n = len(d["x_star"])
    images = np.array([[np.nan] * n if row is None else row for row in d["images"]], dtype=float)
    margins = np.array([-np.inf if m is None else m for m in d["margins"]], dtype=float)
    arrays: dict[str, Any] = {
        "x_star": np.asarray(d["x_star"], dtype=float), "samples": np.asarray(d["samples"], dtype=float),
        "images": images, "fell": fell, "margins": margins,
        "rounds": tuple(Round(**r) for r in d.get("rounds") or ()),
        "sample_round": None if d.get("sample_round") is None else np.asarray(d["sample_round"], dtype=np.int64)}
    kwargs = {f.name: arrays[f.name] if f.name in arrays else d[f.name] for f in dataclasses.fields(Certificate)
              if f.name in arrays or f.name in d}
    return Certificate(**kwargs)


def _same_run(explored: Mapping[str, Any], robot: Robot, config: CertifyConfig, sim: SimConfig,
              validate: ValidateConfig | None) -> bool:
    """Whether an earlier certificate (``explored``, :meth:`GaitCertificate.to_dict`) was made on ``robot`` with the
    same certificate and simulation options (and, for a push certificate, ``validate``'s push duration and phases)."""
    if (explored.get("status") != str(Status.OK) or explored.get("robot") != robot.name
            or explored.get("config") != to_dict(config) or explored.get("sim") != to_dict(sim)):
        return False
    if config.disturbance == "push":
        v = validate or ValidateConfig()
        return bool(explored.get("push") == {"duration": v.push_duration, "phase": list(v.push_phase)})
    return True


def stored_orbit(explored: Mapping[str, Any], robot: Robot, gait: Gait, config: CertifyConfig, sim: SimConfig,
                 validate: ValidateConfig | None) -> Orbit | None:
    """The orbit of an earlier push certificate of this gait (``explored``: :meth:`GaitCertificate.to_dict`, e.g. a
    study's estimate), rebuilt (:func:`.orbit.orbit_from_dict`) instead of searched again: the search is a function of
    the robot, the gait and the options alone, so an orbit searched on the same robot (:attr:`Robot.digest`), the same
    gait (:meth:`Gait.digest`) and the same options is the same orbit. None otherwise, or when the record does not
    hold it whole."""
    if (config.disturbance != "push" or not _same_run(explored, robot, config, sim, validate)
            or explored.get("robot_digest") != robot.digest or explored.get("gait_digest") != gait.digest()):
        return None
    try:
        orbit = orbit_from_dict(explored["orbit"], explored["orbit_state"])
    except (KeyError, TypeError, ValueError):  # not a whole record (an older or edited file): search again
        return None
    return orbit if orbit.ok else None


def stored_exploration(explored: Mapping[str, Any], robot: Robot, config: CertifyConfig, sim: SimConfig,
                       validate: ValidateConfig | None, fp: FixedPoint) -> tuple[np.ndarray, np.ndarray] | None:
    """The exploration of an earlier certificate of the same gait (``explored``: :meth:`GaitCertificate.to_dict` with
    its samples, e.g. a study's estimate) as (samples (N, n), images (N, n), NaN rows: fell): the samples of its rounds
    before its first verification, in the order they were evaluated. None unless it was made on the same robot, with
    the same certificate, simulation and push options (``validate``: a push certificate's duration and phases), from
    the same x* (its step and reduced state, to the last bit), and holds its samples."""
    if (explored.get("samples") is None or not _same_run(explored, robot, config, sim, validate)
            or explored.get("fixed_point_step") != fp.step
            or explored.get("omega_star") != [float(v) for v in fp.omega]):
        return None
    try:
        c = certificate_from_record(explored)
    except (KeyError, TypeError, ValueError):  # not a certificate's samples (an edited file): simulate instead
        return None
    if c.samples.ndim != 2 or c.images.shape != c.samples.shape or c.round_of_sample.shape != c.samples.shape[:1]:
        return None
    kinds = [r.kind for r in c.rounds]
    keep = np.flatnonzero(c.round_of_sample < (kinds.index("verify") if "verify" in kinds else len(kinds)))
    return c.samples[keep], c.images[keep]


def certify_steps(config: CertifyConfig, graph: str, dim: int) -> int:
    """The most steps a certificate simulates: the orbit search on a section of ``dim`` coordinates
    (:meth:`CertifyConfig.orbit_steps`: its walk, the probe, ρ when asked), a state certificate's map at x*
    (``horizon`` maps of up to ``orbit.max_period`` steps), and :attr:`~CertifyConfig.steps_per_sample` for each of
    :attr:`~CertifyConfig.samples_planned` (a push: the pushed step and ``push.horizon`` more, every push walking to
    the horizon). ``graph``: the gait's domain graph (the count does not depend on it)."""
    at_x_star = 0 if config.disturbance == "push" else config.horizon * config.orbit.max_period
    return config.orbit_steps(dim) + at_x_star + config.samples_planned * config.steps_per_sample


def check_certify_work(robot: Robot, gait: Gait, config: CertifyConfig, sim: SimConfig) -> int:
    """Bound a certificate's simulation before it starts (:mod:`robustgait.config.work`; and its budget,
    :func:`~.verification.check_budget`): :func:`certify_steps`,
    each of up to the gait's :func:`~robustgait.sim.engine.step_horizons`, against what the default certificate
    needs on this robot and gait."""
    check_budget(config)
    graph, samples = gait.domain_graph, "sequential.budget" if config.method == "sequential" else "n_samples"
    dim = section_dimension(robot)
    return check_work(Work(certify_steps(config, graph, dim), step_physics_steps(gait, robot.dt, sim)),
                      Work(certify_steps(CertifyConfig(), graph, dim), step_physics_steps(gait, robot.dt, SimConfig())),
                      robot.dt, f"certify.orbit.max_steps {config.orbit.max_steps} + certify.{samples} "
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
        inside = d <= cert.radius if cert.attained else d < cert.radius
        if not inside.any():
            return [0.0] * path.shape[0]
        dist = np.linalg.norm(path[:, inside] - coords.x_star, axis=2)
        return [float(v) for v in np.max(np.where(np.isfinite(dist), dist, np.inf), axis=1)]


def _in_coordinates(pmap: ReducedMap, coords: Coordinates, paths: _Paths | None = None) -> BatchMap:
    """P^k in the certificate's coordinates: z ↦ T P^k(T⁻¹ z)."""
    def P(z: np.ndarray, progress: Progress | None = None) -> np.ndarray:
        out = coords.to_z(pmap(coords.to_xbar(z), progress=progress))
        if paths is not None and pmap.last_path is not None:
            paths.parts.append(pmap.last_path)
        return out
    return P


def fit_shape(pmap: ReducedMap, ball: Coordinates, cfg: CertifyConfig) -> Shape:
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


def orbit_scatter(orbit: Orbit, reduced: ReducedState, coords: Coordinates) -> float:
    """σ of a state certificate: the largest distance, in the certificate's coordinates, of the orbit's last-window
    switching states of x*'s phase from x̄* (0 without them)."""
    states = orbit.phase_states(0)
    if states is None or not len(states):
        return 0.0
    nq = reduced.robot.model.nq
    z = coords.to_z(reduced.phi(states[:, :nq], states[:, nq:]))
    return float(np.max(np.linalg.norm(z - coords.x_star, axis=1)))


@dataclass
class _Sampled:
    """What a certificate's sampling gave: the certificate of the set (``cert``) in its ``coords``, the physics
    steps it simulated, how many samples it replayed; for a state certificate the map's residual at x̄*, the ball's
    certificate beside an ellipsoid's, the horizon's excursion and the orbit's scatter (:func:`certify_gait`)."""

    cert: Certificate
    coords: Coordinates
    steps: int
    replayed: int
    verify_steps: int = 0
    map_residual: float | None = None
    ball: Certificate | None = None
    excursion: list[float] | None = None
    sigma: float | None = None


def _sample_pushes(engine: StepEngine, orbit: Orbit, cfg: CertifyConfig, vcfg: ValidateConfig,
                   stored: tuple[np.ndarray, np.ndarray] | None, progress: bool,
                   verify: bool | Callable[[float], bool]) -> _Sampled:
    """The push certificate's sampling: the impulse disk of J* on the orbit, its exploration at the exploring
    settings (or replayed from ``stored``), its verification at the certifying ones."""
    assert orbit.qpos is not None and orbit.qvel is not None  # a walking orbit (its caller checked orbit.ok)
    coords = Coordinates("push", "N s", False, np.zeros(2), np.eye(2), Shape(np.eye(2)))
    pushes = PushMap(engine, orbit.qpos, orbit.qvel, orbit.band, vcfg, cfg.push)
    exploring = PushMap(engine, orbit.qpos, orbit.qvel, orbit.band, vcfg, cfg.push.exploring())
    replay = None if stored is None else Replay(exploring, *stored)
    cert = _estimate(pushes, np.zeros(2), cfg, progress, f"pushes, {cfg.method}", explore=replay or exploring,
                     verify=verify)
    if cert.basis:
        cert = dataclasses.replace(cert, basis=push_basis(cert, cfg))
    return _Sampled(cert, coords, pushes.physics_steps + exploring.physics_steps,
                    0 if replay is None else replay.replayed, verify_steps=pushes.physics_steps)


def _sample_states(robot: Robot, gait: Gait, engine: StepEngine, orbit: Orbit, cfg: CertifyConfig,
                   stored: tuple[np.ndarray, np.ndarray] | None, progress: bool,
                   verify: bool | Callable[[float], bool]) -> _Sampled | None:
    """The state certificate's sampling: the reduced map of the orbit's period (its ellipsoid fitted when the set is
    one, the ball beside it when asked), its exploration replayed from ``stored`` when given. None when the map
    falls from its own fixed point x̄* within the horizon."""
    assert orbit.qpos is not None and orbit.qvel is not None  # a walking orbit (its caller checked orbit.ok)
    fmap = FullStateMap(robot, gait, orbit.period, engine=engine)
    reduced = ReducedState.at(cfg.state, robot, orbit.qpos, orbit.qvel, gait.stance, cfg)
    pmap = ReducedMap(fmap, reduced, cfg.horizon)
    coords = Coordinates.of(reduced)
    image = coords.to_z(pmap(reduced.x_star[None]))[0]
    first = coords.to_z(pmap.last_path[0])[0] if pmap.last_path is not None else image
    map_residual = float(np.linalg.norm(first - coords.x_star))
    if not np.all(np.isfinite(image)):
        return None
    fmap.physics_steps = 0
    ball: Certificate | None = None
    if cfg.set == "ellipsoid":
        shape = fit_shape(pmap, coords, cfg)
        if cfg.ellipsoid.compare_ball:
            ball = _estimate(_in_coordinates(pmap, coords), coords.x_star, cfg, progress,
                             f"{cfg.state} ball, {cfg.method}")
        coords = dataclasses.replace(coords, shape=shape)
    sigma = orbit_scatter(orbit, reduced, coords)
    paths = _Paths()
    desc = f"{cfg.state} {cfg.set}{'' if cfg.horizon == 1 else f', P^{cfg.horizon}'}, {cfg.method}"
    P = _in_coordinates(pmap, coords, paths)
    replay = None if stored is None else Replay(P, *stored)
    cert = _estimate(P, coords.x_star, cfg, progress, desc, explore=replay, verify=verify)
    excursion = paths.excursion(cert, coords) if cfg.horizon > 1 else None
    return _Sampled(cert, coords, fmap.physics_steps, 0 if replay is None else replay.replayed,
                    map_residual=map_residual, ball=ball, excursion=excursion, sigma=sigma)


def certify_gait(robot: Robot, gait: Gait, config: CertifyConfig | None = None, sim: SimConfig | None = None, *,
                 validate: ValidateConfig | None = None, progress: bool = False,
                 verify: bool | Callable[[float], bool] = True,
                 explored: Mapping[str, Any] | None = None) -> GaitCertificate:
    """Find the orbit the gait walks (:func:`.search.find_orbit`: settled, stable), then certify the set of
    ``config`` around its x* with the configured estimator (``uniform``: :func:`.barrier.certify_map`;
    ``sequential``: :func:`.estimators.certify_map_sequential`) on the map of the orbit's period, in the state, set
    and horizon of the config; or, with ``disturbance = push``, the impulse disk J* (pushes as ``validate``'s:
    duration and phases of ``validate``; the probe's too).

    With ``ellipsoid.compare_ball`` an ellipsoid's certificate also certifies the ball of the same state (its r* and
    the volume ratio are reported). A gait without a stable orbit, or whose reduced map falls from x̄*, returns a
    certificate with that ``status`` and r* = 0 (no exception); too much work for the limits raises
    :class:`RobustGaitError` before any simulation. ``progress``: bars on stderr. ``verify`` false (the sequential
    estimator): the exploration alone, whose r̂ is an estimate with no statement (``certificate.verified`` false) —
    what a study ranks its gaits by (docs/studies.md); a callable of the estimate decides whether to verify it (a
    person study verifies only the gaits it may show). ``explored``: an earlier certificate of this gait with its
    samples (:meth:`GaitCertificate.to_dict`, e.g. a study's estimate): where it was made with the same options from
    the same x* (:func:`stored_exploration`; a state certificate of horizon 1), its exploration is replayed instead of
    simulated again (:class:`.estimators.Replay`) — the same certificate, fewer physics steps
    (``replayed_samples``); otherwise it is ignored. A push certificate also takes its orbit from it when it was
    searched on the same robot and gait with the same options (:func:`stored_orbit`, ``replayed_orbit``).
    """
    cfg = config or CertifyConfig()
    sim = sim or SimConfig()
    push = cfg.disturbance == "push"
    if push and cfg.r_max is None:  # the first round's disk, at the robot's scale
        cfg = dataclasses.replace(cfg, r_max=min(R_MAX_LIMIT["push"], probe_impulse(robot, cfg.push.r_max_scale)))
    vcfg = validate or ValidateConfig()
    check_certify_work(robot, gait, cfg, sim)
    t0 = time.perf_counter()
    engine = make_engine(robot, gait, sim)
    try:
        orbit = None if explored is None else stored_orbit(explored, robot, gait, cfg, sim, vcfg)
        replayed_orbit = orbit is not None
        if orbit is None:
            with tqdm(total=cfg.orbit.max_steps, desc="orbit", unit="step", disable=not progress, leave=False) as bar:
                orbit = find_orbit(Walking(robot, gait, sim, validate=vcfg, engine=engine,
                                           progress=lambda k: bar.update(k - bar.n)), cfg)
        t1 = time.perf_counter()
        note = orbit_speed_note(orbit, gait, sim)

        def result(status: Status, reason: str, **kw: Any) -> GaitCertificate:
            t = time.perf_counter()
            seconds = kw.pop("seconds", {"orbit": t1 - t0, "sampling": 0.0, "total": t - t0, "sim_steps_per_s": 0.0})
            return GaitCertificate(status=status, reason=reason, config=cfg, sim=sim, robot=robot.name,
                                   seconds=seconds, steps_walked=orbit.steps, validate=vcfg if push else None,
                                   replayed_orbit=replayed_orbit, gait_digest=gait.digest(),
                                   robot_digest=robot.digest,
                                   controller=engine.controller_name, controller_note=engine.controller_note,
                                   orbit=orbit, orbit_physics_steps=orbit.physics_steps, speed_note=note, **kw)

        if not orbit.ok:
            return result(orbit.status, orbit.reason, certificate=None, fixed_point=None, map_residual=None,
                          physics_steps=0)
        assert orbit.qpos is not None and orbit.qvel is not None
        fp = orbit.fixed_point(cfg.frame)
        stored = None if explored is None or cfg.method != "sequential" or (not push and cfg.horizon > 1) else \
            stored_exploration(explored, robot, cfg, sim, vcfg if push else None, fp)
        t2 = time.perf_counter()
        if push:
            sampled = _sample_pushes(engine, orbit, cfg, vcfg, stored, progress, verify)
        else:
            states = _sample_states(robot, gait, engine, orbit, cfg, stored, progress, verify)
            if states is None:
                return result(Status.UNSTABLE_FIXED_POINT, f"the return map falls from its own fixed point within "
                              f"{cfg.horizon} map(s) (through the {cfg.reconstruction} reconstruction x̄* is not on a "
                              "walking orbit)", certificate=None, fixed_point=fp, map_residual=None, physics_steps=0)
            sampled = states
        t3 = time.perf_counter()
        return result(Status.OK, "", certificate=sampled.cert, fixed_point=fp, map_residual=sampled.map_residual,
                      physics_steps=sampled.steps, replayed_samples=sampled.replayed, coordinates=sampled.coords,
                      verify_physics_steps=sampled.verify_steps,
                      ball=sampled.ball, excursion=sampled.excursion, sigma=sampled.sigma,
                      seconds={"orbit": t1 - t0, "sampling": t3 - t2, "total": t3 - t0,
                               "sim_steps_per_s": sampled.steps / max(t3 - t2, 1e-9)})
    finally:
        engine.close()
