"""Gaits: parameters, the versioned JSON format, FROST/ambersim YAML import, relabeling (DESIGN §3).

A :class:`Gait` holds, per domain, the Bézier coefficients β ∈ R^{m×8} of the desired actuated-joint
trajectory y_d(τ) and the domain duration T (phase τ = (t − t₀)/T), written for one stance leg. The other
leg's step uses the relabeled coefficients (:meth:`Gait.mirrored`). States are stored in MuJoCo's
convention: ``qpos`` = [base position (world), base quaternion (w, x, y, z), joints in the MJCF's order];
``qvel`` = [base linear velocity (world), base angular velocity (body frame), joints].

Files: ``.json`` is our format (``schema_version`` :data:`SCHEMA_VERSION`, exact round trip);
``.yaml``/``.yml`` is a FROST/ambersim gait (see :func:`import_frost_yaml`).
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from robustgait.errors import RobustGaitError, input_error

if TYPE_CHECKING:
    from robustgait.robots import Robot

SCHEMA_VERSION = 1
BEZIER_DEGREE = 7
DOMAIN_GRAPHS = ("flat", "multicontact")
STANCES = ("left", "right")


@dataclass(frozen=True)
class GaitParams:
    """The four essential constraints of a gait (DESIGN §4): step length [m] (forward displacement of the
    base per step), step duration [s], step width [m] (lateral distance between the feet centres) and
    swing-foot height [m] (sole clearance at mid-step, the maximum); and, for multi-contact gaits only, the
    fraction of the step spent rolling in double support (heel strike to toe-off). The bounds are generic
    sanity bounds; whether a robot can walk them is decided by the gait generator (reach, foot collision,
    IPOPT)."""

    step_length: float = 0.15
    step_duration: float = 0.7
    step_width: float = 0.25
    step_height: float = 0.07
    rolling_fraction: float = 0.2

    BOUNDS = {  # noqa: RUF012 - class-level constant, not a dataclass field
        "step_length": (0.0, 1.5),
        "step_duration": (0.1, 5.0),
        "step_width": (0.0, 1.0),
        "step_height": (0.005, 0.5),
        "rolling_fraction": (0.05, 0.6),
    }

    def __post_init__(self) -> None:
        for name, (lo, hi) in self.BOUNDS.items():
            v = getattr(self, name)
            if not isinstance(v, (int, float)) or not math.isfinite(v) or not lo <= v <= hi:
                raise RobustGaitError(f"GaitParams.{name} = {v!r} is outside its bounds [{lo}, {hi}]")

    def to_dict(self) -> dict[str, float]:
        return {k: float(getattr(self, k)) for k in self.BOUNDS}


@dataclass(frozen=True)
class State:
    """A full MuJoCo state: qpos (7 + m) and qvel (6 + m), MuJoCo's conventions (module docstring)."""

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
        }

    def save(self, path: str | Path) -> None:
        """Write JSON (a ``.json`` path) through :func:`robustgait.io.output.write_text`: the target is checked
        first, the file is written atomically, nothing half-written or temporary is left behind."""
        from robustgait.io.output import write_text

        write_text(path, json.dumps(self.to_dict(), indent=1, allow_nan=False), "json")

    def check_robot(self, robot: Robot) -> None:
        """Raise if this gait cannot drive ``robot`` (output count, joint names, initial state size)."""
        if self.n_outputs != robot.n_joints:
            raise RobustGaitError(f"domains[0].beta: the gait has {self.n_outputs} outputs but robot "
                                  f"'{robot.name}' has {robot.n_joints} actuated joints")
        if self.joints and tuple(self.joints) != robot.spec.joints:
            bad = [j for j in self.joints if j not in robot.spec.joints]
            what = f"unknown joint name '{bad[0]}'" if bad else "joint order differs from the robot spec"
            raise RobustGaitError(f"joints: {what} (gait for robot '{self.robot}', robot '{robot.name}')")
        for key, s in (("initial_state", self.initial_state), ("pre_impact_state", self.pre_impact_state)):
            if s is not None and (s.qpos.shape != (robot.model.nq,) or s.qvel.shape != (robot.model.nv,)):
                raise RobustGaitError(f"{key}: sizes ({s.qpos.size}, {s.qvel.size}), robot '{robot.name}' "
                                      f"needs ({robot.model.nq}, {robot.model.nv})")

    def mirrored(self, robot: Robot) -> Gait:
        """The same gait written for the other stance leg (robot's permutation and signs)."""
        doms = tuple(replace(d, beta=robot.mirror_joints(d.beta.T).T.copy(),
                             ff_torque=None if d.ff_torque is None else robot.mirror_joints(d.ff_torque))
                     for d in self.domains)

        def mirror(s: State | None) -> State | None:
            return None if s is None else State(*robot.mirror_state(s.qpos, s.qvel))

        return replace(self, stance="left" if self.stance == "right" else "right", domains=doms,
                       initial_state=mirror(self.initial_state), pre_impact_state=mirror(self.pre_impact_state))


def gait_from_dict(raw: Any, src: str | Path = "<gait>") -> Gait:
    """Validate and build a :class:`Gait` from the JSON structure of :meth:`Gait.to_dict` (schema and limits:
    :mod:`robustgait.io.gaitfile`)."""
    from robustgait.io.gaitfile import gait_from_raw

    return gait_from_raw(raw, src)


def load_gait_json(path: str | Path) -> Gait:
    from robustgait.io.gaitfile import read_gait_json

    return read_gait_json(path)


def import_frost_yaml(path: str | Path, robot: Robot | None = None, stance: str = "right") -> Gait:
    """Import a FROST/ambersim gait YAML (DESIGN §3).

    ``coeff_jt`` (m·8 numbers) → β = reshape (m, 8) in Fortran order; ``step_dur`` → T; ``ffPos`` (base
    position + quaternion w, x, y, z, normalized), ``startingPos`` (m) → qpos; ``ffVel`` (6: base linear
    velocity in the world frame, angular velocity in the body frame, as ambersim fed MuJoCo's ``qvel``),
    ``startingVel`` (m) → qvel (all four or none). The coefficients are for ``stance`` (AMBER's Atalante gaits:
    right). ``inputparams`` and the base Bézier ``coeff_b`` are kept in ``meta``. Schema and limits:
    :mod:`robustgait.io.gaitfile`.
    """
    from robustgait.io.gaitfile import read_frost_yaml

    return read_frost_yaml(path, robot, stance)


def load_gait(path: str | Path, robot: Robot | None = None) -> Gait:
    """Load a gait file of either format (by extension) and, given a robot, check it fits."""
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix == ".json":
        gait = load_gait_json(path)
    elif suffix in (".yaml", ".yml"):
        gait = import_frost_yaml(path, robot)
    else:
        raise input_error(path, "unknown gait format (expected .json, or .yaml/.yml from FROST/ambersim)")
    if robot is not None:
        try:
            gait.check_robot(robot)
        except RobustGaitError as exc:
            raise input_error(path, str(exc)) from None
    return gait
