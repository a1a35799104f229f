"""Validation trials of one gait: disturbed walks from the certified fixed point, batched.

A trial starts on the gait's periodic orbit — the fixed point x* of the certificate's return map (full
state, canonical stance) — and walks ``period + steps_after`` steps (period = 1 for the step map, 2 for the
stride map) under one disturbance (:mod:`robustgait.validate.disturbances`). All trials of a kind are one
batch: every step is one :meth:`StepEngine.step` call on the trials still walking (``mujoco.rollout``).

Outcome per trial: ``success`` = no fall in those steps; the fall reason and the step it fell in; and
x̄₁ = Φ of the state at the first switching event after the disturbance onset (after ``period`` steps,
written for the canonical stance — the point the certificate's map acts on), its distance to x̄*, and
whether it lies in the certified ball B(r*). The certificate claims that no trial with x̄₁ in B(r*) falls
(for the reduced map through its reconstruction; a real disturbance also moves the other coordinates).
"""

from __future__ import annotations

import json
import math
import time
from collections.abc import Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray
from tqdm import tqdm

from robustgait.certificate.certify import GaitCertificate, certify_gait, certify_steps
from robustgait.certificate.orbit import FixedPoint, Orbit
from robustgait.certificate.push import recovered_steps
from robustgait.certificate.reduced import ReducedState, section_dimension
from robustgait.certificate.search import Walking, find_orbit
from robustgait.config import (
    KINDS,
    R_MAX_UNIT,
    CertifyConfig,
    Frame,
    MapKind,
    PushConfig,
    SimConfig,
    ValidateConfig,
    radius_name,
    to_dict,
)
from robustgait.config.certify import orbit_options
from robustgait.config.work import Work, check_work
from robustgait.domains import step_segments
from robustgait.errors import RobustGaitError
from robustgait.gait import Gait
from robustgait.robots import Robot
from robustgait.rotations import quat_to_mat
from robustgait.sim.engine import StepInputs, step_physics_steps
from robustgait.sim.factory import make_engine
from robustgait.sim.trials import Inputs, Segment, pushed_first_step, simulate_trials
from robustgait.validate import disturbances as dist
from robustgait.validate.disturbances import SIZE_LABELS, Draws
from robustgait.validate.stats import LogisticFit, Rate, binned_rates, logistic_fit

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class CertificateRef:
    """What a validation needs of a gait's certificate: r*, whether the supremum is attained (closed set) or not
    (open set), the centre z* = T x̄* and the transform T (z = T x̄,
    :class:`robustgait.certificate.reduced.Coordinates`) of its coordinates, the space certified (omega, centroidal,
    velocity, or push: then r* is J* [N s] and the check is on the pushes' impulses), the set and horizon, E* [J] for
    an energy state, the map, frame, reconstruction, the orbit search's options (``map`` and every ``orbit`` field:
    :func:`robustgait.config.certify.orbit_options`), and where it came from ("computed" or a file path)."""

    value: float
    attained: bool
    x_star: tuple[float, ...]
    transform: tuple[tuple[float, ...], ...]
    space: str
    set: str
    horizon: int
    energy: float | None
    map: MapKind
    frame: Frame
    reconstruction: str
    orbit: tuple[tuple[str, Any], ...]
    source: str
    push: PushConfig | None = None  # a push certificate's pushed walk: its horizon and recovery

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready (tuples as lists by the encoder): the radius validated against as ``value``, with its
        ``figure`` (``J*`` or ``r*``) and ``unit``."""
        return {**asdict(self), "figure": radius_name(self.space), "unit": R_MAX_UNIT[self.space]}

    @staticmethod
    def of(gc: GaitCertificate) -> CertificateRef:
        c, cfg, co = gc.certificate, gc.config, gc.coordinates
        if c is None or gc.fixed_point is None or co is None:
            raise RobustGaitError(f"the gait has no certificate to validate against ({gc.status}: {gc.reason})")
        return CertificateRef(gc.value, bool(c.attained), tuple(float(v) for v in c.x_star),
                              tuple(tuple(float(v) for v in row) for row in co.transform), cfg.space, cfg.set,
                              cfg.horizon, gc.energy, cfg.map, cfg.frame, cfg.reconstruction,
                              tuple(orbit_options(cfg).items()), "computed",
                              cfg.push if cfg.disturbance == "push" else None)

    @staticmethod
    def load(path: str | Path) -> CertificateRef:
        """From a certificate JSON written by ``robustgait certify -o``."""
        from robustgait.io.certfile import read_certificate

        c = read_certificate(path)
        cfg = c.certify_config(path)
        k = len(c.x_star)
        t = c.transform(path) or np.eye(k).tolist()
        return CertificateRef(c.radius, c.attained, tuple(c.x_star), tuple(tuple(row) for row in t), cfg.space,
                              cfg.set, cfg.horizon, c.energy, cfg.map, cfg.frame, cfg.reconstruction,
                              tuple(orbit_options(cfg).items()), str(path),
                              cfg.push if cfg.disturbance == "push" else None)

    def certify_config(self, base: CertifyConfig) -> CertifyConfig:
        """``base`` with this certificate's state, set, horizon, map, frame, reconstruction and orbit search."""
        from dataclasses import replace

        kw: dict[str, Any] = {"disturbance": "push"} if self.space == "push" else {"state": self.space,
                                                                                  "disturbance": "state"}
        kw.update(set=self.set, reconstruction=self.reconstruction)
        if self.push is not None:
            kw["push"] = self.push
        options = dict(self.orbit)
        orbit = replace(base.orbit, **{k.split(".", 1)[1]: v for k, v in options.items() if k.startswith("orbit.")})
        return replace(base, horizon=self.horizon, map=options.get("map", self.map), frame=self.frame, orbit=orbit,
                       **kw)

    def check_matches(self, config: CertifyConfig) -> None:
        """Refuse a certificate of another space, set or horizon than ``config`` asks for (one line)."""
        for name, mine, asked in (("state", self.space, config.space), ("set", self.set, config.set),
                                  ("horizon", self.horizon, config.horizon)):
            if mine != asked:
                raise RobustGaitError(f"{self.source}: the certificate is of {name} {mine}, not the {name} {asked} "
                                      f"asked for (validate against it with --{name} {mine})")

    def to_z(self, xbar: FloatArray) -> FloatArray:
        return np.asarray(np.atleast_2d(xbar) @ np.asarray(self.transform).T)

    def inside(self, distance: FloatArray) -> NDArray[np.bool_]:
        """Membership in the certified set (closed if r* is attained, else open); NaN distances: False."""
        with np.errstate(invalid="ignore"):
            return np.asarray(distance <= self.value if self.attained else distance < self.value)


@dataclass
class KindResult:
    """The trials of one disturbance kind (arrays over trials, N first) and their timing."""

    kind: str
    size: FloatArray
    params: dict[str, FloatArray]
    success: NDArray[np.bool_]
    fall_reason: list[str | None]
    fall_step: NDArray[np.int64]
    x_first: FloatArray
    distance: FloatArray
    inside: NDArray[np.bool_]
    physics_steps: int
    seconds: float
    energy: FloatArray | None = None  # (N,) kinetic energy the disturbance added at the first section [J]
    energy_star: float | None = None  # E* of the certificate [J] (energy states)
    # a push certificate's own criterion at its horizon (the pushed step and push.horizon more): (N,) whether each
    # trial failed it (fell by then, before it was back in the orbit's band), and that horizon
    horizon_failed: NDArray[np.bool_] | None = None
    horizon: int | None = None

    @property
    def size_label(self) -> tuple[str, str]:
        return SIZE_LABELS[self.kind]

    def success_rate(self) -> Rate:
        return Rate.of(int(self.success.sum()), int(self.success.size))

    def critical(self) -> LogisticFit:
        """The size at which half the trials fail (logistic fit of success against size)."""
        return logistic_fit(self.size, self.success)

    def certificate_check(self) -> dict[str, Rate | int]:
        """Fall rates of the trials whose x̄₁ lies inside the certified set (the certificate says 0; for a push
        certificate: the pushes with |J| ≤ J*) and outside it, the number of trials that fell before reaching their
        first switching event (no x̄₁), and for an energy certificate the falls among the trials that added at most
        E* of kinetic energy at the first section."""
        fell = ~self.success
        reached = np.isfinite(self.distance)
        out = reached & ~self.inside
        check: dict[str, Rate | int] = {"inside": Rate.of(int((fell & self.inside).sum()), int(self.inside.sum())),
                                        "outside": Rate.of(int((fell & out).sum()), int(out.sum())),
                                        "fell_before_event": int((~reached).sum())}
        if self.energy is not None and self.energy_star is not None:
            with np.errstate(invalid="ignore"):
                low = np.isfinite(self.energy) & (self.energy <= self.energy_star)
            check["energy_below_star"] = Rate.of(int((fell & low).sum()), int(low.sum()))
        if self.horizon_failed is not None:
            check["inside_at_horizon"] = Rate.of(int((self.horizon_failed & self.inside).sum()), int(self.inside.sum()))
        return check

    def summary(self) -> dict[str, Any]:
        name, unit = self.size_label
        check = self.certificate_check()
        reasons: dict[str, int] = {}
        for r in self.fall_reason:
            if r is not None:
                reasons[r] = reasons.get(r, 0) + 1
        return {
            "kind": self.kind, "size": name, "unit": unit, "trials": int(self.success.size),
            "size_range": [float(self.size.min()), float(self.size.max())],
            "success": self.success_rate().to_dict(), "critical": self.critical().to_dict(),
            "binned": binned_rates(self.size, self.success),
            "certificate_check": {k: v.to_dict() if isinstance(v, Rate) else v for k, v in check.items()},
            "energy": None if self.energy is None else _quartiles(self.energy), "energy_star": self.energy_star,
            "horizon": self.horizon,
            "fall_reasons": reasons, "physics_steps": self.physics_steps, "seconds": self.seconds,
        }

    def to_dict(self, trials: bool = True) -> dict[str, Any]:
        out = self.summary()
        if trials:
            def clean(a: FloatArray) -> Any:
                return np.where(np.isfinite(a), a, np.nan).tolist()
            out["trials_detail"] = {
                "size": self.size.tolist(),
                "params": {k: v.tolist() for k, v in self.params.items()},
                "success": self.success.tolist(), "fall_reason": self.fall_reason,
                "fall_step": self.fall_step.tolist(),
                "x_first": [None if not np.isfinite(r).all() else r.tolist() for r in self.x_first],
                "distance": [None if not math.isfinite(v) else v for v in clean(self.distance)],
                "inside": self.inside.tolist(),
                "energy": None if self.energy is None else [None if not math.isfinite(v) else v
                                                            for v in clean(self.energy)],
            }
        return out


def _quartiles(a: FloatArray) -> dict[str, float] | None:
    """Median and quartiles of the finite values of ``a`` (None if there are none)."""
    v = a[np.isfinite(a)]
    if v.size == 0:
        return None
    q = np.quantile(v, [0.25, 0.5, 0.75])
    return {"q25": float(q[0]), "median": float(q[1]), "q75": float(q[2])}


@dataclass
class ValidationResult:
    """Validation of one gait: the certificate it was checked against, one :class:`KindResult` per kind,
    the config (saved with the results) and timings [s]."""

    robot: str
    gait: dict[str, Any]
    certificate: CertificateRef
    config: ValidateConfig
    sim: SimConfig
    kinds: dict[str, KindResult] = field(default_factory=dict)
    seconds: dict[str, float] = field(default_factory=dict)

    def to_dict(self, *, trials: bool = True) -> dict[str, Any]:
        return {"robot": self.robot, "gait": self.gait, "certificate": self.certificate.to_dict(),
                "config": to_dict(self.config), "sim": to_dict(self.sim), "seconds": self.seconds,
                "kinds": {k: v.to_dict(trials) for k, v in self.kinds.items()}}

    def to_json(self, *, trials: bool = True) -> str:
        return json.dumps(self.to_dict(trials=trials), allow_nan=False)


def _gait_info(gait: Gait) -> dict[str, Any]:
    return {"robot": gait.robot, "stance": gait.stance, "step_duration": gait.step_duration,
            "params": gait.params.to_dict() if gait.params is not None else None}


class Validator:
    """One gait on one robot, its certificate and fixed point: :meth:`run` a disturbance kind.

    Build it once per gait; the disturbances of a kind depend only on the config (seed) and the robot, so
    every gait validated with one config meets the same disturbances (for ``study validate``, loop over
    gaits with one :class:`ValidateConfig`).

    ``start``: where every trial starts instead of the certificate's fixed point (no fixed-point search; for
    a gait that has none — ``study validate`` starts the gaits that fell or were not certified in the study
    from their initial state, with a :class:`CertificateRef` of r* = 0).
    """

    def __init__(self, robot: Robot, gait: Gait, config: ValidateConfig | None = None, *,
                 certify: CertifyConfig | None = None, sim: SimConfig | None = None,
                 certificate: GaitCertificate | CertificateRef | str | Path | None = None, progress: bool = False,
                 start: FixedPoint | None = None):
        self.robot, self.gait = robot, gait
        self.config = config or ValidateConfig()
        self.sim = sim or SimConfig()
        self.progress = progress
        t0 = time.perf_counter()
        orbit: Orbit | None = None
        base = certify or CertifyConfig()
        if certificate is None:
            gc = certify_gait(robot, gait, certify, self.sim, validate=self.config, progress=progress)
            ref, orbit = CertificateRef.of(gc), gc.orbit
        elif isinstance(certificate, GaitCertificate):
            ref, orbit = CertificateRef.of(certificate), certificate.orbit
        else:
            ref = certificate if isinstance(certificate, CertificateRef) else CertificateRef.load(certificate)
        if certify is not None and certificate is not None:
            ref.check_matches(certify)
        cert_cfg = ref.certify_config(base)
        if start is None and (orbit is None or not orbit.ok):
            orbit = find_orbit(Walking(robot, gait, self.sim, validate=self.config), cert_cfg)
            if not orbit.ok:
                raise RobustGaitError(f"the gait has no stable orbit to start the trials from ({orbit.status}: "
                                      f"{orbit.reason})")
        if start is None:
            assert orbit is not None
            fp: FixedPoint = orbit.fixed_point(cert_cfg.frame)
        else:
            fp = start
        self.orbit = orbit if start is None else None
        state = "omega" if ref.space == "push" else ref.space
        # Φ of the certificate's state at this fixed point: x̄₁ of a trial in the certificate's coordinates; also the
        # kinetic energy a disturbance added (any state: M(q*) of the fixed point)
        self.reduced = ReducedState.at(state, robot, fp.qpos, fp.qvel, gait.stance,  # type: ignore[arg-type]
                                       cert_cfg)
        if start is None and ref.space != "push":
            z = ref.to_z(self.reduced.x_star[None])[0]
            if float(np.linalg.norm(z - np.asarray(ref.x_star))) > 1e-6 * max(1.0, float(np.linalg.norm(z))):
                raise RobustGaitError(f"{ref.source}: the certificate's x* {np.round(ref.x_star, 4).tolist()} is not "
                                      f"this gait's fixed point {np.round(z, 4).tolist()} (another gait, robot or "
                                      "simulation option?)")
        self.certificate, self.fixed_point = ref, fp
        self.period = self.orbit.period if self.orbit is not None else 1
        self.engine = make_engine(robot, gait, self.sim)
        # the undisturbed first step: its segments' horizons and durations, the length of the step
        q, v = fp.qpos[None], fp.qvel[None]
        self.segment_horizons: list[int] = []
        for seg_stance, domain in step_segments(gait.stance, len(self.engine.graph)):
            nominal = self.engine.step(q, v, seg_stance, domain=domain)
            if nominal.fell[0]:
                raise RobustGaitError(f"the gait falls from its {'start' if start is not None else 'own fixed point'} "
                                      f"({nominal.fall_reason[0]}) in the first step, undisturbed")
            self.segment_horizons.append(self.engine.horizons[domain])
            q, v = nominal.qpos, nominal.qvel
        # the segment that ended at the start: by the step map's symmetry, as long as the first step's last one
        self.nominal_at = round(float(nominal.duration[0]) / robot.dt)
        self.step_length = float(np.linalg.norm(q[0, :2] - fp.qpos[:2]))
        self._physics_model: Any = None
        self.seconds_setup = time.perf_counter() - t0

    def close(self) -> None:
        self.engine.close()

    def __enter__(self) -> Validator:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def _base_model(self) -> Any:
        if self._physics_model is None:
            self._physics_model = dist.physics_model(self.robot)
        return self._physics_model

    def inputs_for(self, kind: str, draws: Draws) -> Inputs:
        """The per-segment input function of :func:`simulate_trials` for a kind's draws."""
        cfg, eng, robot = self.config, self.engine, self.robot
        if kind == "push":
            # the push's window in the first step (all its segments: a multi-contact step starts in double support)
            wrench = dist.push_wrench(draws, cfg.push_duration, self.gait.step_duration, robot.dt,
                                      sum(self.segment_horizons))

            return pushed_first_step(eng, wrench)
        if kind in ("mass", "friction", "terrain", "slope"):
            if kind == "mass":
                models = dist.mass_models(self._base_model(), robot, draws, cfg)
            elif kind == "friction":
                models = dist.friction_models(self._base_model(), draws)
            elif kind == "slope":
                r = quat_to_mat(self.fixed_point.qpos[3:7])
                models = dist.slope_models(self._base_model(), draws, math.atan2(r[1, 0], r[0, 0]))
            else:
                fp = self.fixed_point
                layout = dist.terrain_layout(robot, fp.qpos, self.gait.stance, cfg, self.step_length)
                base = dist.terrain_model(robot, layout)
                models = dist.terrain_models(base, layout, draws)
            return lambda seg, idx: StepInputs(models=[models[i] for i in idx])
        if kind == "latency":
            delay = np.round(draws.size / robot.dt).astype(np.int64)

            def latency(seg: Segment, idx: NDArray[np.int64]) -> StepInputs:
                if eng.latency == "torque":  # a law computed centrally: its torque arrives late
                    return StepInputs(delay_steps=delay[idx], torque_tail=seg.torque_tail)
                return StepInputs(ctrl_offset=dist.latency_offsets(eng.controls[(seg.stance, seg.domain)],
                                                                   eng.controls[seg.prev], delay[idx], seg.prev_at))
            return latency
        if kind == "noise":
            def noise(seg: Segment, idx: NDArray[np.int64]) -> StepInputs:
                noise = dist.noise_draws(robot, draws.size, cfg.noise_v_ratio, eng.horizons[seg.domain], cfg.seed,
                                         seg.index)
                return StepInputs(sensor_noise=noise[idx])
            return noise
        raise RobustGaitError(f"unknown disturbance {kind!r}")

    def run(self, kind: str, *, draws: Draws | None = None) -> KindResult:
        """All trials of one disturbance kind (``draws``: override the config's draws, e.g. in tests)."""
        t0 = time.perf_counter()
        cfg = self.config
        d = draws if draws is not None else dist.draw(kind, cfg.trials, cfg, self.robot)
        n = d.size.size
        fp = self.fixed_point
        n_steps = self.period + cfg.steps_after
        ref, nq = self.certificate, self.robot.model.nq
        horizon = 1 + ref.push.horizon if ref.push is not None and kind == "push" else None
        sections = (np.full((n, n_steps, nq + self.robot.model.nv), np.nan)
                    if horizon is not None and horizon <= n_steps else None)
        with tqdm(total=n_steps, desc=f"validate {kind}", unit="step", disable=not self.progress, leave=False) as bar:
            ok, reasons, fall_step, first, physics = simulate_trials(
                self.engine, np.tile(fp.qpos, (n, 1)), np.tile(fp.qvel, (n, 1)), n_steps, self.period,
                self.inputs_for(kind, d), first_at=self.nominal_at, progress=bar.update, sections=sections)
        horizon_failed = None
        if sections is not None and horizon is not None and ref.push is not None:
            # the certificate's own criterion at its horizon: fell by then — unless it had recovered first (the
            # certificate's pushed walk stops there: a later fall is not its)
            horizon_failed = (fall_step > 0) & (fall_step <= horizon)
            band = self.orbit.band if self.orbit is not None and ref.push.recovery else None
            if band is not None:
                back = recovered_steps(band, self.robot, sections[:, :horizon], ref.push.recovery_steps)
                horizon_failed &= back == 0
        reached = np.isfinite(first).all(axis=1)
        energy = np.full(n, np.nan)
        x1 = np.full((n, self.reduced.dim), np.nan)
        if reached.any():
            energy[reached] = self.reduced.kinetic_energy(first[reached, :nq], first[reached, nq:])
            x1[reached] = self.reduced.phi(first[reached, :nq], first[reached, nq:])
        if ref.space == "push":
            # a push certificate certifies impulses: the check is on the push's own |J| (other kinds: nothing inside)
            dist_ = d.size.astype(float) if kind == "push" else np.full(n, np.nan)
        else:
            x1 = ref.to_z(x1)
            dist_ = np.linalg.norm(x1 - np.asarray(ref.x_star), axis=1)
        return KindResult(kind=kind, size=d.size, params=d.params, success=ok, fall_reason=reasons,
                          fall_step=fall_step, x_first=x1, distance=dist_, inside=ref.inside(dist_),
                          physics_steps=physics, seconds=time.perf_counter() - t0, energy=energy,
                          energy_star=ref.energy, horizon_failed=horizon_failed,
                          horizon=horizon if horizon_failed is not None else None)


def validate_steps(config: ValidateConfig, kinds: int, certify: CertifyConfig, graph: str, certifying: bool,
                   dim: int) -> int:
    """The most steps a validation simulates: the certificate when it computes one (:func:`certify_steps`), or else
    the orbit search on a section of ``dim`` coordinates (:meth:`~robustgait.config.CertifyConfig.orbit_steps`); the
    undisturbed first step; and per disturbance kind ``trials`` trials of a map (up to ``orbit.max_period`` steps) and
    ``steps_after`` steps. ``graph``: the gait's domain graph (the count does not depend on it)."""
    setup = certify_steps(certify, graph, dim) if certifying else certify.orbit_steps(dim)
    return setup + 1 + kinds * config.trials * (certify.orbit.max_period + config.steps_after)


def check_validate_work(robot: Robot, gait: Gait, config: ValidateConfig, sim: SimConfig, *, kinds: int = 1,
                        certify: CertifyConfig | None = None, certifying: bool = False, what: str = "") -> int:
    """Bound a validation of ``kinds`` disturbance kinds before it starts (:mod:`robustgait.config.work`):
    :func:`validate_steps`, each step up to the gait's :func:`~robustgait.sim.engine.step_horizons`, against what
    the default validation of as many kinds (and the default certificate, when ``certifying``) needs here."""
    graph, cert, dim = gait.domain_graph, certify or CertifyConfig(), section_dimension(robot)
    work = Work(validate_steps(config, kinds, cert, graph, certifying, dim), step_physics_steps(gait, robot.dt, sim))
    defaults = Work(validate_steps(ValidateConfig(), kinds, CertifyConfig(), graph, certifying, dim),
                    step_physics_steps(gait, robot.dt, SimConfig()))
    return check_work(work, defaults, robot.dt, f"{what}validate.trials {config.trials} × (validate.steps_after "
                      f"{config.steps_after} + {cert.orbit.max_period}) steps × {kinds} disturbance "
                      f"kind{'s' if kinds > 1 else ''}"
                      + (" + the certificate" if certifying else ""))


def validate_gait(robot: Robot, gait: Gait, config: ValidateConfig | None = None, *,
                  certify: CertifyConfig | None = None, sim: SimConfig | None = None,
                  kinds: Sequence[str] | None = None,
                  certificate: GaitCertificate | CertificateRef | str | Path | None = None,
                  progress: bool = False) -> ValidationResult:
    """Validate a gait against the disturbance ``kinds`` (any of :data:`~robustgait.config.KINDS`; default
    ``config.kinds``: ``config.disturbance``, or every kind for ``all``).

    ``certificate``: a :class:`GaitCertificate`, a :class:`CertificateRef`, or a certificate JSON path; None
    certifies the gait with ``certify`` first.
    """
    config = config or ValidateConfig()
    sim = sim or SimConfig()
    kinds = list(config.kinds if kinds is None else (KINDS if "all" in kinds else kinds))
    for k in kinds:
        if k not in KINDS:
            raise RobustGaitError(f"unknown disturbance {k!r} (choose from {', '.join(KINDS)} or all)")
    check_validate_work(robot, gait, config, sim, kinds=len(kinds), certify=certify, certifying=certificate is None)
    t0 = time.perf_counter()
    with Validator(robot, gait, config, certify=certify, sim=sim, certificate=certificate, progress=progress) as v:
        result = ValidationResult(robot=robot.name, gait=_gait_info(gait), certificate=v.certificate,
                                  config=v.config, sim=v.sim, seconds={"setup": v.seconds_setup})
        for k in kinds:
            result.kinds[k] = v.run(k)
            result.seconds[k] = result.kinds[k].seconds
    result.seconds["total"] = time.perf_counter() - t0
    return result
