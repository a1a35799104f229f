"""The simulation-in-the-loop learning loop (``docs/studies.md``): propose a batch → evaluate it (generate, walk,
certify) → rank it with the oracle → all pairwise comparisons → next batch, for ``iterations`` batches.

A study lives in a directory::

    DIR/study.json            the robot and the whole configuration (format_version 2, StudySetup)
    DIR/study.db              the Optuna database (unless config.study.storage names another)
    DIR/gaits/<label>/        gait.json and certificate.json of every evaluated gait
    DIR/report/               written by ``robustgait study report``
    DIR/.lock                 held by the process running the study

Iteration k is proposed from the comparisons of iterations < k only (reproduced from the database on
resume); it is recorded (all its trials WAITING) before any is dispatched; the next iteration starts when
every trial of this one is COMPLETE. A gait proposed again later is not simulated again: its trial is
completed with the stored result (``reused_from``), since an evaluation depends only on the parameters
and the config (:mod:`robustgait.study.evaluate`).

A study that asks a person (docs/person.md) proposes ``batch + person.overdraw`` candidates, in the learner's
order, and records each trial only when it is dispatched: the next candidate is evaluated while fewer than
``batch`` of the iteration's evaluated or running candidates may be shown, so its trials are slots 0 … n − 1 with
n between ``batch`` and ``batch + overdraw``. While a person answers, idle workers evaluate ahead
(:mod:`robustgait.study.ahead`). The runner keeps the loop; what a person study adds to it — the floor, the
over-draw, the evaluations ahead — are policies it calls (:mod:`robustgait.study.policies`).
"""

from __future__ import annotations

import contextlib
import fcntl
import os
import sys
import time
import uuid
from collections.abc import Iterator
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from tqdm import tqdm

from robustgait.certificate.certify import check_certify_work
from robustgait.config import Config, GaitParams, RunConfig, StudyConfig, radius_name
from robustgait.config.study import POSTERIOR_STORE_LIMIT
from robustgait.errors import RobustGaitError, input_error
from robustgait.gait import BEZIER_DEGREE, Domain, Gait
from robustgait.io.output import write_json
from robustgait.io.robotfile import load_robot
from robustgait.io.studyfile import StudySetup, environment_changes, load_config, save_config
from robustgait.learn.history import History, iteration_seed
from robustgait.learn.oracle import batch_comparisons
from robustgait.learn.space import ActionSpace
from robustgait.robots import Robot
from robustgait.robots.spec import SHIPPED_DIR
from robustgait.sim.walk import check_walk_work
from robustgait.study.evaluate import Evaluation
from robustgait.study.executors import Executor, WorkerSpec, make_executor
from robustgait.study.outcome import EvaluationStatus, status_of
from robustgait.study.person import automatic_answer, pending_record, shown_flags, simulated_answer
from robustgait.study.policies import REFERENCE_KEY, AheadPolicy, Asker, FloorPolicy, Overdraw, StudyContext
from robustgait.study.ranking import (  # history_before, study_score: re-exported by robustgait.study.run
    Requirement,
    batch_scores,
    history_before,
    requirements,
    shown,
    study_score,
)
from robustgait.study.storage import StudyStore, TrialRecord, completed_batches, default_url
from robustgait.study.trials import outcome_line
from robustgait.study.verify import CERTIFICATE_FILE, ESTIMATE_FILE, GAITS_DIR, Verifier, gait_label

if TYPE_CHECKING:
    from robustgait.learn.learners import Learner


POLL = 0.5  # s: how often a study waiting for a person looks for the answer and its evaluations ahead

LOCK_FILE = ".lock"



def robot_reference(robot: str) -> str:
    """A shipped robot name as is; a spec path made absolute (the study may be resumed from elsewhere)."""
    if (SHIPPED_DIR / robot / "spec.toml").is_file() and not Path(robot).suffix:
        return robot
    p = Path(robot)
    if not p.is_file():
        raise input_error(robot, "not a shipped robot name nor a robot spec file")
    return str(p.resolve())


@contextlib.contextmanager
def study_lock(directory: Path) -> Iterator[None]:
    """Exclusive lock of a study directory for as long as a process runs it (released by the OS when the
    process dies, so a killed study can be resumed at once)."""
    fh = (directory / LOCK_FILE).open("a+")
    try:
        try:
            fcntl.flock(fh, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            raise input_error(directory, "the study is being run by another process") from None
        fh.seek(0)
        fh.truncate()
        fh.write(str(os.getpid()))
        fh.flush()
        yield
    finally:
        fh.close()


def is_running(directory: Path) -> bool:
    path = directory / LOCK_FILE
    if not path.exists():
        return False
    with path.open("a+") as fh:
        try:
            fcntl.flock(fh, fcntl.LOCK_SH | fcntl.LOCK_NB)
        except BlockingIOError:
            return True
        return False


def storage_url(directory: Path, setup: StudySetup) -> str:
    return setup.config.study.storage or default_url(directory)


def create_study(directory: str | Path, robot: str, config: Config | None = None) -> Path:
    """Make a new study directory (it may exist, empty) with its configuration and database; nothing runs yet.
    ``robot``: a shipped robot name or a spec .toml path (made absolute: a study may be resumed from elsewhere)."""
    d = Path(directory)
    if d.exists() and not d.is_dir():
        raise input_error(d, "exists and is not a directory")
    if (d / "study.json").exists():
        raise input_error(d, "already holds a study: use `robustgait study resume`")
    if d.exists() and any(p.name != LOCK_FILE for p in d.iterdir()):
        raise input_error(d, "exists and is not empty: a new study needs a new or empty directory")
    config = config or Config()
    study = config.study
    if study.storage is not None and study.study_name == StudyConfig().study_name:
        # a shared database holds many studies: a name of its own (saved in study.json)
        study = replace(study, study_name=f"{d.resolve().name}-{uuid.uuid4().hex[:8]}")
    setup = StudySetup(robot_reference(robot), replace(config, study=study))
    loaded = load_robot(setup.robot)
    space = setup.action_space(loaded)
    largest = max(study.batch, study.batch_size(0))
    if largest > space.size:
        raise RobustGaitError(f"a batch of {largest} gaits does not fit in an action space of {space.size}")
    check_evaluation_work(setup.config, loaded, space)
    requirements(study, space.names)  # a requirement on a figure that is not recorded: refused now
    d.mkdir(parents=True, exist_ok=True)
    with study_lock(d):
        store = StudyStore(storage_url(d, setup), study.study_name, space, create=True,
                           user_attrs={"robustgait_config": setup.to_dict(), "directory": str(d.resolve())})
        store.close()
        save_config(d, setup)  # last: a directory with study.json has a database
    return d


def longest_gaits(robot: Robot, config: Config, space: ActionSpace) -> list[Gait]:
    """Stand-ins for the longest-stepping gaits a study may generate on ``robot``: the action space's longest step
    duration (or the configured one) with each rolling fraction it searches, smallest first (the longest single
    support); their domain durations, zero outputs — all that the work checks of an evaluation look at."""
    graph = config.generate.domains

    def axis(name: str) -> tuple[float, ...]:
        return space.values[space.names.index(name)] if name in space.names else (getattr(config.params, name),)

    longest, beta = max(axis("step_duration")), np.zeros((robot.n_joints, BEZIER_DEGREE + 1))
    return [Gait(robot.name, graph, "right", robot.spec.joints,
                 tuple(Domain(f"domain{i}", d, beta) for i, d in enumerate(
                     GaitParams(step_duration=longest, rolling_fraction=rho).domain_durations(graph))))
            for rho in axis("rolling_fraction")]


def check_evaluation_work(config: Config, robot: Robot, space: ActionSpace) -> None:
    """Refuse, before the study starts, what one evaluation would refuse later: the work checks of its walk (to the
    step cap) and of its certificate (:mod:`robustgait.config.work`) on each of the :func:`longest_gaits`."""
    for gait in longest_gaits(robot, config, space):
        try:
            check_walk_work(robot, gait, config.sim, config.sim.step_cap)
            check_certify_work(robot, gait, config.study_certify, config.sim)
        except RobustGaitError as exc:
            raise RobustGaitError(f"study: one evaluation of a {gait.step_duration:g} s gait: {exc}") from None


def open_store(directory: Path, setup: StudySetup, space: ActionSpace) -> StudyStore:
    return StudyStore(storage_url(directory, setup), setup.config.study.study_name, space)


class StudyRunner:
    """Runs (or resumes) the study in ``directory`` to its total budget, its evaluations spread as ``run`` says
    (executor, workers); ``progress``: a bar on stderr; ``verbose``: IPOPT's iteration log in the workers."""

    def __init__(self, directory: str | Path, run: RunConfig | None = None, *, progress: bool = True,
                 verbose: bool = False, executor: Executor | None = None, asker: Asker | None = None):
        self.directory = Path(directory)
        self.setup = load_config(self.directory)
        self.config = self.setup.config.study
        self.name = radius_name(self.setup.config.study_certify.space)  # what the bar reports
        self.run_config = run or RunConfig()
        self.progress, self.verbose = progress, verbose
        self.robot = load_robot(self.setup.robot)
        self.space = self.setup.action_space(self.robot)
        self._learner: Learner | None = None  # made when first asked (it loads torch)
        self._executor = executor
        self._own_executor = executor is None
        self.reqs: list[Requirement] = requirements(self.config, self.space.names)
        self.asker = asker
        ctx = StudyContext(self.directory, self.setup, self.space, self.reqs, self.executor, lambda: self.learner,
                           asker)
        self.floor = FloorPolicy(ctx)  # a person study's floor
        self.overdraw = Overdraw(ctx, self.floor)  # its candidates beyond the batch
        self.ahead = AheadPolicy(ctx, self.floor, self.overdraw)  # its evaluations ahead of a person's answer
        self.verifier = Verifier(self.directory, self.space, self.executor)

    @property
    def learner(self) -> Learner:
        """The study's learner (:func:`~robustgait.learn.learners.make_learner`), made on first use: loading torch and
        BoTorch takes seconds, which the workers spend building their generators."""
        if self._learner is None:
            from robustgait.learn.learners import make_learner

            self._learner = make_learner(self.config.learner, self.space, self.config.learning, self.config.seed)
        return self._learner

    def executor(self) -> Executor:
        if self._executor is None:
            spec = WorkerSpec(self.setup.robot, self.setup.to_dict()["config"], verbose=self.verbose)
            self._executor = make_executor(self.run_config, spec)
        return self._executor

    def run(self) -> None:
        with study_lock(self.directory):
            store = open_store(self.directory, self.setup, self.space)
            if self._has_work(store):
                self.executor().start()  # the workers build their generators while the learner loads
            ok = False
            try:
                store.retry_interrupted()
                self._run(store)
                ok = True
            finally:
                store.close()
                if self._own_executor and self._executor is not None:
                    self._executor.close(wait=ok)

    def _closed(self, k: int, batches: dict[int, list[TrialRecord]], iterations: dict[int, dict[str, Any]]) -> bool:
        """Whether iteration k is done: its batch evaluated and its recommendation stored."""
        return len(batches.get(k, [])) >= self.config.batch_size(k) and "recommendation" in iterations.get(k, {})

    def _has_work(self, store: StudyStore) -> bool:
        """Whether the study has an iteration that is not done (:meth:`_closed`) or a gait to verify."""
        batches, iterations = completed_batches(store.records()), store.iterations()
        return not all(self._closed(k, batches, iterations) for k in range(self.config.iterations)) \
            or bool(self.verifier.needed(store))

    def _run(self, store: StudyStore) -> None:
        cfg = self.config
        done = sum(len(b) for b in completed_batches(store.records()).values())
        with tqdm(total=cfg.trials_planned, initial=done, desc="study", unit="gait", file=sys.stderr,
                  disable=not self.progress, dynamic_ncols=True) as bar:
            self.floor.start(store)
            self.verifier.submit(store, self.verifier.needed(store))  # what a killed run had not verified yet
            for k in range(cfg.iterations):
                batches = completed_batches(store.records())
                iterations = store.iterations()
                if self._closed(k, batches, iterations):
                    continue
                self._propose(store, k, history_before(k, batches, cfg, iterations, self.reqs))
                if cfg.asks_a_person:
                    self._fill(store, k, bar)
                else:
                    self._evaluate(store, k, bar)
                if cfg.asks_a_person:
                    self._ask(store, k)
                self._close_iteration(store, k, bar)
                self.verifier.submit(store, self.verifier.needed(store))
            self.verifier.submit_front(store, self.config, self.setup.config.report.pareto_figure)
            while self.verifier.running:  # the last iteration's verifications, and the trade-off front's
                bar.set_postfix_str(f"verifying the best, recommended and trade-off gaits: {len(self.verifier.running)}"
                                    " left")
                self.verifier.take(store, *self.executor().next_result())
                self.verifier.submit_front(store, self.config, self.setup.config.report.pareto_figure)

    def _ask(self, store: StudyStore, k: int) -> None:
        """Iteration k's answer: stored already (a resumed study), none needed (no gait above the floor), a simulated
        person's, or a person's — the batch is recorded as pending and shown, and the study evaluates ahead
        (``person.ahead``) until the answer is stored."""
        rec = dict(store.iterations().get(k, {}))
        if "answer" in rec:
            return
        batch = completed_batches(store.records())[k]
        show = shown_flags(batch, self.floor.value, self.reqs)
        if not any(show):
            rec["answer"] = automatic_answer(len(batch), f"no gait of the batch is certified at or above the floor "
                                             f"{self.floor.value:.4g} and meets the requirements: nothing to ask")
        elif self.config.metric == "simulated-person":
            rec["answer"] = simulated_answer(self.setup.config, batch, show, k)
        else:
            if "pending" not in rec:
                rec["pending"] = pending_record(batch, self.floor.value, self.reqs,
                                                self.setup.config.study_certify.unit)
                store.set_iteration(k, rec)
            if self.asker is None:
                raise RobustGaitError(f"{self.directory}: iteration {k + 1} waits for a person's answers: "
                                      f"robustgait study serve {self.directory}")
            if self.ahead.wanted(k):
                self.ahead.plan(store, k, batch, show)
            self.asker.show(k)
            while not self.asker.answered(k, 0.0 if self.ahead.busy else POLL):
                if self.ahead.busy:
                    got = self.executor().poll(POLL)
                    if got is not None and self.verifier.take(store, *got):
                        continue
                    if got is not None:
                        index, written = self._finish_ahead(*got)
                        self.ahead.fill()
                        if self.floor.qualifies(index, written):
                            self.asker.render_ahead(index, written)
            return
        store.set_iteration(k, rec)

    def _propose(self, store: StudyStore, k: int, history: History) -> None:
        """Reproduce the proposals of iteration k and enqueue the slots not recorded yet (a study that asks a person:
        none, :meth:`_fill` records each when it dispatches it); a stored slot that differs from the reproduction is
        an error (another version or config wrote this study)."""
        cfg = self.config
        size = self.overdraw.candidates(k)
        t0 = time.perf_counter()
        proposal = self.learner.propose(history, k, size, self.floor.region(store, k))
        if k == 0 and self.floor.index is not None:  # the floor's reference first
            proposal = [self.floor.index, *[i for i in proposal if i != self.floor.index]][:size]
        seconds = time.perf_counter() - t0
        stored = {r.slot: r.index for r in store.records() if r.iteration == k}
        extended = store.iterations().get(k, {}).get("proposals") or []  # with candidates added while filling
        proposal = proposal + [int(i) for i in extended[size:]]
        for slot, index in stored.items():
            if slot >= len(proposal) or proposal[slot] != index:
                changes = environment_changes(self.setup.environment)
                raise RobustGaitError(f"{self.directory}: iteration {k} slot {slot} holds grid index {index} but "
                                      f"the learner reproduces {proposal[slot] if slot < size else 'nothing'}"
                                      + (f" (created with other libraries: {', '.join(changes)})" if changes else ""))
        if k not in store.iterations():
            store.set_iteration(k, {"proposals": proposal, "learner_seed": iteration_seed(cfg.seed, k),
                                    "propose_seconds": seconds})
        if cfg.asks_a_person:
            return
        for slot, index in enumerate(proposal):
            if slot not in stored:
                store.enqueue(k, slot, index, self._trial_attrs())

    def _trial_attrs(self) -> dict[str, Any]:
        return {"seeds": {"learner": self.config.seed, "certify": self.setup.config.certify.seed}}

    def _evaluate(self, store: StudyStore, k: int, bar: tqdm) -> None:
        cache = {r.index: r for r in store.records() if r.state == "COMPLETE" and r.reused_from is None}
        started: dict[int, TrialRecord] = {}
        while (trial := store.start()) is not None:
            if trial.iteration != k:
                raise RobustGaitError(f"trial {trial.number} of iteration {trial.iteration} is waiting while "
                                      f"iteration {k} runs")
            self._dispatch(store, trial, cache, started, bar)
        while started:
            self._collect(store, started, bar)

    def _fill(self, store: StudyStore, k: int, bar: tqdm) -> None:
        """Evaluate iteration k's candidates in the learner's order, each recorded when it is dispatched, while fewer
        than its batch (:meth:`~robustgait.config.StudyConfig.batch_size`) of those evaluated or running may be shown
        (a study that asks a person); the first iteration also waits for the floor's reference evaluation."""
        size = self.config.batch_size(k)
        proposals = store.iterations()[k]["proposals"]
        cache = {r.index: r for r in store.records() if r.state == "COMPLETE" and r.reused_from is None}
        started: dict[int, TrialRecord] = {}
        while True:
            while (trial := store.start()) is not None:  # a retried or recorded trial first
                if trial.iteration != k:
                    raise RobustGaitError(f"trial {trial.number} of iteration {trial.iteration} is waiting while "
                                          f"iteration {k} runs")
                self._dispatch(store, trial, cache, started, bar)
            mine = [r for r in store.records() if r.iteration == k]
            # while the floor is pending, a gait that may be shown under some floor counts: no candidate is drawn
            # beyond the batch before the floor says one is needed (the first question waits for what is started)
            floor = 0.0 if self.floor.pending else self.floor.value
            ready = sum(1 for r in mine if r.state == "COMPLETE" and shown(r, floor, self.reqs))
            slots = len({r.slot for r in mine})
            if ready + len(started) < size and slots == len(proposals) and not started and not self.floor.pending:
                proposals = self.overdraw.more(store, k, proposals, ready)
            if ready + len(started) < size and slots < len(proposals):
                store.enqueue(k, slots, proposals[slots], self._trial_attrs())
                if slots >= size:
                    bar.total += 1
                    bar.refresh()
                continue
            if not started and not self.floor.pending:
                break
            self._collect(store, started, bar)
        self.ahead.record_use(store, k)

    def _dispatch(self, store: StudyStore, trial: TrialRecord, cache: dict[int, TrialRecord],
                  started: dict[int, TrialRecord], bar: tqdm) -> None:
        """Complete ``trial`` from an earlier evaluation of its gait (stored, or made ahead), adopt the running
        evaluation ahead of it, or submit it."""
        earlier = cache.get(trial.index)
        if earlier is not None and earlier.result is not None:
            self._complete(store, trial, earlier.result, bar, reused_from=earlier.number)
            return
        made = self.ahead.take(trial.index)
        if made is not None:
            self._complete(store, trial, made, bar, extra={"evaluated_ahead": True})
            return
        key = self.ahead.key_of(trial.index)
        if key is not None:
            started[key] = trial
            return
        started[trial.number] = trial
        self.executor().submit(trial.number, trial.params, self.floor.verify_above())

    def _collect(self, store: StudyStore, started: dict[int, TrialRecord], bar: tqdm) -> None:
        """Wait for the next finished evaluation: a trial's, one made ahead (kept; completing the trial that
        adopted it) or a verification (stored)."""
        key, result = self.executor().next_result()
        if key == REFERENCE_KEY:
            bar.set_postfix_str(self.floor.set(store, result))
            return
        if self.verifier.take(store, key, result):
            return
        if self.ahead.owns(key):
            index, _ = self._finish_ahead(key, result)
            trial = started.pop(key, None)
            if trial is not None:
                made = self.ahead.take(index)
                assert made is not None
                self._complete(store, trial, made, bar, extra={"evaluated_ahead": True})
            return
        trial = started.pop(key)
        written = self._write_files(trial.index, result)
        self._complete(store, trial, written, bar)
        if self.floor.is_reference(trial):
            bar.set_postfix_str(self.floor.set(store, {**written, "params": trial.params}))

    def _finish_ahead(self, key: int, result: dict[str, Any]) -> tuple[int, dict[str, Any]]:
        """Write the files of the evaluation made ahead under executor ``key`` and keep it (:meth:`Ahead.finish`):
        its grid index and the result as the study stores it."""
        written = self._write_files(self.ahead.index_of(key), result)
        return self.ahead.finish(key, written), written

    def _write_files(self, index: int, result: dict[str, Any]) -> dict[str, Any]:
        """gait.json and certificate.json (atomic writes) → the result without them, with their paths."""
        rel = Path(GAITS_DIR) / gait_label(self.space, index)
        (self.directory / rel).mkdir(parents=True, exist_ok=True)
        out = {k: v for k, v in result.items() if k not in ("gait", "certificate")}
        out["gait_file"] = out["certificate_file"] = None
        if result.get("gait") is not None:
            write_json(self.directory / rel / "gait.json", result["gait"])
            out["gait_file"] = str(rel / "gait.json")
        if result.get("certificate") is not None:
            name = ESTIMATE_FILE if status_of(result) == EvaluationStatus.ESTIMATED else CERTIFICATE_FILE
            write_json(self.directory / rel / name, result["certificate"])
            out["certificate_file"] = str(rel / name)
            out["certificate"] = Evaluation.from_dict({**result, "gait": None}).certificate_summary()
        else:
            out["certificate"] = None
        return out

    def _complete(self, store: StudyStore, trial: TrialRecord, result: dict[str, Any], bar: tqdm,
                  reused_from: int | None = None, extra: dict[str, Any] | None = None) -> None:
        value = study_score(self.config, replace(trial, result=result), self.reqs)
        attrs: dict[str, Any] = {"reused_from": reused_from} if reused_from is not None else {}
        store.complete(trial.number, result, value, {**attrs, **(extra or {})})
        bar.update(1)
        bar.set_postfix_str(f"iteration {trial.iteration + 1}/{self.config.iterations}, last: "
                            f"{outcome_line(result, self.name)}")
        if self.asker is not None and self.floor.qualifies(trial.index, result, self.floor.pending):
            # its video now, while the workers evaluate the batch's other candidates: the batch is shown sooner (while
            # the floor is pending, a gait that may be shown under some floor: the floor's reference is still running)
            self.asker.render_ahead(trial.index, result)

    def _close_iteration(self, store: StudyStore, k: int, bar: tqdm) -> None:
        """Comparisons of the ranked batch and the learner's recommendation after it."""
        batches = completed_batches(store.records())
        batch = batches[k]
        iterations = store.iterations()
        record = dict(iterations.get(k, {}))
        scores = batch_scores(self.config, batch, record, self.reqs)
        t0 = time.perf_counter()
        history = history_before(k + 1, batches, self.config, iterations, self.reqs)
        model = self.learner.model(history, k)
        rec = self.learner.recommend(history, k, model=model)
        if self.space.size <= POSTERIOR_STORE_LIMIT:  # the report's map, without refitting the model
            store.set_posterior(k, self.learner.grid_utility(model))
        rec_trial = next((r for i in sorted(batches) for r in batches[i] if r.index == rec), None)
        record.update({"trials": [r.number for r in batch], "scores": scores,
                       "comparisons": [[batch[w].number, batch[lo].number] for w, lo in batch_comparisons(scores)],
                       "recommendation": rec, "recommended_trial": rec_trial.number if rec_trial else None,
                       "recommend_seconds": time.perf_counter() - t0})
        store.set_iteration(k, record)
        if rec_trial is not None and rec_trial.result is not None:
            bar.set_postfix_str(f"iteration {k + 1}/{self.config.iterations} done, best: "
                                f"{outcome_line(rec_trial.result, self.name)}")


def run_study(directory: str | Path, run: RunConfig | None = None, *, progress: bool = True, verbose: bool = False,
              executor: Executor | None = None, asker: Asker | None = None) -> None:
    """Run or resume the study in ``directory`` to its total budget (see :class:`StudyRunner`); a person study's
    batches wait in ``asker`` for the person's answers (:mod:`robustgait.web`)."""
    StudyRunner(directory, run, progress=progress, verbose=verbose, executor=executor, asker=asker).run()
