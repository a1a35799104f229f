"""Compare the best gaits of two studies (``robustgait study compare A B``): each re-certified with fresh
seeds — the same seeds and the same certificate options for both (study A's, with the seed replaced), so
the two are compared on the same perturbations — and walked to the step cap."""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from robustgait.certificate.certify import certify_gait
from robustgait.config import CertifyConfig, CompareConfig, SimConfig, ValidateConfig
from robustgait.errors import input_error
from robustgait.gait import Gait
from robustgait.io.gaitfile import load_gait
from robustgait.io.robotfile import load_robot
from robustgait.io.studyfile import load_config
from robustgait.robots import Robot
from robustgait.sim import walk
from robustgait.study.outcome import known_figure
from robustgait.study.status import study_status


def recertify(robot: Robot, gait: Gait, config: CertifyConfig, seeds: Sequence[int],
              sim: SimConfig | None = None, validate: ValidateConfig | None = None) -> list[dict[str, Any]]:
    """Certify ``gait`` once per seed (``config`` with its seed replaced); a failed certificate (a fall, no
    fixed point) counts 0 with its status and reason. Per seed: ``seed``, ``value`` (the verified J* or
    r*), ``status``, ``reason``, ``n_inside``."""
    out = []
    for s in seeds:
        gc = certify_gait(robot, gait, dataclasses.replace(config, seed=int(s)), sim, validate=validate)
        out.append({"seed": int(s), "value": float(gc.value) if gc.ok else 0.0, "status": gc.status,
                    "reason": gc.reason, "n_inside": gc.certificate.n_inside if gc.certificate is not None else 0})
    return out


def compare_studies(dir_a: str | Path, dir_b: str | Path, config: CompareConfig | None = None) -> dict[str, Any]:
    """Best gait of each study (the learner's recommendation), re-certified with seeds ``seed_base`` …
    ``seed_base + seeds − 1`` (study A's certificate and simulation options; ``config.samples`` overrides N)
    and walked to study A's step cap. Per study: ``study_value`` (the study's record of its best gait: the
    verified value, else its estimate),
    ``values`` (one per seed), their ``value_mean`` and ``value_sd``, each in
    ``unit``. ``winner``: the study whose gait has the higher mean certificate value (None on a tie)."""
    config = config or CompareConfig()
    dirs = [Path(dir_a), Path(dir_b)]
    setups = [load_config(d) for d in dirs]
    certify, sim = setups[0].config.study_certify, setups[0].config.sim
    if config.samples is not None:
        certify = dataclasses.replace(certify, n_samples=config.samples)
    cap = sim.step_cap
    seed_list = [config.seed_base + i for i in range(config.seeds)]
    studies = []
    for d, setup in zip(dirs, setups, strict=True):
        cfg = setup.config.study
        st = study_status(d)
        best = st["best"]
        if best is None or not best.get("gait_file"):
            raise input_error(d, "the study has no best gait yet (no finished iteration with a generated gait)")
        robot = load_robot(setup.robot)
        gait = load_gait(d / best["gait_file"], robot)
        w = walk(robot, gait, sim)
        certs = recertify(robot, gait, certify, seed_list, sim, setups[0].config.validate)
        r = np.array([c["value"] for c in certs])
        studies.append({"directory": str(d), "metric": cfg.metric, "learner": cfg.learner, "robot": setup.robot,
                        "params": best["params"], "study_value": known_figure(best),
                        "steps_taken": w.steps_taken, "fell": w.fell, "values": r.tolist(),
                        "value_mean": float(r.mean()),
                        "value_sd": float(r.std(ddof=1)) if r.size > 1 else 0.0, "certificates": certs})
    ma, mb = studies[0]["value_mean"], studies[1]["value_mean"]
    same = (dataclasses.replace(setups[0].config.study_certify, seed=0), setups[0].config.sim) == (
        dataclasses.replace(setups[1].config.study_certify, seed=0), setups[1].config.sim)
    return {"seeds": seed_list, "method": certify.method, "n_samples": certify.n_samples,
            "epsilon": certify.sequential.epsilon, "step_cap": cap, "unit": certify.unit,
            "certificate": certify.space, "studies": studies,
            "winner": None if ma == mb else (0 if ma > mb else 1),
            "wins_per_seed": [int(np.sum(np.array(studies[0]["values"])
                                         > np.array(studies[1]["values"]))),
                              int(np.sum(np.array(studies[1]["values"])
                                         > np.array(studies[0]["values"])))],
            "note": "" if same else "the studies used different certificate options; both gaits were "
                                    "re-certified with study A's"}
