"""Certify a gait: fixed point of its return map (:mod:`robustgait.poincare`) → sampled images → r* and a
confidence statement (:mod:`robustgait.estimators`, :mod:`robustgait.barrier`). DESIGN §6;
``robustgait certify`` calls this.

A gait that falls before reaching a fixed point, has none, or falls from its own fixed point is a result,
not an error: the certificate has a ``status`` other than ``ok`` and r* = 0 (in a study it is a data point).
"""

from __future__ import annotations

import time
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np
from tqdm import tqdm

from robustgait.barrier import BARRIERS, Barrier, Certificate, certify_map
from robustgait.errors import RobustGaitError
from robustgait.estimators import METHODS, Method, SequentialConfig, certify_map_sequential, verification_size
from robustgait.gait import Gait
from robustgait.poincare import (
    FRAMES,
    MAPS,
    RECONSTRUCTIONS,
    FixedPoint,
    FixedPointFailure,
    Frame,
    MapKind,
    Reconstruction,
    ReturnMap,
)
from robustgait.robots import Robot
from robustgait.sim.engine import SimConfig

STATUSES = ("ok", "fell_before_fixed_point", "no_fixed_point", "unstable_fixed_point")


@dataclass(frozen=True)
class CertifyConfig:
    """Options of a certificate (defaults: DESIGN §6). ``method``: ``uniform`` (the paper's estimator, N =
    ``n_samples`` uniform samples in B(r_max)) or ``sequential`` (options in ``sequential``, see
    :class:`~robustgait.estimators.SequentialConfig`); ``barrier``: ``ball`` (H = r² − ‖x − x*‖²) or ``paper``
    (H = r − ‖x − x*‖²); ``beta``: 1 − confidence of the violation bound; ``fp_*``: fixed-point search (see
    :meth:`ReturnMap.find_fixed_point`)."""

    n_samples: int = 200
    r_max: float = 2.0
    alpha: float = 0.05
    seed: int = 0
    beta: float = 0.05
    method: Method = "uniform"
    barrier: Barrier = "ball"
    sequential: SequentialConfig = field(default_factory=SequentialConfig)
    map: MapKind = "step"
    reconstruction: Reconstruction = "holonomic"
    frame: Frame = "heading"
    fp_tol: float = 5e-3
    fp_min_steps: int = 10
    fp_max_steps: int = 100
    sim: SimConfig = field(default_factory=SimConfig)

    def __post_init__(self) -> None:
        if isinstance(self.n_samples, bool) or not (isinstance(self.n_samples, int) and self.n_samples >= 1):
            raise RobustGaitError(f"the number of samples must be ≥ 1, got {self.n_samples}")
        if not (np.isfinite(self.r_max) and self.r_max > 0):
            raise RobustGaitError(f"r_max must be positive and finite, got {self.r_max}")
        if not 0 < self.alpha < 1:
            raise RobustGaitError(f"alpha must be in (0, 1), got {self.alpha}")
        if not 0 < self.beta < 1:
            raise RobustGaitError(f"beta must be in (0, 1), got {self.beta}")
        if isinstance(self.seed, bool) or not (isinstance(self.seed, int) and self.seed >= 0):
            raise RobustGaitError(f"the seed must be an integer ≥ 0, got {self.seed!r}")
        if self.method not in METHODS or self.barrier not in BARRIERS:
            raise RobustGaitError(f"method/barrier must be in {METHODS}/{BARRIERS}, got {self.method!r}/"
                                  f"{self.barrier!r}")
        if self.map not in MAPS or self.reconstruction not in RECONSTRUCTIONS or self.frame not in FRAMES:
            raise RobustGaitError(f"map/reconstruction/frame must be in {MAPS}/{RECONSTRUCTIONS}/{FRAMES}")
        if not (self.fp_tol > 0 and 1 <= self.fp_min_steps <= self.fp_max_steps):
            raise RobustGaitError("need fp_tol > 0 and 1 ≤ fp_min_steps ≤ fp_max_steps")
        seq = self.sequential
        if self.method == "sequential" and seq.budget < seq.first_round + verification_size(seq.epsilon, self.beta, 1):
            raise RobustGaitError(f"the sample budget {seq.budget} cannot hold the first round ({seq.first_round}) "
                                  f"and one verification batch ({verification_size(seq.epsilon, self.beta, 1)} for "
                                  f"epsilon = {seq.epsilon:g}, beta = {self.beta:g})")


@dataclass
class GaitCertificate:
    """A gait's certificate.

    status: one of :data:`STATUSES` — ``ok``; ``fell_before_fixed_point`` (the gait fell while its fixed point
    was searched); ``no_fixed_point`` (no iterate converged within ``fp_max_steps``); ``unstable_fixed_point``
    (the reduced map falls from x̄* itself: through the reconstruction x̄* is not on a walking orbit). reason:
    one line (empty if ok). steps_walked: steps of the fixed-point search (completed before a fall).
    certificate (the barrier :class:`Certificate`: r*, samples, images, margins, rounds, statement), fixed_point
    and map_residual ‖P(x̄*) − x̄*‖ are None where the search did not get that far. r_star is 0 unless ok.
    """

    status: str
    certificate: Certificate | None
    fixed_point: FixedPoint | None
    map_residual: float | None
    config: CertifyConfig
    robot: str
    seconds: dict[str, float]
    physics_steps: int
    steps_walked: int
    reason: str = ""

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

    def statement(self) -> str:
        if self.certificate is not None:
            return self.certificate.statement()
        return f"No certificate ({self.status}): {self.reason}; r* = 0 after {self.steps_walked} steps."

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
            "x_star": None if fp is None else [float(v) for v in fp.x_star],
            "fixed_point_residual": None if fp is None else fp.residual,
            "fixed_point_steps": None if fp is None else fp.steps,
            "map_residual": self.map_residual,
            "map": cfg.map,
            "reconstruction": cfg.reconstruction,
            "frame": cfg.frame,
            "method": cfg.method,
            "barrier": cfg.barrier,
            "statement": self.statement(),
        }
        if self.certificate is not None:
            c = self.certificate.to_dict()
            if not samples:
                for key in ("samples", "images", "fell", "margins", "sample_round"):
                    c.pop(key)
            out.update(c)
        out.update({"physics_steps": self.physics_steps, "config": asdict(cfg), "seconds": self.seconds})
        return out


def _estimate(pmap: ReturnMap, x_star: np.ndarray, cfg: CertifyConfig, progress: bool) -> Certificate:
    """Run the configured estimator on the gait's return map (progress bar: samples, stderr)."""
    total = cfg.n_samples if cfg.method == "uniform" else cfg.sequential.budget
    with tqdm(total=total, desc=f"{cfg.map} map, {cfg.method}", unit="sample", disable=not progress,
              leave=False) as bar:
        def P(x: np.ndarray) -> np.ndarray:
            return pmap(x, progress=bar.update)
        if cfg.method == "uniform":
            return certify_map(P, x_star, r_max=cfg.r_max, alpha=cfg.alpha, n_samples=cfg.n_samples, seed=cfg.seed,
                               beta=cfg.beta, barrier=cfg.barrier)
        return certify_map_sequential(P, x_star, r_max=cfg.r_max, alpha=cfg.alpha, beta=cfg.beta, seed=cfg.seed,
                                      barrier=cfg.barrier, config=cfg.sequential)


def certify_gait(robot: Robot, gait: Gait, config: CertifyConfig | None = None, *,
                 progress: bool = False) -> GaitCertificate:
    """Find x* by iterating the map, then certify B(r*) around it with the configured estimator (``uniform``:
    :func:`robustgait.barrier.certify_map`; ``sequential``: :func:`robustgait.estimators.certify_map_sequential`).

    A gait that falls, has no fixed point or falls from it returns a certificate with that ``status`` and
    r* = 0 (no exception); bad options raise :class:`RobustGaitError`. ``progress``: bars on stderr.
    """
    cfg = config or CertifyConfig()
    t0 = time.perf_counter()

    def failed(status: str, reason: str, steps: int, fp: FixedPoint | None = None,
               map_residual: float | None = None) -> GaitCertificate:
        t = time.perf_counter() - t0
        return GaitCertificate(status=status, certificate=None, fixed_point=fp, map_residual=map_residual,
                               config=cfg, robot=robot.name, physics_steps=0, steps_walked=steps, reason=reason,
                               seconds={"fixed_point": t, "sampling": 0.0, "total": t, "sim_steps_per_s": 0.0})

    with ReturnMap(robot, gait, kind=cfg.map, frame=cfg.frame, reconstruction=cfg.reconstruction,
                   sim=cfg.sim) as pmap:
        with tqdm(total=cfg.fp_max_steps, desc="fixed point", unit="step", disable=not progress,
                  leave=False) as bar:
            def on_step(k: int, residual: float) -> None:
                bar.update(k - bar.n)
                bar.set_postfix(residual=f"{residual:.2e}")
            try:
                fp = pmap.find_fixed_point(tol=cfg.fp_tol, min_steps=cfg.fp_min_steps, max_steps=cfg.fp_max_steps,
                                           progress=on_step)
            except FixedPointFailure as exc:
                return failed(exc.status, str(exc), exc.steps)
        t1 = time.perf_counter()
        map_residual = float(np.linalg.norm(pmap(fp.x_star[None])[0] - fp.x_star))
        if not np.isfinite(map_residual):
            return failed("unstable_fixed_point", "the return map falls from its own fixed point (through the "
                          f"{cfg.reconstruction} reconstruction x̄* is not on a walking orbit)", fp.steps, fp)
        pmap.physics_steps = 0
        t2 = time.perf_counter()
        cert = _estimate(pmap, fp.x_star, cfg, progress)
        t3 = time.perf_counter()
        steps = pmap.physics_steps
    return GaitCertificate(status="ok", certificate=cert, fixed_point=fp, map_residual=map_residual, config=cfg,
                           robot=robot.name, physics_steps=steps, steps_walked=fp.steps,
                           seconds={"fixed_point": t1 - t0, "sampling": t3 - t2, "total": t3 - t0,
                                    "sim_steps_per_s": steps / max(t3 - t2, 1e-9)})
