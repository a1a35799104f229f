"""How often does a push certificate pass its first verification batch at a given margin, and what J* does it give?

``run``: per gait of a robot's action-space grid (``--grid N`` points, generated cold), in worker processes, the
default certificate (:func:`robustgait.certify_gait`, the shipped options) at each ``push.verify_margin`` c of
``--margins``: whether its first batch passed, its attempts, J*, its estimate Ĵ, pushes, physics steps and seconds.
The exploration is the same at every margin (common random numbers), so the margins differ only in the disk their
batches are drawn in. One JSON line per gait; a killed run continues (a gait already in ``--out`` is skipped).

``report``: per margin, the share of first batches that passed, and each gait's J* against its J* at the first margin
given (the median of the ratios, and of those whose first batch passed at both).

    python benchmarks/experiments/verify_margin/margins.py run --robot robots/t1/spec.toml --grid 12 \\
        --margins 0.8,0.7,0.65 --out benchmarks/experiments/verify_margin/data/t1_margins.jsonl
    python benchmarks/experiments/verify_margin/margins.py report \
        benchmarks/experiments/verify_margin/data/t1_margins.jsonl
"""

from __future__ import annotations

import os
import sys

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse
import dataclasses
import json
import time
from concurrent.futures import ProcessPoolExecutor, as_completed
from datetime import date
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))  # benchmarks/common.py
from run import label_of  # this directory's run.py: the same gait labels

from common import git_commit, grid_params


def measure(job: dict[str, Any]) -> dict[str, Any]:
    """One gait's row (module docstring, ``run``)."""
    from robustgait import SimConfig, load_robot
    from robustgait.certificate.certify import certify_gait
    from robustgait.config import CertifyConfig, GaitParams
    from robustgait.gaitgen import generate_gait

    robot = load_robot(job["robot"])
    row: dict[str, Any] = {"label": job["label"], "params": job["params"]}
    res = generate_gait(robot, GaitParams(**job["params"]))
    if res.gait is None:
        return {**row, "status": "generation_failed"}
    base = CertifyConfig()
    row["margins"] = {}
    for c in job["margins"]:
        cfg = dataclasses.replace(base, push=dataclasses.replace(base.push, verify_margin=c))
        t0 = time.perf_counter()
        gc = certify_gait(robot, res.gait, cfg, SimConfig(n_threads=1))
        cert = gc.certificate
        verify = [r for r in cert.rounds if r.kind == "verify"] if cert is not None else []
        row["status"] = str(gc.status)
        row["margins"][f"{c:g}"] = {"j_star": gc.r_star if gc.ok else None,
                                    "estimate": None if cert is None else cert.estimate,
                                    "first_passed": bool(verify and verify[0].passed), "attempts": len(verify),
                                    "pushes": 0 if cert is None else cert.n_samples, "physics": gc.physics_steps,
                                    "seconds": time.perf_counter() - t0}
    return row


def cmd_run(args: argparse.Namespace) -> None:
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    done = {json.loads(line)["label"] for line in (out.read_text().splitlines() if out.exists() else []) if line}
    margins = [float(x) for x in args.margins.split(",")]
    jobs = [{"robot": args.robot, "label": label_of(p), "params": p, "margins": margins}
            for p in grid_params(args.robot, args.grid, "flat")]
    jobs = [j for j in jobs if j["label"] not in done]
    commit, day = git_commit(), date.today().isoformat()
    print(f"# verify_margin margins {day} at {commit}: {args.robot}, {len(jobs)} gaits, margins {margins}")
    with ProcessPoolExecutor(args.workers) as pool:
        for f in as_completed([pool.submit(measure, j) for j in jobs]):
            row = {**f.result(), "commit": commit, "date": day}
            with out.open("a") as fh:
                fh.write(json.dumps(row) + "\n")
            passes = {c: m["first_passed"] for c, m in row.get("margins", {}).items()}
            print(f"{row['label']}: {row['status']} first passed {passes}", flush=True)


def cmd_report(args: argparse.Namespace) -> None:
    for path in args.files:
        rows = [json.loads(line) for line in Path(path).read_text().splitlines() if line.strip()]
        ok = [r for r in rows if r.get("margins")]
        margins = list(ok[0]["margins"]) if ok else []
        print(f"## {path}: {len(rows)} gaits (commit {', '.join(sorted({r['commit'] for r in rows}))})\n")
        print(f"| margin c | first batches passed | J* / J* at c = {margins[0]} (median) | the same, gaits whose first "
              "batch passed at both | median seconds |")
        print("|---|---|---|---|---|")
        for c in margins:
            cert = [r for r in ok if r["margins"][c]["j_star"] is not None]
            first = sum(r["margins"][c]["first_passed"] for r in cert)
            ratio = [r["margins"][c]["j_star"] / r["margins"][margins[0]]["j_star"] for r in cert
                     if r["margins"][margins[0]]["j_star"]]
            both = [r["margins"][c]["j_star"] / r["margins"][margins[0]]["j_star"] for r in cert
                    if r["margins"][c]["first_passed"] and r["margins"][margins[0]]["first_passed"]]
            secs = [r["margins"][c]["seconds"] for r in cert]
            print(f"| {c} | {first} of {len(cert)} ({100 * first / max(len(cert), 1):.0f} %) | "
                  f"{np.median(ratio):.3f} | {np.median(both) if both else float('nan'):.3f} | "
                  f"{np.median(secs):.1f} |")
        print()


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("run")
    r.add_argument("--robot", required=True)
    r.add_argument("--grid", type=int, default=12)
    r.add_argument("--margins", default="0.8,0.7,0.65")
    r.add_argument("--workers", type=int, default=1)
    r.add_argument("--out", required=True)
    p = sub.add_parser("report")
    p.add_argument("files", nargs="+")
    args = ap.parse_args()
    cmd_run(args) if args.cmd == "run" else cmd_report(args)


if __name__ == "__main__":
    main()
