"""A study's trial as ``study status`` lists it (:func:`trial_summary`): its evaluation with the verification made
after it, read by the status, the trade-off front and the run that verifies that front."""

from __future__ import annotations

from typing import Any

from robustgait.study.outcome import EvaluationStatus, status_of, verified_value
from robustgait.study.storage import TrialRecord

# comfort: the walk's comfort figures (robustgait.sim.comfort.Comfort.to_dict; None for a study evaluated before them);
# retried: why the gait was generated again with a joint margin (robustgait.study.evaluate.retry_after_fall), or None
TRIAL_KEYS = ("status", "reason", "refusal", "steps_taken", "step_cap", "fell", "fall_reason", "mean_speed",
              "comfort", "gait_file", "certificate_file", "seconds", "retried")


def trial_summary(r: TrialRecord, verification: dict[str, Any] | None = None) -> dict[str, Any]:
    """One trial as ``study status`` lists it: the certificate's figure as ``value`` (the verified figure, None unless
    verified — by the evaluation, or by ``verification``, the record of a gait verified after its trial,
    :meth:`~robustgait.study.storage.StudyStore.set_verification`, whose status (``certified`` or ``not_certified``),
    reason and certificate file then replace the estimate's), ``estimate`` (the exploration's) and ``verified``
    (:func:`~robustgait.study.outcome.known_figure` reads the best known of them). ``score`` is the oracle's score the
    learner ranked the trial by (Optuna's trial value), not the certificate's figure."""
    out: dict[str, Any] = {"number": r.number, "state": r.state, "iteration": r.iteration, "slot": r.slot,
                           "grid_index": r.index, "params": r.params, "score": r.value,
                           "reused_from": r.reused_from, "retry_of": r.retry_of,
                           "evaluated_ahead": bool(r.attrs.get("evaluated_ahead"))}
    res = r.result or {}
    out.update({k: res.get(k) for k in TRIAL_KEYS})
    out["estimate"] = res.get("estimate")
    out["value"] = verified_value(res, verification)
    cert = res.get("certificate") or {}
    if verification is not None and status_of(res) == EvaluationStatus.ESTIMATED:
        out.update(status=verification["status"], reason=verification.get("reason", ""),
                   refusal=verification.get("refusal"), certificate_file=verification.get("certificate_file"))
    out["verified"] = out["value"] is not None
    out["x_star"] = cert.get("x_star")
    out["n_inside"] = cert.get("n_inside")
    return out


def outcome_line(result: dict[str, Any], name: str) -> str:
    """An evaluation's outcome in a few words for a progress bar: its certified value, or why it has none — the
    refusal's status (a gait without a stable orbit is refused, not a zero), a fall, a failed generation —, and the
    joint margin of a gait generated again after a fall at a joint limit."""
    status = status_of(result)
    again = result.get("retried")
    tail = f" (generated again with joint margin {again['joint_margin']:g} rad)" if again else ""
    if status == EvaluationStatus.CERTIFIED:
        return f"{name} {result['value']:.3f}, steps {result['steps_taken']}{tail}"
    if status == EvaluationStatus.ESTIMATED:
        return f"{name} ≈ {result['estimate']:.3f} (estimated), steps {result['steps_taken']}{tail}"
    if status == EvaluationStatus.NOT_CERTIFIED:
        return f"refused ({result.get('refusal') or 'no certificate'}), steps {result['steps_taken']}{tail}"
    if status == EvaluationStatus.FELL:
        return f"fell in step {result.get('steps_taken', 0) + 1}{tail}"
    return str(result.get("status")).replace("_", " ") + tail
