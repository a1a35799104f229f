"""The verified certificates of a study that ranks on estimates (docs/studies.md, ``study.verify = shown``): every gait
gets the exploration's estimate of its certificate, and the study verifies what it shows or recommends — each finished
iteration's best gait and the learner's recommendation after it — on its own workers, beside the next evaluations.

A verification is a worker's task (:func:`robustgait.study.executors.verification_task`) on the gait file the
evaluation wrote; its certificate is written to the gait's directory (``certificate.json``, beside the estimate's
``estimate.json``) and its record stored as a study attribute (:meth:`~robustgait.study.storage.StudyStore.
set_verification`): a completed trial is never written again. A study killed while a verification runs submits it
again when resumed (:meth:`Verifier.needed`), so nothing is lost.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

from robustgait.config import StudyConfig
from robustgait.io.output import write_json
from robustgait.io.schema import read_json
from robustgait.learn.space import ActionSpace
from robustgait.study.executors import Executor
from robustgait.study.front import front_rows
from robustgait.study.outcome import EvaluationStatus, status_of
from robustgait.study.storage import StudyStore, TrialRecord, completed_batches, default_url
from robustgait.study.trials import trial_summary

GAITS_DIR = "gaits"
CERTIFICATE_FILE = "certificate.json"  # a gait's verified certificate
ESTIMATE_FILE = "estimate.json"  # a gait's certificate estimated by exploration alone
VERIFY_KEY_BASE = -1_000_000_000  # executor keys of verifications: below the trials', the floor's and ahead's
_ABBREV = {"step_length": "L", "step_duration": "T", "step_width": "W", "step_height": "H"}


def gait_label(space: ActionSpace, index: int) -> str:
    """Directory name of a gait's files, e.g. ``L0.12_T0.8_W0.24_H0.06``."""
    return params_label(space.value(index))


def params_label(params: dict[str, float]) -> str:
    """:func:`gait_label` of a grid point's parameters."""
    return "_".join(f"{_ABBREV.get(n, n)}{v:g}" for n, v in params.items())


def verification_key(index: int) -> int:
    """The executor key of grid point ``index``'s verification."""
    return VERIFY_KEY_BASE - index


def batch_best(batch: list[TrialRecord]) -> TrialRecord:
    """The gait of a batch the study ranked highest (its score; the first evaluated among equals)."""
    return max(batch, key=lambda r: (r.value or 0.0, -r.number))


class Verifier:
    """The verifications of a study in ``directory`` over ``space``, run on the executor ``executor()`` gives:
    :meth:`submit` the gaits :meth:`needed` names, :meth:`take` each finished one (``running``: executor key → grid
    index)."""

    def __init__(self, directory: Path, space: ActionSpace, executor: Callable[[], Executor]):
        self.directory, self.space, self.executor = directory, space, executor
        self.running: dict[int, int] = {}

    def needed(self, store: StudyStore) -> list[int]:
        """The grid indices the study shows and has not verified: each finished iteration's best gait
        (:func:`batch_best`) and the learner's recommendation after it."""
        batches, iterations = completed_batches(store.records()), store.iterations()
        out: list[int] = []
        for k, rec in sorted(iterations.items()):
            if "recommendation" not in rec or k not in batches:
                continue
            out += [batch_best(batches[k]).index, int(rec["recommendation"])]
        return list(dict.fromkeys(out))

    def submit(self, store: StudyStore, indices: list[int]) -> None:
        """Submit the verification of each gait of ``indices`` that holds an estimate and has none stored or
        running."""
        done, running = store.verifications(), set(self.running.values())
        evaluated = {r.index: r for r in store.records() if r.state == "COMPLETE" and r.reused_from is None}
        for index in indices:
            r = evaluated.get(index)
            res = (r.result or {}) if r is not None else {}
            if (index in done or index in running or status_of(res) != EvaluationStatus.ESTIMATED
                    or not res.get("gait_file")):
                continue
            gait = read_json(self.directory / res["gait_file"], "gait")
            key = verification_key(index)
            self.executor().submit_verify(key, gait, stored_estimate(self.directory, res))
            self.running[key] = index

    def submit_front(self, store: StudyStore, config: StudyConfig, figure: str) -> None:
        """Submit the verification of the trade-off front's gaits that hold an estimate only (``study pareto`` and the
        report show that front of verified values, :func:`~robustgait.study.pareto.study_pareto`; ``figure``: its
        comfort objective); called again as verifications end, since a verified value below its estimate can bring
        other gaits onto the front. Nothing for a study that verifies every gait."""
        if config.verifies_all:
            return
        verifications = store.verifications()
        trials = [trial_summary(r, verifications.get(r.index)) for r in store.records()]
        self.submit(store, [r["grid_index"] for r in front_rows(trials, figure) if not r["verified"]])

    def take(self, store: StudyStore, key: int, result: dict[str, Any]) -> bool:
        """If ``key`` is a verification's: write its certificate and store its record (True); else False."""
        index = self.running.pop(key, None)
        if index is None:
            return False
        store_verification(store, self.directory, self.space, index, result)
        return True


def verify_now(directory: Path, indices: list[int], *, progress: bool = True) -> int:
    """Verify, in this process, each gait of ``indices`` whose certificate the study holds only as an estimate (the
    commands that show or use verified values verify on demand: ``study pareto``, ``study validate``): its certificate
    written and its record stored as a study run's verifications are. Returns how many were verified."""
    from tqdm import tqdm

    from robustgait.io.gaitfile import gait_from_dict
    from robustgait.io.robotfile import load_robot
    from robustgait.io.studyfile import load_config
    from robustgait.study.evaluate import verify_gait

    setup = load_config(directory)
    space = setup.action_space()
    store = StudyStore(setup.config.study.storage or default_url(directory), setup.config.study.study_name, space)
    try:
        done = store.verifications()
        evaluated = {r.index: r for r in store.records() if r.state == "COMPLETE" and r.reused_from is None}
        todo = [i for i in dict.fromkeys(indices) if i not in done and i in evaluated
                and status_of(evaluated[i].result or {}) == EvaluationStatus.ESTIMATED
                and (evaluated[i].result or {}).get("gait_file")]
        if not todo:
            return 0
        robot = load_robot(setup.robot)
        for index in tqdm(todo, desc="verifying", unit="gait", disable=not progress, leave=False):
            res = evaluated[index].result or {}
            gait = gait_from_dict(read_json(directory / res["gait_file"], "gait"))
            record = verify_gait(robot, gait, setup.config, stored_estimate(directory, res))
            store_verification(store, directory, space, index, record)
        return len(todo)
    finally:
        store.close()


def stored_estimate(directory: Path, result: dict[str, Any]) -> dict[str, Any] | None:
    """The estimate's certificate of a trial's ``result`` (``estimate.json``, with its samples: its exploration is
    replayed by the verification), or None when the trial holds none or its file is gone."""
    name = result.get("certificate_file")
    if status_of(result) != EvaluationStatus.ESTIMATED or not name or not (directory / name).is_file():
        return None
    out = read_json(directory / name, "estimate")
    return out if isinstance(out, dict) else None


def store_verification(store: StudyStore, directory: Path, space: ActionSpace, index: int,
                       result: dict[str, Any]) -> None:
    """Write a verification's certificate (``certificate.json`` in the gait's directory) and store its record."""
    rel = Path(GAITS_DIR) / gait_label(space, index)
    record = {k: v for k, v in result.items() if k != "certificate"}
    record["certificate_file"] = None
    if result.get("certificate") is not None:
        write_json(directory / rel / CERTIFICATE_FILE, result["certificate"])
        record["certificate_file"] = str(rel / CERTIFICATE_FILE)
    store.set_verification(index, record)
