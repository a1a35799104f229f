"""Validation trials of one gait (issue 12): disturbed walks from the certified fixed point, batched.

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
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray
from tqdm import tqdm

from robustgait.certify import GaitCertificate, certify_gait
from robustgait.config import KINDS, CertifyConfig, Frame, MapKind, SimConfig, ValidateConfig, to_dict
from robustgait.config.work import check_work
from robustgait.errors import RobustGaitError
from robustgait.gait import Gait
from robustgait.poincare import FixedPoint, ReturnMap, reduce_state
from robustgait.robots import Robot
from robustgait.sim.engine import StepEngine, StepInputs
from robustgait.validate import disturbances as dist
from robustgait.validate.disturbances import SIZE_LABELS, Draws
from robustgait.validate.stats import LogisticFit, Rate, binned_rates, logistic_fit

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class CertificateRef:
    """What a validation needs of a gait's certificate: r*, whether the supremum is attained (closed ball)
    or not (open ball), x̄*, the map, frame and reconstruction, the fixed-point search options, and where
    it came from ("computed" or a file path)."""

    r_star: float
    attained: bool
    x_star: tuple[float, ...]
    map: MapKind
    frame: Frame
    reconstruction: str
    fp_tol: float
    fp_min_steps: int
    fp_max_steps: int
    source: str

    @staticmethod
    def of(gc: GaitCertificate) -> CertificateRef:
        c, cfg = gc.certificate, gc.config
        if c is None or gc.fixed_point is None:
            raise RobustGaitError(f"the gait has no certificate to validate against ({gc.status}: {gc.reason})")
        return CertificateRef(float(c.r_star), bool(c.attained), tuple(float(v) for v in c.x_star), cfg.map,
                              cfg.frame, cfg.reconstruction, cfg.fp_tol, cfg.min_steps, cfg.fp_max_steps,
                              "computed")

    @staticmethod
    def load(path: str | Path) -> CertificateRef:
        """From a certificate JSON written by ``robustgait certify -o``."""
        from robustgait.io.certfile import read_certificate

        c = read_certificate(path)
        cfg = c.certify_config(path)
        return CertificateRef(c.r_star, c.attained, tuple(c.x_star), cfg.map, cfg.frame, cfg.reconstruction,
                              cfg.fp_tol, cfg.min_steps, cfg.fp_max_steps, str(path))

    def certify_config(self, base: CertifyConfig) -> CertifyConfig:
        """``base`` with this certificate's map, frame, reconstruction and fixed-point search."""
        from dataclasses import replace

        return replace(base, map=self.map, frame=self.frame, reconstruction=self.reconstruction,  # type: ignore[arg-type]
                       fp_tol=self.fp_tol, fp_min_steps=self.fp_min_steps, fp_max_steps=self.fp_max_steps)

    def inside(self, distance: FloatArray) -> NDArray[np.bool_]:
        """Membership in the certified ball (closed if r* is attained, else open); NaN distances: False."""
        with np.errstate(invalid="ignore"):
            return np.asarray(distance <= self.r_star if self.attained else distance < self.r_star)


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

    @property
    def size_label(self) -> tuple[str, str]:
        return SIZE_LABELS[self.kind]

    def success_rate(self) -> Rate:
        return Rate.of(int(self.success.sum()), int(self.success.size))

    def critical(self) -> LogisticFit:
        """The size at which half the trials fail (logistic fit of success against size)."""
        return logistic_fit(self.size, self.success)

    def certificate_check(self) -> dict[str, Rate | int]:
        """Fall rates of the trials whose x̄₁ lies inside B(r*) (the certificate says 0) and outside it,
        and the number of trials that fell before reaching their first switching event (no x̄₁)."""
        fell = ~self.success
        reached = np.isfinite(self.distance)
        out = reached & ~self.inside
        return {"inside": Rate.of(int((fell & self.inside).sum()), int(self.inside.sum())),
                "outside": Rate.of(int((fell & out).sum()), int(out.sum())),
                "fell_before_event": int((~reached).sum())}

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
            }
        return out


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
        from dataclasses import asdict

        return {"robot": self.robot, "gait": self.gait, "certificate": asdict(self.certificate),
                "config": to_dict(self.config), "sim": to_dict(self.sim), "seconds": self.seconds,
                "kinds": {k: v.to_dict(trials) for k, v in self.kinds.items()}}

    def to_json(self, *, trials: bool = True) -> str:
        return json.dumps(self.to_dict(trials=trials), allow_nan=False)


def _gait_info(gait: Gait) -> dict[str, Any]:
    return {"robot": gait.robot, "stance": gait.stance, "step_duration": gait.step_duration,
            "params": gait.params.to_dict() if gait.params is not None else None}


def simulate_trials(engine: StepEngine, qpos: FloatArray, qvel: FloatArray, n_steps: int, period: int,
                    frame: Frame, inputs: Callable[[int, NDArray[np.int64], str, NDArray[np.int64]], StepInputs | None],
                    *, first_at: int, progress: Callable[[int], None] | None = None
                    ) -> tuple[NDArray[np.bool_], list[str | None], NDArray[np.int64], FloatArray, int]:
    """Walk K trials from canonical start states (K, nq), (K, nv) for ``n_steps`` steps (stances alternate
    from the gait's), each step one batched :meth:`StepEngine.step` on the trials still walking.

    ``inputs(k, idx, stance, prev_at)`` gives the per-sample inputs of step k (0-based) for the trials ``idx``
    (``prev_at``: the physics step of each one's previous switching event; ``first_at`` for step 0).
    Returns success (K,), fall reasons, the 1-based step of each fall (0 = none), x̄ after ``period`` steps
    (K, 3; canonical stance; NaN if fell before) and the physics steps simulated.
    """
    robot = engine.robot
    k_all = qpos.shape[0]
    qpos, qvel = qpos.copy(), qvel.copy()
    alive = np.ones(k_all, dtype=bool)
    fall_step = np.zeros(k_all, dtype=np.int64)
    reasons: list[str | None] = [None] * k_all
    x_first = np.full((k_all, 3), np.nan)
    prev_at = np.full(k_all, first_at, dtype=np.int64)
    stance = next(iter(engine.gaits))
    physics = 0
    for k in range(n_steps):
        idx = np.flatnonzero(alive)
        if idx.size == 0:
            break
        b = engine.step(qpos[idx], qvel[idx], stance, inputs=inputs(k, idx, stance, prev_at[idx]))
        physics += b.physics_steps
        for j in np.flatnonzero(b.fell):
            reasons[idx[j]] = b.fall_reason[j]
        fall_step[idx[b.fell]] = k + 1
        alive[idx[b.fell]] = False
        ok = ~b.fell
        qpos[idx[ok]], qvel[idx[ok]] = b.qpos[ok], b.qvel[ok]
        prev_at[idx[ok]] = np.round(b.duration[ok] / robot.dt).astype(np.int64)
        if k == period - 1 and ok.any():
            qp, qv = b.qpos[ok], b.qvel[ok]
            if period % 2 == 1:  # the state starts a step of the other stance: write it for the canonical one
                qp, qv = robot.mirror_state(qp, qv)
            x_first[idx[ok]] = reduce_state(qp, qv, frame)
        stance = "left" if stance == "right" else "right"
        if progress is not None:
            progress(1)
    return alive, reasons, fall_step, x_first, physics


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
        if len(gait.domains) != 1:
            raise RobustGaitError(f"validate runs one-domain (flat-foot) gaits; this one is {gait.domain_graph} with "
                                  f"{len(gait.domains)} domains")
        self.robot, self.gait = robot, gait
        self.config = config or ValidateConfig()
        self.sim = sim or SimConfig()
        self.progress = progress
        t0 = time.perf_counter()
        fp: FixedPoint | None = None
        if certificate is None:
            gc = certify_gait(robot, gait, certify, self.sim, progress=progress)
            ref, fp = CertificateRef.of(gc), gc.fixed_point
        elif isinstance(certificate, GaitCertificate):
            ref, fp = CertificateRef.of(certificate), certificate.fixed_point
        else:
            ref = certificate if isinstance(certificate, CertificateRef) else CertificateRef.load(certificate)
        if start is not None:
            fp = start
        if fp is None:
            with ReturnMap(robot, gait, ref.certify_config(certify or CertifyConfig()), self.sim) as pmap:
                fp = pmap.find_fixed_point()
            if float(np.linalg.norm(fp.x_star - np.asarray(ref.x_star))) > 1e-6:
                raise RobustGaitError(f"{ref.source}: the certificate's x* {np.round(ref.x_star, 4).tolist()} is not "
                                      f"this gait's fixed point {np.round(fp.x_star, 4).tolist()} (another gait, "
                                      "robot or simulation option?)")
        self.certificate, self.fixed_point = ref, fp
        self.period = 1 if ref.map == "step" else 2
        self.engine = StepEngine(robot, gait, self.sim)
        nominal = self.engine.step(fp.qpos[None], fp.qvel[None], gait.stance)
        if nominal.fell[0]:
            raise RobustGaitError(f"the gait falls from its {'start' if start is not None else 'own fixed point'} "
                                  f"({nominal.fall_reason[0]}) in the first step, undisturbed")
        self.nominal_at = round(float(nominal.duration[0]) / robot.dt)
        self.step_length = float(np.linalg.norm(nominal.qpos[0, :2] - fp.qpos[:2]))
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

    def inputs_for(self, kind: str, draws: Draws) -> Callable[[int, NDArray[np.int64], str, NDArray[np.int64]],
                                                              StepInputs | None]:
        """The per-step input function of :func:`simulate_trials` for a kind's draws."""
        cfg, eng, robot = self.config, self.engine, self.robot
        if kind == "push":
            wrench = dist.push_wrench(draws, cfg.push_duration, self.gait.step_duration, robot.dt, eng.horizon)
            return lambda k, idx, stance, prev_at: StepInputs(base_wrench=wrench[idx]) if k == 0 else None
        if kind in ("mass", "friction", "terrain"):
            if kind == "mass":
                models = dist.mass_models(self._base_model(), robot, draws, cfg)
            elif kind == "friction":
                models = dist.friction_models(self._base_model(), draws)
            else:
                fp = self.fixed_point
                layout = dist.terrain_layout(robot, fp.qpos, self.gait.stance, cfg, self.step_length)
                base = dist.terrain_model(robot, layout)
                models = dist.terrain_models(base, layout, draws)
            return lambda k, idx, stance, prev_at: StepInputs(models=[models[i] for i in idx])
        if kind == "latency":
            delay = np.round(draws.size / robot.dt).astype(np.int64)

            def latency(k: int, idx: NDArray[np.int64], stance: str, prev_at: NDArray[np.int64]) -> StepInputs:
                other = "left" if stance == "right" else "right"
                return StepInputs(ctrl_offset=dist.latency_offsets(eng.controls[(stance, 0)], eng.controls[(other, 0)],
                                                                   delay[idx], prev_at))
            return latency
        if kind == "noise":
            def noise(k: int, idx: NDArray[np.int64], stance: str, prev_at: NDArray[np.int64]) -> StepInputs:
                off = dist.noise_offsets(robot, draws.size, cfg.noise_v_ratio, eng.horizon, cfg.seed, k)
                return StepInputs(ctrl_offset=off[idx])
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
        with tqdm(total=n_steps, desc=f"validate {kind}", unit="step", disable=not self.progress, leave=False) as bar:
            ok, reasons, fall_step, x1, physics = simulate_trials(
                self.engine, np.tile(fp.qpos, (n, 1)), np.tile(fp.qvel, (n, 1)), n_steps, self.period,
                self.certificate.frame, self.inputs_for(kind, d), first_at=self.nominal_at, progress=bar.update)
        dist_ = np.linalg.norm(x1 - np.asarray(self.certificate.x_star), axis=1)
        return KindResult(kind=kind, size=d.size, params=d.params, success=ok, fall_reason=reasons,
                          fall_step=fall_step, x_first=x1, distance=dist_, inside=self.certificate.inside(dist_),
                          physics_steps=physics, seconds=time.perf_counter() - t0)


def check_validate_work(robot: Robot, gait: Gait, config: ValidateConfig, sim: SimConfig, what: str = "") -> int:
    """Bound one disturbance kind's work (one batch of trials, each 1 (or 2, stride map) + ``steps_after``
    steps) before it starts (:func:`robustgait.config.work.check_work`)."""
    return check_work(config.trials * (2 + config.steps_after), gait.step_duration * sim.max_step_tau, robot.dt,
                      f"{what}validate.trials {config.trials} × (validate.steps_after {config.steps_after} + 1) per "
                      "kind")


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
    check_validate_work(robot, gait, config, sim)
    t0 = time.perf_counter()
    with Validator(robot, gait, config, certify=certify, sim=sim, certificate=certificate, progress=progress) as v:
        result = ValidationResult(robot=robot.name, gait=_gait_info(gait), certificate=v.certificate,
                                  config=v.config, sim=v.sim, seconds={"setup": v.seconds_setup})
        for k in kinds:
            result.kinds[k] = v.run(k)
            result.seconds[k] = result.kinds[k].seconds
    result.seconds["total"] = time.perf_counter() - t0
    return result
