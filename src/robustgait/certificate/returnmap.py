"""The return map on full states: k physical steps from the switching surface, batched (``docs/certificate.md``,
"The maps").

Section S: the switching events of the simulator (swing-foot touchdown once τ ≥ ``min_switch_tau``, the paper's
x⁻ ∈ S). A state on S starts a step of one stance. *Canonical* states are written for the gait's own stance
(``gait.stance``); a state that starts a step of the other stance is mirrored (:meth:`Robot.mirror_state`). The map
of an orbit of period k is k steps on alternating legs from a canonical state, then a mirror if k is odd: k = 1 is
the **step map** (one step, mirrored: the walk of a robot whose left and right are mirror images), k = 2 the
**stride map** (two steps, one on each leg, unmirrored), and a period-4 orbit is certified on the 4-step map.

In **section coordinates** (:func:`.reduced.section_coordinates`: the canonical state without the base's x, y and
yaw, positions divided by the step duration) the map is equivariant: states are rebuilt with the x, y and yaw of a
reference (:meth:`FullStateMap.section_map`).
"""

from __future__ import annotations

from collections.abc import Callable

import mujoco
import numpy as np
from numpy.typing import NDArray

from robustgait.certificate.numerics import BatchMap, flow_projection
from robustgait.certificate.reduced import section_coordinates, section_state
from robustgait.config import SimConfig
from robustgait.domains import other_side, step_segments
from robustgait.errors import RobustGaitError
from robustgait.gait import Gait
from robustgait.robots import Robot
from robustgait.sim.engine import StepEngine
from robustgait.sim.factory import make_engine

FloatArray = NDArray[np.float64]


class FullStateMap:
    """The batched map Δ: (K, nq), (K, nv) → (K, nq), (K, nv) of ``steps`` physical steps from canonical section
    states (module docstring), simulated with ``sim`` (or on ``engine``, which the map then does not close); NaN rows
    for the samples that fell. ``physics_steps`` counts what it simulated."""

    def __init__(self, robot: Robot, gait: Gait, steps: int, sim: SimConfig | None = None,
                 engine: StepEngine | None = None):
        if steps < 1:
            raise RobustGaitError(f"a map is at least one step, got {steps}")
        self.robot, self.gait, self.steps = robot, gait, steps
        self._own = engine is None
        self.engine = engine or make_engine(robot, gait, sim)
        self.physics_steps = 0

    def close(self) -> None:
        if self._own:
            self.engine.close()

    def __enter__(self) -> FullStateMap:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    @property
    def mirrored(self) -> bool:
        """An odd number of steps ends on the other stance: the image is mirrored back to the gait's."""
        return self.steps % 2 == 1

    def phases(self) -> list[tuple[str, int]]:
        """(stance, domain) of one map in simulation order (:func:`robustgait.domains.step_segments` per step)."""
        n, stance, out = len(self.engine.graph), self.gait.stance, []
        for _ in range(self.steps):
            out += step_segments(stance, n)
            stance = other_side(stance)
        return out

    def run(self, qpos: FloatArray, qvel: FloatArray, phases: list[tuple[str, int]],
            progress: Callable[[int], None] | None = None) -> tuple[FloatArray, FloatArray, list[str | None]]:
        """Simulate phases in order (``progress`` on the last); a sample that falls in one is NaN afterwards. Returns
        the states and each sample's fall reason (None if it did not fall)."""
        reasons: list[str | None] = [None] * qpos.shape[0]
        for j, (stance, d) in enumerate(phases):
            b = self.engine.step(qpos, qvel, stance, domain=d, progress=progress if j == len(phases) - 1 else None)
            self.physics_steps += b.physics_steps
            reasons = [r0 if r0 is not None else r1 for r0, r1 in zip(reasons, b.fall_reason, strict=True)]
            qpos, qvel = b.qpos, b.qvel
        fell = np.array([r is not None for r in reasons])
        qpos, qvel = qpos.copy(), qvel.copy()
        qpos[fell] = np.nan
        qvel[fell] = np.nan
        return qpos, qvel, reasons

    def __call__(self, qpos: FloatArray, qvel: FloatArray, progress: Callable[[int], None] | None = None
                 ) -> tuple[FloatArray, FloatArray, list[str | None]]:
        """Δ of canonical states (K, nq), (K, nv): the images (NaN rows for falls) and each sample's fall reason.

        A canonical state lies on the section at the end of a single support of the other leg, so the map simulates
        the rest of that step (multi-contact: its double support) and the single supports of its steps, then
        mirrors if the number of steps is odd."""
        qpos, qvel, reasons = self.run(qpos, qvel, self.phases(), progress)
        if self.mirrored:
            qpos, qvel = self.robot.mirror_state(qpos, qvel)
        return qpos, qvel, reasons

    def section_map(self, reference: FloatArray) -> BatchMap:
        """Δ in section coordinates, x_S ↦ x_S(Δ(x)) (N, d) → (N, d), NaN rows for falls; the states rebuilt with the
        base's x, y and yaw of ``reference`` (a qpos: the map is equivariant under them, yaw up to the friction
        pyramid)."""
        t = self.gait.step_duration

        def F(xs: FloatArray) -> FloatArray:
            qpos, qvel = section_state(xs, reference, t)
            qpos, qvel, _ = self(qpos, qvel)
            return section_coordinates(qpos, qvel, t)
        return F

    def touchdown_projection(self, x: FloatArray, reference: FloatArray) -> FloatArray | None:
        """Π (d, d) of :func:`.numerics.flow_projection` at the image of x (section coordinates): the flow f there by a
        backward difference over the last physics step, (x_S(end) − x_S(one step before)) / Δt, and the gradient of
        the guard — the signed distance of the landing sole (the gait's stance sole in canonical coordinates, after
        any number of steps) to the floor, ``mj_geomDistance`` — by central differences in the position coordinates.
        None for time switching (the event time does not depend on the state), a fall, or a flow tangent to the
        guard."""
        if self.engine.config.switching != "impact":
            return None
        t = self.gait.step_duration
        qpos, qvel = section_state(x[None], reference, t)
        states = self._image_and_before(qpos, qvel)
        if states is None:
            return None
        ends = section_coordinates(*states, t)
        flow = (ends[1] - ends[0]) / self.robot.dt
        return flow_projection(flow, self._guard_gradient(ends[1], states[0][1]))

    def _image_and_before(self, qpos: FloatArray, qvel: FloatArray) -> tuple[FloatArray, FloatArray] | None:
        """The map's image of one state and the state one physics step before it, canonical: (2, nq), (2, nv); None
        if it falls."""
        phases = self.phases()
        qpos, qvel, reasons = self.run(qpos, qvel, phases[:-1])
        if reasons[0] is not None:
            return None
        start = self.engine.full_states(qpos, qvel)[0]
        stance, d = phases[-1]
        b = self.engine.step(qpos, qvel, stance, domain=d, record=True)
        self.physics_steps += b.physics_steps
        if b.fell[0]:
            return None
        tr = b.trajectory[0]
        before = tr[-2] if len(tr) >= 2 else start
        nq, nv = self.engine.nq, self.engine.nv
        q = np.vstack([before[1:1 + nq], b.qpos[0]])
        v = np.vstack([before[1 + nq:1 + nq + nv], b.qvel[0]])
        return self.robot.mirror_state(q, v) if self.mirrored else (q, v)

    def _guard_gradient(self, x: FloatArray, reference: FloatArray, h: float = 1e-6) -> FloatArray:
        """∇g (d,) at x (section coordinates) by central differences of step h: g = the signed distance of the gait's
        stance sole to the floor."""
        m, t = self.robot.model, self.gait.step_duration
        data = mujoco.MjData(m)
        sole, floor = self.robot.sole_geom_id[self.gait.stance], self.robot.floor_geom_id
        n_pos = self.engine.nq - 4
        e = np.eye(x.shape[0])[:n_pos] * h
        qpos, _ = section_state(np.vstack([x + e, x - e]), reference, t)
        dist = np.empty(len(qpos))
        for i, q in enumerate(qpos):
            data.qpos[:] = q
            mujoco.mj_kinematics(m, data)
            dist[i] = mujoco.mj_geomDistance(m, data, sole, floor, 1.0, None)
        grad = np.zeros(x.shape[0])
        grad[:n_pos] = (dist[:n_pos] - dist[n_pos:]) / (2 * h)
        return grad
