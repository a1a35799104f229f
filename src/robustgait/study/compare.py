"""Compare the best gaits of two studies (``robustgait study compare A B``): each re-certified with fresh
seeds — the same seeds and the same certificate options for both (study A's, with the seed replaced), so
the two are compared on the same perturbations — and walked to the step cap."""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from robustgait.certify import CertifyConfig, certify_gait
from robustgait.errors import RobustGaitError, input_error
from robustgait.gait import Gait, load_gait
from robustgait.robots import Robot, load_robot
from robustgait.sim import walk
from robustgait.study.config import load_config
from robustgait.study.status import study_status


def recertify(robot: Robot, gait: Gait, config: CertifyConfig, seeds: Sequence[int]) -> list[dict[str, Any]]:
    """Certify ``gait`` once per seed (``config`` with its seed replaced); a failed certificate (a fall, no
    fixed point) counts r* = 0 with its status and reason."""
    out = []
    for s in seeds:
        gc = certify_gait(robot, gait, dataclasses.replace(config, seed=int(s)))
        out.append({"seed": int(s), "r_star": float(gc.r_star) if gc.ok else 0.0, "status": gc.status,
                    "reason": gc.reason, "n_inside": gc.certificate.n_inside if gc.certificate is not None else 0})
    return out


def compare_studies(dir_a: str | Path, dir_b: str | Path, *, seeds: int = 5, seed_base: int = 1000,
                    samples: int | None = None) -> dict[str, Any]:
    """Best gait of each study (the learner's recommendation), re-certified with seeds ``seed_base`` …
    ``seed_base + seeds − 1`` (study A's certificate options; ``samples`` overrides N) and walked to study
    A's step cap. ``winner``: the study whose gait has the higher mean r* (None on a tie)."""
    if seeds < 1:
        raise RobustGaitError(f"--seeds must be ≥ 1, got {seeds}")
    dirs = [Path(dir_a), Path(dir_b)]
    configs = [load_config(d) for d in dirs]
    certify = configs[0].evaluation.certify
    if samples is not None:
        certify = dataclasses.replace(certify, n_samples=samples)
    cap = configs[0].evaluation.step_cap
    seed_list = [seed_base + i for i in range(seeds)]
    studies = []
    for d, cfg in zip(dirs, configs, strict=True):
        st = study_status(d)
        best = st["best"]
        if best is None or not best.get("gait_file"):
            raise input_error(d, "the study has no best gait yet (no finished iteration with a generated gait)")
        robot = load_robot(cfg.robot)
        gait = load_gait(d / best["gait_file"], robot)
        w = walk(robot, gait, steps=cap, config=certify.sim)
        certs = recertify(robot, gait, certify, seed_list)
        r = np.array([c["r_star"] for c in certs])
        studies.append({"directory": str(d), "metric": cfg.metric, "learner": cfg.learner, "robot": cfg.robot,
                        "params": best["params"], "study_r_star": best["r_star"], "steps_taken": w.steps_taken,
                        "fell": w.fell, "r_star": r.tolist(), "r_star_mean": float(r.mean()),
                        "r_star_sd": float(r.std(ddof=1)) if r.size > 1 else 0.0, "certificates": certs})
    ma, mb = studies[0]["r_star_mean"], studies[1]["r_star_mean"]
    same = dataclasses.replace(configs[0].evaluation.certify, seed=0) == dataclasses.replace(
        configs[1].evaluation.certify, seed=0)
    return {"seeds": seed_list, "n_samples": certify.n_samples, "step_cap": cap, "studies": studies,
            "winner": None if ma == mb else (0 if ma > mb else 1),
            "wins_per_seed": [int(np.sum(np.array(studies[0]["r_star"]) > np.array(studies[1]["r_star"]))),
                              int(np.sum(np.array(studies[1]["r_star"]) > np.array(studies[0]["r_star"])))],
            "note": "" if same else "the studies used different certificate options; both gaits were "
                                    "re-certified with study A's"}
