"""Compliant springs in the gait problem (``generate.springs = "compliant"``; ``docs/gaitgen.md``, "Springs, rigid or
compliant"): a closed chain's springs as unactuated coordinates of the problem, their torque −k (s − springref) − d ṡ in
the dynamics (:meth:`robustgait.dynamics.Dynamics.spring_torque`). Per node the NLP carries each spring's (s, ṡ, s̈);
consecutive nodes are tied by the stance roll's linear-acceleration rule (:func:`spring_collocation`), and the step is
periodic in each spring after relabeling, onto its partner on the other leg (:func:`spring_mirror`).
"""

from __future__ import annotations

import itertools
from typing import Any

import casadi as cs
import numpy as np

from robustgait.dynamics import Dynamics
from robustgait.errors import RobustGaitError
from robustgait.gaitgen.linefoot import roll_collocation


def spring_mirror(dyn: Dynamics) -> list[tuple[int, int, float]]:
    """For each compliant spring j (:attr:`~robustgait.dynamics.Dynamics.springs`, adam indices), its partner k on the
    other leg and the sign σ of the mirror (``Robot.mirror_state``: s_j of the mirrored state = σ s_k): (j, k, σ)."""
    robot, names = dyn.robot, [*dyn.robot.spec.joints, *dyn.passive]
    q0, v0 = robot.model.qpos0.copy(), np.zeros(robot.model.nv)
    base, _ = robot.mirror_state(q0, v0)
    out = []
    for sp in dyn.springs:
        q = q0.copy()
        q[dyn.qpos_idx[sp.index]] += 1.0
        diff = robot.mirror_state(q, v0)[0] - base
        adr = int(np.argmax(np.abs(diff)))
        partner = [i for i in (s.index for s in dyn.springs) if int(dyn.qpos_idx[i]) == adr]
        if not partner or abs(abs(diff[adr]) - 1.0) > 1e-9:
            raise RobustGaitError(f"{robot.name}: the mirror does not map the spring '{names[sp.index]}' onto "
                                  f"another spring")
        out.append((sp.index, partner[0], float(np.sign(diff[adr]))))
    return out


def spring_collocation(x: cs.SX, nodes: list[dict[str, Any]], springs: list[int], m: int, h: Any) -> cs.SX:
    """The linear-acceleration rule (:func:`~robustgait.gaitgen.linefoot.roll_collocation`) between consecutive
    nodes on each compliant spring j's (s_j, ṡ_j, s̈_j), read from the NLP's variables ``x`` at the nodes' ``sp``,
    ``spd`` and ``spdd`` slices (``nodes``: each node's slices; the springs' joint indices j ≥ the ``m`` planned
    ones), h [s] apart: 2 (N − 1) rows per spring [rad, rad/s]."""
    rows = []
    for a, b in itertools.pairwise(nodes):
        for j in springs:
            here = cs.vertcat(*(x[a[key].start + j - m] for key in ("sp", "spd", "spdd")))
            there = cs.vertcat(*(x[b[key].start + j - m] for key in ("sp", "spd", "spdd")))
            rows.append(roll_collocation(here, there, h))
    return cs.vertcat(*rows)
