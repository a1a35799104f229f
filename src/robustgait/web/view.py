"""What the page of a person study shows (docs/person.md): the JSON of ``GET api/state``, made from the study's records
(:class:`~robustgait.web.records.StudySnapshot`) and the page's own state (which batch is shown, whether a runner
drives the study, which videos exist). Pure: reads nothing but its arguments (and what ``video_url`` looks at).

The state, its keys in this order: ``study`` (the directory's name), ``robot``, ``phase`` (``complete`` | ``waiting``
| ``preparing`` | ``evaluating`` | ``stopped``), ``blind``, ``labels``, ``iterations`` (planned), ``iteration``
(the pending one, 0-based, or None), ``iterations_done``, ``trials_done``, ``trials_planned``, ``certificate`` (the
radius' name), ``unit``, ``floor`` (``{"value", "source"}`` or None), ``answers`` (:func:`answers_view`); while a
batch waits: ``batch`` and ``hidden`` (:func:`batch_view`) and ``evaluated`` (how many gaits were evaluated to fill
it); when the study is complete, or always when not blind:
``recommendation`` (:func:`gait_view`) and ``recommendation_note`` when there are such."""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from typing import Any

from robustgait.config import radius_name
from robustgait.io.studyfile import StudySetup
from robustgait.sim.comfort import FIGURES
from robustgait.study.person import pending_iteration, recommendation
from robustgait.study.ranking import Requirement
from robustgait.study.run import completed_batches
from robustgait.study.storage import TrialRecord
from robustgait.web.records import StudySnapshot

VideoUrl = Callable[[int, TrialRecord], str | None]
"""``(iteration, trial) -> URL`` of the trial's rendered video, None when it has none."""


def gait_names(n: int) -> list[str]:
    """How the page names a batch's gaits: A, B, C, …"""
    return [chr(ord("A") + i) if i < 26 else f"G{i + 1}" for i in range(n)]


def video_url(token: str, k: int, slot: int) -> str:
    """The URL path of iteration k's video in ``slot``, as :mod:`robustgait.web.routes` serves it."""
    return f"/{token}/video/{k}/{slot}.mp4"


def _finite(v: Any) -> Any:
    return None if isinstance(v, float) and not math.isfinite(v) else v


def page_state(setup: StudySetup, snap: StudySnapshot, *, study: str, reqs: Sequence[Requirement],
               ready: int | None, running: bool, video_url: VideoUrl,
               video_errors: Mapping[tuple[int, int], str]) -> dict[str, Any]:
    """The page's state (the module docstring's keys) of the study ``study`` set up as ``setup``, its records
    ``snap``; ``ready``: the pending iteration whose videos are rendered (None: none); ``running``: a study runner
    drives the study; ``video_url`` and ``video_errors`` (``(iteration, slot) -> why``): each shown gait's video or
    why it has none. The phase is ``complete`` exactly when every planned iteration has its recommendation."""
    cfg = setup.config
    records, iterations, floor = snap.records, snap.iterations, snap.floor
    batches = completed_batches(records)
    by_number = {r.number: r for r in records}
    k = pending_iteration(iterations)
    finished = [i for i in sorted(iterations) if "recommendation" in iterations[i]]
    complete = len(finished) == cfg.study.iterations
    phase = ("complete" if complete else "waiting" if k is not None and ready == k else
             "preparing" if k is not None and running else "evaluating" if running else "stopped")
    blind = cfg.person.blind
    unit = cfg.study_certify.unit
    out: dict[str, Any] = {
        "study": study, "robot": setup.robot, "phase": phase, "blind": blind,
        "labels": cfg.person.labels, "iterations": cfg.study.iterations, "iteration": k,
        "iterations_done": len(finished), "trials_done": sum(len(b) for b in batches.values()),
        "trials_planned": cfg.study.trials_planned, "certificate": radius_name(cfg.study_certify.space),
        "unit": unit, "floor": None if floor is None else {"value": floor["value"], "source": floor["source"]},
        "answers": answers_view(iterations)}
    if phase == "waiting" and k is not None:
        out["batch"], out["hidden"] = batch_view(k, batches.get(k, []), iterations[k], blind=blind,
                                                 figures=cfg.person.figures, video_url=video_url,
                                                 video_errors=video_errors)
        out["evaluated"] = int(iterations[k]["pending"].get("size", len(out["batch"]) + len(out["hidden"])))
    if complete or not blind:  # blind: only at the end
        value = -math.inf if floor is None else float(floor["value"])
        pick, note = recommendation(iterations, by_number, value, reqs)
        if pick is not None:
            out["recommendation"] = gait_view(pick, cfg.person.figures, blind=False)
        if note:
            out["recommendation_note"] = note
    return out


def gait_view(r: TrialRecord, figures: Sequence[str], *, blind: bool) -> dict[str, Any]:
    """One gait as the page shows it: ``slot``, ``iteration``; not blind, also ``params``, the study's certificate
    figure (named by the state's ``certificate``, in its ``unit``) as ``value`` (verified; None unless ``verified``) and
    ``estimate``, and ``figures`` (those of ``figures`` that are comfort figures, in that order: ``{"name", "value"
    (None when not finite or not recorded), "unit" ('' for a dimensionless figure), "what"}``)."""
    res = r.result or {}
    comfort = res.get("comfort") or {}
    view: dict[str, Any] = {"slot": r.slot, "iteration": r.iteration}
    if not blind:
        view["params"] = r.params
        view.update(value=res.get("value"), estimate=res.get("estimate"), verified=bool(res.get("verified")))
        view["figures"] = [{"name": n, "value": _finite(comfort.get(n)), "unit": FIGURES[n][0],
                            "what": FIGURES[n][1]} for n in figures if n in FIGURES]
    return view


def batch_view(k: int, batch: list[TrialRecord], rec: dict[str, Any], *, blind: bool, figures: Sequence[str],
               video_url: VideoUrl, video_errors: Mapping[tuple[int, int], str]
               ) -> tuple[list[dict[str, Any]], list[dict[str, Any]]]:
    """Iteration k's pending batch (``batch``: its completed trials; ``rec``: its record, with ``pending``): the
    cards of its shown gaits (:func:`gait_view` with ``name``, ``video`` and ``no_video``) and its hidden gaits
    (``{"slot", "name", "why"}``, ``why`` None when blind). KeyError when ``rec`` has no pending batch."""
    names = gait_names(len(batch))
    shown = rec["pending"]["shown"]
    cards = [{**gait_view(r, figures, blind=blind), "name": names[r.slot], "video": video_url(k, r),
              "no_video": video_errors.get((k, r.slot))} for r in batch if r.slot in shown]
    hidden = [{"slot": int(s), "name": names[int(s)], "why": None if blind else why}
              for s, why in rec["pending"]["hidden"].items()]
    return cards, hidden


def answers_view(iterations: dict[int, dict[str, Any]]) -> list[dict[str, Any]]:
    """The answers stored so far, by iteration: ``{"iteration", "by", "tiers" (the gaits' names, best tier first),
    "labels" (name -> label, labelled gaits only), "answered_at", "note"}``."""
    out = []
    for k in sorted(iterations):
        a = iterations[k].get("answer")
        if a is None:
            continue
        names = gait_names(len(a["ranks"]))
        tiers: dict[int, list[str]] = {}
        for s, rank in enumerate(a["ranks"]):
            if rank is not None:
                tiers.setdefault(rank, []).append(names[s])
        out.append({"iteration": k, "by": a.get("by"), "tiers": [tiers[t] for t in sorted(tiers)],
                    "labels": {names[s]: lab for s, lab in enumerate(a.get("labels") or []) if lab},
                    "answered_at": a.get("answered_at"), "note": a.get("note")})
    return out
