"""Gaits as data: the Bézier outputs of each domain, the states, relabeling for the other stance (``docs/gaits.md``).

A :class:`Gait` holds, per domain, the Bézier coefficients β ∈ R^{m×8} of the desired actuated-joint
trajectory y_d(τ) and the domain duration T (phase τ = (t − t₀)/T), written for one stance leg. The other
leg's step uses the relabeled coefficients (:meth:`Gait.mirrored`). States are stored in MuJoCo's
convention: ``qpos`` = [base position (world), base quaternion (w, x, y, z), joints in the MJCF's order];
``qvel`` = [base linear velocity (world), base angular velocity (body frame), joints] — every joint of the model:
the planned ones (the outputs) and those a robot holds at an angle (``held``: their names and angles, in the
robot spec's order; their states are at those angles, at rest).

Files are read and written by :mod:`robustgait.io.gaitfile`: ``.json`` is our format (``schema_version``
:data:`SCHEMA_VERSION`, exact round trip), ``.yaml``/``.yml`` a FROST/ambersim gait. The parameters a gait was
made for are a :class:`~robustgait.config.GaitParams`.
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from robustgait.config import GaitParams
from robustgait.errors import RobustGaitError
from robustgait.robots.loops import closed_state, padded_state, passive_addresses, reduced_state

if TYPE_CHECKING:
    from robustgait.robots import Robot

SCHEMA_VERSION = 1
BEZIER_DEGREE = 7


@dataclass(frozen=True)
class State:
    """A full MuJoCo state: qpos (7 + m + h) and qvel (6 + m + h), MuJoCo's conventions (module docstring; m planned
    and h held joints)."""

    qpos: NDArray[np.float64]
    qvel: NDArray[np.float64]

    def to_dict(self) -> dict[str, list[float]]:
        return {"qpos": self.qpos.tolist(), "qvel": self.qvel.tolist()}


@dataclass(frozen=True)
class Domain:
    """One continuous domain: its duration T [s], β (m, 8) and optional feedforward torques sampled on a
    phase grid (``ff_tau`` (K,), ``ff_torque`` (K, m)), linearly interpolated in τ."""

    name: str
    duration: float
    beta: NDArray[np.float64]
    ff_tau: NDArray[np.float64] | None = None
    ff_torque: NDArray[np.float64] | None = None

    def to_dict(self) -> dict[str, Any]:
        out: dict[str, Any] = {"name": self.name, "duration": self.duration, "beta": self.beta.tolist()}
        if self.ff_tau is not None and self.ff_torque is not None:
            out["feedforward"] = {"tau": self.ff_tau.tolist(), "torque": self.ff_torque.tolist()}
        return out


@dataclass(frozen=True)
class Gait:
    """A periodic walking gait (see module docstring)."""

    robot: str
    domain_graph: str
    stance: str
    joints: tuple[str, ...]
    domains: tuple[Domain, ...]
    initial_state: State | None = None
    pre_impact_state: State | None = None
    params: GaitParams | None = None
    solver: dict[str, Any] | None = None
    meta: dict[str, Any] = field(default_factory=dict)
    held: tuple[tuple[str, float], ...] = ()

    @property
    def n_outputs(self) -> int:
        return int(self.domains[0].beta.shape[0])

    @property
    def step_duration(self) -> float:
        return float(sum(d.duration for d in self.domains))

    def to_dict(self) -> dict[str, Any]:
        return {
            "schema_version": SCHEMA_VERSION,
            "robot": self.robot,
            "domain_graph": self.domain_graph,
            "stance": self.stance,
            "joints": list(self.joints),
            "domains": [d.to_dict() for d in self.domains],
            "initial_state": self.initial_state.to_dict() if self.initial_state else None,
            "pre_impact_state": self.pre_impact_state.to_dict() if self.pre_impact_state else None,
            "params": self.params.to_dict() if self.params else None,
            "solver": self.solver,
            "meta": self.meta,
        } | ({"held": dict(self.held)} if self.held else {})

    def digest(self) -> str:
        """SHA-256 (hex) of what a walk of the gait depends on: :meth:`to_dict` without its solver's record
        (``solver``, ``meta``) — two gaits with one digest walk alike on one robot."""
        d = {k: v for k, v in self.to_dict().items() if k not in ("meta", "solver")}
        return hashlib.sha256(json.dumps(d, sort_keys=True, default=str).encode()).hexdigest()

    def check_robot(self, robot: Robot) -> None:
        """Raise if this gait cannot drive ``robot`` (output count, joint names, initial state size)."""
        if self.n_outputs != robot.n_joints:
            raise RobustGaitError(f"domains[0].beta: the gait has {self.n_outputs} outputs but robot "
                                  f"'{robot.name}' has {robot.n_joints} actuated joints")
        if self.joints and tuple(self.joints) != robot.spec.joints:
            bad = [j for j in self.joints if j not in robot.spec.joints]
            what = f"unknown joint name '{bad[0]}'" if bad else "joint order differs from the robot spec"
            raise RobustGaitError(f"joints: {what} (gait for robot '{self.robot}', robot '{robot.name}')")
        held = tuple((h.name, h.angle) for h in robot.spec.held)
        if self.held != held:
            names = ", ".join(f"{n} = {a:g}" for n, a in self.held) or "none"
            raise RobustGaitError(f"held: the gait holds {names}, robot '{robot.name}' holds "
                                  f"{', '.join(f'{n} = {a:g}' for n, a in held) or 'none'} (joints.held)")
        nq, nv = robot.model.nq, robot.model.nv
        if robot.passive_ids:  # a gait file holds no passive joints (robots.loops.reduced_state)
            qadr, vadr = passive_addresses(robot.model, robot.passive_ids)
            nq, nv = nq - len(qadr), nv - len(vadr)
        for key, s in (("initial_state", self.initial_state), ("pre_impact_state", self.pre_impact_state)):
            if s is not None and (s.qpos.shape != (nq,) or s.qvel.shape != (nv,)):
                raise RobustGaitError(f"{key}: sizes ({s.qpos.size}, {s.qvel.size}), robot '{robot.name}' "
                                      f"needs ({nq}, {nv})")

    def closed(self, robot: Robot) -> Gait:
        """This gait with its states in ``robot``'s full size, the loops of a robot with closed chains closed
        (:func:`robustgait.robots.loops.closed_state`; a gait file holds no passive joints): what the simulator
        starts from. A robot without passive joints gets the gait as it is."""
        if not robot.passive_ids:
            return self

        def close(s: State | None) -> State | None:
            return None if s is None else State(*closed_state(robot.model, robot.passive_ids, s.qpos, s.qvel))

        return replace(self, initial_state=close(self.initial_state), pre_impact_state=close(self.pre_impact_state))

    def mirrored(self, robot: Robot) -> Gait:
        """The same gait written for the other stance leg (robot's permutation and signs)."""
        doms = tuple(replace(d, beta=robot.mirror_joints(d.beta.T).T.copy(),
                             ff_torque=None if d.ff_torque is None else robot.mirror_joints(d.ff_torque))
                     for d in self.domains)

        def mirror(s: State | None) -> State | None:
            if s is None:
                return None
            if not robot.passive_ids:
                return State(*robot.mirror_state(s.qpos, s.qvel))
            # a state without passive joints (robots.loops.reduced_state): mirrored in the model's size
            m, p = robot.model, robot.passive_ids
            return State(*reduced_state(m, p, *robot.mirror_state(*padded_state(m, p, s.qpos, s.qvel))))

        return replace(self, stance="left" if self.stance == "right" else "right", domains=doms,
                       initial_state=mirror(self.initial_state), pre_impact_state=mirror(self.pre_impact_state))
