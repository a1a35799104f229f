"""Certify a gait: fixed point of its return map (:mod:`robustgait.poincare`) → sampled images → r* and a
confidence statement (:mod:`robustgait.barrier`). DESIGN §6; ``robustgait certify`` calls this."""

from __future__ import annotations

import time
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np
from tqdm import tqdm

from robustgait.barrier import Certificate, certify_map
from robustgait.errors import RobustGaitError
from robustgait.gait import Gait
from robustgait.poincare import FRAMES, MAPS, RECONSTRUCTIONS, FixedPoint, Frame, MapKind, Reconstruction, ReturnMap
from robustgait.robots import Robot
from robustgait.sim.engine import SimConfig


@dataclass(frozen=True)
class CertifyConfig:
    """Options of a certificate (defaults: DESIGN §6). ``fp_*``: fixed-point search (see
    :meth:`ReturnMap.find_fixed_point`); ``beta``: 1 − confidence of the violation bound."""

    n_samples: int = 200
    r_max: float = 2.0
    alpha: float = 0.05
    seed: int = 0
    beta: float = 0.05
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
        if self.map not in MAPS or self.reconstruction not in RECONSTRUCTIONS or self.frame not in FRAMES:
            raise RobustGaitError(f"map/reconstruction/frame must be in {MAPS}/{RECONSTRUCTIONS}/{FRAMES}")
        if not (self.fp_tol > 0 and 1 <= self.fp_min_steps <= self.fp_max_steps):
            raise RobustGaitError("need fp_tol > 0 and 1 ≤ fp_min_steps ≤ fp_max_steps")


@dataclass
class GaitCertificate:
    """A gait's certificate: the barrier :class:`Certificate` (r*, samples, images, margins, confidence),
    the fixed point it is about, the map's own residual ‖P(x̄*) − x̄*‖, the options, and timings [s]."""

    certificate: Certificate
    fixed_point: FixedPoint
    map_residual: float
    config: CertifyConfig
    robot: str
    seconds: dict[str, float]
    physics_steps: int

    @property
    def r_star(self) -> float:
        return self.certificate.r_star

    def to_dict(self, *, samples: bool = True) -> dict[str, Any]:
        """JSON-ready; everything but ``seconds`` is deterministic for a given seed."""
        c = self.certificate.to_dict()
        if not samples:
            for key in ("samples", "images", "fell", "margins"):
                c.pop(key)
        cfg = asdict(self.config)
        return {
            "robot": self.robot,
            "r_star": c.pop("r_star"),
            "x_star": c.pop("x_star"),
            "fixed_point_residual": self.fixed_point.residual,
            "fixed_point_steps": self.fixed_point.steps,
            "map_residual": self.map_residual,
            "map": self.config.map,
            "reconstruction": self.config.reconstruction,
            "frame": self.config.frame,
            **c,
            "physics_steps": self.physics_steps,
            "config": cfg,
            "seconds": self.seconds,
        }


def certify_gait(robot: Robot, gait: Gait, config: CertifyConfig | None = None, *,
                 progress: bool = False) -> GaitCertificate:
    """Find x* by walking, sample N perturbations uniformly in B_{r_max}(x̄*), run the map once on each, and
    compute r* (:func:`robustgait.barrier.certify_map`). ``progress`` shows progress bars on stderr."""
    cfg = config or CertifyConfig()
    t0 = time.perf_counter()
    with ReturnMap(robot, gait, kind=cfg.map, frame=cfg.frame, reconstruction=cfg.reconstruction,
                   sim=cfg.sim) as pmap:
        with tqdm(total=cfg.fp_max_steps, desc="fixed point", unit="step", disable=not progress,
                  leave=False) as bar:
            def on_step(k: int, residual: float) -> None:
                bar.update(k - bar.n)
                bar.set_postfix(residual=f"{residual:.2e}")
            fp = pmap.find_fixed_point(tol=cfg.fp_tol, min_steps=cfg.fp_min_steps, max_steps=cfg.fp_max_steps,
                                       progress=on_step)
        t1 = time.perf_counter()
        map_residual = float(np.linalg.norm(pmap(fp.x_star[None])[0] - fp.x_star))
        if not np.isfinite(map_residual):
            raise RobustGaitError("the return map fell from its own fixed point (reconstruction left the orbit)")
        pmap.physics_steps = 0
        t2 = time.perf_counter()
        with tqdm(total=cfg.n_samples, desc=f"{cfg.map} map", unit="sample", disable=not progress,
                  leave=False) as bar:
            cert = certify_map(lambda x: pmap(x, progress=bar.update), fp.x_star, r_max=cfg.r_max,
                               alpha=cfg.alpha, n_samples=cfg.n_samples, seed=cfg.seed, beta=cfg.beta)
        t3 = time.perf_counter()
        steps = pmap.physics_steps
    return GaitCertificate(certificate=cert, fixed_point=fp, map_residual=map_residual, config=cfg,
                           robot=robot.name, physics_steps=steps,
                           seconds={"fixed_point": t1 - t0, "sampling": t3 - t2, "total": t3 - t0,
                                    "sim_steps_per_s": steps / max(t3 - t2, 1e-9)})
