"""Reading input files safely and validating their data (``docs/inputs.md``).

Every input file goes through two stages:

1. :func:`read_bytes` / :func:`read_json` / :func:`read_yaml` / :func:`read_toml`: the path must be a
   regular file (not a directory, FIFO or device: reading those could block forever) of at most
   :data:`~robustgait.io.limits.MAX_INPUT_BYTES`, UTF-8 text, and well-formed for its syntax (JSON without
   duplicate keys, YAML without aliases, TOML).
2. :func:`validate`: pydantic validates the data into a schema — a :func:`table` (a dataclass refusing
   unknown keys) whose fields carry their limits (:mod:`robustgait.io.limits`) — strictly: ``"0.7"`` or
   ``true`` where a number belongs are refused, NaN and infinities too. The same schema library and the same
   formatter of its error objects (:func:`robustgait.config.base.explain`) serve the configuration: errors read
   ``FILE: field: problem`` with the value found there, the limit and its unit.

Checks that involve several fields (a permutation, matching row counts) are done by the builders after
:func:`validate`, with :func:`field_error`. A new input file needs a schema (its limits in
:mod:`robustgait.io.limits`, or a config section) and a reader next to the others (``io/configfile.py`` is the
smallest example).
"""

from __future__ import annotations

import json
import math
import stat
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Any, TypeVar

import yaml
from pydantic import ConfigDict, ValidationError
from pydantic.dataclasses import dataclass as pydantic_dataclass

from robustgait.config.base import Format, explain, format_path, validator
from robustgait.errors import RobustGaitError, input_error
from robustgait.io.limits import MAX_INPUT_BYTES, MAX_NESTING

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover - exercised on 3.10 only
    import tomli as tomllib

T = TypeVar("T")
FORMATS: dict[str, Format] = {".json": "json", ".yaml": "yaml", ".yml": "yaml", ".toml": "toml"}
_TABLE = ConfigDict(extra="forbid", allow_inf_nan=False, defer_build=True)
_LENIENT = ConfigDict(extra="ignore", allow_inf_nan=False, defer_build=True)


def table(cls: type[T] | None = None, *, extra: str = "forbid") -> Any:
    """Make ``cls`` a file schema: a pydantic dataclass that refuses unknown keys (``extra="ignore"``: a format
    whose writers add keys we do not use, such as FROST's YAML)."""
    settings = _TABLE if extra == "forbid" else _LENIENT

    def make(c: type[T]) -> Any:
        return pydantic_dataclass(c, config=settings)

    return make(cls) if cls is not None else make


def field_error(src: str | Path | None, field: str, problem: str) -> RobustGaitError:
    """``FILE: field: problem`` (or ``FILE: problem`` for the whole file)."""
    return input_error(src, f"{field}: {problem}" if field else problem)


# -------------------------------------------------------------------------------------------------- reading
def read_bytes(path: str | Path, what: str = "file") -> bytes:
    """The bytes of a regular input file of at most :data:`MAX_INPUT_BYTES` (one-line errors otherwise)."""
    p = Path(path)
    try:
        st = p.stat()
    except FileNotFoundError:
        raise input_error(p, f"{what} not found") from None
    except (OSError, ValueError) as exc:
        raise input_error(p, f"cannot read {what}: {getattr(exc, 'strerror', None) or exc}") from None
    if stat.S_ISDIR(st.st_mode):
        raise input_error(p, f"is a directory, not a {what}")
    if not stat.S_ISREG(st.st_mode):
        raise input_error(p, f"is not a regular file (a device, FIFO or socket), not a {what}")
    if st.st_size > MAX_INPUT_BYTES:
        raise input_error(p, f"{what} is {st.st_size / 2**20:.0f} MiB, over the {MAX_INPUT_BYTES // 2**20} MiB limit")
    try:
        with p.open("rb") as fh:
            data = fh.read(MAX_INPUT_BYTES + 1)
    except OSError as exc:
        raise input_error(p, f"cannot read {what}: {exc.strerror or exc}") from None
    if len(data) > MAX_INPUT_BYTES:
        raise input_error(p, f"{what} is over the {MAX_INPUT_BYTES // 2**20} MiB limit")
    return data


def read_text(path: str | Path, what: str = "file") -> str:
    """:func:`read_bytes` decoded as UTF-8 (a leading byte-order mark is dropped)."""
    data = read_bytes(path, what)
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise input_error(path, f"not UTF-8 text (byte 0x{data[exc.start]:02x} at offset {exc.start})") from None
    return text.removeprefix("\ufeff")


def _no_duplicates(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for key, value in pairs:
        if key in out:
            raise ValueError(f"duplicate key {key!r}")
        out[key] = value
    return out


def read_json(path: str | Path, what: str = "file") -> Any:
    """Parse a JSON file. NaN/Infinity literals parse (as floats) so that the schema names their field."""
    text = read_text(path, what)
    try:
        return json.loads(text, object_pairs_hook=_no_duplicates)
    except json.JSONDecodeError as exc:
        raise input_error(path, f"malformed JSON: {exc.msg} (line {exc.lineno}, column {exc.colno})") from None
    except RecursionError:
        raise input_error(path, "malformed JSON: nested too deeply") from None
    except ValueError as exc:  # duplicate keys, integers of more than 4300 digits
        raise input_error(path, f"malformed JSON: {exc}") from None


class _SafeLoaderNoAliases(yaml.SafeLoader):
    """PyYAML's safe loader without anchors/aliases: a few aliased lines can expand to gigabytes."""

    def compose_node(self, parent: Any, index: Any) -> Any:
        if self.check_event(yaml.AliasEvent):
            mark = self.peek_event().start_mark
            raise yaml.composer.ComposerError(None, None, "YAML aliases (*name) are not supported", mark)
        return super().compose_node(parent, index)


def read_yaml(path: str | Path, what: str = "file") -> Any:
    text = read_text(path, what)
    try:
        return yaml.load(text, Loader=_SafeLoaderNoAliases)
    except yaml.MarkedYAMLError as exc:
        mark = exc.problem_mark
        where = f" (line {mark.line + 1}, column {mark.column + 1})" if mark is not None else ""
        raise input_error(path, f"malformed YAML: {exc.problem or exc.context or 'syntax error'}{where}") from None
    except yaml.YAMLError as exc:
        first = (str(exc).splitlines() or [type(exc).__name__])[0]
        raise input_error(path, f"malformed YAML: {first}") from None
    except RecursionError:
        raise input_error(path, "malformed YAML: nested too deeply") from None


def read_toml(path: str | Path, what: str = "file") -> dict[str, Any]:
    text = read_text(path, what)
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise input_error(path, f"malformed TOML: {' '.join(str(exc).split())}") from None
    except RecursionError:
        raise input_error(path, "malformed TOML: nested too deeply") from None


READERS = {"json": read_json, "yaml": read_yaml, "toml": read_toml}


# ----------------------------------------------------------------------------------------------- validation
def validate(raw: Any, schema: type[T], src: str | Path, fmt: Format = "json") -> T:
    """Validate ``raw`` into ``schema`` (pydantic), errors as one line ``FILE: field: problem``."""
    try:
        out: T = validator(schema)(raw)
        return out
    except ValidationError as exc:
        raise input_error(src, explain(exc, schema, fmt=fmt)) from None
    except RecursionError:
        raise input_error(src, "nested too deeply") from None


# --------------------------------------------------------------------------------------- free-form values
def check_free_form(value: Any, src: str | Path, field: str) -> None:
    """A free-form value (``meta``, ``solver``, FROST ``inputparams``) must be plain JSON data: objects with
    string keys, lists, strings, finite numbers, true/false, null; nested at most :data:`MAX_NESTING` deep."""
    for path, bad in _free_form_problems(value, [field], 0):
        raise field_error(src, format_path(path), bad)


def _free_form_problems(value: Any, path: list[str | int], depth: int) -> Iterator[tuple[list[str | int], str]]:
    if depth > MAX_NESTING:
        yield path, f"nested more than {MAX_NESTING} levels deep"
    elif isinstance(value, dict):
        for k, v in value.items():
            if not isinstance(k, str):
                yield path, f"keys must be strings (got {type(k).__name__} {k!r})"
                return
            yield from _free_form_problems(v, [*path, k], depth + 1)
    elif isinstance(value, (list, tuple)):
        for i, v in enumerate(value):
            yield from _free_form_problems(v, [*path, i], depth + 1)
    elif isinstance(value, float):
        if not math.isfinite(value):
            yield path, f"must be a finite number (got {value})"
    elif isinstance(value, int) and not isinstance(value, bool):
        if abs(value) >= 2**63:
            yield path, "integer out of range (|n| < 2^63)"
    elif not (value is None or isinstance(value, (str, bool))):
        yield path, f"must be plain data (JSON types), got {type(value).__name__}"
