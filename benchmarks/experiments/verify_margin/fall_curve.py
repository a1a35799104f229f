"""Does the exploration's own fall curve say where a push certificate's first verification batch will pass?

Per certified gait of ``recovery_horizon/data/{t1,exo,atalante}_ccaa935.jsonl`` (whose first batches passed or failed
at the margin 0.8 with the shipped defaults): the gait generated cold, its exploration alone (``certify_gait`` with
``verify=False``, the shipped defaults: the first round and the exploration rounds), a logistic fit of falls against
|J| / Ĵ over the explored pushes (P(fall) = σ(a + b |J|/Ĵ), maximum likelihood with a small ridge), and V(c) = the
predicted falling share of the disk c Ĵ (area-weighted). A first batch of 154 pushes passes with probability
(1 − V)^154: a predictor of a failing first batch would let the margin shrink where it must and only there.

    python benchmarks/experiments/verify_margin/fall_curve.py run --t1-spec T1.toml --out data/fall_curve.jsonl
    python benchmarks/experiments/verify_margin/fall_curve.py report data/fall_curve.jsonl
"""

from __future__ import annotations

import os

os.environ.setdefault("OMP_NUM_THREADS", "1")

import argparse
import json
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Any

import numpy as np
from scipy.optimize import minimize

HERE = Path(__file__).resolve().parent
RECOVERY = HERE.parent / "recovery_horizon" / "data"
MARGINS = (0.5, 0.6, 0.7, 0.8, 0.9)


def fall_fit(d: np.ndarray, fell: np.ndarray) -> np.ndarray:
    """(a, b) of P(fall | d) = σ(a + b d), maximum likelihood with a ridge of 1e-3 (finite under perfect separation)."""

    def nll(th: np.ndarray) -> float:
        z = th[0] + th[1] * d
        return float(np.sum(np.logaddexp(0.0, z) - fell * z) + 1e-3 * (th @ th))

    return np.asarray(minimize(nll, np.array([-5.0, 5.0]), method="BFGS").x)


def disk_share(th: np.ndarray, c: float, dim: int = 2) -> float:
    """V(c) = ∫₀^c P(fall | ρ) dim ρ^(dim−1) / c^dim dρ: the predicted falling share of the disk of radius c."""
    rho = np.linspace(0.0, c, 2001)[1:]
    p = 1.0 / (1.0 + np.exp(-(th[0] + th[1] * rho)))
    return float(np.trapezoid(p * dim * rho ** (dim - 1) / c**dim, rho))


def one(job: dict[str, Any]) -> dict[str, Any]:
    from robustgait import load_robot
    from robustgait.certificate.certify import certify_gait
    from robustgait.config import CertifyConfig, Config, GaitParams, SimConfig
    from robustgait.gaitgen import GaitGenerator

    robot = load_robot(job["robot"])
    gait = GaitGenerator(robot, Config().generate).solve(GaitParams(**job["params"])).gait
    gc = certify_gait(robot, gait, CertifyConfig(), SimConfig(n_threads=1), verify=False)
    c = gc.certificate
    assert c is not None and c.estimate is not None
    d = np.linalg.norm(c.samples - c.x_star, axis=1) / c.estimate
    fell = c.fell.astype(float)
    th = fall_fit(d, fell)
    return {"label": job["label"], "robot": job["robot"], "estimate": c.estimate, "known": job["known"],
            "theta": th.tolist(), "V": {f"{m:.2f}": disk_share(th, m) for m in MARGINS},
            "d": d.tolist(), "fell": fell.tolist()}


def cmd_run(args: argparse.Namespace) -> None:
    jobs = []
    for robot, name in ((args.t1_spec, "t1"), ("exo", "exo"), ("robots/atalante/spec.toml", "atalante")):
        for line in (RECOVERY / f"{name}_ccaa935.jsonl").read_text().splitlines():
            r = json.loads(line)
            if r.get("j_star") is not None:
                jobs.append({"robot": robot, "label": f"{name} {r['label']}", "params": r["params"],
                             "known": {"first_passed": r["first_passed"], "ratio": r["j_star"] / r["estimate"]}})
    with ProcessPoolExecutor(args.workers) as ex, open(args.out, "a") as fo:
        for row in ex.map(one, jobs):
            fo.write(json.dumps(row) + "\n")
            fo.flush()


def cmd_report(args: argparse.Namespace) -> None:
    rows = [json.loads(line) for f in args.files for line in Path(f).read_text().splitlines()]
    print("| gait | first batch at 0.8 | J*/Ĵ | V(0.6) | V(0.8) | (1 − V(0.8))^154 |")
    print("|---|---|---|---|---|---|")
    for r in sorted(rows, key=lambda r: r["V"]["0.80"]):
        v = r["V"]
        print(f"| {r['label']} | {'passed' if r['known']['first_passed'] else '**failed**'} | "
              f"{r['known']['ratio']:.2f} | {v['0.60']:.4f} | {v['0.80']:.4f} | {(1 - v['0.80']) ** 154:.3f} |")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("run")
    r.add_argument("--t1-spec", required=True, help="the spec robot init writes for Booster T1")
    r.add_argument("--workers", type=int, default=2)
    r.add_argument("--out", required=True)
    rep = sub.add_parser("report")
    rep.add_argument("files", nargs="+")
    args = ap.parse_args()
    {"run": cmd_run, "report": cmd_report}[args.cmd](args)


if __name__ == "__main__":
    main()
