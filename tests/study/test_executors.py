"""Executors (study/executors.py): a study killed with SIGKILL leaves no process behind — its local workers die with
it (prctl PR_SET_PDEATHSIG and a watchdog thread), and a Ray cluster it started is taken down by its guard (on the
interrupted Ray study that tests/study/test_study.py resumes: :func:`run_interrupted_ray_study`)."""

from __future__ import annotations

import json
import os
import shutil
import signal
import sqlite3
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path

import pytest

from robustgait.study.executors import descendants, proc_stat

REPO = Path(__file__).resolve().parents[2]
# a study that keeps its workers busy for a while: 1 iteration of 2 gaits, a 5-step walk, 10 certificate samples
CLI_SMALL = ["--robot", "exo", "--iterations", "1", "--batch", "2", "--method", "uniform", "--samples", "10", "--steps",
             "5", "--seed", "0", "--quiet"]


def alive(procs: dict[int, int]) -> dict[int, str]:
    """The processes of ``procs`` (pid → start time) still running (zombies are dead: they hold no memory) → name."""
    out = {}
    for pid, start in procs.items():
        s = proc_stat(pid)
        if s is not None and s[1] != "Z" and s[2] == start:
            out[pid] = Path(f"/proc/{pid}/comm").read_text().strip() if Path(f"/proc/{pid}/comm").exists() else "?"
    return out


def cpu_seconds(pid: int) -> float:
    """User + system CPU time [s] a process has used (/proc; 0 if it is gone)."""
    try:
        text = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return 0.0
    fields = text[text.rindex(")") + 2:].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def cmdline(pid: int) -> str:
    try:
        return Path(f"/proc/{pid}/cmdline").read_bytes().replace(b"\0", b" ").decode(errors="replace")
    except OSError:
        return ""


def local_worker(pid: int, name: str) -> bool:
    """A local executor's worker: a multiprocessing child, not its resource tracker (which only waits)."""
    cmd = cmdline(pid)
    return "multiprocessing" in cmd and "resource_tracker" not in cmd


def ray_actor(pid: int, name: str) -> bool:
    return name.startswith("ray::Evaluation")


def workers_at_work(procs: dict[int, int], worker: Callable[[int, str], bool], cpu: float = 0.5) -> bool:
    """Whether every evaluating process below the study (``worker`` says which) has used ``cpu`` s of CPU: well past
    its start, whose first act is to arm its death with its parent
    (:func:`robustgait.study.executors.die_with_parent`)."""
    workers = [pid for pid, name in alive(procs).items() if worker(pid, name)]
    return bool(workers) and all(cpu_seconds(pid) >= cpu for pid in workers)


def kill_study_and_watch(tmp_path: Path, extra: list[str], ready: Callable[[dict[int, str]], bool], timeout: float,
                         worker: Callable[[int, str], bool] = local_worker) -> tuple[dict[int, int], float]:
    """Start ``study run`` with ``extra`` options in its own session, wait until ``ready`` says yes to the processes
    below it (pid → name), SIGKILL it alone, and wait up to ``timeout`` s for them to go: (the processes it had,
    seconds until all went or the timeout)."""
    env = {**os.environ, "PYTHONPATH": str(REPO / "src")}
    proc = subprocess.Popen([sys.executable, "-m", "robustgait.cli", "study", "run", str(tmp_path / "study"),
                             *CLI_SMALL, *extra], env=env, start_new_session=True, stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL)
    procs: dict[int, int] = {}
    try:
        t0 = time.monotonic()
        while not ready(alive(procs)):
            assert proc.poll() is None, "the study ended before it could be killed"
            assert time.monotonic() - t0 < 180, f"the study started only {alive(procs)}"
            time.sleep(0.2)
            procs = descendants(proc.pid)
        while not workers_at_work(procs, worker):  # past their start-up, which arms their death with the study
            assert proc.poll() is None, "the study ended before it could be killed"
            assert time.monotonic() - t0 < 180, f"the workers did not start working: {alive(procs)}"
            time.sleep(0.1)
            procs = descendants(proc.pid)
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait()
        killed = time.monotonic()
        while alive(procs) and time.monotonic() - killed < timeout:
            time.sleep(0.1)
        return procs, time.monotonic() - killed
    finally:
        for pid in alive(procs):  # whatever the assertion below says, leave nothing running
            os.kill(pid, signal.SIGKILL)
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)


@pytest.mark.slow  # seconds of its own: plain pytest stays ≤ 60 s; CI runs it
@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")
def test_a_sigkilled_study_leaves_no_worker_behind(tmp_path):
    """2 local workers (and multiprocessing's resource tracker) below the study; SIGKILL the study process alone:
    within 5 s none of them runs. Before, both workers ran on (0.76 and 0.80 GB) until killed by hand."""
    procs, took = kill_study_and_watch(tmp_path, ["--workers", "2"], lambda p: len(p) >= 3, timeout=5.0)
    assert len(procs) >= 3
    left = alive(procs)
    assert not left, f"left running {took:.1f} s after the study was killed: {left}"


def trial_states(db: Path) -> dict[str, int]:
    """How many trials of a study's database are in each state (read-only; none while it cannot be read)."""
    try:
        with sqlite3.connect(f"file:{db}?mode=ro", uri=True, timeout=5) as con:
            return dict(con.execute("select state, count(*) from trials group by state").fetchall())
    except sqlite3.Error:
        return {}


def run_interrupted_ray_study(root: Path) -> None:
    """The tiny study (tests/study/test_study.py's ``CLI_TINY``, as conftest's ``tiny_study``) as ``study run
    --executor ray --workers 2`` in ``root/study``, interrupted twice: one of its two Ray actors is SIGKILLed half a CPU
    second into a gait's evaluation (its process title names the task), then — its first iteration complete, so the
    killed actor's task was run again, and a gait of the second being evaluated — the study process alone is
    SIGKILLed, and everything below it must be gone within 5 s (its guard takes the local Ray down). A copy of the
    study as the kill left it goes to ``root/killed``; ``study resume --executor ray --workers 1`` finishes
    ``root/study``. What was seen goes to ``root/facts.json``: the actors, the one killed, those that replaced it,
    the processes at the kill and those left, and the resume's exit code and error output."""
    from tests.study.test_study import CLI_TINY, cli

    d = root / "study"
    env = {**os.environ, "PYTHONPATH": str(REPO / "src")}
    with open(root / "run.err", "w") as err:
        proc = subprocess.Popen([sys.executable, "-m", "robustgait.cli", "study", "run", str(d), *CLI_TINY,
                                 "--executor", "ray", "--workers", "2", "--quiet"], env=env, start_new_session=True,
                                stdout=subprocess.DEVNULL, stderr=err)
    procs: dict[int, int] = {}
    task_cpu: dict[int, float] = {}  # actor → its CPU time when it was first seen evaluating

    def wait_for(what: str, done: Callable[[], object]) -> object:
        t0 = time.monotonic()
        while not (out := done()):
            assert proc.poll() is None, f"the study ended before {what}: {(root / 'run.err').read_text()[-2000:]}"
            assert time.monotonic() - t0 < 900, f"no {what} in 900 s: {alive(procs)}"
            time.sleep(0.1)
        return out

    def actors() -> list[int]:
        procs.update(descendants(proc.pid))
        return sorted(pid for pid, name in alive(procs).items() if ray_actor(pid, name))

    def evaluating() -> int | None:
        """An actor half a CPU second into a task (Ray titles an actor's process with the method it runs)."""
        for pid in actors():
            if "EvaluationWorker.run" in cmdline(pid):
                task_cpu.setdefault(pid, cpu_seconds(pid))
                if cpu_seconds(pid) >= task_cpu[pid] + 0.5:
                    return pid
        return None

    try:
        victim = int(wait_for("actor evaluating a gait", evaluating))  # type: ignore[call-overload]
        first = actors()
        os.kill(victim, signal.SIGKILL)
        restarted = wait_for("actor in place of the killed one", lambda: [p for p in actors() if p not in first])

        def second_iteration_running() -> bool:
            states = trial_states(d / "study.db")
            return states.get("COMPLETE", 0) >= 3 and states.get("RUNNING", 0) >= 1

        wait_for("gait of the second iteration being evaluated", second_iteration_running)
        actors()  # every process below the study now
        at_kill = alive(procs)
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait()
        killed = time.monotonic()
        while alive(procs) and time.monotonic() - killed < 5.0:
            time.sleep(0.1)
        left = alive(procs)
        facts = {"actors": first, "killed_actor": victim, "restarted": restarted,
                 "processes": {str(pid): name for pid, name in at_kill.items()},
                 "left": {str(pid): name for pid, name in left.items()},
                 "seconds_to_go": time.monotonic() - killed}
    finally:
        for pid in alive(procs):  # whatever the tests say, leave nothing running
            os.kill(pid, signal.SIGKILL)
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
    shutil.copytree(d, root / "killed")
    res = cli("study", "resume", str(d), "--executor", "ray", "--workers", "1", "--quiet")
    facts["resume"] = {"returncode": res.returncode, "stderr": res.stderr}
    (root / "facts.json").write_text(json.dumps(facts))


@pytest.mark.slow
@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")
def test_a_sigkilled_ray_study_leaves_no_ray_process_behind(interrupted_study):
    """--executor ray: the local Ray the study started (GCS, raylet, agents, actors) and the guard; SIGKILL the study
    process alone (conftest's ``interrupted_study``, :func:`run_interrupted_ray_study`): within 5 s none of them runs.
    Without the guard Ray's two agents ran on for 62 s."""
    facts = interrupted_study["facts"]
    # GCS, raylet, monitor, dashboard, log monitor, 2 agents, 2 actors (and the guard)
    assert len(facts["processes"]) >= 9, facts["processes"]
    assert not facts["left"], f"left running {facts['seconds_to_go']:.1f} s after the study was killed: {facts['left']}"
