"""Learner quality on the real problem: a coarse grid of exo's action space evaluated once (generate, walk,
certify: the study's own evaluation), then polar, eubo and random replayed against that table.

Phase 1 (resumable): the grid takes ``--grid`` evenly spaced values of each action-space axis (default
4 × 4 × 3 × 3 = 144 gaits); every gait is evaluated with the study defaults (step cap 50, the
sequential estimator, seed 0; ``--method uniform --samples N``: the paper's) by the local executor and
appended to ``--table`` (JSON lines) as soon as it is done, so a killed run continues where it stopped.
Phase 2: each learner runs ``--seeds`` times at the paper's budget
(``--iterations`` × ``--batch``) with the robustness oracle on the table's scores; it prints, per learner,
mean ± sd of the true r* (and steps) of the gait it returns (its recommendation after the last iteration)
and of that gait's rank in the table (1 = the best score), and the table's best for reference.

    python benchmarks/experiments/learners/run.py [--grid 4,4,3,3] [--seeds 20] [--iterations 10] [--batch 5]
        [--workers 2] [--method sequential] [--samples 200] [--table
        benchmarks/experiments/learners/data/table_exo.jsonl]

``--synthetic 7,7,5`` replaces the table by smooth synthetic utilities on a normalized grid of that shape
(two Gaussian bumps of heights 1 and 0.6 and width 0.3 at random places, one utility per seed) and prints
the normalized simple regret of each learner for each ``--models`` entry ``lengthscale:outputscale:fixed|fit``
(how the preference model's defaults were chosen, docs/studies.md).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

import numpy as np

from robustgait import load_robot
from robustgait.config import (
    CertifyConfig,
    Config,
    LearnerConfig,
    PreferenceModelConfig,
    SimConfig,
    StudyConfig,
    to_dict,
)
from robustgait.learn import ActionSpace, Outcome, make_learner, replay, score
from robustgait.robots.spec import ACTION_FIELDS
from robustgait.study.executors import LocalExecutor, WorkerSpec
from robustgait.study.outcome import known_figure

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))  # benchmarks/common.py


def coarse_space(full: ActionSpace, counts: list[int]) -> ActionSpace:
    """``counts[k]`` evenly spaced values (by grid position) of each axis of ``full``."""
    values = []
    for vals, n in zip(full.values, counts, strict=True):
        idx = np.unique(np.round(np.linspace(0, len(vals) - 1, min(n, len(vals)))).astype(int))
        values.append(tuple(vals[i] for i in idx))
    return ActionSpace(full.names, tuple(values))


def evaluation_sections(cfg: Config) -> dict:
    """What an evaluation depends on: the generation, simulation and certificate sections."""
    d = to_dict(cfg)
    return {k: d[k] for k in ("generate", "sim", "certify")}


def config_hash(cfg: Config) -> str:
    """Rows evaluated with other evaluation settings or another exo model (spec or MJCF) are not reused.
    (A change of the generator's or the certificate's code is not seen: delete the table then.)"""
    import hashlib

    robot = load_robot("exo")
    h = hashlib.sha256(json.dumps(evaluation_sections(cfg), sort_keys=True).encode())
    for f in (robot.spec.source, robot.spec.mjcf):
        if f is not None:
            h.update(Path(f).read_bytes())
    return h.hexdigest()[:12]


def load_table(path: Path, config: str) -> dict[str, dict]:
    rows = {}
    if path.is_file():
        for line in path.read_text().splitlines():
            if line.strip():
                r = json.loads(line)
                if r.get("config") == config:
                    rows[key(r["params"])] = r
    return rows


def key(params: dict[str, float]) -> str:
    """The row of a gait: its values on the action space's axes (a stored gait's params also hold the fields
    outside the space, e.g. the rolling fraction of flat-foot gaits)."""
    return ",".join(f"{params[k]:.6g}" for k in sorted(ACTION_FIELDS))


def evaluate_table(space: ActionSpace, path: Path, workers: int, method: str, samples: int,
                   step_cap: int) -> dict[str, dict]:
    cfg = Config(sim=SimConfig(step_cap=step_cap), study=StudyConfig(metric="robustness"),  # the table: r*
                 certify=CertifyConfig(method=method, disturbance="state", n_samples=samples))  # type: ignore[arg-type]
    h = config_hash(cfg)
    rows = load_table(path, h)
    todo = [i for i in range(space.size) if key(space.value(i)) not in rows]
    print(f"table {path} (config {h}): {len(rows)} of {space.size} gaits already evaluated; {len(todo)} to go",
          flush=True)
    if not todo:
        return rows
    spec = WorkerSpec("exo", to_dict(cfg))
    path.parent.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    with LocalExecutor(spec, workers) as ex, path.open("a") as fh:
        for i in todo:
            ex.submit(i, space.value(i))
        for n in range(len(todo)):
            i, res = ex.next_result()
            # the table's r_star: the evaluation's verified value, else its estimate (r*: the state certificate)
            row = {k: (known_figure(res) or 0.0) if k == "r_star" else res[k]
                   for k in ("params", "status", "reason", "steps_taken", "step_cap", "fell", "r_star", "seconds")
                   } | {"config": h}
            fh.write(json.dumps(row) + "\n")
            fh.flush()
            rows[key(row["params"])] = row
            print(f"[{n + 1}/{len(todo)}] {row['params']} {row['status']} steps {row['steps_taken']} "
                  f"r* {row['r_star']:.3f} ({time.perf_counter() - t0:.0f} s)", flush=True)
    return rows


def smooth_utility(space: ActionSpace, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    x = space.normalized()
    centres = rng.uniform(0, 1, (2, space.dim))
    return sum(h * np.exp(-((x - c) ** 2).sum(1) / (2 * 0.3**2)) for h, c in zip((1.0, 0.6), centres, strict=True))


def synthetic(args: argparse.Namespace) -> None:
    shape = [int(v) for v in args.synthetic.split(",")]
    space = ActionSpace(tuple(f"x{i}" for i in range(len(shape))),
                        tuple(tuple(np.linspace(0, 1, n).round(9)) for n in shape))
    print(f"synthetic: grid {'×'.join(map(str, shape))} ({space.size} points), {args.iterations} × {args.batch}, "
          f"{args.seeds} utilities; load {os.getloadavg()}")
    for spec in args.models.split(","):
        ls, os_, hp = spec.split(":")
        cfg = LearnerConfig(model=PreferenceModelConfig(lengthscale=(float(ls),), outputscale=float(os_),
                                                        hyperparameters=hp))
        for name in args.learners.split(","):
            t0 = time.perf_counter()
            reg = []
            for seed in range(args.seeds):
                u = smooth_utility(space, 100 + seed)
                rec = replay(make_learner(name, space, cfg, seed), lambda i, u=u: u[i], args.iterations,
                             args.batch).recommendations[-1]
                assert rec is not None
                reg.append((u.max() - u[rec]) / (u.max() - u.min()))
            print(f"  {spec:16s} {name:7s} regret {np.mean(reg):.3f} ± {np.std(reg, ddof=1) / np.sqrt(len(reg)):.3f} "
                  f"(se)  {(time.perf_counter() - t0) / args.seeds:.2f} s/run", flush=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--grid", default="4,4,3,3", help="values per axis of the coarse grid")
    ap.add_argument("--seeds", type=int, default=20)
    ap.add_argument("--iterations", type=int, default=10)
    ap.add_argument("--batch", type=int, default=5)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--method", choices=("sequential", "uniform"), default="sequential")
    ap.add_argument("--samples", type=int, default=200, help="uniform only")
    ap.add_argument("--steps", type=int, default=50, help="step cap")
    ap.add_argument("--table", type=Path, default=Path(__file__).parent / "data" / "table_exo.jsonl")
    ap.add_argument("--learners", default="polar,eubo,random")
    ap.add_argument("--synthetic", help="grid shape, e.g. 7,7,5: synthetic utilities instead of the exo table")
    ap.add_argument("--models", default="0.4:10:fixed", help="preference models for --synthetic")
    args = ap.parse_args()
    if args.synthetic:
        synthetic(args)
        return
    full = ActionSpace.from_robot(load_robot("exo"))
    space = coarse_space(full, [int(v) for v in args.grid.split(",")])
    print(f"coarse grid: {space.describe()} = {space.size} gaits; load {os.getloadavg()}", flush=True)
    rows = evaluate_table(space, args.table, args.workers, args.method, args.samples, args.steps)
    table = [rows[key(space.value(i))] for i in range(space.size)]
    scores = np.array([score("robustness", Outcome(r["steps_taken"], r["step_cap"], r["r_star"],
                                                   r["status"] == "certified")) for r in table])
    r_true = np.array([r["r_star"] for r in table])
    steps = np.array([r["steps_taken"] for r in table])
    rank = np.array([1 + int(np.sum(scores > s)) for s in scores])  # ties share the better rank
    statuses = {s: sum(r["status"] == s for r in table) for s in sorted({r["status"] for r in table})}
    print(f"table: {statuses}; best r* {r_true.max():.4f} ({int(np.sum(scores == scores.max()))} gaits with the "
          f"best score); median r* of the certified {np.median(r_true[r_true > 0]) if np.any(r_true > 0) else 0:.4f}")
    budget = args.iterations * args.batch
    print(f"replay: {args.seeds} seeds × {args.iterations} iterations × {args.batch} gaits ({budget} evaluations "
          f"of {space.size}); robustness oracle; the returned gait = the learner's recommendation")
    print(f"{'learner':8s} {'true r* (mean ± sd)':>22s} {'rank (mean ± sd)':>18s} {'steps':>6s} {'unique':>7s} "
          f"{'best found':>10s} {'s/run':>6s}")
    results = {}
    for name in args.learners.split(","):
        got_r, got_rank, got_steps, uniq, found = [], [], [], [], []
        t0 = time.perf_counter()
        for seed in range(args.seeds):
            res = replay(make_learner(name, space, LearnerConfig(), seed), lambda i: scores[i], args.iterations,
                         args.batch)
            rec = res.recommendations[-1]
            assert rec is not None
            got_r.append(r_true[rec])
            got_rank.append(rank[rec])
            got_steps.append(steps[rec])
            uniq.append(res.unique)
            found.append(any(rank[i] == 1 for b in res.proposals for i in b))
        secs = (time.perf_counter() - t0) / args.seeds
        results[name] = {"r_star": got_r, "rank": got_rank}
        print(f"{name:8s} {np.mean(got_r):>10.4f} ± {np.std(got_r, ddof=1):<9.4f} {np.mean(got_rank):>8.1f} ± "
              f"{np.std(got_rank, ddof=1):<7.1f} {np.mean(got_steps):>6.1f} {np.mean(uniq):>7.1f} "
              f"{np.mean(found):>10.0%} {secs:>6.1f}", flush=True)
    for name in results:
        if name != "random" and "random" in results:
            d = np.array(results[name]["r_star"]) - np.array(results["random"]["r_star"])
            print(f"{name} − random (paired by seed): r* {d.mean():+.4f} ± {d.std(ddof=1) / np.sqrt(d.size):.4f} (se)")
    print(f"load average after: {os.getloadavg()}")


if __name__ == "__main__":
    main()
