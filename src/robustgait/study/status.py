"""What a study holds: trials, per-iteration records, its best gait (``robustgait study status``).

Reads the database only (it never runs anything, and works while the study runs)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from robustgait.config import radius_name
from robustgait.io.studyfile import environment_changes, load_config
from robustgait.study.evaluate import refusal_of
from robustgait.study.outcome import EvaluationStatus, status_of
from robustgait.study.person import pending_iteration, stored_floor
from robustgait.study.run import completed_batches, is_running, open_store
from robustgait.study.storage import TrialRecord
from robustgait.study.trials import trial_summary


def figure_text(entry: dict[str, Any], unit: str, digits: int = 4) -> str:
    """A gait's certificate figure as a person reads it (an entry of ``trials`` or ``best``): the verified value,
    "≈ the estimate (estimated)" for a gait whose certificate was only estimated, or "—" for one without (``unit``
    empty: the number alone)."""
    unit = f" {unit}" if unit else ""
    if entry.get("verified") and entry.get("value") is not None:
        return f"{entry['value']:.{digits}g}{unit} (verified)"
    if status_of(entry) == EvaluationStatus.ESTIMATED and entry.get("estimate") is not None:
        return f"≈ {entry['estimate']:.{digits}g}{unit} (estimated)"
    return "—"


def _best_entry(r: TrialRecord | None, records: dict[int, TrialRecord],
                verifications: dict[int, dict[str, Any]]) -> dict[str, Any] | None:
    if r is None:
        return None
    src = records.get(r.reused_from, r) if r.reused_from is not None else r
    s = trial_summary(r, verifications.get(r.index))
    v = trial_summary(src, verifications.get(r.index))
    return {"trial": r.number, "iteration": r.iteration, "params": r.params, "grid_index": r.index,
            "value": s["value"], "estimate": s["estimate"], "verified": s["verified"],
            "steps_taken": s["steps_taken"],
            "status": s["status"], "score": r.value, "comfort": s["comfort"], "gait_file": v["gait_file"],
            "certificate_file": v["certificate_file"]}


def outcome_counts(records: list[TrialRecord], verifications: dict[int, dict[str, Any]] | None = None
                   ) -> dict[str, int]:
    """How the evaluated gaits ended (COMPLETE trials, a reused evaluation counted once per trial): ``certified``
    (verified), ``estimated`` (a certificate estimated, not verified), ``refused: <status>`` (walked the cap without a
    certificate — the certificate's refusal: unsettled, unstable, fell in its search …), ``fell`` (before the cap),
    ``generation_failed``; an estimated gait verified later counts as its verification ended."""
    out: dict[str, int] = {}
    for r in records:
        if r.state != "COMPLETE" or r.result is None:
            continue
        res = trial_summary(r, (verifications or {}).get(r.index))
        key = str(res.get("status"))
        if key == EvaluationStatus.NOT_CERTIFIED:
            refusal = refusal_of(res)
            key = "refused" if refusal is None else f"refused: {refusal.value}"
        out[key] = out.get(key, 0) + 1
    return dict(sorted(out.items()))


def utilisation(records: list[TrialRecord]) -> dict[str, float] | None:
    """How much of the machine the study's evaluations used: ``cpu_seconds`` Σ of the evaluations' process CPU time
    (every thread; an evaluation reused from another trial counted once), ``busy_seconds`` the wall time during which
    at least one evaluation ran (the union of the evaluations' intervals as their workers recorded them — a trial's
    start–complete interval when its worker did not: time the study was stopped, or spent between batches on the
    learner, is not counted), ``cores`` of the machine, and ``share`` = cpu_seconds / (busy_seconds × cores) ∈ [0, 1].
    None when no completed evaluation recorded its CPU time."""
    done = [r for r in records if r.state == "COMPLETE" and r.reused_from is None and r.started is not None
            and r.completed is not None and (r.result or {}).get("cpu_seconds") is not None]
    if not done:
        return None
    spans = sorted(tuple(map(float, (r.result or {}).get("worker", {}).get("wall") or (r.started, r.completed)))
                   for r in done)
    busy, end = 0.0, -float("inf")
    for start, stop in spans:
        busy += max(0.0, stop - max(start, end))
        end = max(end, stop)
    results = [r.result or {} for r in done]
    cpu = float(sum(res["cpu_seconds"] for res in results))
    cores = float(max(res.get("worker", {}).get("cores", 1) for res in results))
    return {"cpu_seconds": cpu, "busy_seconds": busy, "cores": cores,
            "share": cpu / (busy * cores) if busy > 0 else 0.0}


def study_status(directory: str | Path) -> dict[str, Any]:
    """JSON-ready: ``trials_done``, ``trials_planned``, ``state`` (complete | running | stopped),
    ``person`` (a person study: its ``floor``, the ``pending`` iteration, every ``answer``, the gaits evaluated
    ``ahead`` of an answer and how many of them were then proposed; else None), ``require``,
    ``best`` (the learner's recommendation after the last finished iteration: trial, params, the certificate's figure —
    ``figure_name`` J* or r*, in ``unit`` — as ``value`` (verified; None unless ``verified``) and ``estimate``
    (:func:`~robustgait.study.outcome.known_figure` reads the best known), steps_taken, comfort, gait file),
    ``verify`` (``study.verify``: which gaits get the verified certificate), ``best_observed`` (the evaluated gait with
    the highest oracle score), one record per iteration and one per trial (``trials``, including FAIL trials of
    interrupted runs, :func:`~robustgait.study.trials.trial_summary`, each with its ``unit``), each with its
    ``comfort`` figures (``docs/comfort.md``; None when not measured or evaluated before they existed), and
    ``outcomes`` (:func:`outcome_counts`), ``utilisation`` (:func:`utilisation`)."""
    d = Path(directory)
    setup = load_config(d)
    cfg = setup.config.study
    unit = setup.config.study_certify.unit
    space = setup.action_space()
    store = open_store(d, setup, space)
    try:
        records = store.records()
        iterations = store.iterations()
        floor = stored_floor(store)
        verifications = store.verifications()
    finally:
        store.close()
    by_number = {r.number: r for r in records}
    batches = completed_batches(records)
    done = sum(len(b) for b in batches.values())
    finished = [k for k in sorted(iterations) if "recommendation" in iterations[k]]
    best = None
    if finished:
        n = iterations[finished[-1]].get("recommended_trial")
        best = by_number.get(n) if n is not None else None
    complete = [r for r in records if r.state == "COMPLETE"]
    observed = max(complete, key=lambda r: (r.value or 0.0, -r.number), default=None)
    per_iteration = []
    for k in range(cfg.iterations):
        rec = iterations.get(k, {})
        batch = batches.get(k, [])
        n = rec.get("recommended_trial")
        per_iteration.append({
            "iteration": k, "trials": [r.number for r in batch], "proposals": rec.get("proposals"),
            "comparisons": rec.get("comparisons"), "done": "recommendation" in rec,
            "best": _best_entry(by_number.get(n) if n is not None else None, by_number, verifications),
            "batch_best": _best_entry(max(batch, key=lambda r: (r.value or 0.0, -r.number), default=None),
                                      by_number, verifications)})
    state = ("complete" if len(finished) == cfg.iterations else
             "running" if is_running(d) else "stopped")
    person = None
    if cfg.asks_a_person:  # the floor, the batch waiting for answers, every answer (docs/person.md)
        person = {"floor": floor, "pending": pending_iteration(iterations),
                  "answers": [{"iteration": k, **iterations[k]["answer"]} for k in sorted(iterations)
                              if "answer" in iterations[k]],
                  "ahead": {key: sum(int(iterations[k].get("ahead", {}).get(key, 0)) for k in iterations)
                            for key in ("evaluated", "used")}}
    return {"directory": str(d.resolve()), "state": state, "robot": setup.robot, "metric": cfg.metric,
            "require": list(cfg.require), "person": person,
            "unit": unit, "certificate": setup.config.study_certify.space,
            "figure_name": radius_name(setup.config.study_certify.space),
            "learner": cfg.learner, "seed": cfg.seed, "trials_done": done, "trials_planned": cfg.trials_planned,
            "iterations_done": len(finished), "iterations_planned": cfg.iterations,
            "unique_gaits": len({r.index for r in complete}),
            "outcomes": outcome_counts(records, verifications),
            "utilisation": utilisation(records),
            "best": _best_entry(best, by_number, verifications),
            "best_observed": _best_entry(observed, by_number, verifications), "verify": cfg.verify,
            "iterations": per_iteration,
            "trials": [{**trial_summary(r, verifications.get(r.index)), "unit": unit}
                       for r in sorted(records, key=lambda r: r.number)],
            "config": setup.to_dict()["config"], "environment": setup.environment,
            "environment_changes": environment_changes(setup.environment)}
