"""Reading input files safely and validating their data against msgspec schemas (``docs/inputs.md``).

Every input file goes through two stages:

1. :func:`read_bytes` / :func:`read_json` / :func:`read_yaml` / :func:`read_toml`: the path must be a
   regular file (not a directory, FIFO or device: reading those could block forever) of at most
   :data:`~robustgait.io.limits.MAX_INPUT_BYTES`, UTF-8 text, and well-formed for its syntax (JSON without
   duplicate keys, YAML without aliases, TOML).
2. :func:`validate`: ``msgspec.convert`` into a schema (:class:`Table` subclasses with bounded fields built
   from :mod:`robustgait.io.limits`) — strict: ``"0.7"`` or ``true`` where a number belongs are refused,
   unknown keys are refused, NaN and infinities fail every bound. msgspec's message is rewritten into
   ``FILE: field: problem`` with the value found there, the limit and its unit.

Checks that involve several fields (a permutation, matching row counts) are done by the builders after
:func:`validate`, with :func:`field_error`. A new input file (for example a study config) needs only a
schema and :func:`load_file`::

    class StudyFile(Table):
        iterations: Annotated[int, Meta(ge=1, le=1000)] = 10
    cfg = load_file("study.toml", StudyFile, what="study config")

Why msgspec and not pydantic: measured by ``benchmarks/bench_schema.py`` (see ``docs/inputs.md``).
"""

from __future__ import annotations

import json
import math
import re
import stat
import sys
import types
import typing
from collections.abc import Iterator
from pathlib import Path
from typing import Annotated, Any, Literal, TypeVar, Union, get_args, get_origin

import msgspec
import yaml

from robustgait.errors import RobustGaitError, input_error
from robustgait.io.limits import MAX_INPUT_BYTES, MAX_NESTING, number_text

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover - exercised on 3.10 only
    import tomli as tomllib

Format = Literal["json", "yaml", "toml"]
T = TypeVar("T")
FORMATS: dict[str, Format] = {".json": "json", ".yaml": "yaml", ".yml": "yaml", ".toml": "toml"}

# What msgspec's type names are called in each file format.
_NOUNS: dict[str, str] = {"float": "a number", "int": "an integer", "str": "a string", "bool": "a boolean",
                          "null": "null", "bytes": "bytes", "datetime": "a date-time", "date": "a date",
                          "time": "a time"}
_CONTAINERS: dict[Format, dict[str, str]] = {
    "json": {"object": "an object", "array": "a list"},
    "yaml": {"object": "a mapping", "array": "a list"},
    "toml": {"object": "a table", "array": "an array"},
}


class Table(msgspec.Struct, forbid_unknown_fields=True, kw_only=True):
    """Base of the schemas: unknown keys are refused, fields are given by name."""


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


def load_file(path: str | Path, schema: type[T], *, what: str = "file",
              formats: tuple[Format, ...] = ("toml", "json", "yaml")) -> T:
    """Read a config file (format by extension, one of ``formats``) and validate it into ``schema``."""
    fmt = FORMATS.get(Path(path).suffix.lower())
    if fmt is None or fmt not in formats:
        exts = ", ".join(e for e, f in FORMATS.items() if f in formats)
        raise input_error(path, f"unknown {what} format {Path(path).suffix or '(no extension)'!r} (expected {exts})")
    return validate(READERS[fmt](path, what), schema, path, fmt)


# ----------------------------------------------------------------------------------------------- validation
def validate(raw: Any, schema: type[T], src: str | Path, fmt: Format = "json") -> T:
    """``msgspec.convert(raw, schema)`` with errors rewritten as ``FILE: field: problem``."""
    try:
        return msgspec.convert(raw, schema)
    except msgspec.ValidationError as exc:
        raise input_error(src, explain(str(exc), raw, schema, fmt)) from None
    except RecursionError:
        raise input_error(src, "nested too deeply") from None


def _parse_path(loc: str) -> list[str | int | None]:
    """``$.a[3].b[...]`` → ["a", 3, "b", None] (None: a dict key msgspec did not name)."""
    parts: list[str | int | None] = []
    for m in re.finditer(r"\.([^.\[]+)|\[(\d+)\]|\[\.\.\.\]", loc[1:]):
        if m.group(1) is not None:
            parts.append(m.group(1))
        elif m.group(2) is not None:
            parts.append(int(m.group(2)))
        else:
            parts.append(None)
    return parts


def _strip(tp: Any) -> tuple[Any, list[msgspec.Meta]]:
    """Remove ``Annotated`` layers, collecting their msgspec.Meta."""
    metas: list[msgspec.Meta] = []
    while get_origin(tp) is Annotated:
        args = get_args(tp)
        metas.extend(a for a in args[1:] if isinstance(a, msgspec.Meta))
        tp = args[0]
    return tp, metas


def _is_struct(tp: Any) -> bool:
    return isinstance(tp, type) and issubclass(tp, msgspec.Struct)


def _pick_union(tp: Any, value: Any) -> Any:
    """The member of a union a raw value was meant for (by its kind); Optional unwraps."""
    if get_origin(tp) not in (Union, types.UnionType):
        return tp
    members = [a for a in get_args(tp) if a is not type(None)]
    for m in members:
        base, _ = _strip(m)
        o = get_origin(base) or base
        container = _is_struct(base) or o in (dict, list, tuple)
        if isinstance(value, dict) and (_is_struct(base) or o is dict):
            return m
        if isinstance(value, (list, tuple)) and o in (list, tuple):
            return m
        if not isinstance(value, (dict, list, tuple)) and not container:
            return m
    return members[0] if len(members) == 1 else tp


def _resolve(tp: Any, value: Any) -> tuple[Any, list[msgspec.Meta]]:
    """The bare type and constraints of annotation ``tp`` for raw ``value`` (Annotated, unions unwrapped)."""
    base, metas = _strip(tp)
    base, more = _strip(_pick_union(base, value))
    return base, metas + more


def _struct_hints(tp: type) -> dict[str, Any]:
    return typing.get_type_hints(tp, include_extras=True)


def _child(tp: Any, value: Any, part: str | int) -> Any:
    """The annotation one step down the path from ``tp`` (whose raw value is ``value``)."""
    base, _ = _resolve(tp, value)
    if _is_struct(base):
        return _struct_hints(base).get(str(part), Any)
    origin, args = get_origin(base), get_args(base)
    if origin is dict and len(args) == 2:
        return args[1]
    if origin is list and args:
        return args[0]
    if origin is tuple and args:
        if len(args) == 2 and args[1] is Ellipsis:
            return args[0]
        return args[part] if isinstance(part, int) and part < len(args) else Any
    return Any


_MISSING = object()


def _locate(raw: Any, schema: Any, parts: list[str | int | None]) -> tuple[list[str | int], Any, Any]:
    """Walk the raw data and the schema along a path; resolve unnamed dict keys by re-validating items."""
    value, tp = raw, schema
    named: list[str | int] = []
    for part in parts:
        child_tp = None
        if part is None and isinstance(value, dict):
            child_tp = _child(tp, value, "")
            for k, v in value.items():
                try:
                    msgspec.convert(v, child_tp)
                except (msgspec.ValidationError, TypeError):
                    part = k
                    break
            if part is None:
                return named, _MISSING, Any
        elif part is None:
            return named, _MISSING, Any
        if child_tp is None:
            child_tp = _child(tp, value, part)
        if isinstance(value, dict) and part in value:
            value = value[part]
        elif isinstance(value, (list, tuple)) and isinstance(part, int) and part < len(value):
            value = value[part]
        else:
            value = _MISSING
        named.append(part)
        tp = child_tp
    return named, value, tp


def format_path(parts: list[str | int]) -> str:
    """["domains", 0, "beta"] → ``domains[0].beta``."""
    out = ""
    for p in parts:
        out += f"[{p}]" if isinstance(p, int) else (f".{p}" if out else str(p))
    return out


def _show(value: Any) -> str:
    if value is _MISSING:
        return ""
    if isinstance(value, bool):
        return " (true)" if value else " (false)"
    if isinstance(value, float):
        if math.isfinite(value) and value.is_integer() and abs(value) < 1e6:
            return f" ({value:.1f})"
        return f" ({value:.6g})" if math.isfinite(value) else f" ({value})"
    if isinstance(value, (int, str)):
        text = repr(value)
        return f" ({text[:40]}…)" if len(text) > 40 else f" ({text})"
    if isinstance(value, (list, tuple)):
        return f" ({len(value)} item{'' if len(value) == 1 else 's'})"
    return ""


def _nouns(spec: str, fmt: Format) -> str:
    words = [_CONTAINERS[fmt].get(w.strip(), _NOUNS.get(w.strip(), w.strip())) for w in spec.split("|")]
    return " or ".join(words)


def _meta(metas: list[msgspec.Meta], attr: str) -> Any:
    for m in metas:
        v = getattr(m, attr, None)
        if v is not None:
            return v
    return None


def _bound_text(metas: list[msgspec.Meta]) -> str:
    lo = ("<", _meta(metas, "gt")) if _meta(metas, "gt") is not None else ("≤", _meta(metas, "ge"))
    hi = ("<", _meta(metas, "lt")) if _meta(metas, "lt") is not None else ("≤", _meta(metas, "le"))
    extra = _meta(metas, "extra") or {}
    unit = f" {extra['unit']}" if extra.get("unit") else ""
    left = f"{number_text(lo[1])} {lo[0]} " if lo[1] is not None else ""
    right = f" {hi[0]} {number_text(hi[1])}" if hi[1] is not None else ""
    return f"{left}x{right}{unit}"


def _length_text(metas: list[msgspec.Meta], tp: Any, value: Any) -> str:
    lo, hi = _meta(metas, "min_length"), _meta(metas, "max_length")
    if get_origin(tp) is tuple and Ellipsis not in get_args(tp):
        lo = hi = len(get_args(tp))
    if isinstance(value, str):
        return "must not be empty" if lo == 1 and not value else f"must have {lo}–{hi} characters"
    if lo is not None and lo == hi:
        want = f"exactly {lo}"
    elif lo is not None and hi is not None:
        want = f"{lo} to {hi}"
    else:
        want = f"at least {lo}" if lo is not None else f"at most {hi}"
    got = f" (got {len(value)})" if isinstance(value, (list, tuple, dict)) else ""
    return f"must have {want} item{'s' if want != 'exactly 1' else ''}{got}"


def explain(message: str, raw: Any, schema: Any, fmt: Format = "json") -> str:
    """Rewrite a msgspec ValidationError message as ``field: problem`` (see module docstring)."""
    m = re.fullmatch(r"(?s)(.*?) - at `key` in `(\$[^`]*)`", message)
    if m:
        named, _, _ = _locate(raw, schema, _parse_path(m.group(2)))
        got = re.search(r"got `([^`]+)`", m.group(1))
        what = f" (got {_nouns(got.group(1), fmt)})" if got else ""
        return _join(format_path(named), f"keys must be strings{what}")
    m = re.fullmatch(r"(?s)(.*?)(?: - at `(\$[^`]*)`)?", message)
    assert m is not None
    problem, loc = m.group(1), m.group(2) or "$"
    parts = _parse_path(loc)
    field_m = re.fullmatch(r"Object (missing required|contains unknown) field `(.+)`", problem)
    if field_m:
        named, value, tp = _locate(raw, schema, parts)
        base, _ = _resolve(tp, value)
        name = field_m.group(2)
        if field_m.group(1) == "missing required":
            hint = _meta(_strip(_struct_hints(base).get(name, Any))[1], "description") if _is_struct(base) else None
            return _join(format_path([*named, name]), "required, but missing" + (f" ({hint})" if hint else ""))
        known = ", ".join(base.__struct_encode_fields__) if _is_struct(base) else ""
        return _join(format_path([*named, name]), "unknown key" + (f" (known: {known})" if known else ""))
    named, value, tp = _locate(raw, schema, parts)
    base, metas = _resolve(tp, value)
    field = format_path(named)
    hint = _meta(metas, "description")
    if isinstance(value, float) and not math.isfinite(value) and re.match(r"Expected `(float|int)` [<>]", problem):
        return _join(field, f"must be a finite number (got {value})")
    if m2 := re.fullmatch(r"Expected `([^`]+)`, got `([^`]+)`", problem):
        text = f"expected {_nouns(m2.group(1), fmt)}, got {_nouns(m2.group(2), fmt)}{_show(value)}"
        return _join(field, text + _quoted_number_hint(value, m2.group(1), fmt))
    if re.fullmatch(r"Expected `(float|int)` [<>]=? .*", problem):
        return _join(field, f"must satisfy {_bound_text(metas)}{_show(value).replace(' (', ' (got ', 1)}")
    if re.fullmatch(r"Expected `(array|str|object)` of length .*", problem):
        text = _length_text(metas, base, value)
        return _join(field, text + (f" ({hint})" if hint else ""))
    if m2 := re.fullmatch(r"Invalid enum value (.*)", problem):
        choices = [a for a in get_args(base) if a is not None]
        allowed = ", ".join(repr(c) for c in choices) if choices else "?"
        return _join(field, f"must be one of {allowed} (got {m2.group(1)})")
    if problem == "Number out of range":
        return _join(field, f"number out of range{_show(value).replace(' (', ' (got ', 1)}")
    return _join(field, problem[:1].lower() + problem[1:])


def _quoted_number_hint(value: Any, expected: str, fmt: Format) -> str:
    """Why a number arrived as text: quotes, or YAML 1.1 (PyYAML) reading ``1e6`` or ``1.0e6`` as a string
    (its floats need a dot and a signed exponent)."""
    if not isinstance(value, str) or not ({"float", "int"} & {w.strip() for w in expected.split("|")}):
        return ""
    try:
        number = float(value)
    except ValueError:
        return ""
    if fmt == "yaml" and re.fullmatch(r"[-+]?[\d.]+[eE][-+]?\d+", value.strip()):
        return f": YAML reads this exponent form as text, write {number!r}"
    return ": a quoted number is text, remove the quotes"


def _join(field: str, problem: str) -> str:
    return f"{field}: {problem}" if field else problem


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
