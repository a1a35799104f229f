"""The machinery of robustgait's configuration: one schema library (pydantic v2) for every config section and
every input file, and one formatter of its error objects.

A config section is a frozen dataclass made with :func:`config` (a pydantic dataclass): every field carries its
type, default and a :class:`Doc` — one line of help, its unit and its limits — in its annotation::

    @config
    class CertifyConfig:
        alpha: Annotated[Float, Doc("DTBF decay rate α", gt=0, lt=1)] = 0.05
        method: Annotated[Method, Doc("r* estimator")] = "sequential"

Everything else reads the fields from there: validation (pydantic checks the bounds, the choices of a
``Literal``, unknown keys, strict types — no ``"0.7"`` or ``true`` for a number, no NaN), the command line
(:mod:`robustgait.cli.options` builds each option's type, choices, default and help from the field), the TOML of
``robustgait config show`` (:func:`to_toml`), the limits table in ``docs/inputs.md``. A bad value raises
:class:`ConfigError` (a :class:`~robustgait.errors.RobustGaitError`) with one line ``field: problem``, made by
:func:`explain` from pydantic's error objects (``ValidationError.errors()``: location, type, input, context), never
from its message strings.
"""

from __future__ import annotations

import dataclasses
import enum
import functools
import json
import math
import types
import typing
from collections.abc import Callable, Iterator, Mapping
from typing import Annotated, Any, Literal, TypeVar, Union, cast, get_args, get_origin

import annotated_types as at
from pydantic import ConfigDict, Strict, TypeAdapter, ValidationError
from pydantic.dataclasses import dataclass as pydantic_dataclass
from typing_extensions import dataclass_transform

from robustgait.errors import RobustGaitError

T = TypeVar("T")
Format = Literal["python", "json", "yaml", "toml"]

# Strict scalars: a number is a number (an integer is accepted where a float belongs), never text or a boolean.
Float = Annotated[float, Strict()]
Int = Annotated[int, Strict()]
Bool = Annotated[bool, Strict()]
Str = Annotated[str, Strict()]

SETTINGS = ConfigDict(extra="forbid", allow_inf_nan=False, defer_build=True)


class TextEnum(str, enum.Enum):
    """An enumeration whose members are their text: equal to it, printed and stored as it (``str(m) == m.value``)."""

    def __str__(self) -> str:
        return str(self.value)


def number_text(v: float) -> str:
    """A limit's number as people write it: π, 2^63 − 1, 1e7, 0.01."""
    if v == math.pi:
        return "π"
    if float(v).is_integer() and v > 2**20 and (int(v) + 1).bit_count() == 1:
        return f"2^{(int(v) + 1).bit_length() - 1} − 1"
    if float(v).is_integer() and abs(v) >= 1e5:
        return f"{v:.0e}".replace("e+0", "e").replace("e+", "e")
    return f"{v:g}"


class Doc(at.GroupedMetadata):
    """A field's one line of help, its unit and its limits (``ge``/``gt``/``le``/``lt``: pydantic checks them).

    ``Annotated[Float, Doc("DTBF decay rate α", gt=0, lt=1)]``. Iterating yields the annotated-types bounds,
    which is how pydantic sees them; :func:`doc_of` finds the object itself for help texts and messages."""

    __slots__ = ("ge", "gt", "help", "le", "lt", "unit")

    def __init__(self, help: str = "", *, unit: str = "", ge: float | None = None, gt: float | None = None,
                 le: float | None = None, lt: float | None = None):
        self.help, self.unit = help, unit
        self.ge, self.gt, self.le, self.lt = ge, gt, le, lt

    def __iter__(self) -> Iterator[object]:
        for cls, v in ((at.Ge, self.ge), (at.Gt, self.gt), (at.Le, self.le), (at.Lt, self.lt)):
            if v is not None:
                yield cls(v)

    @property
    def bounded(self) -> bool:
        return any(v is not None for v in (self.ge, self.gt, self.le, self.lt))

    @property
    def low(self) -> float | None:
        return self.ge if self.ge is not None else self.gt

    @property
    def high(self) -> float | None:
        return self.le if self.le is not None else self.lt

    def contains(self, value: float) -> bool:
        if math.isnan(value):
            return False
        return not ((self.ge is not None and value < self.ge) or (self.gt is not None and value <= self.gt)
                    or (self.le is not None and value > self.le) or (self.lt is not None and value >= self.lt))

    def text(self) -> str:
        """``0.01 ≤ x ≤ 10 s`` style ('' when unbounded)."""
        if not self.bounded:
            return ""
        unit = f" {self.unit}" if self.unit else ""
        lo = "" if self.low is None else f"{number_text(self.low)} {'<' if self.gt is not None else '≤'} "
        hi = "" if self.high is None else f" {'<' if self.lt is not None else '≤'} {number_text(self.high)}"
        return f"{lo}x{hi}{unit}"

    def __repr__(self) -> str:
        return f"Doc({self.help!r}, {self.text()!r})"


class ConfigError(RobustGaitError):
    """A config value that does not validate; ``str(err)`` is one line ``[source: ]field: problem``."""


class FieldProblem(ValueError):
    """Raised by a cross-field check (a model validator) to name the field at fault, relative to the section."""

    def __init__(self, field: str, problem: str):
        super().__init__(problem)
        self.field, self.problem = field, problem


@dataclass_transform(frozen_default=True, field_specifiers=(dataclasses.field,))
def config(cls: type[T]) -> type[T]:
    """Make ``cls`` a frozen, validated config dataclass (see the module docstring). Constructing it with a bad
    value raises :class:`ConfigError` naming the field (``CertifyConfig.alpha: must satisfy 0 < x < 1 (got 2)``);
    :func:`dataclasses.replace` validates too. Validators are built on first use (``defer_build``: importing the
    config, e.g. for ``--help``, stays cheap)."""
    dc: Any = pydantic_dataclass(frozen=True, config=SETTINGS)(cls)
    _raise_config_errors(dc)
    return dc


def _raise_config_errors(dc: Any) -> None:
    """Wrap ``dc.__init__`` so that pydantic's ValidationError becomes a one-line :class:`ConfigError`. The first
    construction completes the deferred dataclass, which installs pydantic's final ``__init__``: wrap that one too."""
    init = dc.__init__

    @functools.wraps(init)
    def __init__(self: Any, *args: Any, **kwargs: Any) -> None:
        try:
            init(self, *args, **kwargs)
        except ValidationError as exc:
            text = explain(exc, dc)
            head = text.split(":", 1)[0]
            raise ConfigError(f"{dc.__name__}{'.' if ':' in text and ' ' not in head else ': '}{text}") from None
        finally:
            if dc.__dict__.get("__init__") is not __init__:
                _raise_config_errors(dc)

    dc.__init__ = __init__


# ----------------------------------------------------------------------------------------------- introspection
def strip(tp: Any) -> tuple[Any, list[Any]]:
    """Remove ``Annotated`` layers: (bare type, their metadata in order)."""
    metas: list[Any] = []
    while get_origin(tp) is Annotated:
        args = get_args(tp)
        metas.extend(args[1:])
        tp = args[0]
    return tp, metas


def doc_of(metas: list[Any]) -> Doc | None:
    return next((m for m in reversed(metas) if isinstance(m, Doc)), None)


def is_union(tp: Any) -> bool:
    return get_origin(tp) in (Union, types.UnionType)


def union_members(tp: Any) -> list[Any]:
    return [a for a in get_args(tp) if a is not type(None)]


def is_config(tp: Any) -> bool:
    return isinstance(tp, type) and dataclasses.is_dataclass(tp)


@functools.cache
def hints(cls: Any) -> dict[str, Any]:
    return typing.get_type_hints(cls, include_extras=True)


@dataclasses.dataclass(frozen=True)
class FieldInfo:
    """One field of a config tree: its dotted ``path``, annotation, bare type, default, :class:`Doc`, the
    choices of a ``Literal`` (() otherwise) and whether None is allowed."""

    path: str
    annotation: Any
    bare: Any
    default: Any
    doc: Doc
    choices: tuple[Any, ...]
    optional: bool

    @property
    def name(self) -> str:
        return self.path.rsplit(".", 1)[-1]

    @property
    def scalar(self) -> Any:
        """float, int, bool or str for a scalar field (Literal: the type of its choices), else None."""
        if self.choices:
            return type(self.choices[0])
        base = self.bare
        return base if base in (float, int, bool, str) else None

    @property
    def arity(self) -> int | None:
        """The number of items of a fixed-size tuple field, else None."""
        if get_origin(self.bare) is tuple and Ellipsis not in get_args(self.bare):
            return len(get_args(self.bare))
        return None

    def adapter(self) -> TypeAdapter[Any]:
        return _adapter(self.annotation)

    @property
    def item_doc(self) -> Doc | None:
        """The :class:`Doc` with limits of the items of a tuple field (``impact_velocity``: each in ±10 m/s)."""
        if get_origin(self.bare) is not tuple:
            return None
        docs = [doc_of(strip(a)[1]) for a in get_args(self.bare) if a is not Ellipsis]
        return next((d for d in docs if d is not None and d.bounded), None)

    def limits_text(self) -> str:
        """The field's limits (or its items'), without the unit: ``0 < x ≤ 10``, ``each -10 ≤ x ≤ 10``."""
        d = self.doc if self.doc.bounded else self.item_doc
        if d is None:
            return ""
        text = d.text().removesuffix(f" {d.unit}") if d.unit else d.text()
        return text if d is self.doc else f"each {text}"


@functools.cache
def _adapter(tp: Any) -> TypeAdapter[Any]:
    return TypeAdapter(tp, config=None if is_config(strip(tp)[0]) else SETTINGS)


@functools.cache
def _field_info(cls: Any, name: str, prefix: str) -> FieldInfo:
    f = next(f for f in dataclasses.fields(cls) if f.name == name)
    ann = hints(cls)[name]
    bare, metas = strip(ann)
    optional = False
    if is_union(bare):
        members = union_members(bare)
        optional = len(members) < len(get_args(bare))
        if len(members) == 1:
            bare, more = strip(members[0])
            metas += more
    if f.default is not dataclasses.MISSING:
        default = f.default
    elif f.default_factory is not dataclasses.MISSING and not is_config(bare):  # a section is not built for this
        default = f.default_factory()
    else:
        default = dataclasses.MISSING
    choices = tuple(get_args(bare)) if get_origin(bare) is Literal else ()
    return FieldInfo(f"{prefix}{name}", ann, bare, default, doc_of(metas) or Doc(), choices, optional)


def fields_of(cls: type, prefix: str = "") -> Iterator[FieldInfo]:
    """Every leaf field of a config tree (nested sections are walked), depth first, in declaration order."""
    for f in dataclasses.fields(cls):
        info = _field_info(cls, f.name, prefix)
        if is_config(info.bare):
            yield from fields_of(info.bare, f"{info.path}.")
        else:
            yield info


def field_at(cls: type, path: str) -> FieldInfo:
    """The :class:`FieldInfo` of a dotted path (``certify.sequential.epsilon``) in a config tree."""
    parts = path.split(".")
    for i, name in enumerate(parts):
        if not is_config(cls) or name not in {f.name for f in dataclasses.fields(cls)}:
            known = ", ".join(f.name for f in dataclasses.fields(cls)) if is_config(cls) else ""
            raise ConfigError(f"{path}: unknown setting" + (f" (known in this section: {known})" if known else ""))
        info = _field_info(cls, name, ".".join(parts[:i]) + "." if i else "")
        if i == len(parts) - 1:
            return info
        cls = info.bare
    raise AssertionError("unreachable")


def choices_of(tp: Any) -> tuple[Any, ...]:
    """The values of a ``Literal`` type (``choices_of(Method) == ("uniform", "sequential")``)."""
    bare, _ = strip(tp)
    return tuple(get_args(bare))


# ------------------------------------------------------------------------------------------- plain data
def to_dict(obj: Any) -> dict[str, Any]:
    """A config as plain data (nested dicts, tuples as lists): what is saved next to a result."""
    return json.loads(json.dumps(dataclasses.asdict(obj)))


def from_dict(cls: type[T], raw: Any, source: str | None = None, fmt: Format = "python") -> T:
    """Validate plain data (a parsed config file, a saved config) into ``cls``; a missing key keeps its default.
    Errors: :class:`ConfigError` ``source: field: problem``."""
    try:
        out: T = _adapter(cast(Any, cls)).validate_python(raw)
        return out
    except ValidationError as exc:
        text = explain(exc, cls, fmt=fmt)
        raise ConfigError(f"{source}: {text}" if source else text) from None


def merge(base: Mapping[str, Any], over: Mapping[str, Any]) -> dict[str, Any]:
    """``base`` with ``over`` on top, nested tables merged key by key (values of ``over`` win)."""
    out = dict(base)
    for k, v in over.items():
        out[k] = merge(out[k], v) if isinstance(v, Mapping) and isinstance(out.get(k), Mapping) else v
    return out


def nest(path: str, value: Any) -> dict[str, Any]:
    """``nest("a.b.c", 1) == {"a": {"b": {"c": 1}}}``."""
    out: Any = value
    for part in reversed(path.split(".")):
        out = {part: out}
    result: dict[str, Any] = out
    return result


# ------------------------------------------------------------------------------------------------ TOML out
def toml_value(v: Any) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        if math.isinf(v):
            return "inf" if v > 0 else "-inf"
        return repr(v)
    if isinstance(v, str):
        return json.dumps(v, ensure_ascii=False)
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(toml_value(x) for x in v) + "]"
    raise TypeError(f"no TOML for {type(v).__name__}")


def field_comment(info: FieldInfo) -> str:
    """``help [unit]; limits; choices`` of a field, for comments and --help."""
    d = info.doc
    bits = [d.help + (f" [{d.unit}]" if d.unit else "")]
    if info.limits_text():
        bits.append(info.limits_text())
    if info.choices:
        bits.append("one of " + ", ".join(str(c) for c in info.choices))
    return "; ".join(b for b in bits if b)


def to_toml(obj: Any, *, comments: bool = True, unset: Mapping[str, str] | None = None) -> str:
    """A config tree as TOML: one table per section, each key with its help, unit and limits as a comment. A
    field whose value is None (TOML has no null) is written as a comment saying what not setting it means
    (``unset``: path → that text; default: 'not set')."""
    lines: list[str] = []

    def section(o: Any, prefix: str) -> None:
        cls: Any = type(o)
        scalars = [f for f in dataclasses.fields(cls) if not is_config(strip(hints(cls)[f.name])[0])]
        tables = [f for f in dataclasses.fields(cls) if is_config(strip(hints(cls)[f.name])[0])]
        if scalars and prefix:
            if lines:
                lines.append("")
            lines.append(f"[{prefix}]")
        for f in scalars:
            info = _field_info(cls, f.name, f"{prefix}." if prefix else "")
            value = getattr(o, f.name)
            if comments:
                lines.append(f"# {field_comment(info)}")
            if value is None:
                lines.append(f"# {f.name} = ...  ({(unset or {}).get(info.path, 'not set')})")
            else:
                lines.append(f"{f.name} = {toml_value(value)}")
        for f in tables:
            section(getattr(o, f.name), f"{prefix}.{f.name}" if prefix else f.name)

    section(obj, "")
    return "\n".join(lines) + "\n"


def to_markdown(cls: Any, unset: Mapping[str, str] | None = None) -> str:
    """One markdown table per section of a config class: key, default, unit, limits or choices, help."""
    out: list[str] = []
    section = None
    for f in fields_of(cls):
        head = f.path.rsplit(".", 1)[0] if "." in f.path else ""
        if head != section:
            section = head
            out += ["", f"### `[{head}]`" if head else "### (top level)", "",
                    "| key | default | unit | limits / choices | help |", "|---|---|---|---|---|"]
        d = f.doc
        if f.default is None:
            default = (unset or {}).get(f.path, "not set")
        else:
            default = f"`{toml_value(f.default)}`"
        limits = f.limits_text() or ", ".join(f"`{c}`" for c in f.choices)
        out.append(f"| `{f.name}` | {default} | {d.unit} | {limits} | {d.help} |".replace("\n", " "))
    return "\n".join(out).lstrip("\n") + "\n"


# ------------------------------------------------------------------------------------------- error messages
_NOUNS = {"float": "a number", "int": "an integer", "str": "a string", "bool": "a boolean", "NoneType": "null",
          "bytes": "bytes", "datetime": "a date-time", "date": "a date", "time": "a time"}
_CONTAINERS: dict[Format, dict[str, str]] = {
    "python": {"dict": "a dict", "list": "a list", "tuple": "a list"},
    "json": {"dict": "an object", "list": "a list", "tuple": "a list"},
    "yaml": {"dict": "a mapping", "list": "a list", "tuple": "a list"},
    "toml": {"dict": "a table", "list": "an array", "tuple": "an array"},
}
_EXPECTED = {"float_type": "float", "int_type": "int", "string_type": "str", "bool_type": "bool", "list_type": "list",
             "tuple_type": "tuple", "dict_type": "dict", "dataclass_type": "dict", "model_type": "dict",
             "model_attributes_type": "dict", "dataclass_exact_type": "dict", "none_required": "NoneType",
             "float_parsing": "float", "int_parsing": "int"}
_BOUND_TYPES = ("greater_than", "greater_than_equal", "less_than", "less_than_equal")


def _noun(kind: str, fmt: Format) -> str:
    return _CONTAINERS[fmt].get(kind, _NOUNS.get(kind, kind))


def _kind(value: Any) -> str:
    if isinstance(value, Mapping):
        return "dict"
    if isinstance(value, (list, tuple)):
        return "list"
    return type(value).__name__


def show(value: Any) -> str:
    """`` (value)`` for a message: short, finite numbers without noise, containers by their length."""
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


def format_path(parts: list[str | int]) -> str:
    """["domains", 0, "beta"] → ``domains[0].beta``."""
    out = ""
    for p in parts:
        out += f"[{p}]" if isinstance(p, int) else (f".{p}" if out else str(p))
    return out


def _member_for_tag(tp: Any, tag: str) -> Any | None:
    """The member of union ``tp`` that pydantic names ``tag`` in an error location (``float``, ``list[float]``,
    a class name), or None if ``tag`` names no member."""
    head = tag.split("[", 1)[0]
    for m in union_members(tp):
        base, _ = strip(m)
        name = getattr(get_origin(base) or base, "__name__", "")
        if name == head or (get_origin(base) is Literal and head == "literal"):
            return m
    return None


@dataclasses.dataclass
class _Where:
    parts: list[str | int]
    tp: Any
    metas: list[Any]
    key_error: bool = False


def _walk(root: Any, loc: tuple[str | int, ...]) -> _Where:
    """Follow an error location through the annotations: the readable path (union tags dropped), the leaf's
    annotation and the metadata collected on the way to it (its :class:`Doc`)."""
    tp: Any = root
    metas: list[Any] = []
    parts: list[str | int] = []
    for item in loc:
        bare, metas = strip(tp)
        if is_union(bare) and isinstance(item, str):
            member = _member_for_tag(bare, item)
            if member is not None:
                tp = member
                continue
        if is_union(bare):
            members = union_members(bare)
            bare, more = strip(members[0]) if len(members) == 1 else (bare, [])
            metas += more
        if item == "[key]":
            return _Where(parts, Any, [], key_error=True)
        if is_config(bare):
            tp = hints(bare).get(str(item), Any)
        elif get_origin(bare) in (list, tuple, dict) or (isinstance(bare, type) and issubclass(bare, (list, tuple))):
            args = get_args(bare)
            if get_origin(bare) is dict:
                tp = args[1] if len(args) == 2 else Any
            elif get_origin(bare) is tuple and args and Ellipsis not in args:
                tp = args[item] if isinstance(item, int) and item < len(args) else Any
            else:
                tp = args[0] if args else Any
        else:
            tp = Any
        parts.append(item)
    bare, metas = strip(tp)
    if is_union(bare):
        members = union_members(bare)
        if len(members) == 1:
            _, more = strip(members[0])
            metas = metas + more
    return _Where(parts, tp, metas)


def _length_text(metas: list[Any], tp: Any, value: Any, ctx: Mapping[str, Any]) -> str:
    lo = next((m.min_length for m in metas if isinstance(m, at.MinLen)), ctx.get("min_length"))
    hi = next((m.max_length for m in metas if isinstance(m, at.MaxLen)), ctx.get("max_length"))
    bare, _ = strip(tp)
    if get_origin(bare) is tuple and Ellipsis not in get_args(bare):
        lo = hi = len(get_args(bare))
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


def _quoted_number_hint(value: Any, expected: str, fmt: Format) -> str:
    """Why a number arrived as text: quotes, or YAML 1.1 (PyYAML) reading ``1e6`` as a string."""
    if not isinstance(value, str) or expected not in ("float", "int"):
        return ""
    try:
        number = float(value)
    except ValueError:
        return ""
    import re

    if fmt == "yaml" and re.fullmatch(r"[-+]?[\d.]+[eE][-+]?\d+", value.strip()):
        return f": YAML reads this exponent form as text, write {number!r}"
    return ": a quoted number is text, remove the quotes"


def _known_keys(tp: Any) -> str:
    bare, _ = strip(tp)
    if is_union(bare):
        bare = next((strip(m)[0] for m in union_members(bare) if is_config(strip(m)[0])), bare)
    return ", ".join(f.name for f in dataclasses.fields(bare)) if is_config(bare) else ""


def _problem(err: Mapping[str, Any], where: _Where, root: Any, fmt: Format) -> tuple[list[str | int], str]:
    """(path, problem) of one pydantic error."""
    kind, value, ctx = err["type"], err.get("input"), err.get("ctx") or {}
    parts, metas = where.parts, where.metas
    doc = doc_of(metas)
    if where.key_error:
        return parts, f"keys must be strings (got {_noun(_kind(value), fmt)}{show(value)})"
    if kind == "missing" and err["loc"] and isinstance(err["loc"][-1], int):  # a fixed-size tuple too short
        parent = _walk(root, tuple(err["loc"][:-1]))
        pdoc = doc_of(parent.metas)
        hint = f" ({pdoc.help})" if pdoc is not None and pdoc.help else ""
        return parent.parts, _length_text(parent.metas, parent.tp, value, ctx) + hint
    if kind in ("missing", "missing_argument", "missing_keyword_only_argument"):
        hint = f" ({doc.help})" if doc is not None and doc.help else ""
        return parts, "required, but missing" + hint
    if kind in ("extra_forbidden", "unexpected_keyword_argument", "unexpected_positional_argument"):
        parent = _walk(root, tuple(err["loc"][:-1])).tp if err["loc"] else root
        known = _known_keys(parent)
        return parts, "unknown key" + (f" (known: {known})" if known else "")
    if kind == "finite_number" or (kind in _BOUND_TYPES and isinstance(value, float) and not math.isfinite(value)):
        return parts, f"must be a finite number (got {value})"
    if kind in _BOUND_TYPES:
        limit = doc.text() if doc is not None and doc.bounded else _ctx_bound(kind, ctx)
        return parts, f"must satisfy {limit}{show(value).replace(' (', ' (got ', 1)}"
    if kind in ("too_short", "too_long", "string_too_short", "string_too_long"):
        return parts, _length_text(metas, where.tp, value, ctx)
    if kind == "literal_error":
        bare, _ = strip(where.tp)
        if is_union(bare):
            bare = next((strip(m)[0] for m in union_members(bare) if get_origin(strip(m)[0]) is Literal), bare)
        allowed = ", ".join(repr(c) for c in get_args(bare)) or str(ctx.get("expected", "?"))
        return parts, f"must be one of {allowed} (got {value!r})"
    if kind == "string_pattern_mismatch":
        return parts, "must not contain NUL bytes" if isinstance(value, str) and "\0" in value else \
            f"must match {ctx.get('pattern')!r}"
    if kind in _EXPECTED:
        expected = _EXPECTED[kind]
        text = f"expected {_noun(expected, fmt)}, got {_noun(_kind(value), fmt)}{show(value)}"
        return parts, text + _quoted_number_hint(value, expected, fmt)
    if kind == "value_error":
        exc = ctx.get("error")
        if isinstance(exc, FieldProblem):
            return [*parts, *exc.field.split(".")], exc.problem
        return parts, str(exc) if exc is not None else err.get("msg", "invalid value")
    if kind in ("int_from_float", "int_parsing_size"):
        return parts, f"expected an integer, got {value!r}"
    msg = str(err.get("msg", kind))
    return parts, msg[:1].lower() + msg[1:]


def _ctx_bound(kind: str, ctx: Mapping[str, Any]) -> str:
    op, key = {"greater_than": ("<", "gt"), "greater_than_equal": ("≤", "ge"), "less_than": ("<", "lt"),
               "less_than_equal": ("≤", "le")}[kind]
    v = number_text(ctx[key]) if key in ctx else "?"
    return f"{v} {op} x" if key in ("gt", "ge") else f"x {op} {v}"


def explain(exc: ValidationError, root: Any, *, fmt: Format = "python") -> str:
    """One line ``field: problem`` for a pydantic ValidationError raised validating ``root`` (a config class or a
    file schema), made from its error objects; `` (and N more problems)`` when other fields fail too. The value
    that matched no member of a union gets one message ("expected a number or a list"), or that of the member it
    got furthest into."""
    errors: list[dict[str, Any]] = [dict(e) for e in exc.errors(include_url=False)]
    if not errors:
        return "invalid"
    groups: dict[str, list[tuple[dict[str, Any], _Where]]] = {}
    for e in errors:
        w = _walk(root, tuple(e["loc"]))
        groups.setdefault(format_path(w.parts), []).append((e, w))
    same = next(iter(groups.values()))
    err, where = max(same, key=lambda ew: len(ew[0]["loc"]))
    if len(same) > 1 and all(e["type"] in _EXPECTED for e, _ in same):
        value = err.get("input")
        kinds = dict.fromkeys(_EXPECTED[e["type"]] for e, _ in same)
        parts, problem = where.parts, (f"expected {' or '.join(_noun(k, fmt) for k in kinds)}, got "
                                       f"{_noun(_kind(value), fmt)}{show(value)}")
    else:
        parts, problem = _problem(err, where, root, fmt)
    field = format_path(parts)
    text = f"{field}: {problem}" if field else problem
    if len(groups) > 1:
        text += f" (and {len(groups) - 1} more problem{'s' if len(groups) > 2 else ''})"
    return " ".join(text.split())


def validator(cls: Any) -> Callable[[Any], Any]:
    """Validate plain data into ``cls`` (raises pydantic's ValidationError; :func:`from_dict` formats it)."""
    return _adapter(cls).validate_python
