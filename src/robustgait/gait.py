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
import yaml
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
    swing-foot height [m] (sole clearance at mid-step, the maximum). The bounds are generic sanity bounds;
    whether a robot can walk them is decided by the gait generator (reach, foot collision, IPOPT)."""

    step_length: float = 0.15
    step_duration: float = 0.7
    step_width: float = 0.25
    step_height: float = 0.07

    BOUNDS = {  # noqa: RUF012 - class-level constant, not a dataclass field
        "step_length": (0.0, 1.5),
        "step_duration": (0.1, 5.0),
        "step_width": (0.0, 1.0),
        "step_height": (0.005, 0.5),
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
        """Write JSON atomically (a temporary file renamed into place: nothing half-written)."""
        path = Path(path)
        tmp = path.with_name(path.name + ".tmp")
        tmp.write_text(json.dumps(self.to_dict(), indent=1, allow_nan=False))
        tmp.replace(path)

    def check_robot(self, robot: Robot) -> None:
        """Raise if this gait cannot drive ``robot`` (output count, joint names, initial state size)."""
        if self.n_outputs != robot.n_joints:
            raise RobustGaitError(f"gait has {self.n_outputs} outputs but robot '{robot.name}' has "
                                  f"{robot.n_joints} actuated joints")
        if self.joints and tuple(self.joints) != robot.spec.joints:
            bad = [j for j in self.joints if j not in robot.spec.joints]
            what = f"unknown joint name '{bad[0]}'" if bad else "joint order differs from the robot spec"
            raise RobustGaitError(f"gait for robot '{self.robot}': {what} (robot '{robot.name}')")
        s = self.initial_state
        if s is not None and (s.qpos.shape != (robot.model.nq,) or s.qvel.shape != (robot.model.nv,)):
            raise RobustGaitError(f"gait initial state has sizes ({s.qpos.size}, {s.qvel.size}), robot "
                                  f"'{robot.name}' needs ({robot.model.nq}, {robot.model.nv})")

    def mirrored(self, robot: Robot) -> Gait:
        """The same gait written for the other stance leg (robot's permutation and signs)."""
        doms = tuple(replace(d, beta=robot.mirror_joints(d.beta.T).T.copy(),
                             ff_torque=None if d.ff_torque is None else robot.mirror_joints(d.ff_torque))
                     for d in self.domains)

        def mirror(s: State | None) -> State | None:
            return None if s is None else State(*robot.mirror_state(s.qpos, s.qvel))

        return replace(self, stance="left" if self.stance == "right" else "right", domains=doms,
                       initial_state=mirror(self.initial_state), pre_impact_state=mirror(self.pre_impact_state))


def _array(value: Any, shape: tuple[int | None, ...], what: str, src: str | Path) -> NDArray[np.float64]:
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise input_error(src, f"{what} is not a numeric array") from None
    if arr.ndim != len(shape) or any(s is not None and a != s for a, s in zip(arr.shape, shape, strict=True)):
        want = "×".join("m" if s is None else str(s) for s in shape)
        raise input_error(src, f"{what} has shape {'×'.join(map(str, arr.shape)) or 'scalar'}, expected {want}")
    if not np.all(np.isfinite(arr)):
        raise input_error(src, f"{what} contains NaN or infinite values")
    return arr


def _state(value: Any, src: str | Path, what: str) -> State | None:
    if value is None:
        return None
    if not isinstance(value, dict) or "qpos" not in value or "qvel" not in value:
        raise input_error(src, f"{what} must be an object with 'qpos' and 'qvel'")
    return State(_array(value["qpos"], (None,), f"{what}.qpos", src),
                 _array(value["qvel"], (None,), f"{what}.qvel", src))


def gait_from_dict(raw: Any, src: str | Path = "<gait>") -> Gait:
    """Validate and build a :class:`Gait` from the JSON structure of :meth:`Gait.to_dict`."""
    if not isinstance(raw, dict):
        raise input_error(src, "a gait file must hold a JSON object")
    version = raw.get("schema_version")
    if version != SCHEMA_VERSION:
        raise input_error(src, f"unsupported schema_version {version!r} (this robustgait reads {SCHEMA_VERSION})")
    for key in ("robot", "domain_graph", "stance", "domains"):
        if key not in raw:
            raise input_error(src, f"missing key '{key}'")
    if raw["domain_graph"] not in DOMAIN_GRAPHS:
        raise input_error(src, f"domain_graph must be one of {DOMAIN_GRAPHS}, got {raw['domain_graph']!r}")
    if raw["stance"] not in STANCES:
        raise input_error(src, f"stance must be 'left' or 'right', got {raw['stance']!r}")
    if not isinstance(raw["domains"], list) or not raw["domains"]:
        raise input_error(src, "'domains' must be a non-empty list")
    joints = tuple(raw.get("joints") or ())
    domains = []
    for i, d in enumerate(raw["domains"]):
        if not isinstance(d, dict) or "beta" not in d or "duration" not in d:
            raise input_error(src, f"domain {i} needs 'duration' and 'beta'")
        beta = _array(d["beta"], (len(joints) or None, BEZIER_DEGREE + 1), f"domain {i} beta", src)
        duration = float(_array(d["duration"], (), f"domain {i} duration", src))
        if duration <= 0:
            raise input_error(src, f"domain {i} duration must be positive, got {duration}")
        ff_tau = ff_torque = None
        if d.get("feedforward") is not None:
            ff_tau = _array(d["feedforward"].get("tau"), (None,), f"domain {i} feedforward tau", src)
            ff_torque = _array(d["feedforward"].get("torque"), (ff_tau.size, beta.shape[0]),
                               f"domain {i} feedforward torque", src)
        domains.append(Domain(str(d.get("name", f"domain{i}")), duration, beta, ff_tau, ff_torque))
    if len({d.beta.shape[0] for d in domains}) != 1:
        raise input_error(src, "all domains must have the same number of outputs")
    params = None
    if raw.get("params") is not None:
        try:
            params = GaitParams(**raw["params"])
        except TypeError as exc:
            raise input_error(src, f"bad 'params': {exc}") from None
        except RobustGaitError as exc:
            raise input_error(src, str(exc)) from None
    return Gait(robot=str(raw["robot"]), domain_graph=raw["domain_graph"], stance=raw["stance"],
                joints=joints, domains=tuple(domains),
                initial_state=_state(raw.get("initial_state"), src, "initial_state"),
                pre_impact_state=_state(raw.get("pre_impact_state"), src, "pre_impact_state"),
                params=params, solver=raw.get("solver"), meta=dict(raw.get("meta") or {}))


def _reject_constant(token: str) -> float:
    raise ValueError(f"non-finite number {token}")


def load_gait_json(path: str | Path) -> Gait:
    path = Path(path)
    try:
        raw = json.loads(path.read_text(), parse_constant=_reject_constant)
    except json.JSONDecodeError as exc:
        raise input_error(path, f"malformed JSON: {exc}") from None
    except ValueError as exc:
        raise input_error(path, f"malformed JSON: {exc}") from None
    return gait_from_dict(raw, path)


def import_frost_yaml(path: str | Path, robot: Robot | None = None, stance: str = "right") -> Gait:
    """Import a FROST/ambersim gait YAML (DESIGN §3).

    ``coeff_jt`` (m·8 numbers) → β = reshape (m, 8) in Fortran order; ``step_dur`` → T; ``ffPos`` (base
    position + quaternion w, x, y, z), ``startingPos`` (m) → qpos; ``ffVel`` (6: base linear velocity in the
    world frame, angular velocity in the body frame, as ambersim fed MuJoCo's ``qvel``), ``startingVel`` (m)
    → qvel. The coefficients are for ``stance`` (AMBER's Atalante gaits: right). ``inputparams`` and the
    base Bézier ``coeff_b`` are kept in ``meta``.
    """
    path = Path(path)
    try:
        raw = yaml.safe_load(path.read_text())
    except yaml.YAMLError as exc:
        first = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise input_error(path, f"malformed YAML: {first}") from None
    if not isinstance(raw, dict):
        raise input_error(path, "a FROST gait YAML must be a mapping")
    for key in ("coeff_jt", "step_dur"):
        if key not in raw:
            raise input_error(path, f"missing key '{key}'")
    flat = _array(raw["coeff_jt"], (None,), "coeff_jt", path)
    m = robot.n_joints if robot is not None else flat.size // (BEZIER_DEGREE + 1)
    if flat.size != m * (BEZIER_DEGREE + 1):
        raise input_error(path, f"coeff_jt has {flat.size} coefficients, expected {m * (BEZIER_DEGREE + 1)} "
                          f"({m} joints × {BEZIER_DEGREE + 1})")
    beta = flat.reshape(m, BEZIER_DEGREE + 1, order="F")
    duration = float(_array(raw["step_dur"], (), "step_dur", path))
    if duration <= 0:
        raise input_error(path, f"step_dur must be positive, got {duration}")
    state = None
    if all(k in raw for k in ("ffPos", "startingPos", "ffVel", "startingVel")):
        qpos = np.concatenate([_array(raw["ffPos"], (7,), "ffPos", path),
                               _array(raw["startingPos"], (m,), "startingPos", path)])
        qvel = np.concatenate([_array(raw["ffVel"], (6,), "ffVel", path),
                               _array(raw["startingVel"], (m,), "startingVel", path)])
        qpos[3:7] /= np.linalg.norm(qpos[3:7])
        state = State(qpos, qvel)
    meta: dict[str, Any] = {"source": f"frost-yaml:{path.name}"}
    if "inputparams" in raw:
        meta["frost_inputparams"] = raw["inputparams"]
    if "coeff_b" in raw:
        meta["frost_coeff_b"] = list(map(float, raw["coeff_b"]))
    return Gait(robot=robot.name if robot is not None else "unknown", domain_graph="flat", stance=stance,
                joints=robot.spec.joints if robot is not None else (), domains=(Domain("single_support", duration,
                beta),), initial_state=state, meta=meta)


def load_gait(path: str | Path, robot: Robot | None = None) -> Gait:
    """Load a gait file of either format (by extension) and, given a robot, check it fits."""
    path = Path(path)
    if not path.is_file():
        raise input_error(path, "gait file not found")
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
