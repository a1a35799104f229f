"""Where evaluations run (``docs/studies.md``): local worker processes (default) or Ray actors.

Every worker loads the robot and builds the gait generator once (seconds: docs/performance.md), then evaluates gait
after gait with it. The study's driver process keeps the database: workers receive parameters and return
:meth:`Evaluation.to_dict`, so they need no access to the study directory (Ray workers may run on other
machines). Each local worker gets one MuJoCo rollout thread per core rather than a share of the cores
(docs/studies.md: a batch of 5 gaits on 2 workers ends with one worker certifying alone, which then uses every
core); results do not depend on the thread count (the certificate is identical for any
count).

Both executors retry the task of a worker that died (a local process killed or crashed, a Ray actor
lost): local ones up to ``retries`` times by restarting the pool, Ray ones by restarting the actor and
re-running its task (``max_restarts`` / ``max_task_retries`` = unlimited).

The other way round, a local worker dies with the process that started it, however that process ends — even
by SIGKILL, which leaves it no chance to stop its workers (:func:`die_with_parent`; before, a study killed with
``kill -9`` left its two workers running, 0.76 GB each, until killed by hand). A local Ray that the Ray executor
started takes most of its processes down with the driver by itself, but its two agents outlived a killed driver by
62 s: a guard process takes them down at once (:func:`start_guard`). Nothing is lost: the study's database has
every completed evaluation, and ``study resume`` re-runs the interrupted ones (docs/studies.md).
"""

from __future__ import annotations

import contextlib
import ctypes
import multiprocessing
import multiprocessing.connection
import os
import signal
import sys
import threading
import time
from collections import deque
from collections.abc import Iterator
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass, replace
from typing import Any

from robustgait.config import RunConfig
from robustgait.errors import RobustGaitError

# Filled once per worker process by _init_worker: (robot, generator, evaluation config).
_WORKER: dict[str, Any] = {}
Task = dict[str, Any]  # evaluation_task or verification_task
PR_SET_PDEATHSIG = 1  # <linux/prctl.h>
GUARD_INTERVAL = 0.5  # seconds between the guard's looks at the processes below the driver
_BLAS_VARS = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")


@dataclass(frozen=True)
class WorkerSpec:
    """What a worker needs: the robot (shipped name or spec path), the study's configuration as plain data
    (:func:`robustgait.config.to_dict`; :func:`robustgait.study.evaluate.evaluate` uses its ``generate``, ``sim``
    and ``certify`` sections), MuJoCo threads, and IPOPT's log on/off."""

    robot: str
    config: dict[str, Any]
    threads: int = 1
    verbose: bool = False


class EvaluationWorker:
    """A robot and its gait generator, built once; :meth:`evaluate` many times."""

    def __init__(self, spec: WorkerSpec):
        from robustgait.config import Config, from_dict
        from robustgait.gaitgen import GaitGenerator
        from robustgait.io.robotfile import load_robot

        cfg = from_dict(Config, spec.config, "<study config>")
        self.config = replace(cfg, sim=replace(cfg.sim, n_threads=spec.threads))
        self.robot = load_robot(spec.robot)
        self.generator = GaitGenerator(self.robot, self.config.generate, verbose=spec.verbose)

    def run(self, task: Task) -> dict[str, Any]:
        """A task of :func:`evaluation_task` (:meth:`evaluate`) or :func:`verification_task` (:meth:`verify`), with
        its CPU time and when and where it ran."""
        cpu, wall = time.process_time(), time.time()
        out = self.verify(task["verify"], task.get("explored")) if "verify" in task else self.evaluate(task["params"],
                                                                                   task.get("verify_above"))
        # the worker runs one task at a time, so its process CPU time (every thread) is this task's
        out["cpu_seconds"] = time.process_time() - cpu
        # when it ran (POSIX s): an evaluation made ahead of its trial ran before the trial started
        out["worker"] = {"pid": os.getpid(), "host": os.uname().nodename, "cores": os.cpu_count() or 1,
                         "wall": [wall, time.time()]}
        return out

    def evaluate(self, params: dict[str, float], verify_above: float | None = None) -> dict[str, Any]:
        """:func:`robustgait.study.evaluate.evaluate` of ``params`` (its ``verify_above``), as a dict."""
        from robustgait.config import GaitParams
        from robustgait.study.evaluate import evaluate

        ev = evaluate(self.robot, GaitParams(**params), self.config, generator=self.generator,
                      verify_above=verify_above)
        return ev.to_dict()

    def verify(self, gait: dict[str, Any], explored: dict[str, Any] | None = None) -> dict[str, Any]:
        """The verified certificate of a study's gait (:func:`robustgait.study.evaluate.verify_gait`; ``explored``: its
        estimate's certificate, whose exploration is replayed)."""
        from robustgait.io.gaitfile import gait_from_dict
        from robustgait.study.evaluate import verify_gait

        return verify_gait(self.robot, gait_from_dict(gait), self.config, explored)

    def pid(self) -> int:
        return os.getpid()


def die_with_parent() -> list[str]:
    """Make this process (a worker started by :mod:`multiprocessing`) die by SIGKILL as soon as the process that
    started it dies, whatever killed it; returns the means in place (for the record and the tests).

    * ``pdeathsig`` (Linux): ``prctl(PR_SET_PDEATHSIG, SIGKILL)`` — the kernel kills this process when its parent
      exits, at once, even while it computes in C with the GIL held (a gait's IPOPT solve). The signal follows the
      *thread* that started this process: the executor's workers are started by the thread that runs the study
      (:meth:`LocalExecutor.submit`), which lives as long as the executor. A parent that died before the call is
      caught by comparing ``os.getppid()`` with the parent's pid afterwards (the orphan has been re-parented).
    * ``watchdog`` (everywhere): a daemon thread that waits on the parent's sentinel (:func:`multiprocessing.
      parent_process`: a pipe the parent holds open until it exits) and then kills this process; it needs the GIL,
      so a worker inside a long C call without ``pdeathsig`` (macOS, Windows) dies when that call returns.
    """
    parent = multiprocessing.parent_process()
    if parent is None:  # not a multiprocessing child: nothing to follow
        return []
    means = []
    if sys.platform.startswith("linux"):
        libc = ctypes.CDLL(None, use_errno=True)
        if libc.prctl(PR_SET_PDEATHSIG, int(signal.SIGKILL), 0, 0, 0) == 0:
            means.append("pdeathsig")
    if os.getppid() != parent.pid:  # the parent died before prctl: this process is an orphan already
        os.kill(os.getpid(), signal.SIGKILL)

    def watch() -> None:
        multiprocessing.connection.wait([parent.sentinel])
        os.kill(os.getpid(), signal.SIGKILL)

    threading.Thread(target=watch, name="robustgait-parent-watchdog", daemon=True).start()
    means.append("watchdog")
    return means


def proc_stat(pid: int) -> tuple[int, str, int] | None:
    """(parent pid, state, start time in clock ticks since boot) of a process, from /proc; None if it is gone."""
    try:
        with open(f"/proc/{pid}/stat") as f:
            text = f.read()
    except OSError:
        return None
    fields = text[text.rindex(")") + 2:].split()  # after the command name, which may hold spaces and parentheses
    return int(fields[1]), fields[0], int(fields[19])


def descendants(root: int) -> dict[int, int]:
    """Every living process below ``root`` (Linux: /proc; zombies are dead) → its start time, which with the pid
    names one process (a pid is reused only by a later process)."""
    children: dict[int, list[int]] = {}
    starts: dict[int, int] = {}
    for name in os.listdir("/proc"):
        if name.isdigit() and (s := proc_stat(int(name))) is not None and s[1] != "Z":
            children.setdefault(s[0], []).append(int(name))
            starts[int(name)] = s[2]
    out: dict[int, int] = {}
    todo = [root]
    while todo:
        for c in children.get(todo.pop(), []):
            out[c] = starts[c]
            todo.append(c)
    return out


def _guard(driver: int) -> None:
    """The guard process (:func:`start_guard`): while the driver lives, note the processes below it every
    :data:`GUARD_INTERVAL`; when it dies, SIGKILL those of them still running (the same pid and start time).

    Every process once seen below the driver is kept until it is gone, not only those of the last look: a look taken
    while the driver dies reads /proc as its children are re-parented, and finds only part of the tree (a raylet's
    agents are then no longer below the driver)."""
    parent = multiprocessing.parent_process()
    assert parent is not None
    me = os.getpid()
    seen: dict[int, int] = {}
    while True:
        seen = {pid: start for pid, start in seen.items() if _same_process(pid, start)}
        seen.update((pid, start) for pid, start in descendants(driver).items() if pid != me)
        if multiprocessing.connection.wait([parent.sentinel], timeout=GUARD_INTERVAL):
            break
    for pid, start in seen.items():
        if _same_process(pid, start):
            with contextlib.suppress(ProcessLookupError):
                os.kill(pid, signal.SIGKILL)


def _same_process(pid: int, start: int) -> bool:
    """Whether process ``pid`` still runs and is the one that started at ``start`` (a pid is reused only later)."""
    s = proc_stat(pid)
    return s is not None and s[1] != "Z" and s[2] == start


def start_guard() -> multiprocessing.process.BaseProcess | None:
    """A process that outlives this one by a moment: if this process dies, however (SIGKILL included), it kills every
    process this one left below it — the processes of a local Ray (:class:`RayExecutor`), which the driver cannot
    stop when it is killed. Stop it with ``terminate()`` before an orderly exit (a daemon: multiprocessing stops it
    at exit anyway). Linux only (it reads /proc): None elsewhere."""
    if not sys.platform.startswith("linux"):
        return None
    guard = multiprocessing.get_context("spawn").Process(target=_guard, args=(os.getpid(),), daemon=True,
                                                         name="robustgait-guard")
    guard.start()
    return guard


def _init_worker(spec: WorkerSpec) -> None:
    _WORKER["means"] = die_with_parent()  # first: a parent killed while the generator builds takes its worker along
    _WORKER["worker"] = EvaluationWorker(spec)


def _run_task(task: Task) -> dict[str, Any]:
    return _WORKER["worker"].run(task)


def evaluation_task(params: dict[str, float], verify_above: float | None = None) -> Task:
    """A worker's task: evaluate the gait of ``params`` (:meth:`EvaluationWorker.evaluate`)."""
    return {"params": params, "verify_above": verify_above}


def verification_task(gait: dict[str, Any], explored: dict[str, Any] | None = None) -> Task:
    """A worker's task: the verified certificate of a study's gait (:meth:`EvaluationWorker.verify`), with its
    estimate's certificate (``explored``, with its samples) when the study holds one."""
    return {"verify": gait, "explored": explored}


@contextlib.contextmanager
def blas_threads(n: int) -> Iterator[None]:
    """Set the BLAS/OpenMP thread variables that spawned workers inherit (restored afterwards): IPOPT's
    linear algebra in every worker must not spread over all cores."""
    old = {k: os.environ.get(k) for k in _BLAS_VARS}
    os.environ.update({k: str(n) for k in _BLAS_VARS})
    try:
        yield
    finally:
        for k, v in old.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v


class Executor:
    """Runs evaluations: :meth:`submit` (key, params) and :meth:`submit_verify` (key, gait), :meth:`next_result` →
    (key, result dict)."""

    workers: int = 1

    def start(self) -> None:
        """Start the workers now (each builds its robot and generator), before the first evaluation is submitted;
        they start on the first submit otherwise."""

    def submit(self, key: int, params: dict[str, float], verify_above: float | None = None) -> None:
        """Evaluate the gait of ``params`` (:func:`evaluation_task`)."""
        self.submit_task(key, evaluation_task(params, verify_above))

    def submit_verify(self, key: int, gait: dict[str, Any], explored: dict[str, Any] | None = None) -> None:
        """Verify a study's gait (:func:`verification_task`)."""
        self.submit_task(key, verification_task(gait, explored))

    def submit_task(self, key: int, task: Task) -> None:
        raise NotImplementedError

    def next_result(self) -> tuple[int, dict[str, Any]]:
        """The next finished evaluation (blocks; an error if none is pending)."""
        got = self._next(None)
        assert got is not None  # an untimed wait returns a finished evaluation
        return got

    def poll(self, timeout: float) -> tuple[int, dict[str, Any]] | None:
        """The next finished evaluation, waiting at most ``timeout`` seconds for one (None: none finished or none is
        pending)."""
        return self._next(timeout) if self.pending else None

    def _next(self, timeout: float | None) -> tuple[int, dict[str, Any]] | None:
        raise NotImplementedError

    @property
    def pending(self) -> int:
        raise NotImplementedError

    def close(self, wait: bool = True) -> None:
        """Stop the workers; ``wait=False`` abandons running evaluations (after an error or Ctrl-C)."""

    def __enter__(self) -> Executor:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


class LocalExecutor(Executor):
    """``workers`` processes (spawn context: no fork of a process holding threads and a database
    connection), started on the first submit, each with ``threads`` MuJoCo rollout threads (default: one
    per core, not cores // workers: while every worker certifies, the OS shares the cores among them; when
    a batch's last gait is certified alone, its worker uses the cores the others left idle)."""

    def __init__(self, spec: WorkerSpec, workers: int = 1, retries: int = 2, threads: int | None = None):
        if workers < 1:
            raise RobustGaitError(f"--workers must be ≥ 1, got {workers}")
        self.workers = workers
        self.spec = replace(spec, threads=threads if threads is not None else (os.cpu_count() or 1))
        self.retries = retries
        self._pool: ProcessPoolExecutor | None = None
        self._futures: dict[Future[dict[str, Any]], tuple[int, Task]] = {}
        self._attempts: dict[int, int] = {}
        self._env: contextlib.ExitStack | None = None

    def _ensure_pool(self) -> ProcessPoolExecutor:
        if self._env is None:  # workers inherit the environment when they are spawned
            self._env = contextlib.ExitStack()
            self._env.enter_context(blas_threads(1))
        if self._pool is None:
            self._pool = ProcessPoolExecutor(max_workers=self.workers, mp_context=multiprocessing.get_context("spawn"),
                                             initializer=_init_worker, initargs=(self.spec,))
        return self._pool

    def start(self) -> None:
        """Spawn every worker now: one empty task each (the pool starts a process per task while none is idle); their
        results are not results of the study."""
        if self._pool is None:
            pool = self._ensure_pool()
            for _ in range(self.workers):
                pool.submit(os.getpid)

    def submit_task(self, key: int, task: Task) -> None:
        self._futures[self._ensure_pool().submit(_run_task, task)] = (key, task)

    @property
    def pending(self) -> int:
        return len(self._futures)

    def _next(self, timeout: float | None) -> tuple[int, dict[str, Any]] | None:
        while True:
            if not self._futures:
                raise RobustGaitError("no evaluation is pending")
            done, _ = wait(list(self._futures), timeout=timeout, return_when=FIRST_COMPLETED)
            if not done:
                return None
            fut = next(iter(done))
            key, task = self._futures.pop(fut)
            try:
                return key, fut.result()
            except BrokenProcessPool:
                self._restart([(key, task)])

    def _restart(self, lost: list[tuple[int, Task]]) -> None:
        """A worker died: every task of the broken pool is lost; start a new pool and resubmit them."""
        lost += list(self._futures.values())
        self._futures.clear()
        if self._pool is not None:
            self._pool.shutdown(wait=False, cancel_futures=True)
            self._pool = None
        for key, task in lost:
            self._attempts[key] = self._attempts.get(key, 0) + 1
            if self._attempts[key] > self.retries:
                what = "verifying a gait" if "verify" in task else f"evaluating {task['params']}"
                raise RobustGaitError(f"a worker process died {self._attempts[key]} times {what}")
            self.submit_task(key, task)

    def close(self, wait: bool = True) -> None:
        if self._pool is not None:
            self._pool.shutdown(wait=wait, cancel_futures=True)
            self._pool = None
        if self._env is not None:
            self._env.close()
            self._env = None


class RayExecutor(Executor):
    """One Ray actor per worker, each with ``cpus_per_worker`` CPUs (and as many MuJoCo threads). Connects
    to ``address`` (e.g. ``auto``: a running cluster) or starts a local Ray, with a guard (:func:`start_guard`) that
    takes it down if this process is killed. A dead actor is restarted and its task re-run by Ray (unlimited
    restarts and task retries)."""

    def __init__(self, spec: WorkerSpec, workers: int = 1, address: str | None = None, cpus_per_worker: int = 1):
        try:
            import ray
        except ImportError:
            raise RobustGaitError('the Ray executor needs Ray: pip install "robustgait[ray]"') from None
        if workers < 1:
            raise RobustGaitError(f"--workers must be ≥ 1, got {workers}")
        self.ray = ray
        self.workers = workers
        self._own = not ray.is_initialized()
        # the local Ray is this process's: nothing of it may outlive a killed driver (guarded from before it starts)
        self._guard = start_guard() if self._own and address is None else None
        if self._own:
            kwargs: dict[str, Any] = {"include_dashboard": False, "log_to_driver": spec.verbose,
                                      "configure_logging": False}
            if address is None:
                kwargs["num_cpus"] = max(workers * cpus_per_worker, os.cpu_count() or 1)
            try:
                with blas_threads(1):
                    ray.init(address=address, **kwargs)
            except ConnectionError as exc:
                raise RobustGaitError(f"--address {address}: cannot connect to a Ray cluster ({exc})") from None
            finally:
                if not ray.is_initialized():
                    self._stop_guard()
        actor: Any = ray.remote(num_cpus=cpus_per_worker, max_restarts=-1, max_task_retries=-1)(EvaluationWorker)
        self.spec = replace(spec, threads=cpus_per_worker)
        self.actors: list[Any] = [actor.remote(self.spec) for _ in range(workers)]
        self._idle: deque[Any] = deque(self.actors)
        self._queue: deque[tuple[int, Task]] = deque()
        self._running: dict[Any, tuple[Any, int]] = {}

    def _dispatch(self) -> None:
        while self._idle and self._queue:
            actor = self._idle.popleft()
            key, task = self._queue.popleft()
            self._running[actor.run.remote(task)] = (actor, key)

    def submit_task(self, key: int, task: Task) -> None:
        self._queue.append((key, task))
        self._dispatch()

    @property
    def pending(self) -> int:
        return len(self._queue) + len(self._running)

    def _next(self, timeout: float | None) -> tuple[int, dict[str, Any]] | None:
        if not self._running:
            raise RobustGaitError("no evaluation is pending")
        ready, _ = self.ray.wait(list(self._running), num_returns=1, timeout=timeout)
        if not ready:
            return None
        actor, key = self._running.pop(ready[0])
        try:
            result = self.ray.get(ready[0])
        except self.ray.exceptions.RayError as exc:
            raise RobustGaitError(f"a Ray worker failed evaluating trial {key}: {exc}") from None
        self._idle.append(actor)
        self._dispatch()
        return key, result

    def pids(self) -> list[int]:
        """Process ids of the actors (blocks until they are built)."""
        return [int(pid) for pid in self.ray.get([a.pid.remote() for a in self.actors])]

    def close(self, wait: bool = True) -> None:
        for a in self.actors:
            self.ray.kill(a)
        self.actors = []
        if self._own:
            self.ray.shutdown()
        self._stop_guard()

    def _stop_guard(self) -> None:
        """An orderly end (or no Ray to guard): the guard has nothing to do."""
        if self._guard is not None:
            self._guard.terminate()
            self._guard.join()
            self._guard = None


def make_executor(run: RunConfig, spec: WorkerSpec) -> Executor:
    """The executor of ``run`` (``local`` or ``ray``) with ``run.n_workers`` workers."""
    if run.executor == "local":
        if run.address is not None:
            raise RobustGaitError("run.address (--address) is for the Ray executor (--executor ray)")
        return LocalExecutor(spec, run.n_workers)
    return RayExecutor(spec, run.n_workers, run.address)
