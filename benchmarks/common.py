"""Helpers shared by the benchmarks (``perf/``) and experiments (``experiments/<question>/``): where things are, what
commit a figure was measured at, and the start states several speed measurements share.

A script imports this module after putting ``benchmarks/`` on ``sys.path``::

    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # perf/X.py; parents[2] for experiments/Q/run.py
    from common import REPO, git_commit

Logic the package has is called from ``robustgait``, never copied here.
"""

from __future__ import annotations

import argparse
import os
import subprocess
from pathlib import Path
from typing import Any

import numpy as np

REPO = Path(__file__).resolve().parents[1]
"""The repository's root."""
SHARED = REPO.parent / "shared"
"""``../shared`` beside the repository: the Atalante model and gait, and the third-party robots."""
ATALANTE_SPEC = REPO / "robots" / "atalante" / "spec.toml"
ATALANTE_GAIT = SHARED / "atalante" / "jt_bez_2023-09-10.yaml"
T1_SPEC = REPO / "robots" / "t1" / "spec.toml"
EXO_GAIT = REPO / "tests" / "data" / "exo_gait.json"
"""The default ``robustgait gait generate --robot exo`` gait, stored."""
EXO_MULTICONTACT_GAIT = REPO / "tests" / "data" / "exo_multicontact_gait.json"


def git_commit(where: Path = REPO) -> str:
    """``git describe --always --dirty`` of the checkout holding ``where`` (a figure's commit; ``-dirty`` when the
    working tree had changes), or ``"?"`` outside a checkout."""
    out = subprocess.run(["git", "-C", str(where), "describe", "--always", "--dirty"], capture_output=True,
                         text=True, check=False)
    return out.stdout.strip() or "?"


def cli(*args: str, cwd: Path = REPO) -> tuple[int, str, float]:
    """Run ``robustgait ARGS`` in a fresh process, as a user would: (exit code, stdout + stderr, wall seconds)."""
    import sys
    import time

    t0 = time.perf_counter()
    p = subprocess.run([sys.executable, "-c", "import sys; from robustgait.cli import main; sys.exit(main())",
                        *args], capture_output=True, text=True, cwd=cwd)
    return p.returncode, p.stdout + p.stderr, time.perf_counter() - t0


def start_states(qpos: np.ndarray, qvel: np.ndarray, k: int, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """K certificate-like start states (K, nq), (K, nv): the section state ``qpos`` (nq,), ``qvel`` (nv,) with its
    base angular velocity perturbed uniformly in a ball of 0.3 rad/s."""
    rng = np.random.default_rng(seed)
    d = rng.normal(size=(k, 3))
    d *= (0.3 * rng.uniform(size=(k, 1)) ** (1 / 3)) / np.linalg.norm(d, axis=1, keepdims=True)
    qv = np.tile(qvel, (k, 1))
    qv[:, 3:6] += d
    return np.tile(qpos, (k, 1)), qv


def load_average() -> str:
    """The machine's load averages over 1, 5 and 15 min, as a phrase (a figure's context)."""
    return "load average " + " ".join(f"{v:.2f}" for v in os.getloadavg())


def add_gait_arguments(ap: argparse.ArgumentParser) -> None:
    """``--exo-gait FILE`` and the exo gait's parameters ``--step-length`` … (the defaults of flat-foot
    :class:`robustgait.config.GaitParams`), read by :func:`default_gaits`."""
    from robustgait.config import GaitParams

    ap.add_argument("--exo-gait", help="use this exo gait file instead of regenerating the default one")
    defaults = GaitParams().resolved("flat")
    for name in ("step_length", "step_duration", "step_width", "step_height"):
        ap.add_argument(f"--{name.replace('_', '-')}", type=float, default=getattr(defaults, name),
                        help=f"exo gait parameter (default {getattr(defaults, name)})")


def default_gaits(args: argparse.Namespace) -> dict[str, tuple[Any, Any]]:
    """{name: (robot, gait)}: ``exo`` with the gait file ``args.exo_gait`` or, when None, the gait generated from the
    parameters of :func:`add_gait_arguments`; ``atalante`` with its FROST gait when ``../shared/atalante`` is there
    (else skipped, with a line saying so)."""
    from robustgait import load_gait, load_robot
    from robustgait.config import GaitParams
    from robustgait.gaitgen import generate_gait

    out = {}
    exo = load_robot("exo")
    if args.exo_gait:
        out["exo"] = (exo, load_gait(args.exo_gait, exo))
    else:
        params = GaitParams(args.step_length, args.step_duration, args.step_width, args.step_height)
        res = generate_gait(exo, params)
        if res.gait is None:
            raise SystemExit(f"exo gait generation failed: {res.status} {res.reason}")
        print(f"exo gait regenerated: {params} ({res.status}, {res.iterations} iterations)")
        out["exo"] = (exo, res.gait)
    if ATALANTE_GAIT.is_file() and ATALANTE_SPEC.is_file():
        robot = load_robot(ATALANTE_SPEC)
        out["atalante"] = (robot, load_gait(ATALANTE_GAIT, robot))
    else:
        print("../shared/atalante is missing: the Atalante gait is skipped")
    return out


def grid_params(robot_name: str, n: int, domains: str) -> list[dict[str, float]]:
    """n points of the robot's action-space grid, evenly spaced in grid order (the studies' grid)."""
    from robustgait.io.robotfile import load_robot
    from robustgait.learn.space import ActionSpace

    space = ActionSpace.from_robot(load_robot(robot_name), domains)
    idx = np.unique(np.linspace(0, space.size - 1, n).round().astype(int))
    return [space.value(int(i)) for i in idx]


YARDSTICK_STEPS = 120_000
"""Physics steps of the yardstick (:func:`yardstick`)."""


def yardstick() -> float:
    """CPU seconds of a fixed raw MuJoCo workload — ``mujoco.rollout`` on one thread of the shipped ``exo`` model,
    100 states of its default gait's start, 1 200 physics steps each under the gait's first step's controls
    (:data:`YARDSTICK_STEPS` in all) —, the unit in which the performance figures give a command's CPU time
    ("yardsticks"): a figure measured beside it in the same run is comparable across machines and load."""
    import time

    from mujoco import rollout

    from robustgait import SimConfig, load_gait, load_robot
    from robustgait.sim.engine import StepEngine

    robot = load_robot("exo")
    gait = load_gait(EXO_GAIT, robot)
    k, n = 100, YARDSTICK_STEPS // 100
    s = gait.initial_state
    assert s is not None
    qpos, qvel = start_states(np.asarray(s.qpos), np.asarray(s.qvel), k)
    with StepEngine(robot, gait, SimConfig(n_threads=1)) as eng:
        init = eng.full_states(qpos, qvel)
        series = eng.controls[(gait.stance, 0)]
    ctrl = np.repeat(series[None, np.minimum(np.arange(n), len(series) - 1)], k, axis=0)
    data = [robot.new_data()]
    with rollout.Rollout(nthread=1) as pool:
        t0 = time.process_time()
        pool.rollout(robot.model, data, init, ctrl)
        cpu = time.process_time() - t0
    return cpu
