"""A cache of study evaluations for the simulated-person benchmark (``benchmarks/experiments/persons/run.py``):
an evaluation is a function of
(robot, parameters, configuration) alone (``robustgait.study.evaluate``), so 20 persons × 3 learners need each grid
gait evaluated once, whatever study visits it.

Layout: ``CACHE/<key>/<index>.walk.json`` — the first stage of the evaluation (:func:`generate_and_walk`: the gait,
its walk, its comfort figures), ``CACHE/<key>/<index>.json`` — the whole evaluation (:func:`certify_evaluation` of
the first stage, exactly what :func:`evaluate` returns); ``key`` hashes the robot and the sections an evaluation
depends on (``generate``, ``sim``, ``comfort``, ``certify`` as certified, ``validate``), so another configuration
never reads these results. The first stage of every grid gait is cheap (a solve and a 50-step walk: what a person's
utility needs, for the regret against the grid's best), the certificate (most of an evaluation) is computed only for
the gaits a study visits or the regret needs.

    python benchmarks/experiments/persons/cache.py grid --cache DIR [--workers 2]     # first stage of every \\
        exo grid gait
"""

from __future__ import annotations

import argparse
import hashlib
import json
import multiprocessing
import os
import sys
import time
from collections import deque
from pathlib import Path
from typing import Any

from robustgait.config import Config, GaitParams, to_dict
from robustgait.io.output import write_json
from robustgait.io.robotfile import load_robot
from robustgait.learn.space import ActionSpace
from robustgait.study.evaluate import Evaluation, certify_evaluation, generate_and_walk
from robustgait.study.executors import Executor
from robustgait.study.storage import current_names
from robustgait.study.verify import params_label

_WORKER: dict[str, Any] = {}


def cache_key(robot: str, config: Config) -> str:
    """A hash of the robot and of every section an evaluation depends on."""
    d = to_dict(config)
    parts = {"robot": robot, "generate": d["generate"], "sim": d["sim"], "comfort": d["comfort"],
             "certify": to_dict(config.study_certify), "validate": d["validate"]}
    return hashlib.sha256(json.dumps(parts, sort_keys=True).encode()).hexdigest()[:16]


class EvaluationCache:
    """The cache directory of one (robot, configuration); see the module docstring."""

    def __init__(self, root: str | Path, robot: str, config: Config):
        self.robot_name, self.config = robot, config
        self.dir = Path(root) / cache_key(robot, config)
        self.dir.mkdir(parents=True, exist_ok=True)
        self.robot = load_robot(robot)
        self.space = ActionSpace.from_robot(self.robot, config.generate.domains)
        self._generator: Any = None
        self.computed = {"walk": 0, "certify": 0, "seconds_walk": 0.0, "seconds_certify": 0.0}

    @staticmethod
    def key(params: dict[str, float]) -> str:
        """A gait's file name: its parameters (``L0.12_T0.8_W0.24_H0.06``; off-grid gaits too, such as the default)."""
        return params_label({k: v for k, v in params.items() if k != "rolling_fraction"})

    def params(self, index: int) -> dict[str, float]:
        return self.space.value(index)

    def walked(self, params: dict[str, float]) -> dict[str, Any] | None:
        p = self.dir / f"{self.key(params)}.walk.json"
        return current_names(json.loads(p.read_text())) if p.is_file() else None

    def full(self, params: dict[str, float]) -> dict[str, Any] | None:
        p = self.dir / f"{self.key(params)}.json"
        return current_names(json.loads(p.read_text())) if p.is_file() else None

    def import_study(self, directory: str | Path) -> int:
        """Store the evaluations of a study run with this configuration (its database's results with its gait and
        certificate files: what the evaluation returned); returns how many were new."""
        from robustgait.io.studyfile import load_config
        from robustgait.study.run import open_store

        d = Path(directory)
        setup = load_config(d)
        if cache_key(setup.robot, setup.config) != self.dir.name:
            raise ValueError(f"{d} was evaluated with another configuration")
        store = open_store(d, setup, setup.action_space())
        try:
            records = [r for r in store.records() if r.state == "COMPLETE" and r.reused_from is None]
        finally:
            store.close()
        new = 0
        for r in records:
            if self.full(r.params) is not None or r.result is None:
                continue
            res = dict(r.result)
            res["gait"] = json.loads((d / res["gait_file"]).read_text()) if res.get("gait_file") else None
            res["certificate"] = (json.loads((d / res["certificate_file"]).read_text())
                                  if res.get("certificate_file") else None)
            for k in ("gait_file", "certificate_file", "worker"):
                res.pop(k, None)
            write_json(self.dir / f"{self.key(r.params)}.json", res)
            new += 1
        return new

    def generator(self) -> Any:
        if self._generator is None:
            from robustgait.gaitgen import GaitGenerator

            self._generator = GaitGenerator(self.robot, self.config.generate)
        return self._generator

    def walk_stage(self, params: dict[str, float]) -> dict[str, Any]:
        got = self.walked(params)
        if got is None:
            t0 = time.perf_counter()
            ev = generate_and_walk(self.robot, GaitParams(**params), self.config, generator=self.generator())
            got = ev.to_dict()
            write_json(self.dir / f"{self.key(params)}.walk.json", got)
            self.computed["walk"] += 1
            self.computed["seconds_walk"] += time.perf_counter() - t0
        return got

    def evaluation(self, params: dict[str, float]) -> dict[str, Any]:
        """The whole evaluation of the gait of ``params`` (computed and stored when missing)."""
        got = self.full(params)
        if got is None:
            first = self.walk_stage(params)
            t0 = time.perf_counter()
            ev = certify_evaluation(self.robot, Evaluation.from_dict(first), self.config)
            got = ev.to_dict()
            write_json(self.dir / f"{self.key(params)}.json", got)
            self.computed["certify"] += 1
            self.computed["seconds_certify"] += time.perf_counter() - t0
        return got


class CachedExecutor(Executor):
    """A study executor that answers from an :class:`EvaluationCache`, evaluating in this process what it lacks."""

    def __init__(self, cache: EvaluationCache):
        self.cache = cache
        self.queue: deque[tuple[int, dict[str, float]]] = deque()

    def submit(self, key: int, params: dict[str, float]) -> None:
        self.queue.append((key, params))

    def pending(self) -> int:
        return len(self.queue)

    def next_result(self) -> tuple[int, dict[str, Any]]:
        key, params = self.queue.popleft()
        out = dict(self.cache.evaluation(params))
        out["worker"] = {"pid": os.getpid(), "host": os.uname().nodename, "cache": str(self.cache.dir)}
        return key, out

    def close(self, wait: bool = True) -> None:
        self.queue.clear()


def _init(root: str, robot: str, config: dict[str, Any]) -> None:
    from robustgait.config import from_dict

    _WORKER["cache"] = EvaluationCache(root, robot, from_dict(Config, config, "<bench config>"))


def _walk_one(index: int) -> tuple[int, float]:
    t0 = time.perf_counter()
    cache = _WORKER["cache"]
    cache.walk_stage(cache.params(index))
    return index, time.perf_counter() - t0


def precompute_walks(root: str | Path, robot: str, config: Config, workers: int = 2) -> dict[str, float]:
    """The first stage of every grid gait not cached yet, on ``workers`` processes; returns counts and seconds."""
    cache = EvaluationCache(root, robot, config)
    todo = [i for i in range(cache.space.size) if cache.walked(cache.params(i)) is None]
    t0 = time.perf_counter()
    cpu = 0.0
    ctx = multiprocessing.get_context("spawn")
    with ctx.Pool(workers, initializer=_init, initargs=(str(root), robot, to_dict(config))) as pool:
        for n, (_, s) in enumerate(pool.imap_unordered(_walk_one, todo), 1):
            cpu += s
            if n % 20 == 0:
                print(f"{n}/{len(todo)} walked, {time.perf_counter() - t0:.0f} s", file=sys.stderr, flush=True)
    return {"gaits": cache.space.size, "computed": len(todo), "wall": time.perf_counter() - t0,
            "seconds_per_gait": cpu / max(len(todo), 1)}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    g = sub.add_parser("grid", help="the first stage (generate + walk) of every grid gait")
    g.add_argument("--cache", required=True)
    g.add_argument("--robot", default="exo")
    g.add_argument("--workers", type=int, default=2)
    args = ap.parse_args()
    if args.cmd == "grid":
        print(json.dumps(precompute_walks(args.cache, args.robot, Config(), args.workers)))


if __name__ == "__main__":
    main()
