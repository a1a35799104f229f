"""Certify a gait: fixed point of its return map (:mod:`robustgait.poincare`) → sampled images → r* and a
confidence statement (:mod:`robustgait.estimators`, :mod:`robustgait.barrier`). ``docs/certificate.md``;
``robustgait certify`` calls this.

A gait that falls before reaching a fixed point, has none, or falls from its own fixed point is a result,
not an error: the certificate has a ``status`` other than ``ok`` and r* = 0 (in a study it is a data point).
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any

import numpy as np
from tqdm import tqdm

from robustgait.barrier import Certificate, certify_map
from robustgait.config import CertifyConfig, SimConfig, to_dict
from robustgait.config.work import check_work
from robustgait.estimators import certify_map_sequential
from robustgait.gait import Gait
from robustgait.poincare import FixedPoint, FixedPointFailure, ReturnMap
from robustgait.robots import Robot

STATUSES = ("ok", "fell_before_fixed_point", "no_fixed_point", "unstable_fixed_point")


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
    sim: SimConfig
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
        out.update({"physics_steps": self.physics_steps, "config": to_dict(cfg), "sim": to_dict(self.sim),
                    "seconds": self.seconds})
        return out


def _estimate(pmap: ReturnMap, x_star: np.ndarray, cfg: CertifyConfig, progress: bool) -> Certificate:
    """Run the configured estimator on the gait's return map (progress bar: samples, stderr)."""
    with tqdm(total=cfg.samples_planned, desc=f"{cfg.map} map, {cfg.method}", unit="sample", disable=not progress,
              leave=False) as bar:
        def P(x: np.ndarray) -> np.ndarray:
            return pmap(x, progress=bar.update)
        if cfg.method == "uniform":
            return certify_map(P, x_star, cfg)
        return certify_map_sequential(P, x_star, cfg)


def check_certify_work(robot: Robot, gait: Gait, config: CertifyConfig, sim: SimConfig) -> int:
    """Bound a certificate's simulation before it starts (:func:`robustgait.config.work.check_work`): the
    fixed-point steps, the samples (N, or the sequential budget) and the map at x*, each a step (two for the
    stride map) of up to the gait's step duration × ``max_step_tau``."""
    per_map = 2 if config.map == "stride" else 1
    what = "sequential.budget" if config.method == "sequential" else "n_samples"
    return check_work(per_map * (config.fp_max_steps + config.samples_planned + 1),
                      gait.step_duration * sim.max_step_tau, robot.dt,
                      f"certify.fp_max_steps {config.fp_max_steps} + certify.{what} {config.samples_planned}")


def certify_gait(robot: Robot, gait: Gait, config: CertifyConfig | None = None, sim: SimConfig | None = None, *,
                 progress: bool = False) -> GaitCertificate:
    """Find x* by iterating the map, then certify B(r*) around it with the configured estimator (``uniform``:
    :func:`robustgait.barrier.certify_map`; ``sequential``: :func:`robustgait.estimators.certify_map_sequential`).

    A gait that falls, has no fixed point or falls from it returns a certificate with that ``status`` and
    r* = 0 (no exception); too much work for the limits raises :class:`RobustGaitError` before any simulation.
    ``progress``: bars on stderr.
    """
    cfg = config or CertifyConfig()
    sim = sim or SimConfig()
    check_certify_work(robot, gait, cfg, sim)
    t0 = time.perf_counter()

    def failed(status: str, reason: str, steps: int, fp: FixedPoint | None = None,
               map_residual: float | None = None) -> GaitCertificate:
        t = time.perf_counter() - t0
        return GaitCertificate(status=status, certificate=None, fixed_point=fp, map_residual=map_residual,
                               config=cfg, sim=sim, robot=robot.name, physics_steps=0, steps_walked=steps,
                               reason=reason,
                               seconds={"fixed_point": t, "sampling": 0.0, "total": t, "sim_steps_per_s": 0.0})

    with ReturnMap(robot, gait, cfg, sim) as pmap:
        with tqdm(total=cfg.fp_max_steps, desc="fixed point", unit="step", disable=not progress,
                  leave=False) as bar:
            def on_step(k: int, residual: float) -> None:
                bar.update(k - bar.n)
                bar.set_postfix(residual=f"{residual:.2e}")
            try:
                fp = pmap.find_fixed_point(progress=on_step)
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
                           sim=sim, robot=robot.name, physics_steps=steps, steps_walked=fp.steps,
                           seconds={"fixed_point": t1 - t0, "sampling": t3 - t2, "total": t3 - t0,
                                    "sim_steps_per_s": steps / max(t3 - t2, 1e-9)})
