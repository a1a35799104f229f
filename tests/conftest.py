"""Shared fixtures: the shipped ``exo`` robot with a gait made by the package (tests/data/exo_gait.json, the
default ``robustgait gait generate --robot exo`` gait), and the Atalante model and FROST gait from
../shared/atalante (read, never copied; tests that need it are skipped with the reason when it is absent)."""

from __future__ import annotations

import os
import shutil
import sys
from pathlib import Path

# MuJoCo picks its GL backend once, at import: make offscreen rendering headless before any test imports it.
os.environ.setdefault("MUJOCO_GL", "egl")
# Compile each module once per checkout, whatever PYTHONDONTWRITEBYTECODE says: the test modules' assertion rewriting
# and robustgait's modules are otherwise compiled again by every xdist worker and every CLI subprocess of every run
# (git ignores __pycache__).
sys.dont_write_bytecode = False

import pytest  # noqa: E402 (after the environment it must see)

REPO = Path(__file__).resolve().parents[1]
ATALANTE_DIR = REPO.parent / "shared" / "atalante"
ATALANTE_SPEC = REPO / "robots" / "atalante" / "spec.toml"
ATALANTE_GAIT = ATALANTE_DIR / "jt_bez_2023-09-10.yaml"
EXO_GAIT = REPO / "tests" / "data" / "exo_gait.json"
EXO_MC_GAIT = REPO / "tests" / "data" / "exo_multicontact_gait.json"
T1_MODEL = REPO.parent / "shared" / "robots" / "booster_t1" / "t1.xml"

class WorkStarted(AssertionError):
    """A test that must end before any work built a simulation engine or a gait problem."""


@pytest.fixture
def no_work(monkeypatch):  # type: ignore[no-untyped-def]
    """Fail the test if a simulation engine (:class:`robustgait.sim.engine.StepEngine`) or a gait problem
    (:class:`robustgait.gaitgen.GaitGenerator`) is built: what "refused before any work" means, whatever the machine's
    speed."""
    from robustgait.gaitgen.solve import GaitGenerator
    from robustgait.sim.engine import StepEngine

    def started(what: str):  # type: ignore[no-untyped-def]
        def refuse(*args, **kwargs):  # type: ignore[no-untyped-def]
            raise WorkStarted(f"{what} was built: the input should have been refused before any work")
        return refuse

    monkeypatch.setattr(StepEngine, "__init__", started("a simulation engine"))
    monkeypatch.setattr(GaitGenerator, "__init__", started("a gait problem"))


needs_atalante = pytest.mark.skipif(not (ATALANTE_DIR / "loadedExo.xml").is_file(),
                                    reason="../shared/atalante (AMBER lab model) is not beside the repository")


@pytest.fixture(scope="session")
def atalante():  # type: ignore[no-untyped-def]
    if not (ATALANTE_DIR / "loadedExo.xml").is_file():
        pytest.skip("../shared/atalante is not beside the repository")
    from robustgait import load_robot

    return load_robot(ATALANTE_SPEC)


@pytest.fixture(scope="session")
def atalante_gait(atalante):  # type: ignore[no-untyped-def]
    from robustgait import load_gait

    return load_gait(ATALANTE_GAIT, atalante)


@pytest.fixture(scope="session")
def exo():  # type: ignore[no-untyped-def]
    from robustgait import load_robot

    return load_robot("exo")


@pytest.fixture(scope="session")
def exo_gait(exo):  # type: ignore[no-untyped-def]
    from robustgait import load_gait

    return load_gait(EXO_GAIT, exo)


@pytest.fixture(scope="session")
def exo_mc_gait(exo):  # type: ignore[no-untyped-def]
    """A multi-contact exo gait made by ``robustgait gait generate --robot exo --domains multicontact``."""
    from robustgait import load_gait

    return load_gait(EXO_MC_GAIT, exo)


@pytest.fixture(scope="session", params=["exo", "atalante"])
def flat_robot_gait(request):  # type: ignore[no-untyped-def]
    """(robot, flat-foot gait): the shipped exo with its stored gait, and Atalante with its FROST gait (skipped
    with the reason when ../shared is absent)."""
    if request.param == "exo":
        return request.getfixturevalue("exo"), request.getfixturevalue("exo_gait")
    return request.getfixturevalue("atalante"), request.getfixturevalue("atalante_gait")


def shared_dir(tmp_path_factory, name: str, make) -> Path:  # type: ignore[no-untyped-def]
    """A directory made once per test run and shared by the pytest-xdist workers (each worker has a session of its
    own, and what is shared takes tens of seconds to make: ``robot init`` walks the default gait, a study runs): the
    first worker to ask makes it, under a file lock in the run's common temporary directory, with ``make(directory)``
    into a directory of its own that is renamed into place when complete; the others read it. Tests that write into
    it copy it first."""
    from filelock import FileLock

    root = tmp_path_factory.getbasetemp()
    if os.environ.get("PYTEST_XDIST_WORKER"):
        root = root.parent  # pytest-N/popen-gwK → pytest-N, common to this run's workers
    d = root / f"shared_{name}"
    with FileLock(str(root / f"shared_{name}.lock")):
        if not d.is_dir():
            part = root / f"shared_{name}.part"
            shutil.rmtree(part, ignore_errors=True)
            part.mkdir()
            make(part)
            part.rename(d)  # a failed make leaves no directory that looks complete
    return d


def shared_spec(tmp_path_factory, name: str, make) -> Path:  # type: ignore[no-untyped-def]
    """A spec made once per test run (:func:`shared_dir`) with ``make(directory, spec_path)``."""
    return shared_dir(tmp_path_factory, name, lambda d: make(d, d / f"{name}.toml")) / f"{name}.toml"


@pytest.fixture(scope="session")
def tiny_study(tmp_path_factory):  # type: ignore[no-untyped-def]
    """The tiny exo study (``tests.study.test_study.CLI_TINY``: 2 iterations × 3 gaits) run uninterrupted by
    ``study run`` with 2 local workers, once per test run: the reference that resumed, Ray and validated runs are
    compared with. Read it in place; copy it before writing into it (a report, a validation)."""
    from tests.study.test_study import CLI_TINY, cli

    def make(d: Path) -> None:
        res = cli("study", "run", str(d / "study"), *CLI_TINY, "--workers", "2", "--quiet")
        assert res.returncode == 0, res.stderr

    return shared_dir(tmp_path_factory, "tiny_study", make) / "study"


@pytest.fixture(scope="session")
def reported_study(tmp_path_factory, tiny_study):  # type: ignore[no-untyped-def]
    """A copy of :func:`tiny_study` validated and reported once per test run, for the tests that check its validation
    (tests/study/test_validate.py), report and status (tests/study/test_study.py): ``study validate --trials 8
    --steps-after 3 --json`` with 2 worker processes, again with 1 after the stored results of half its gaits (the
    first by name, at least one) were removed — those validated again on one process, the others read back — then
    ``study report --no-video`` run by the CLI's ``main`` in a fresh interpreter that says whether torch was imported.
    ``{"study": the directory, "validate": [the 2-worker run, the 1-worker run], "removed": the gaits whose results
    were removed, "report": the report's run}``, each run ``{"returncode", "stdout", "stderr"}`` (the report's stdout:
    the page's path, then ``True``/``False``: torch imported). Read in place; copy before writing."""
    import json
    import subprocess

    from robustgait.study.validate import RUNS_DIR, VALIDATION_DIR
    from tests.study.test_study import cli

    def run(res: subprocess.CompletedProcess) -> dict:  # type: ignore[type-arg]
        return {"returncode": res.returncode, "stdout": res.stdout, "stderr": res.stderr}

    def make(d: Path) -> None:
        study = shutil.copytree(tiny_study, d / "study")
        args = ("study", "validate", str(study), "--trials", "8", "--steps-after", "3", "--json", "--quiet")
        runs = [run(cli(*args, "--workers", "2"))]
        # the 1-process run validates half the gaits again (the rollout's thread count must not change results; each
        # gait costs its orbit search) and reads the others' stored results back
        stored = sorted((study / VALIDATION_DIR / RUNS_DIR).glob("*/*.json"))
        removed = stored[:max(1, len(stored) // 2)]
        for f in removed:
            f.unlink()
        runs.append(run(cli(*args, "--workers", "1")))
        code = ("import sys; from robustgait.cli import main; code = main(['study', 'report', sys.argv[1], "
                "'--no-video']); print('torch' in sys.modules); sys.exit(code)")
        env = {**os.environ, "PYTHONPATH": str(REPO / "src")}
        report = subprocess.run([sys.executable, "-c", code, str(study)], env=env, capture_output=True, text=True,
                                check=False)
        (d / "runs.json").write_text(json.dumps({"validate": runs, "removed": [f.stem for f in removed],
                                                 "report": run(report)}))

    d = shared_dir(tmp_path_factory, "reported_study", make)
    return {"study": d / "study", **json.loads((d / "runs.json").read_text())}


@pytest.fixture(scope="session")
def interrupted_study(tmp_path_factory):  # type: ignore[no-untyped-def]
    """The tiny study run on Ray and interrupted — a Ray actor SIGKILLed mid-task, then the study process SIGKILLed in
    its second iteration — and resumed (:func:`tests.study.test_executors.run_interrupted_ray_study`), once per test
    run: ``{"killed": the study as the kill left it, "study": the resumed study, "facts": what was seen}``, checked by
    test_study.py (the killed actor's task run again; resume equals the uninterrupted run) and test_executors.py (no
    Ray process left). Read in place; copy before writing."""
    import json

    from tests.study.test_executors import run_interrupted_ray_study

    pytest.importorskip("ray")
    if not sys.platform.startswith("linux"):
        pytest.skip("reads /proc")
    d = shared_dir(tmp_path_factory, "interrupted_study", run_interrupted_ray_study)
    return {"killed": d / "killed", "study": d / "study", "facts": json.loads((d / "facts.json").read_text())}


@pytest.fixture(scope="session")
def t1_spec(tmp_path_factory):  # type: ignore[no-untyped-def]
    """The spec ``robot init`` writes for Booster T1 (../shared/robots, MuJoCo Menagerie, meshes removed), as a user
    brings it (skipped with the reason when absent)."""
    if not T1_MODEL.is_file():
        pytest.skip("../shared/robots/booster_t1 (Booster T1) is not beside the repository")
    from robustgait.cli import main

    def make(d: Path, spec: Path) -> None:
        assert main(["robot", "init", str(T1_MODEL), "-o", str(spec)]) == 0

    return shared_spec(tmp_path_factory, "t1", make)


@pytest.fixture(scope="session")
def t1(t1_spec):  # type: ignore[no-untyped-def]
    """Booster T1 with the spec ``robot init`` writes for it (:func:`t1_spec`)."""
    from robustgait import load_robot

    return load_robot(t1_spec)


@pytest.fixture(scope="session")
def t1_narrow(tmp_path_factory):  # type: ignore[no-untyped-def]
    """Booster T1 with narrow soles — four 5 mm contact spheres per foot on a 0.19 × 0.04 m footprint
    (:func:`tests.models.narrow_t1_xml`) — and the spec ``robot init`` writes for it (skipped when T1 is absent)."""
    if not T1_MODEL.is_file():
        pytest.skip("../shared/robots/booster_t1 (Booster T1) is not beside the repository")
    from robustgait import load_robot
    from robustgait.cli import main
    from tests.models import narrow_t1_xml

    def make(d: Path, spec: Path) -> None:
        assert main(["robot", "init", str(narrow_t1_xml(T1_MODEL, d)), "-o", str(spec)]) == 0

    return load_robot(shared_spec(tmp_path_factory, "t1_narrow", make))


def write_frost_yaml(gait, path, *, inputparams=None):  # type: ignore[no-untyped-def]
    """Write a one-domain gait as a FROST/ambersim YAML (``coeff_jt`` in Fortran order, ``step_dur``, the initial
    state as ``ffPos``/``startingPos``/``ffVel``/``startingVel``): a FROST file for any robot, for the importer's
    tests without the AMBER lab's file."""
    import yaml

    s = gait.initial_state
    data = {"coeff_jt": gait.domains[0].beta.ravel(order="F").tolist(), "step_dur": float(gait.domains[0].duration),
            "ffPos": s.qpos[:7].tolist(), "startingPos": s.qpos[7:].tolist(), "ffVel": s.qvel[:6].tolist(),
            "startingVel": s.qvel[6:].tolist(), "coeff_output": [0.0], "SL": 0.1}
    if inputparams is not None:
        data["inputparams"] = inputparams
    path.write_text(yaml.safe_dump(data))
    return path


# the orbit searches of one gait in several test modules, made once per worker: those modules share the xdist group
# ORBITS, so that one worker runs them all
ORBITS = "orbits"
_ORBITS: dict[tuple[str, ...], object] = {}


def walked_orbit(robot, gait, config=None):  # type: ignore[no-untyped-def]
    """``find_orbit(Walking(robot, gait), config)``, searched once per worker for a robot, a gait and the options the
    search reads (``orbit``, ``map``, ``push``); the orbit is a frozen result, shared as it is."""
    from robustgait import CertifyConfig
    from robustgait.certificate import Walking, find_orbit

    cfg = config or CertifyConfig()
    key = (robot.digest, gait.digest(), repr(cfg.orbit), repr(cfg.map), repr(cfg.push))
    if key not in _ORBITS:
        _ORBITS[key] = find_orbit(Walking(robot, gait), cfg)
    return _ORBITS[key]


@pytest.fixture(scope="session", params=["exo", "exo-multicontact", "atalante"])
def robot_gait(request):  # type: ignore[no-untyped-def]
    """(robot, gait) for the shipped exo with its stored flat-foot and multi-contact gaits, and for Atalante with
    its FROST gait."""
    if request.param == "exo":
        return request.getfixturevalue("exo"), request.getfixturevalue("exo_gait")
    if request.param == "exo-multicontact":
        return request.getfixturevalue("exo"), request.getfixturevalue("exo_mc_gait")
    return request.getfixturevalue("atalante"), request.getfixturevalue("atalante_gait")


def standing_gait(robot, *, extras: bool = False):  # type: ignore[no-untyped-def]
    """A valid one-domain gait for ``robot`` without a solve: hold the spec's cold-start posture for 0.7 s,
    starting at rest with both soles on the floor (a gait that stands; the file layer is what it tests).
    ``extras``: also feedforward torques (zero), params, a solver report and meta, so every field is filled."""
    import mujoco
    import numpy as np

    from robustgait.gait import Domain, Gait, State

    m = robot.model
    d = mujoco.MjData(m)
    d.qpos[:] = m.qpos0
    d.qpos[robot.qpos_idx] = robot.spec.posture
    mujoco.mj_kinematics(m, d)
    lowest = min(d.geom_xpos[g][2] - np.min(m.geom_size[g]) for g in robot.sole_geom_id.values())
    d.qpos[2] -= lowest
    from robustgait.config import GaitParams

    beta = np.repeat(np.asarray(robot.spec.posture, dtype=float)[:, None], 8, axis=1)
    ff = (np.linspace(0.0, 1.0, 5), np.zeros((5, robot.n_joints))) if extras else (None, None)
    state = State(d.qpos.copy(), np.zeros(m.nv))
    return Gait(robot=robot.name, domain_graph="flat", stance="right", joints=robot.spec.joints,
                domains=(Domain("single_support", 0.7, beta, *ff),), initial_state=state,
                pre_impact_state=state if extras else None, params=GaitParams().resolved("flat") if extras else None,
                solver={"status": "none", "iterations": 0} if extras else None,
                meta={"source": "test", "tags": ["standing", 1.5, None, True]} if extras else {})


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """Modules with the most ``slow`` tests first, then those whose tests share an ``xdist_group``, each module's tests
    in their own order: pytest-xdist hands tests out in collection order (a group as one unit), so the long ones
    start early and the short ones fill the gaps at the end instead of one worker finishing a long test or group
    alone."""
    def module(item: pytest.Item) -> str:
        return item.module.__name__ if item.module else ""

    slow: dict[str, int] = {}
    grouped: dict[str, int] = {}
    for item in items:
        slow[module(item)] = slow.get(module(item), 0) + (item.get_closest_marker("slow") is not None)
        grouped[module(item)] = grouped.get(module(item), 0) + (item.get_closest_marker("xdist_group") is not None)
    items.sort(key=lambda item: (-slow[module(item)], -grouped[module(item)]))
