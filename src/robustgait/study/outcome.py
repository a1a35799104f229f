"""How a study's evaluation ended, and what its record says of the gait's certificate figure.

The figure (J* [N s] of a push certificate, r* of a state certificate) has three names in every record a study
writes — the evaluation (:meth:`~robustgait.study.evaluate.Evaluation.summary`), a later verification's record, the
trial ``study status`` lists, the page's view, the report's points:

* ``value``: the verified figure (None unless verified);
* ``estimate``: the exploration's estimate Ĵ or r̂ (None without a certificate);
* ``verified``: whether there is a verified ``value``.

A study that ranks on estimates (``study.verify = shown``) ranks every gait by its ``estimate`` and verifies what it
shows; one that verifies every gait ranks by ``value`` (:func:`ranked_figure`). What a person or a plot is shown is the
best that is known (:func:`known_figure`): the verified value, else the estimate, marked as one."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from robustgait.config.base import TextEnum


class EvaluationStatus(TextEnum):
    """How an evaluation ended: equal to its value, the text a study stores."""

    CERTIFIED = "certified"  # walked the cap, its certificate verified
    ESTIMATED = "estimated"  # walked the cap on a stable orbit, its certificate's figure only estimated
    GENERATION_FAILED = "generation_failed"
    FELL = "fell"  # before the cap
    NOT_CERTIFIED = "not_certified"  # walked the cap, refused by the certificate (its refusal: an orbit status)


RANKED: tuple[EvaluationStatus, ...] = (EvaluationStatus.CERTIFIED, EvaluationStatus.ESTIMATED)
"""The statuses of a gait with a certificate figure the study ranks by: verified, or estimated by exploration."""


def status_of(record: Mapping[str, Any]) -> EvaluationStatus | None:
    """The status of a stored record (None when it has none, or one this package does not know)."""
    try:
        return EvaluationStatus(record.get("status"))
    except ValueError:
        return None


def verified_value(record: Mapping[str, Any], verification: Mapping[str, Any] | None = None) -> float | None:
    """The verified figure of an evaluation's record or, when its gait was verified after its trial, of that
    ``verification`` (None when it refused the gait); None when not verified."""
    r = verification if verification is not None else record
    return None if r.get("value") is None else float(r["value"])


def known_figure(record: Mapping[str, Any], verification: Mapping[str, Any] | None = None) -> float | None:
    """The best a record knows of its gait's figure — what a person or a plot is shown: the verified value
    (:func:`verified_value`), else the estimate of a gait still ``estimated``, else None (fell, refused, not
    generated). ``record`` may be a stored evaluation or a trial as ``study status`` lists it."""
    v = verified_value(record, verification)
    if v is not None or verification is not None:
        return v
    if status_of(record) == EvaluationStatus.ESTIMATED and record.get("estimate") is not None:
        return float(record["estimate"])
    return None


def ranked_figure(record: Mapping[str, Any], ranks_verified: bool) -> float:
    """The figure a study ranks a stored evaluation by: its verified ``value`` when the study verifies every gait
    (``ranks_verified``: :attr:`~robustgait.config.StudyConfig.verifies_all`), else its ``estimate``, so that every
    gait of a study that ranks on estimates is ranked by the same estimator, verified or not; 0 for a gait without a
    certificate figure (not :data:`RANKED`)."""
    if status_of(record) not in RANKED:
        return 0.0
    v = record.get("value") if ranks_verified else record.get("estimate")
    return 0.0 if v is None else float(v)
