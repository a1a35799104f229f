"""Paper-size studies: ``--iterations`` × ``--batch`` (10 × 5) gaits of ``--robot`` (exo; a spec path such as
robots/atalante/spec.toml) on ``--domains`` (flat; multicontact searches the spec's ``[action_space.multicontact]``),
for each of ``--metrics`` (default: push — the default study, ranked by J* — and the stability baseline; the paper's
pair is ``--metrics robustness,stability``), then ``study compare`` of the two best gaits.

Per study it prints: wall time (goal ≤ 10 min on 2 cores), unique gaits, the learner's best after every
iteration (its certificate — J* or r*, the first study's — and steps), the best gait's certificate and steps, and
the default gait's (``Config().params``) with the same estimator and seed (the first study's), then both
re-certified with ``--compare-seeds`` fresh seeds.
Studies live in ``--out`` (default benchmarks/experiments/study_size/data/<metric>, or
<robot>_<domains>_<metric> for another robot or domain graph); an existing one is resumed
(the wall time is then that of the resumed part only, and is flagged), so a killed benchmark continues.

    python benchmarks/experiments/study_size/run.py [--robot exo] [--domains flat|multicontact] [--iterations \\
        10] [--batch 5]
        [--workers 2] [--method sequential] [--samples 200]
        [--learner polar] [--metrics push,stability] [--compare-seeds 5] [--out DIR]
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

import numpy as np

from robustgait import load_gait, load_robot
from robustgait.config import (
    CertifyConfig,
    CompareConfig,
    Config,
    GenerationConfig,
    RunConfig,
    StudyConfig,
    radius_name,
)
from robustgait.io.studyfile import load_config
from robustgait.study.compare import compare_studies, recertify
from robustgait.study.evaluate import evaluate
from robustgait.study.outcome import known_figure
from robustgait.study.run import create_study, run_study
from robustgait.study.status import study_status

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))  # benchmarks/common.py


def run_one(d: Path, metric: str, args: argparse.Namespace) -> dict:
    resumed = (d / "study.json").exists()
    if not resumed:
        cfg = Config(study=StudyConfig(metric=metric, learner=args.learner, iterations=args.iterations,
                                       batch=args.batch, seed=args.seed),
                     certify=CertifyConfig(method=args.method, n_samples=args.samples, seed=args.seed),
                     generate=GenerationConfig(domains=args.domains))
        create_study(d, args.robot, cfg)
    load0 = os.getloadavg()[0]
    t0 = time.perf_counter()
    run_study(d, RunConfig(workers=args.workers))
    wall = time.perf_counter() - t0
    st = study_status(d)
    return {"metric": metric, "directory": str(d), "wall_s": wall, "resumed": resumed, "load_before": load0,
            "load_after": os.getloadavg()[0], "status": st}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--robot", default="exo", help="shipped robot name or spec .toml path")
    ap.add_argument("--domains", choices=("flat", "multicontact"), default="flat")
    ap.add_argument("--iterations", type=int, default=10)
    ap.add_argument("--batch", type=int, default=5)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--method", choices=("sequential", "uniform"), default="sequential")
    ap.add_argument("--samples", type=int, default=200, help="uniform only")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--learner", default="polar")
    ap.add_argument("--metrics", default="push,stability")
    ap.add_argument("--compare-seeds", type=int, default=5)
    ap.add_argument("--out", type=Path, default=Path(__file__).parent / "data")
    args = ap.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    print(f"machine: {os.cpu_count()} cores; load {os.getloadavg()}", flush=True)
    label = "" if (args.robot, args.domains) == ("exo", "flat") else f"{Path(args.robot).stem}_{args.domains}_"
    runs = [run_one(args.out / f"{label}{m}", m, args) for m in args.metrics.split(",")]
    robot = load_robot(args.robot)
    cfg0 = load_config(runs[0]["directory"]).config
    default = evaluate(robot, cfg0.params, cfg0)  # the study's estimator, seed and domain graph
    fresh = [args.seed + 1000 + i for i in range(args.compare_seeds)]
    cert0 = cfg0.study_certify  # what the first study ranks by, for every gait below
    name, unit = radius_name(cert0.space), cert0.unit
    default_fresh = (recertify(robot, default.gait, cert0, fresh, cfg0.sim, cfg0.validate)
                     if default.gait is not None and default.status == "certified" else [])
    for run in runs:
        st = run["status"]
        best = st["best"]
        flag = " (resumed: wall time of the resumed part)" if run["resumed"] else ""
        print(f"\n== {run['metric']}: {st['trials_done']} gaits in {run['wall_s']:.0f} s{flag} "
              f"(load {run['load_before']:.1f} → {run['load_after']:.1f}); {st['unique_gaits']} unique")
        for it in st["iterations"]:
            b = it["best"]
            if b:
                print(f"  iteration {it['iteration'] + 1:2d}: best {known_figure(b) or 0.0:.4f}, "
                      f"{b['steps_taken']} steps, {', '.join(f'{v:g}' for v in b['params'].values())}")
        if best:
            gait = load_gait(Path(run["directory"]) / best["gait_file"], robot)
            again = recertify(robot, gait, cert0, fresh, cfg0.sim, cfg0.validate)
            r = np.array([c["value"] for c in again])
            print(f"  best gait: {known_figure(best) or 0.0:.4f} (study seed), {best['steps_taken']} steps; "
                  f"fresh seeds {fresh[0]}–{fresh[-1]}: {name} {r.mean():.4f} ± "
                  f"{r.std(ddof=1) if r.size > 1 else 0:.4f} {unit}")
    rd = np.array([c["value"] for c in default_fresh]) if default_fresh else np.zeros(1)
    sd = rd.std(ddof=1) if rd.size > 1 else 0.0
    print(f"\ndefault gait {cfg0.params.to_dict()}: {default.status}, {default.steps_taken} steps, {name} "
          f"{default.value if default.value is not None else default.estimate or 0.0:.4f} (study seed); "
          f"fresh seeds: {rd.mean():.4f} ± {sd:.4f}")
    if len(runs) == 2:
        cmp = compare_studies(runs[0]["directory"], runs[1]["directory"],
                              CompareConfig(seeds=args.compare_seeds, seed_base=args.seed + 1000))
        print("\nstudy compare (A = " + runs[0]["metric"] + ", B = " + runs[1]["metric"] + "):")
        for ab, s in zip("AB", cmp["studies"], strict=True):
            print(f"  {ab}: {', '.join(f'{v:g}' for v in s['params'].values())}: {name} "
                  f"{s['value_mean']:.4f} ± {s['value_sd']:.4f} "
                  f"[{', '.join(f'{v:.3f}' for v in s['values'])}], {s['steps_taken']} steps")
        w = cmp["winner"]
        print(f"  higher mean {name}: " + ("tie" if w is None else runs[w]["metric"]) +
              f" (per seed: {cmp['wins_per_seed'][0]} vs {cmp['wins_per_seed'][1]})")
        (args.out / "compare.json").write_text(json.dumps(cmp, indent=1))
    print(f"\nload average after: {os.getloadavg()}")


if __name__ == "__main__":
    main()
