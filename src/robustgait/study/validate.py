"""Every unique gait of a study under the same disturbances (``robustgait study validate DIR``): does
r* — or the steps taken — predict how often a gait survives disturbances it never met in the study?

One :class:`~robustgait.config.ValidateConfig` for all gaits, so every gait meets the same draws (common
random numbers: :mod:`robustgait.validate.disturbances` draws from the seed and the robot only). The simulation
and certificate options are the study's (its ``sim`` and ``certify`` sections): the study's certificates were
computed with them, and their fixed points are found again with them.

Which gaits, and where their trials start:

* one gait per grid point of the action space (a gait proposed again is the same gait: its first trial);
* ``certified`` gaits start every trial on their periodic orbit — the fixed point of the study's certificate
  (``gaits/<label>/certificate.json``), exactly as ``robustgait validate GAIT --certificate CERT``;
* gaits that ``fell`` before the step cap or were ``not_certified`` have no certified fixed point: their trials
  start from the gait's initial state (where the study's walk started; a multi-contact gait walked on to its first
  heel strike, the section its trials start from), with r* = 0 as in the study, and no certificate check. Without
  them every validated gait would have walked the cap and the steps-taken correlation could never be defined;
* ``generation_failed`` gaits have no gait file: skipped and counted; gaits the validation refuses (a gait that
  falls in its first undisturbed step) are skipped with the reason.

Files, in the study directory (every one written atomically by :mod:`robustgait.io.output`)::

    DIR/validation/<kind>.json                            the last run's summary of one kind: config, one
                                                          row per gait, the skipped gaits, the correlations
    DIR/validation/runs/<kind>-<config key>/<label>.json  one gait's results with every trial, written as
                                                          soon as that gait is done

A run reuses every per-gait file whose key matches — the SHA-256 of the gait and certificate files and of
the validation config (:func:`config_key`) — so a killed run continues where it stopped and a repeated run
computes nothing.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import multiprocessing
import os
import sys
import time
from collections.abc import Iterator, Sequence
from concurrent.futures import Future, ProcessPoolExecutor, as_completed
from concurrent.futures.process import BrokenProcessPool
from dataclasses import asdict, dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np
from tqdm import tqdm

from robustgait.config import KINDS, CertifyConfig, SimConfig, ValidateConfig, radius_name, to_dict
from robustgait.config.certify import orbit_options
from robustgait.errors import RobustGaitError, input_error
from robustgait.io.certfile import certificate_value
from robustgait.io.output import write_json
from robustgait.io.schema import read_json
from robustgait.io.studyfile import load_config
from robustgait.study.outcome import EvaluationStatus
from robustgait.study.storage import current_names
from robustgait.validate.disturbances import SIZE_LABELS
from robustgait.validate.stats import Correlation, spearman

VALIDATION_DIR = "validation"
RUNS_DIR = "runs"
FORMAT_VERSION = 2


@dataclass(frozen=True)
class StudyGait:
    """One unique gait of a study as the study saw it: the trials that proposed it, its parameters and
    outcome (``status``, ``value`` — its verified J* or r*, 0 unless certified —, ``steps_taken`` of ``step_cap``), and
    its files (relative to the study directory; None when not written)."""

    label: str
    trials: tuple[int, ...]
    grid_index: int
    params: dict[str, float]
    status: str
    reason: str
    value: float
    steps_taken: int
    step_cap: int
    gait_file: str | None
    certificate_file: str | None

    def row(self) -> dict[str, Any]:
        return {k: list(v) if isinstance(v, tuple) else v for k, v in asdict(self).items()}


def study_gaits(directory: Path) -> tuple[dict[str, Any], list[StudyGait]]:
    """The study's status and its unique gaits (completed trials, first trial of each grid index)."""
    from robustgait.study.status import study_status
    from robustgait.study.verify import params_label

    st = study_status(directory)
    done = sorted((t for t in st["trials"] if t["state"] == "COMPLETE"), key=lambda t: t["number"])
    if not done:
        raise input_error(directory, "the study has no completed trial: nothing to validate")
    by_index: dict[int, list[dict[str, Any]]] = {}
    for t in done:
        by_index.setdefault(t["grid_index"], []).append(t)
    out = []
    for ts in by_index.values():
        t = next((x for x in ts if x["reused_from"] is None), ts[0])
        gait_file = t["gait_file"]
        label = Path(gait_file).parent.name if gait_file else params_label(t["params"])
        out.append(StudyGait(label, tuple(x["number"] for x in ts), int(t["grid_index"]), dict(t["params"]),
                             str(t["status"]), str(t["reason"] or ""),
                             float(t["value"] or 0.0),
                             int(t["steps_taken"] or 0), int(t["step_cap"] or st["config"]["sim"]["step_cap"]),
                             gait_file, t["certificate_file"] if t["verified"] else None))
    return st, sorted(out, key=lambda g: g.trials[0])


def config_key(config: ValidateConfig, certify: CertifyConfig, sim: SimConfig, kind: str) -> str:
    """16 hex digits of the SHA-256 of the kind and everything the results depend on: the validation config (not
    its workers nor the kind choice), the certificate and simulation options (not the rollout threads)."""
    parts = {"validate": {k: v for k, v in to_dict(config).items() if k not in ("workers", "disturbance")},
             "certify": to_dict(certify), "sim": to_dict(replace(sim, n_threads=0))}
    text = json.dumps({"format_version": FORMAT_VERSION, "kind": kind, "config": parts}, sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def _files_key(directory: Path, g: StudyGait) -> str:
    h = hashlib.sha256()
    for rel in (g.gait_file, g.certificate_file):
        try:
            h.update(b"\0" if rel is None else (directory / rel).read_bytes())
        except OSError as exc:
            raise input_error(directory / str(rel), f"cannot read the study's file ({exc.strerror or exc})") from None
    return h.hexdigest()


def run_path(directory: Path, kind: str, key: str, label: str) -> Path:
    return directory / VALIDATION_DIR / RUNS_DIR / f"{kind}-{key}" / f"{label}.json"


def summary_path(directory: str | Path, kind: str) -> Path:
    return Path(directory) / VALIDATION_DIR / f"{kind}.json"


# ---- one gait (in a worker process or in this one) -------------------------------------------------------
@dataclass(frozen=True)
class _Task:
    label: str
    robot: str
    gait: str
    certificate: str | None
    config: ValidateConfig
    certify: CertifyConfig
    sim: SimConfig
    kinds: tuple[str, ...]
    certified: bool = False  # the study certified this gait (its trials start on its periodic orbit)
    recertify: bool = False  # certify it again with ``certify`` instead of reading the study's certificate


def orbitless_start(robot: Any, gait: Any, c: CertifyConfig) -> tuple[Any, Any]:
    """A start and a :class:`CertificateRef` of r* = 0 for a gait without a certified fixed point: its initial
    state as a section state (a multi-contact gait walked to its first heel strike), x̄ of that state (the
    certificate's state, identity transform) as the 'centre' (there is no set: nothing lies inside it)."""
    from robustgait.certificate.orbit import FixedPoint
    from robustgait.certificate.reduced import ReducedState, reduce_state
    from robustgait.certificate.search import initial_section
    from robustgait.sim.factory import make_engine
    from robustgait.validate.run import CertificateRef

    if gait.initial_state is None:
        raise RobustGaitError("the gait has no initial state to start the trials from")
    engine = make_engine(robot, gait)
    try:  # a multi-contact gait: walked from its start to its first heel strike
        qs, vs = initial_section(robot, gait, engine)
    except RobustGaitError as exc:
        raise RobustGaitError(f"no section state to start the trials from: {exc}") from None
    finally:
        engine.close()
    q, v = qs[0], vs[0]
    start = FixedPoint(q.copy(), v.copy(), reduce_state(q[None], v[None], c.frame)[0], 0)
    state = "omega" if c.space == "push" else c.state
    xbar = ReducedState.at(state, robot, q, v, gait.stance, c).x_star
    k = xbar.shape[0]
    ref = CertificateRef(0.0, False, tuple(float(x) for x in xbar), tuple(tuple(r) for r in np.eye(k).tolist()),
                         c.space, c.set, c.horizon, None, c.map, c.frame, c.reconstruction,
                         tuple(orbit_options(c).items()),
                         "none: no certified fixed point (started from the gait's initial state)")
    return start, ref


def _validate_one(task: _Task) -> dict[str, Any]:
    """Validate one gait against ``task.kinds``: {label, certificate, setup_seconds, kinds: {kind:
    KindResult.to_dict()}} or {label, error} when the validation refuses the gait."""
    from robustgait.io.gaitfile import load_gait
    from robustgait.io.robotfile import load_robot
    from robustgait.validate.run import Validator

    try:
        robot = load_robot(task.robot)
        gait = load_gait(task.gait, robot)
        if task.certified and task.recertify:
            start, ref = None, None  # the Validator certifies the gait with task.certify
        elif task.certificate:
            start, ref = None, task.certificate
        else:
            start, ref = orbitless_start(robot, gait, task.certify)
        with Validator(robot, gait, task.config, certify=task.certify, sim=task.sim, certificate=ref,
                       start=start) as v:
            kinds = {k: v.run(k).to_dict(trials=True) for k in task.kinds}
            return {"label": task.label, "certificate": v.certificate.to_dict(), "setup_seconds": v.seconds_setup,
                    "kinds": kinds}
    except RobustGaitError as exc:
        return {"label": task.label, "error": str(exc)}


@contextlib.contextmanager
def _results(tasks: list[_Task], workers: int) -> Iterator[Iterator[dict[str, Any]]]:
    """Yield the tasks' results as they finish: in this process (``workers`` = 1; the rollout uses every
    core) or in ``workers`` spawned processes with cores // workers rollout threads each, which die with this one
    however it ends (:func:`robustgait.study.executors.die_with_parent`)."""
    if workers <= 1 or len(tasks) <= 1:
        yield (_validate_one(t) for t in tasks)
        return
    from robustgait.study.executors import blas_threads, die_with_parent

    n = min(workers, len(tasks))
    threads = max(1, (os.cpu_count() or 1) // n)
    with blas_threads(1):
        pool = ProcessPoolExecutor(max_workers=n, mp_context=multiprocessing.get_context("spawn"),
                                   initializer=die_with_parent)
    ok = False
    try:
        futures: list[Future[dict[str, Any]]] = [
            pool.submit(_validate_one, replace(t, sim=replace(t.sim, n_threads=threads)))
            for t in tasks]
        yield (f.result() for f in as_completed(futures))
        ok = True
    except BrokenProcessPool:
        raise RobustGaitError("a validation worker process died (killed, or out of memory?); the gaits done so "
                              "far are stored: run the same command again to continue") from None
    finally:
        pool.shutdown(wait=ok, cancel_futures=True)


# ---- the study ---------------------------------------------------------------------------------------------
def _load_run(path: Path, key: str, files: str) -> dict[str, Any] | None:
    """A stored per-gait result if it is for these files and this config, else None."""
    if not path.is_file():
        return None
    try:
        raw = read_json(path, "stored validation")
    except RobustGaitError:
        return None  # unreadable: computed again and replaced
    if not isinstance(raw, dict) or raw.get("config_key") != key or raw.get("files_sha256") != files:
        return None
    return raw


def validate_study(directory: str | Path, config: ValidateConfig | None = None,
                   kinds: Sequence[str] | None = None, *, certify: CertifyConfig | None = None,
                   progress: bool = True) -> dict[str, dict[str, Any]]:
    """Validate every unique gait of the study in ``directory`` against each of ``kinds`` (default
    ``config.kinds``; ``("all",)``: every kind) with one config, the study's certificate and simulation options,
    in ``config.workers`` processes. ``certify``: certificate options other than the study's (e.g. another state,
    set or horizon): every gait the study certified is certified again with them and checked against that
    certificate (its r* is the one correlated); write ``DIR/validation/<kind>.json`` per kind and return those summaries
    ({kind: summary}, see :func:`kind_summary`). Gaits already validated with the same files and config are not
    run again (module docstring)."""
    from robustgait.io.gaitfile import load_gait
    from robustgait.io.robotfile import load_robot
    from robustgait.validate.run import check_validate_work

    t0 = time.perf_counter()
    d = Path(directory)
    setup = load_config(d)
    cfg = config or ValidateConfig()
    sim = replace(setup.config.sim, n_threads=0)
    recertify = certify is not None and certify != setup.config.study_certify
    certify = certify if certify is not None else setup.config.study_certify
    kinds = list(cfg.kinds if kinds is None else (KINDS if "all" in kinds else dict.fromkeys(kinds)))
    for k in kinds:
        if k not in KINDS:
            raise RobustGaitError(f"unknown disturbance {k!r} (choose from {', '.join(KINDS)} or all)")
    status, gaits = study_gaits(d)
    estimated = [g.grid_index for g in gaits if g.status == EvaluationStatus.ESTIMATED]
    if estimated and not recertify:  # the validation checks verified certificates: verified on demand
        from robustgait.study.verify import verify_now

        verify_now(d, estimated)
        status, gaits = study_gaits(d)
    runnable = [g for g in gaits if g.gait_file is not None]
    if not runnable:
        raise input_error(d, f"no gait of the study has a gait file ({len(gaits)} unique gaits, all failed "
                          "generation): nothing to validate")
    robot = load_robot(setup.robot)
    for g in runnable:  # bound the work before any of it (as `robustgait validate` does)
        assert g.gait_file is not None
        check_validate_work(robot, load_gait(d / g.gait_file, robot), cfg, sim, kinds=len(kinds), certify=certify,
                            certifying=recertify and g.certificate_file is not None, what=f"{d / g.gait_file}: ")
    keys = {k: config_key(cfg, certify, sim, k) for k in kinds}
    files = {g.label: _files_key(d, g) for g in runnable}
    results: dict[str, dict[str, dict[str, Any]]] = {g.label: {} for g in runnable}
    cached: dict[str, set[str]] = {g.label: set() for g in runnable}
    tasks = []
    for g in runnable:
        for k in kinds:
            got = _load_run(run_path(d, k, keys[k], g.label), keys[k], files[g.label])
            if got is not None:
                results[g.label][k] = got
                cached[g.label].add(k)
        missing = tuple(k for k in kinds if k not in results[g.label])
        if missing:
            assert g.gait_file is not None
            tasks.append(_Task(g.label, setup.robot, str(d / g.gait_file),
                               str(d / g.certificate_file) if g.certificate_file else None, cfg, certify, sim, missing,
                               certified=g.certificate_file is not None, recertify=recertify))
    errors = _run_tasks(d, tasks, len(runnable), kinds, keys, files, results, cfg.workers, progress)
    seconds = time.perf_counter() - t0
    out = {}
    for k in kinds:
        summary = kind_summary(k, cfg, certify, sim, keys[k], status, gaits,
                               {lb: r[k] for lb, r in results.items() if k in r},
                               {lb for lb, c in cached.items() if k in c}, errors, seconds)
        (d / VALIDATION_DIR).mkdir(exist_ok=True)
        write_json(summary_path(d, k), summary)
        out[k] = summary
    return out


def _run_tasks(d: Path, tasks: list[_Task], n_gaits: int, kinds: list[str], keys: dict[str, str],
               files: dict[str, str], results: dict[str, dict[str, dict[str, Any]]], workers: int,
               progress: bool) -> dict[str, str]:
    """Validate the gaits of ``tasks`` in ``workers`` processes, each kind's result written to its run file as it
    finishes and put in ``results`` (label → kind → stored run, in place); returns {label: error} of the gaits whose
    validation failed. ``n_gaits``: the gaits validated in all (a bar's total; the others were cached)."""
    errors: dict[str, str] = {}
    with tqdm(total=n_gaits, initial=n_gaits - len(tasks), desc=f"study validate {','.join(kinds)}",
              unit="gait", file=sys.stderr, disable=not progress, dynamic_ncols=True) as bar, \
            _results(tasks, workers) as finished:
        for res in finished:
            label = res["label"]
            if "error" in res:
                errors[label] = res["error"]
            else:
                for k, kr in res["kinds"].items():
                    stored = {"format_version": FORMAT_VERSION, "kind": k, "label": label, "config_key": keys[k],
                              "files_sha256": files[label], "certificate": res["certificate"],
                              "setup_seconds": res["setup_seconds"], "result": kr}
                    path = run_path(d, k, keys[k], label)
                    path.parent.mkdir(parents=True, exist_ok=True)
                    write_json(path, stored)
                    results[label][k] = json.loads(json.dumps(stored))  # as a later run reads it back
                sr = next(iter(res["kinds"].values()))["success"]
                bar.set_postfix_str(f"{label}: success {sr['k']}/{sr['n']}")
            bar.update(1)
    return errors


def kind_summary(kind: str, config: ValidateConfig, certify: CertifyConfig, sim: SimConfig, key: str,
                 status: dict[str, Any], gaits: list[StudyGait],
                 stored: dict[str, dict[str, Any]], cached: set[str], errors: dict[str, str],
                 seconds: float) -> dict[str, Any]:
    """JSON-ready summary of one kind: ``gaits`` (one row per validated gait: the study's view of it — params,
    status, ``study_value``, steps — the ``value`` its trials were checked against (J* or r* of its certificate file,
    0 without one) and its success rate with the 95 % Wilson interval, the size at which half fail, the certificate
    check, where its trials started, whether it came from an earlier run), ``skipped`` (with the reason) and
    ``skipped_counts``, and ``correlations`` (Spearman ρ, p, n of the certificate's value with the success rate
    (``value``) and with s₅₀ (``value_critical``), of steps taken with the success rate (``steps_taken``), or undefined
    with the reason)."""
    name, unit = SIZE_LABELS[kind]
    rows, skipped = [], []
    for g in gaits:
        if g.label in stored:
            res = stored[g.label]["result"]
            cert = stored[g.label]["certificate"]
            rows.append({**g.row(), "value": certificate_value(cert) if g.certificate_file else 0.0,
                         "study_value": g.value,
                         "start": "fixed_point" if g.certificate_file else "initial_state",
                         "certificate": stored[g.label]["certificate"], "success": res["success"],
                         "critical": res["critical"], "size_range": res["size_range"],
                         "certificate_check": res["certificate_check"] if g.certificate_file else None,
                         "fall_reasons": res["fall_reasons"], "from_earlier_run": g.label in cached,
                         "seconds": res["seconds"]})
        elif g.gait_file is None:
            skipped.append({**g.row(), "why": f"no gait file ({g.status}: {g.reason})"})
        else:
            skipped.append({**g.row(), "why": errors.get(g.label, "not validated")})
    counts: dict[str, int] = {}
    for s in skipped:
        what = EvaluationStatus.GENERATION_FAILED.value if s["gait_file"] is None else "refused"
        counts[what] = counts.get(what, 0) + 1
    success = np.array([r["success"]["rate"] for r in rows], dtype=float)
    y = f"{kind} success"
    cap = status["config"]["sim"]["step_cap"]
    steps = np.array([r["steps_taken"] for r in rows], dtype=float)
    corr_steps = spearman(steps, success, "steps taken", y)
    if corr_steps.reason.startswith("steps taken is the same") and steps[0] == cap:
        corr_steps = replace(corr_steps, reason=f"{corr_steps.reason}: every validated gait walked the step cap")
    value = np.array([r["value"] for r in rows], dtype=float)
    s50 = np.array([np.nan if r["critical"]["s50"] is None else r["critical"]["s50"] for r in rows], dtype=float)
    has = np.isfinite(s50)
    star = radius_name(certify.space)  # the certificate the gaits carry
    correlations: dict[str, Correlation] = {
        "value": spearman(value, success, star, y),
        "value_critical": spearman(value[has], s50[has], star, f"{kind} s₅₀ (gaits with a fit)"),
        "steps_taken": corr_steps}
    return {"format_version": FORMAT_VERSION, "kind": kind, "size": name, "unit": unit, "config": to_dict(config),
            "certify": to_dict(certify), "sim": to_dict(sim), "config_key": key,
            "study": {k: status[k] for k in ("directory", "robot", "metric", "learner", "state", "trials_done",
                                             "trials_planned", "unique_gaits")} | {"step_cap": cap},
            "n_validated": len(rows), "n_from_earlier_runs": sum(r["from_earlier_run"] for r in rows),
            "gaits": rows, "skipped": skipped, "skipped_counts": counts,
            "correlations": {k: c.to_dict() for k, c in correlations.items()}, "seconds": seconds}


def load_summaries(directory: str | Path) -> dict[str, dict[str, Any]]:
    """The stored summaries of ``study validate`` in ``DIR/validation/`` ({kind: summary}, kinds in
    :data:`KINDS` order; none: {}), the gaits' and correlations' keys read by
    :func:`~robustgait.study.storage.current_names`. A file that cannot be read raises a one-line error naming it."""
    out = {}
    for k in KINDS:
        p = summary_path(directory, k)
        if p.is_file():
            raw = read_json(p, "study validation summary")
            if not isinstance(raw, dict) or raw.get("format_version") != FORMAT_VERSION:
                raise input_error(p, f"unsupported study validation file (format_version {FORMAT_VERSION} expected)")
            out[k] = {**raw, "gaits": [current_names(g) for g in raw.get("gaits", [])],
                      "skipped": [current_names(g) for g in raw.get("skipped", [])],
                      "correlations": current_names(raw.get("correlations", {}))}
    return out
