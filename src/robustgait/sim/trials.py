"""Disturbed walks of many trials at once, shared by the validation (:mod:`robustgait.validate`) and the push
certificate (:mod:`robustgait.certificate.push`): every domain of every step is one batched :meth:`StepEngine.step`
call on the trials still walking, with per-trial inputs given by a function of the :class:`Segment` being run."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from robustgait.domains import other_side, step_segments
from robustgait.sim.engine import StepEngine, StepInputs

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class Segment:
    """One batched engine call of a trial: a domain of a step. ``step``: the trial's step (0-based); ``index``: the
    segment's index in the trial (for a flat-foot gait the step); ``stance``, ``domain``: what the engine runs;
    ``prev``: the (stance, domain) of the segment before it (the one that ended at the trial's start for the first);
    for the samples being run, ``offset`` (physics steps from the start of this step to the start of this segment),
    ``prev_at`` (the physics step at which the previous segment's event happened, counted in that segment) and,
    under a delayed state-feedback law, ``torque_tail`` (the torques it computed before this segment)."""

    step: int
    index: int
    stance: str
    domain: int
    prev: tuple[str, int]
    offset: NDArray[np.int64]
    prev_at: NDArray[np.int64]
    torque_tail: FloatArray | None = None  # a delayed law's torques before the segment (FeedbackStepBatch)


Inputs = Callable[[Segment, NDArray[np.int64]], "StepInputs | None"]
# after step k (0-based): the trials idx still walking and their section states (len(idx), nq + nv), canonical →
# which of them are done (they stop walking, without a fall)
Stop = Callable[[int, NDArray[np.int64], FloatArray], NDArray[np.bool_]]


def simulate_trials(engine: StepEngine, qpos: FloatArray, qvel: FloatArray, n_steps: int, period: int,
                    inputs: Inputs, *, first_at: int, progress: Callable[[int], None] | None = None,
                    sections: FloatArray | None = None, stop: Stop | None = None
                    ) -> tuple[NDArray[np.bool_], list[str | None], NDArray[np.int64], FloatArray, int]:
    """Walk K trials from canonical section states (K, nq), (K, nv) for ``n_steps`` steps (stances alternate from
    the gait's), each domain of a step one batched :meth:`StepEngine.step` on the trials still walking
    (:func:`robustgait.domains.step_segments`: a multi-contact step is the previous leg's double support, then the
    single support that ends at the next heel strike).

    ``inputs(segment, idx)`` gives the per-sample inputs of a :class:`Segment` for the trials ``idx``
    (``first_at``: the physics step of the event that ended the segment before the trials' start). Returns success
    (K,), fall reasons, the 1-based step of each fall (0 = none), the full state (qpos, qvel) at the section after
    ``period`` steps ((K, nq + nv); canonical stance; NaN if fell before) and the physics steps simulated.
    ``sections`` (K, n_steps, nq + nv), if given, is filled with the state at the section after every step, written
    for the canonical stance (NaN from a fall on, and after a trial stopped). ``stop(k, idx, states)`` after each
    step k (0-based): the trials it marks are done and walk no further (a recovered push: no fall; their state after
    ``period`` steps is NaN if they stopped before).
    """
    robot = engine.robot
    k_all = qpos.shape[0]
    qpos, qvel = qpos.copy(), qvel.copy()
    alive = np.ones(k_all, dtype=bool)
    done = np.zeros(k_all, dtype=bool)
    fall_step = np.zeros(k_all, dtype=np.int64)
    reasons: list[str | None] = [None] * k_all
    first = np.full((k_all, engine.nq + engine.nv), np.nan)
    prev_at = np.full(k_all, first_at, dtype=np.int64)
    stance = next(iter(engine.gaits))
    prev: tuple[str, int] = (other_side(stance), 0)
    tails: FloatArray | None = None
    physics = 0
    index = 0
    n_domains = len(engine.graph)
    for k in range(n_steps):
        offset = np.zeros(k_all, dtype=np.int64)
        for seg_stance, domain in step_segments(stance, n_domains):
            idx = np.flatnonzero(alive & ~done)
            if idx.size == 0:
                break
            seg = Segment(k, index, seg_stance, domain, prev, offset[idx], prev_at[idx],
                          None if tails is None else tails[idx])
            b = engine.step(qpos[idx], qvel[idx], seg_stance, domain=domain, inputs=inputs(seg, idx))
            physics += b.physics_steps
            tail = getattr(b, "torque_tail", None)
            if tail is not None:  # the first segment runs every trial: its tail has the largest delay's width
                tails = np.zeros((k_all, *tail.shape[1:])) if tails is None else tails
                tails[idx] = tail
            for j in np.flatnonzero(b.fell):
                reasons[idx[j]] = b.fall_reason[j]
            fall_step[idx[b.fell]] = k + 1
            alive[idx[b.fell]] = False
            ok = ~b.fell
            qpos[idx[ok]], qvel[idx[ok]] = b.qpos[ok], b.qvel[ok]
            at = np.round(b.duration[ok] / robot.dt).astype(np.int64)
            prev_at[idx[ok]] = at
            offset[idx[ok]] += at
            prev = (seg_stance, domain)
            index += 1
        if k == period - 1 or sections is not None or stop is not None:
            ok_all = np.flatnonzero(alive & ~done)
            if sections is not None:
                sections[:, k] = np.nan
            if ok_all.size:
                qp, qv = qpos[ok_all], qvel[ok_all]
                if k % 2 == 0:  # the state starts a step of the other stance: write it for the canonical one
                    qp, qv = robot.mirror_state(qp, qv)
                if k == period - 1:
                    first[ok_all] = np.hstack([qp, qv])
                if sections is not None:
                    sections[ok_all, k] = np.hstack([qp, qv])
                if stop is not None:
                    done[ok_all[stop(k, ok_all, np.hstack([qp, qv]))]] = True
        stance = other_side(stance)
        if progress is not None:
            progress(1)
        if not (alive & ~done).any():
            break
    return alive, reasons, fall_step, first, physics


def wrench_window(force: FloatArray, start: NDArray[np.int64], width: int, horizon: int) -> FloatArray:
    """Base wrench series (N, horizon, 6) [N, N m]: the horizontal world-frame force (N, 2) of push i over the
    physics steps [start_i, start_i + width) (cut at the horizon), zero elsewhere. Shared by the push map
    (:func:`robustgait.certificate.push.push_series`) and the validation's pushes
    (:func:`robustgait.validate.disturbances.push_wrench`)."""
    out = np.zeros((force.shape[0], horizon, 6))
    for i in range(force.shape[0]):
        a = min(int(start[i]), horizon)
        out[i, a:a + width, :2] = force[i]
    return out


def pushed_first_step(engine: StepEngine, wrench: FloatArray) -> Inputs:
    """Inputs that apply a base wrench series (K, H, 6) over the first step of each trial, counted from the trial's
    start across the step's segments (a multi-contact step starts in the previous leg's rolling double support, so
    a push late in the step falls in its single support); H: the physics steps of the undisturbed first step. Later
    steps are undisturbed."""

    def push(seg: Segment, idx: NDArray[np.int64]) -> StepInputs | None:
        if seg.step != 0:
            return None
        if not seg.offset.any():
            return StepInputs(base_wrench=wrench[idx])
        h = engine.horizons[seg.domain]
        at = seg.offset[:, None] + np.arange(h)[None, :]
        w = wrench[idx[:, None], np.minimum(at, wrench.shape[1] - 1)]
        w[at >= wrench.shape[1]] = 0.0  # past the first step's window: no push
        return StepInputs(base_wrench=w)
    return push
