"""The files of ``robustgait robot init`` (``docs/robots.md``, "Your robot"): the robot's model it reads — an MJCF
(.xml) or a URDF (.urdf), parsed by MuJoCo as the spec loader parses it (:func:`robustgait.io.robotfile.
parse_model`) — and the spec it writes, atomically and only once the loader accepts it. One-line errors for an
unknown extension, a directory, a missing or unparsable file; the inspection itself is
:mod:`robustgait.inspection`."""

from __future__ import annotations

from pathlib import Path
from typing import Literal

import mujoco

from robustgait.errors import RobustGaitError, input_error
from robustgait.io.output import atomic_output
from robustgait.io.robotfile import load_robot, parse_model

ModelKind = Literal["mjcf", "urdf"]
MODEL_SUFFIXES: dict[str, ModelKind] = {".xml": "mjcf", ".mjcf": "mjcf", ".urdf": "urdf"}


def model_kind(path: str | Path) -> ModelKind:
    """``mjcf`` or ``urdf`` from the file's extension (a one-line error for any other)."""
    p = Path(path)
    kind = MODEL_SUFFIXES.get(p.suffix.lower())
    if kind is None:
        raise input_error(p, f"unknown robot model format {p.suffix or '(no extension)'!r} (robustgait reads an "
                          "MJCF .xml or a URDF .urdf)")
    return kind


def read_model(path: str | Path) -> tuple[mujoco.MjSpec, ModelKind]:
    """The model file parsed by MuJoCo (MuJoCo compiles a URDF with its own defaults: ``fusestatic`` merges every
    link attached by a fixed joint into its parent, visual geometry is discarded, a joint's ``effort`` becomes its
    ``actuatorfrcrange``). Returns the parsed spec and the file's kind."""
    p = Path(path)
    kind = model_kind(p)
    if p.is_dir():
        raise input_error(p, "is a directory: give the robot's MJCF or URDF file")
    if not p.is_file():
        raise input_error(p, "robot model file not found")
    return parse_model(p), kind


def write_spec(path: str | Path, text: str) -> Path:
    """Write a spec TOML atomically (:mod:`robustgait.io.output`), after loading it with :func:`load_robot` from
    its temporary file beside the target (so that the model's relative path resolves the same): a spec the loader
    refuses is not written."""
    target = Path(path)
    with atomic_output(target, "toml") as tmp:
        tmp.write_text(text, encoding="utf-8")
        try:
            load_robot(tmp)
        except RobustGaitError as exc:
            raise RobustGaitError(f"{target}: the written spec does not load (nothing written): "
                                  f"{str(exc).replace(str(tmp), target.name)}") from None
    return target
