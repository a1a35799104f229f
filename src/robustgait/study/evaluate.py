"""One evaluation of the loop (``docs/studies.md``): gait parameters → generate (HZD) → walk to the step cap (with its
comfort figures, ``docs/comfort.md``) → certify.

:func:`evaluate` never raises for a bad gait: a failed generation, a fall at step k, a gait without a
fixed point are outcomes with a status and a reason. Gait generation starts cold (from the spec's
posture), never from a neighbour, so an evaluation is a function of (robot, parameters, config) alone:
the same in any order, on any worker, after any crash — which is what makes studies reproducible and
resumable, and lets a study reuse the result of a gait it already evaluated.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from robustgait.certificate.certify import GaitCertificate, certify_gait
from robustgait.certificate.orbit import Status as OrbitStatus
from robustgait.config import Config, GaitParams
from robustgait.errors import RobustGaitError
from robustgait.gait import Gait
from robustgait.io.gaitfile import gait_from_dict
from robustgait.robots import Robot
from robustgait.sim import walk
from robustgait.study.outcome import EvaluationStatus
from robustgait.study.storage import current_evaluation

if TYPE_CHECKING:
    from robustgait.gaitgen import GaitGenerator

def refusal_of(result: Mapping[str, Any]) -> OrbitStatus | None:
    """The certificate's status of a refused gait (``not_certified``) from its stored record
    (:meth:`Evaluation.summary`, a verification's record): its ``refusal``. None for any other outcome, and for a
    record written before refusals were stored."""
    if result.get("status") != EvaluationStatus.NOT_CERTIFIED or result.get("refusal") is None:
        return None
    return OrbitStatus(result["refusal"])


@dataclass
class Evaluation:
    """The outcome of :func:`evaluate`.

    status: ``certified`` (walked the cap, its certificate computed and verified), ``estimated`` (walked the cap, on a
    stable orbit, its certificate's figure estimated by exploration only: ``study.verify = shown``),
    ``generation_failed``, ``fell`` (before the cap), ``not_certified`` (walked the cap but the certificate refused it:
    ``refusal``, its :class:`robustgait.certificate.orbit.Status` — ``unsettled``, ``unstable``, ``fell`` in the
    orbit search, ``unstable_fixed_point``; the oracles rank it below every certified or estimated gait)
    (:class:`EvaluationStatus`); reason: why, in one line ('' when certified or estimated). generation:
    :meth:`GaitGenResult.summary`. The certificate's figure (``config.study_certify``: J* in N s for a push
    certificate, r* in the state's unit for a state certificate; :func:`robustgait.config.radius_name` names it):
    value, the verified figure (None unless verified: :attr:`verified`); estimate, the exploration's (None before the
    certificate). The study ranks by one of them (:func:`robustgait.study.outcome.ranked_figure`). certificate:
    :meth:`GaitCertificate.to_dict` with the samples (None unless certified or estimated). comfort: what a passenger
    feels on the walk (:meth:`robustgait.sim.comfort.Comfort.to_dict`, ``config.comfort``; None when the walk completed
    no measured step or the gait was not generated). seconds: per stage (generate, walk, certify; build when
    :func:`evaluate` built the generator itself; first: the evaluation a retry replaced, retry: its diagnosis and the
    margin's generator; total). retried: None, or why the gait was generated again with a joint margin
    (:func:`retry_after_fall`: ``joint_margin``, the first evaluation's
    ``status``, ``reason``, ``cause`` and ``limit_joint``).
    """

    params: GaitParams
    status: EvaluationStatus
    reason: str
    step_cap: int
    steps_taken: int = 0
    fell: bool = False
    fall_reason: str | None = None
    mean_speed: float | None = None
    generation: dict[str, Any] = field(default_factory=dict)
    certificate: dict[str, Any] | None = None
    comfort: dict[str, Any] | None = None
    gait: Gait | None = None
    seconds: dict[str, float] = field(default_factory=dict)
    retried: dict[str, Any] | None = None
    value: float | None = None
    estimate: float | None = None
    refusal: OrbitStatus | None = None

    @property
    def verified(self) -> bool:
        """Whether the certificate's figure was verified (:attr:`value` is set)."""
        return self.value is not None

    def certificate_summary(self) -> dict[str, Any] | None:
        """The certificate without its samples (what a study keeps in its database)."""
        if self.certificate is None:
            return None
        drop = ("samples", "images", "fell", "margins", "config", "sim", "orbit_state")
        return {k: v for k, v in self.certificate.items() if k not in drop}

    def summary(self) -> dict[str, Any]:
        """JSON-ready, without the gait and the certificate's samples."""
        return {"params": self.params.to_dict(), "status": self.status, "reason": self.reason,
                "step_cap": self.step_cap, "steps_taken": self.steps_taken, "fell": self.fell,
                "fall_reason": self.fall_reason, "mean_speed": self.mean_speed,
                "value": self.value, "estimate": self.estimate, "verified": self.verified,
                "generation": self.generation, "certificate": self.certificate_summary(), "comfort": self.comfort,
                "seconds": self.seconds, "retried": self.retried,
                "refusal": None if self.refusal is None else self.refusal.value}

    def to_dict(self) -> dict[str, Any]:
        """Everything, JSON-ready (what a worker sends back)."""
        return {**self.summary(), "certificate": self.certificate,
                "gait": self.gait.to_dict() if self.gait is not None else None}

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> Evaluation:
        """An evaluation from :meth:`to_dict` or a study's stored record (read by
        :func:`~robustgait.study.storage.current_evaluation`)."""
        d = current_evaluation(d)
        return cls(params=GaitParams(**d["params"]), status=EvaluationStatus(d["status"]), reason=d["reason"],
                   step_cap=d["step_cap"],
                   steps_taken=d["steps_taken"], fell=d["fell"], fall_reason=d["fall_reason"],
                   mean_speed=d["mean_speed"], value=d["value"], estimate=d["estimate"],
                   generation=d["generation"],
                   certificate=d["certificate"], comfort=d.get("comfort"),  # absent: evaluated before comfort
                   gait=gait_from_dict(d["gait"]) if d.get("gait") else None, seconds=d["seconds"],
                   retried=d.get("retried"),  # absent: evaluated before the retry
                   refusal=refusal_of(d))


def evaluate(robot: Robot, params: GaitParams, config: Config | None = None, *,
             generator: GaitGenerator | None = None, verify_above: float | None = None) -> Evaluation:
    """Generate the gait of ``params`` (cold start, ``config.generate``), walk it up to ``config.sim.step_cap``
    steps and, if it walked the cap, certify it (``config.certify``). Pass a ``generator`` built for ``robot`` with
    ``config.generate`` to reuse it (building costs seconds). The certificate is ``config.study_certify`` (J* for the
    ``push`` metric). Never raises for a bad gait (see :class:`Evaluation`). The two stages are
    :func:`generate_and_walk` and :func:`certify_evaluation`, one after the other; a gait whose undisturbed walk fell
    (in the walk, or in the certificate's orbit search) after one of its joints reached the end of its range is
    generated again with ``generate.retry_joint_margin`` and evaluated once more, as ``gait generate`` does
    (:func:`retry_after_fall`). The certificate is verified when the study verifies every gait
    (:attr:`~robustgait.config.StudyConfig.verifies_all`) or, given ``verify_above``, when its estimate is at least
    that (a person study's floor: the gaits it may show); otherwise it is the exploration's estimate (status
    ``estimated``)."""
    cfg = config or Config()
    first = certify_evaluation(robot, generate_and_walk(robot, params, cfg, generator=generator), cfg, verify_above)
    return retry_after_fall(robot, params, cfg, first, generator, verify_above)


def fell_undisturbed(ev: Evaluation, config: Config) -> int | None:
    """Steps within which ``ev``'s gait fell undisturbed — in the walk to the cap, or in the certificate's orbit
    search (``config.study_certify.orbit``: at most ``max_steps`` + ``hold_steps``) —, or None if it did not."""
    if ev.gait is None:
        return None
    if ev.status == EvaluationStatus.FELL:
        return ev.steps_taken + 1
    if ev.refusal == OrbitStatus.FELL:
        o = config.study_certify.orbit
        return o.max_steps + o.hold_steps
    return None


def retry_after_fall(robot: Robot, params: GaitParams, config: Config, ev: Evaluation,
                     generator: GaitGenerator | None = None, verify_above: float | None = None) -> Evaluation:
    """``ev`` itself, unless its gait fell undisturbed (:func:`fell_undisturbed`) after one of its joints reached
    the end of its range with room to give (:func:`robustgait.gaitgen.walkcheck.margin_after`): then the evaluation
    of the gait generated with that margin, its ``retried`` saying why (the margin, the first evaluation's status,
    reason and cause) and its seconds counting both."""
    from robustgait.gaitgen.walkcheck import diagnose_fall, margin_after, retry_generator

    steps = fell_undisturbed(ev, config)
    if steps is None or ev.gait is None:
        return ev
    t0 = time.perf_counter()
    diagnosis = diagnose_fall(robot, ev.gait, config, steps)
    if diagnosis is None:
        return ev
    cause, joint, _ = diagnosis
    margin = margin_after(robot, config, joint)
    if margin is None:
        return ev
    again, gen = retry_generator(robot, config, margin, generator)
    retry = time.perf_counter() - t0  # the diagnosis, and the margin's generator when it was built now
    out = certify_evaluation(robot, generate_and_walk(robot, params, again, generator=gen), again, verify_above)
    out.retried = {"joint_margin": margin, "status": ev.status, "reason": ev.reason, "cause": cause,
                   "limit_joint": joint}
    out.seconds["first"] = ev.seconds.get("total", 0.0)
    out.seconds["retry"] = retry
    out.seconds["total"] = out.seconds.get("total", 0.0) + out.seconds["first"] + retry
    return out


def generate_and_walk(robot: Robot, params: GaitParams, config: Config | None = None, *,
                      generator: GaitGenerator | None = None) -> Evaluation:
    """The first stage of :func:`evaluate`: generate the gait and walk it to the step cap with its comfort figures.
    The result's status is ``generation_failed``, ``fell``, or (walked the cap) ``not_certified`` with the reason
    ``not certified yet`` until :func:`certify_evaluation` certifies it."""
    from robustgait.gaitgen import GaitGenerator

    cfg = config or Config()
    cap = cfg.sim.step_cap
    t0 = time.perf_counter()
    gen = generator or GaitGenerator(robot, cfg.generate)
    t_build = time.perf_counter()
    res = gen.solve(params)
    t_gen = time.perf_counter()
    seconds = {"generate": t_gen - t_build} | ({} if generator is not None else {"build": t_build - t0})
    ev = Evaluation(params=res.params or params, status=EvaluationStatus.GENERATION_FAILED,
                    reason=f"{res.status}: {res.reason}",
                    step_cap=cap, generation=res.summary(), seconds=seconds)
    if res.gait is None:
        seconds["total"] = t_gen - t0
        return ev
    ev.gait = res.gait
    try:
        w = walk(robot, res.gait, cfg.sim, comfort=cfg.comfort)
    except RobustGaitError as exc:  # e.g. the generated gait has no initial state to start from
        ev.status, ev.reason, ev.fell = EvaluationStatus.FELL, f"walk failed: {exc}", True
    else:
        ev.steps_taken, ev.fell, ev.fall_reason, ev.mean_speed = w.steps_taken, w.fell, w.fall_reason, w.mean_speed
        ev.comfort = w.comfort.to_dict() if w.comfort is not None else None
        if w.steps_taken < cap:
            ev.status, ev.reason = EvaluationStatus.FELL, f"fell in step {w.steps_taken + 1} ({w.fall_reason})"
        else:
            ev.status, ev.reason = EvaluationStatus.NOT_CERTIFIED, NOT_CERTIFIED_YET
    t_walk = time.perf_counter()
    seconds["walk"] = t_walk - t_gen
    seconds["total"] = t_walk - t0
    return ev


NOT_CERTIFIED_YET = "not certified yet"


def certify_evaluation(robot: Robot, ev: Evaluation, config: Config | None = None,
                       verify_above: float | None = None) -> Evaluation:
    """The second stage of :func:`evaluate`: certify a gait that walked the cap (``config.study_certify``; a fall, no
    fixed point: a status, not an exception; verified as :func:`evaluate` says); any other evaluation is returned as it
    is. Adds to ``ev.seconds``."""
    if ev.gait is None or ev.status != EvaluationStatus.NOT_CERTIFIED or ev.reason != NOT_CERTIFIED_YET:
        return ev
    cfg = config or Config()
    t0 = time.perf_counter()
    everything = cfg.study.verifies_all or cfg.study_certify.method != "sequential"
    verify: bool | Callable[[float], bool] = everything or (
        (lambda estimate: estimate >= verify_above) if verify_above is not None else False)
    # a fall, no stable orbit: a status, not an exception
    gc = certify_gait(robot, ev.gait, cfg.study_certify, cfg.sim, validate=cfg.validate, verify=verify)
    record_certificate(ev, gc)
    ev.seconds["certify"] = time.perf_counter() - t0
    ev.seconds["total"] = ev.seconds.get("total", 0.0) + ev.seconds["certify"]
    return ev


def record_certificate(ev: Evaluation, gc: GaitCertificate) -> None:
    """Put a gait's certificate in its evaluation: the status (``certified`` when verified, ``estimated`` when only
    explored, ``not_certified`` with the refusal's status and reason), the estimate and the verified value."""
    if not gc.ok or gc.certificate is None:
        ev.status, ev.reason, ev.refusal = EvaluationStatus.NOT_CERTIFIED, f"{gc.status}: {gc.reason}", gc.status
        return
    estimate = gc.estimate
    assert estimate is not None  # a certificate was made
    ev.estimate = estimate
    ev.certificate = gc.to_dict(samples=True)
    if gc.verified:
        ev.status, ev.reason, ev.value = EvaluationStatus.CERTIFIED, "", float(gc.value)
    else:
        ev.status, ev.reason = EvaluationStatus.ESTIMATED, ""


def verify_gait(robot: Robot, gait: Gait, config: Config,
                explored: Mapping[str, Any] | None = None) -> dict[str, Any]:
    """The verified certificate of a study's gait (``config.study_certify``, verified whatever its estimate): a record
    with its ``status`` (``certified`` or ``not_certified``), ``reason``, ``refusal`` (the certificate's status value
    when refused, else None), ``value`` (the verified figure, None unless certified), ``estimate``, ``verified``,
    ``certificate`` (:meth:`GaitCertificate.to_dict` with the samples; None when refused) and ``seconds``.
    Deterministic for a gait and a configuration, as the evaluation is: the same orbit and exploration as its
    estimate — ``explored``, the estimate's certificate with its samples, is replayed rather than simulated again
    (:func:`~robustgait.certificate.certify.certify_gait`), with the same result."""
    t0 = time.perf_counter()
    gc = certify_gait(robot, gait, config.study_certify, config.sim, validate=config.validate, verify=True,
                      explored=explored)
    c = gc.certificate
    ok = gc.ok and c is not None
    return {"status": EvaluationStatus.CERTIFIED if ok else EvaluationStatus.NOT_CERTIFIED,
            "reason": "" if ok else f"{gc.status}: {gc.reason}", "refusal": None if ok else gc.status.value,
            "value": float(gc.value) if ok else None, "estimate": gc.estimate, "verified": ok,
            "certificate": gc.to_dict(samples=True) if ok else None, "seconds": time.perf_counter() - t0}
