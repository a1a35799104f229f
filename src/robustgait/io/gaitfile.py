"""Gait files: robustgait's JSON and FROST/ambersim YAML — their schemas, reading them into a
:class:`~robustgait.gait.Gait`, writing either (``docs/gaits.md``, limits in ``docs/inputs.md``)."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any, Literal

import annotated_types as at
import numpy as np
import yaml
from numpy.typing import NDArray
from pydantic import StringConstraints

from robustgait.config import GaitFormat, GaitParams
from robustgait.config.base import Float, Str
from robustgait.errors import RobustGaitError, input_error
from robustgait.gait import BEZIER_DEGREE, SCHEMA_VERSION, Domain, Gait, State
from robustgait.io import limits as L
from robustgait.io.output import write_text
from robustgait.io.schema import check_free_form, field_error, read_json, read_yaml, table, validate

if TYPE_CHECKING:
    from robustgait.robots import Robot

N_COEF = BEZIER_DEGREE + 1
Name = Annotated[str, StringConstraints(strict=True, min_length=1, max_length=200, pattern=r"^[^\x00]+$")]
Coef = Annotated[Float, L.BEZIER_COEFFICIENT]
BetaRow = Annotated[list[Coef], at.MinLen(N_COEF), at.MaxLen(N_COEF)]
Qpos = Annotated[Float, L.QPOS]
Qvel = Annotated[Float, L.QVEL]
Duration = Annotated[Float, L.DOMAIN_DURATION]
Torque = Annotated[Float, L.FEEDFORWARD_TORQUE]
Phase = Annotated[Float, L.FEEDFORWARD_PHASE]
FeedforwardPhases = Annotated[list[Phase], at.MinLen(2), at.MaxLen(L.MAX_FEEDFORWARD_SAMPLES)]
FeedforwardTorques = Annotated[list[Annotated[list[Torque], at.MinLen(1), at.MaxLen(L.MAX_JOINTS)]],
                               at.MinLen(2), at.MaxLen(L.MAX_FEEDFORWARD_SAMPLES)]


@table
class FeedforwardFile:
    tau: FeedforwardPhases
    torque: FeedforwardTorques


@table
class DomainFile:
    duration: Duration
    beta: Annotated[list[BetaRow], at.MinLen(1), at.MaxLen(L.MAX_JOINTS)]
    name: Annotated[Str, at.MaxLen(200)] = ""
    feedforward: FeedforwardFile | None = None


@table
class StateFile:
    qpos: Annotated[list[Qpos], at.MinLen(8), at.MaxLen(7 + L.MAX_JOINTS)]
    qvel: Annotated[list[Qvel], at.MinLen(7), at.MaxLen(6 + L.MAX_JOINTS)]


@table
class GaitFile:
    """robustgait's gait JSON, ``schema_version`` 1 (:func:`gait_to_dict` writes exactly these keys)."""

    schema_version: Literal[1]
    robot: Name
    domain_graph: Literal["flat", "multicontact"]
    stance: Literal["left", "right"]
    domains: Annotated[list[DomainFile], at.MinLen(1), at.MaxLen(L.MAX_DOMAINS)]
    joints: Annotated[list[Name], at.MaxLen(L.MAX_JOINTS)] = dataclasses.field(default_factory=list)
    initial_state: StateFile | None = None
    pre_impact_state: StateFile | None = None
    params: GaitParams | None = None
    solver: dict[str, Any] | None = None
    meta: dict[str, Any] = dataclasses.field(default_factory=dict)
    held: dict[Name, Annotated[Float, L.POSTURE]] = dataclasses.field(default_factory=dict)


@table(extra="ignore")
class FrostFile:
    """A FROST/ambersim gait YAML (other keys, which ambersim writes too, are ignored)."""

    coeff_jt: Annotated[list[Coef], at.MinLen(N_COEF), at.MaxLen(N_COEF * L.MAX_JOINTS)]
    step_dur: Duration
    ffPos: Annotated[list[Qpos], at.MinLen(7), at.MaxLen(7)] | None = None  # FROST's key names
    startingPos: Annotated[list[Qpos], at.MinLen(1), at.MaxLen(L.MAX_JOINTS)] | None = None
    ffVel: Annotated[list[Qvel], at.MinLen(6), at.MaxLen(6)] | None = None
    startingVel: Annotated[list[Qvel], at.MinLen(1), at.MaxLen(L.MAX_JOINTS)] | None = None
    coeff_b: Annotated[list[Coef], at.MaxLen(N_COEF * L.MAX_JOINTS)] | None = None
    inputparams: dict[str, Any] | None = None
    ff_tau: FeedforwardPhases | None = None  # robustgait's keys: ambersim's files have no feedforward
    ff_torque: FeedforwardTorques | None = None


def _unit_quaternion(qpos: NDArray[np.float64], src: str | Path, field: str) -> NDArray[np.float64]:
    """qpos with its base quaternion (entries 3:7) normalized; a quaternion that cannot be is refused."""
    norm = float(np.linalg.norm(qpos[3:7]))
    if norm < L.MIN_QUATERNION_NORM:
        raise field_error(src, f"{field}[3:7]", f"base quaternion has norm {norm:.3g}: it cannot be normalized "
                          f"(a rotation needs a norm ≥ {L.MIN_QUATERNION_NORM:g}, e.g. [1, 0, 0, 0])")
    if abs(norm - 1.0) > 1e-12:
        qpos = qpos.copy()
        qpos[3:7] /= norm
    return qpos


def _state(s: StateFile | None, m: int, src: str | Path, field: str, held: int = 0) -> State | None:
    """A state of m planned and ``held`` held joints."""
    if s is None:
        return None
    joints = f"{m} joints" + (f" + {held} held" if held else "")
    if len(s.qpos) != 7 + m + held:
        raise field_error(src, f"{field}.qpos", f"has {len(s.qpos)} values, expected {7 + m + held} "
                          f"(base position 3 + quaternion 4 + {joints})")
    if len(s.qvel) != 6 + m + held:
        raise field_error(src, f"{field}.qvel", f"has {len(s.qvel)} values, expected {6 + m + held} "
                          f"(base linear 3 + angular 3 + {joints})")
    qpos = _unit_quaternion(np.array(s.qpos, dtype=np.float64), src, f"{field}.qpos")
    return State(qpos, np.array(s.qvel, dtype=np.float64))


def _feedforward(tau_in: list[float], torque_in: list[list[float]], m: int, src: str | Path, tau_field: str,
                 torque_field: str) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Feedforward phases (K,) and torques (K, m) as arrays: phases increasing strictly, one row per phase of
    ``m`` torques (both file formats)."""
    tau = np.array(tau_in, dtype=np.float64)
    if np.any(np.diff(tau) <= 0):
        raise field_error(src, tau_field, "phases must increase strictly")
    if len(torque_in) != tau.size or any(len(row) != m for row in torque_in):
        bad = next((k for k, row in enumerate(torque_in) if len(row) != m), None)
        raise field_error(src, torque_field + (f"[{bad}]" if bad is not None else ""),
                          f"must be {tau.size} rows (one per phase) of {m} torques (one per joint)")
    return tau, np.array(torque_in, dtype=np.float64)


def _step_duration(total: float, src: str | Path, field: str) -> None:
    if not L.STEP_DURATION.contains(total):
        raise field_error(src, field, f"the step lasts {total:g} s; it must satisfy {L.STEP_DURATION.text()}")


def gait_from_dict(raw: Any, src: str | Path = "<gait>") -> Gait:
    """Validate the JSON structure of :meth:`Gait.to_dict` and build the :class:`Gait`."""
    g = validate(raw, GaitFile, src, "json")
    assert g.schema_version == SCHEMA_VERSION
    if len(set(g.joints)) != len(g.joints):
        dup = next(j for j in g.joints if g.joints.count(j) > 1)
        raise field_error(src, "joints", f"joint {dup!r} is listed twice")
    m = len(g.joints) or len(g.domains[0].beta)
    domains = []
    for i, d in enumerate(g.domains):
        if len(d.beta) != m:
            what = f"'joints' names {m} joints" if g.joints else f"domain 0 has {m} rows"
            raise field_error(src, f"domains[{i}].beta", f"has {len(d.beta)} rows (one per joint), but {what}")
        ff = d.feedforward
        ff_tau, ff_torque = (None, None) if ff is None else _feedforward(
            ff.tau, ff.torque, m, src, f"domains[{i}].feedforward.tau", f"domains[{i}].feedforward.torque")
        domains.append(Domain(d.name or f"domain{i}", float(d.duration), np.array(d.beta, dtype=np.float64),
                              ff_tau, ff_torque))
    _step_duration(sum(d.duration for d in g.domains), src, "domains[].duration")
    if g.solver is not None:
        check_free_form(g.solver, src, "solver")
    check_free_form(g.meta, src, "meta")
    params = g.params
    if params is not None and params.step_duration is None:  # the gait's own duration
        params = dataclasses.replace(params, step_duration=sum(d.duration for d in g.domains))
    for name in g.held:
        if name in g.joints:
            raise field_error(src, f"held.{name}", "is also a planned joint (joints)")
    h = len(g.held)
    return Gait(robot=g.robot, domain_graph=g.domain_graph, stance=g.stance, joints=tuple(g.joints),
                domains=tuple(domains), initial_state=_state(g.initial_state, m, src, "initial_state", h),
                pre_impact_state=_state(g.pre_impact_state, m, src, "pre_impact_state", h), params=params,
                solver=dict(g.solver) if g.solver is not None else None, meta=dict(g.meta),
                held=tuple((k, float(v)) for k, v in g.held.items()))


def read_gait_json(path: str | Path) -> Gait:
    return gait_from_dict(read_json(path, "gait file"), path)


FROST_STATE_KEYS = ("ffPos", "startingPos", "ffVel", "startingVel")
FROST_FEEDFORWARD_KEYS = ("ff_tau", "ff_torque")


def _all_or_none(f: FrostFile, keys: tuple[str, ...], path: str | Path, what: str) -> bool:
    """Whether the keys that together make ``what`` are given; one missing among the others is refused."""
    given = [k for k in keys if getattr(f, k) is not None]
    if given and len(given) < len(keys):
        missing = next(k for k in keys if k not in given)
        raise field_error(path, missing, f"missing: {what} needs all of {', '.join(keys)} or none of them")
    return bool(given)


def import_frost_yaml(path: str | Path, robot: Robot | None = None, stance: str = "right") -> Gait:
    """Import a FROST/ambersim gait YAML (``docs/gaits.md``).

    ``coeff_jt`` (m·8 numbers) → β = reshape (m, 8) in Fortran order; ``step_dur`` → T; ``ffPos`` (base
    position + quaternion w, x, y, z, normalized), ``startingPos`` (m) → qpos; ``ffVel`` (6: base linear
    velocity in the world frame, angular velocity in the body frame, as ambersim fed MuJoCo's ``qvel``),
    ``startingVel`` (m) → qvel (all four or none; a ``robot`` that holds joints: its every joint in the MJCF's order,
    and the gait holds them at the spec's angles). The coefficients are for ``stance`` (AMBER's Atalante gaits:
    right). ``inputparams`` and the base Bézier ``coeff_b`` are kept in ``meta``. robustgait's own keys
    ``ff_tau`` (K phases) and ``ff_torque`` (K rows of m torques), written by :func:`save_frost_yaml`, are the
    domain's feedforward torques (both or none).
    """
    raw = read_yaml(path, "gait file")
    if not isinstance(raw, dict):
        raise field_error(path, "", f"a FROST gait YAML must be a mapping, got {type(raw).__name__}")
    f = validate(raw, FrostFile, path, "yaml")
    n = len(f.coeff_jt)
    if robot is not None:
        m = robot.n_joints
        if n != m * N_COEF:
            raise field_error(path, "coeff_jt", f"has {n} coefficients, expected {m * N_COEF} ({m} joints × {N_COEF})")
    elif n % N_COEF:
        raise field_error(path, "coeff_jt", f"has {n} coefficients, not a multiple of {N_COEF} (joints × {N_COEF})")
    else:
        m = n // N_COEF
    beta = np.array(f.coeff_jt, dtype=np.float64).reshape(m, N_COEF, order="F")
    _step_duration(f.step_dur, path, "step_dur")
    held = tuple((h.name, h.angle) for h in robot.spec.held) if robot is not None else ()
    state = None
    if _all_or_none(f, FROST_STATE_KEYS, path, "the initial state"):
        assert f.ffPos is not None and f.startingPos is not None and f.ffVel is not None and f.startingVel is not None
        for key, values in (("startingPos", f.startingPos), ("startingVel", f.startingVel)):
            if len(values) != m + len(held):
                raise field_error(path, key, f"has {len(values)} values, expected {m + len(held)} (one per joint"
                                  + (f", {len(held)} of them held" if held else "") + ")")
        qpos = _unit_quaternion(np.array(f.ffPos + f.startingPos, dtype=np.float64), path, "ffPos")
        state = State(qpos, np.array(f.ffVel + f.startingVel, dtype=np.float64))
    ff_tau = ff_torque = None
    if _all_or_none(f, FROST_FEEDFORWARD_KEYS, path, "the feedforward"):
        assert f.ff_tau is not None and f.ff_torque is not None
        ff_tau, ff_torque = _feedforward(f.ff_tau, f.ff_torque, m, path, "ff_tau", "ff_torque")
    meta: dict[str, Any] = {"source": f"frost-yaml:{Path(path).name}"}
    if f.inputparams is not None:
        check_free_form(f.inputparams, path, "inputparams")
        meta["frost_inputparams"] = f.inputparams
    if f.coeff_b is not None:
        meta["frost_coeff_b"] = [float(v) for v in f.coeff_b]
    return Gait(robot=robot.name if robot is not None else "unknown", domain_graph="flat", stance=stance,
                joints=robot.spec.joints if robot is not None else (),
                domains=(Domain("single_support", float(f.step_dur), beta, ff_tau, ff_torque),),
                initial_state=state, meta=meta, held=held)


def load_gait(path: str | Path, robot: Robot | None = None) -> Gait:
    """Load a gait file of either format (by extension: ``.json`` robustgait, ``.yaml``/``.yml`` FROST/ambersim)
    and, given a robot, check it fits."""
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix == ".json":
        gait = read_gait_json(path)
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


GAIT_SUFFIXES: dict[str, GaitFormat] = {".json": "json", ".yaml": "frost", ".yml": "frost"}


def gait_format(path: str | Path, to: GaitFormat | None = None) -> GaitFormat:
    """The format a gait is written in: ``to``, or else the one of ``path``'s suffix (``.json`` robustgait JSON,
    ``.yaml``/``.yml`` FROST/ambersim); a ``to`` that the suffix contradicts is refused (one line)."""
    suffix = Path(path).suffix.lower()
    named = GAIT_SUFFIXES.get(suffix)
    if to is None and named is None:
        raise input_error(path, f"unknown gait format {suffix or '(no extension)'!r} (write .json, or .yaml/.yml "
                          "for FROST/ambersim)")
    if to is not None and named != to:
        want = "a .json file" if to == "json" else "a .yaml or .yml file"
        raise input_error(path, f"--to {to} writes {want}, but the output is named {suffix or '(no extension)'!r} "
                          "(rename it, or leave --to out: the suffix picks the format)")
    fmt = to or named
    assert fmt is not None
    return fmt


def save_gait(gait: Gait, path: str | Path, to: GaitFormat | None = None, src: str | Path = "<gait>") -> Path:
    """Write a gait as robustgait JSON or, for ``to="frost"`` or a ``.yaml``/``.yml`` path, as a FROST/ambersim
    YAML (:func:`save_frost_yaml`; ``src`` names the gait if it cannot be), through
    :func:`robustgait.io.output.write_text`: the target is checked first, the file is written atomically, nothing
    half-written or temporary is left behind."""
    if gait_format(path, to) == "frost":
        return save_frost_yaml(gait, path, src)
    return write_text(path, json.dumps(gait.to_dict(), indent=1, allow_nan=False), "json")


class _YamlDumper(yaml.SafeDumper):
    """PyYAML's safe dumper without anchors and aliases (the reader refuses them; a list shared twice in
    ``inputparams`` is written twice). Floats are written as ``repr`` (the shortest text that reads back to the
    same double), which is what makes the export exact."""

    def ignore_aliases(self, data: Any) -> bool:
        return True


def frost_yaml_dict(gait: Gait, src: str | Path = "<gait>") -> dict[str, Any]:
    """The FROST/ambersim mapping of ``gait``, the inverse of :func:`import_frost_yaml` (``docs/gaits.md``).

    ``coeff_jt`` = β (m, 8) raveled in Fortran order (FROST's ``OutputParams(:)``); ``step_dur`` = T; the
    initial state as ``ffPos`` (qpos[:7]), ``startingPos`` (qpos[7:], every joint: held ones too, whose angles the
    importer takes from the robot spec), ``ffVel`` (qvel[:6]), ``startingVel`` (qvel[6:]); FROST's ``coeff_b`` and
    ``inputparams`` kept in ``meta`` by the importer; the feedforward as robustgait's ``ff_tau`` (K) and
    ``ff_torque`` (K, m). A gait the layout cannot hold is refused, one line:
    more than one domain (a multi-contact gait: ambersim's file is one domain), or a left stance (the importer
    reads the coefficients as right-stance). Params, the solver report, the other meta, the pre-impact state
    and the joint names are not written: none of them is needed to walk the gait.
    """
    if len(gait.domains) != 1 or gait.domain_graph != "flat":
        raise field_error(src, "domain_graph", f"a {gait.domain_graph} gait has {len(gait.domains)} domains, a "
                          "FROST/ambersim gait YAML holds one (coeff_jt, step_dur): keep it as .json")
    if gait.stance != "right":
        raise field_error(src, "stance", f"a {gait.stance}-stance gait: FROST/ambersim gait YAMLs hold right-stance "
                          "coefficients (write its right-stance relabeling: --mirror, Gait.mirrored)")
    d = gait.domains[0]
    out: dict[str, Any] = {"coeff_jt": d.beta.ravel(order="F").tolist(), "step_dur": float(d.duration)}
    s = gait.initial_state
    if s is not None:
        out |= {"ffPos": s.qpos[:7].tolist(), "startingPos": s.qpos[7:].tolist(), "ffVel": s.qvel[:6].tolist(),
                "startingVel": s.qvel[6:].tolist()}
    if d.ff_tau is not None and d.ff_torque is not None:
        out |= {"ff_tau": d.ff_tau.tolist(), "ff_torque": d.ff_torque.tolist()}
    for key in ("coeff_b", "inputparams"):
        if f"frost_{key}" in gait.meta:
            out[key] = gait.meta[f"frost_{key}"]
    validate(out, FrostFile, src, "yaml")  # what the importer would refuse is not written
    return out


def save_frost_yaml(gait: Gait, path: str | Path, src: str | Path = "<gait>") -> Path:
    """Write ``gait`` as a FROST/ambersim gait YAML (:func:`frost_yaml_dict`; a ``.yaml``/``.yml`` path),
    atomically through :func:`robustgait.io.output.write_text`. :func:`import_frost_yaml` reads it back to the
    same β, T, initial state and feedforward, bit for bit. ``src`` names the gait in error messages."""
    if gait_format(path) != "frost":
        raise input_error(path, "a FROST/ambersim gait is written to a .yaml or .yml file")
    data = frost_yaml_dict(gait, src)
    rows = ", ".join(gait.joints) if gait.joints else f"{gait.n_outputs} joints in the robot's order"
    head = "".join(f"# {' '.join(line.splitlines())}\n" for line in (  # a name's line break must not end the comment
        f"FROST/ambersim gait written by robustgait: robot {gait.robot}, right stance, T = {data['step_dur']!r} s",
        f"coeff_jt: Bezier coefficients (m, 8) in Fortran order, rows: {rows}"))
    body = yaml.dump(data, Dumper=_YamlDumper, default_flow_style=None, sort_keys=False, allow_unicode=True)
    return write_text(path, head + body, "gait")
