"""Command-line options generated from the configuration (:mod:`robustgait.config`): a command names the config
fields it exposes and the flag of each; the type, the choices, the limits, the default and the help text all come
from the field, and a value is validated by the field's own annotation (pydantic) while parsing.

Every command also takes ``--config FILE.toml`` (a configuration file, e.g. written by ``robustgait config show``)
and ``--override KEY=VALUE`` (one field, any field: ``--override certify.sequential.spread=0.2``). The effective
configuration is, from bottom to top: the defaults (or a preset), the file, the overrides, the flags.
"""

from __future__ import annotations

import argparse
import math
import sys
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any, get_args, get_origin

from pydantic import ValidationError

from robustgait.config import Config, ConfigError, field_at, merge, nest, with_overrides
from robustgait.config.base import Doc, FieldInfo, explain
from robustgait.errors import RobustGaitError

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover - exercised on 3.10 only
    import tomli as tomllib

CONFIG_OPTION = "--config"
OVERRIDE_OPTION = "--override"


@dataclass(frozen=True)
class Flag:
    """A command-line flag and the config field(s) it sets (one value for several fields: ``study run --seed``
    seeds the learner and the certificates)."""

    flag: str
    paths: tuple[str, ...]

    @property
    def field(self) -> FieldInfo:
        return field_at(Config, self.paths[0])


FlagTable = Mapping[str, "str | tuple[str, ...]"]


def flags(table: FlagTable) -> list[Flag]:
    """``{"--samples": "certify.n_samples", "--seed": ("study.seed", "certify.seed")}`` → flags."""
    return [Flag(f, (p,) if isinstance(p, str) else tuple(p)) for f, p in table.items()]


def _scalar(text: str, kind: Any) -> Any:
    """Text → the field's scalar type: integers as plain digits (``1e9`` and ``0.5`` are not integers), numbers
    finite or not (the field's limits refuse NaN), strings as given."""
    if kind is int:
        try:
            return int(text.strip())
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected an integer, got {text!r}") from None
    if kind is float:
        try:
            return float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    return text


def parse_value(info: FieldInfo, text: str) -> Any:
    """Parse one flag's text for a field and validate it with the field's annotation (bounds, choices)."""
    kind = info.scalar
    arity = info.arity
    if get_origin(info.bare) is tuple and Ellipsis in get_args(info.bare):  # a list: comma-separated
        value: Any = [p.strip() for p in text.split(",") if p.strip()]
        if field_at_item(info, 0) is not str:
            value = [_scalar(p, field_at_item(info, 0)) for p in value]
    elif arity is not None:
        parts = [p for p in text.replace(",", " ").split() if p]
        if len(parts) != arity:
            raise argparse.ArgumentTypeError(f"expected {arity} values separated by commas, got {text!r}")
        value = [_scalar(p, field_at_item(info, i)) for i, p in enumerate(parts)]
    elif info.choices:
        value = text
    else:
        value = _scalar(text, kind if kind is not None else str)
    try:
        out = info.adapter().validate_python(value)
    except ValidationError as exc:
        raise argparse.ArgumentTypeError(explain(exc, info.annotation).lstrip(": ")) from None
    if isinstance(out, float) and not math.isfinite(out):  # unbounded numbers
        raise argparse.ArgumentTypeError(f"expected a finite number, got {text!r}")
    return out


def field_at_item(info: FieldInfo, i: int) -> Any:
    """The scalar type of item ``i`` of a fixed-size tuple field."""
    from typing import get_args

    from robustgait.config.base import strip

    bare, _ = strip(get_args(info.bare)[i])
    return bare if bare in (int, float, str, bool) else str


def _type(info: FieldInfo) -> Callable[[str], Any]:
    def parse(text: str) -> Any:
        return parse_value(info, text)

    parse.__name__ = {int: "integer", float: "number"}.get(info.scalar, "value")
    return parse


def default_text(info: FieldInfo) -> str:
    if info.default is None:
        return ""
    d = info.default
    if isinstance(d, tuple):
        return ",".join(str(v) for v in d)
    if isinstance(d, bool):
        return "on" if d else "off"
    return f"{d:g}" if isinstance(d, float) else str(d)


def help_text(info: FieldInfo) -> str:
    """``help (default D unit; limits)`` for --help, from the field (``%`` escaped for argparse)."""
    doc = info.doc
    bits = []
    d = default_text(info)
    unit = f" {doc.unit}" if doc.unit and not doc.bounded else ""
    if d:
        bits.append(f"default {d}{unit}")
    if doc.bounded:
        bits.append(doc.text())
    text = doc.help + (f" ({'; '.join(bits)})" if bits else "")
    return text.replace("%", "%%")


def add_flags(parser: argparse.ArgumentParser, table: Sequence[Flag]) -> None:
    """Add one option per flag; its value is stored under the flag's config paths (see :func:`config_from`)."""
    known: list[Flag] = getattr(parser, "robustgait_flags", [])
    for f in table:
        info = f.field
        also = f" (also sets {', '.join(f.paths[1:])})" if len(f.paths) > 1 else ""
        kw: dict[str, Any] = {"dest": "cfg:" + "|".join(f.paths), "default": argparse.SUPPRESS,
                              "help": help_text(info) + also}
        if info.scalar is bool and info.arity is None:
            kw["action"] = argparse.BooleanOptionalAction
        else:
            kw["type"] = _type(info)
            if info.choices:
                kw["choices"] = list(info.choices)
            kw["metavar"] = info.name.upper() if not info.choices else None
            if info.choices:
                kw.pop("metavar")
        action = parser.add_argument(f.flag, **kw)
        action.robustgait_paths = f.paths  # type: ignore[attr-defined]
        known.append(f)
    parser.robustgait_flags = known  # type: ignore[attr-defined]
    parser.set_defaults(robustgait_flags=known)


def add_config_file(parser: argparse.ArgumentParser) -> None:
    """``--config FILE.toml`` and ``--override KEY=VALUE`` (repeatable) on a command."""
    parser.add_argument(CONFIG_OPTION, metavar="FILE.toml", dest="config_file",
                        help="read the configuration from a TOML file (robustgait config show writes one); "
                        "flags override it")
    parser.add_argument(OVERRIDE_OPTION, metavar="KEY=VALUE", dest="overrides", action="append", default=[],
                        help="set any config field, e.g. certify.sequential.spread=0.2 (repeatable; flags "
                        "override it)")


def _override(text: str) -> dict[str, Any]:
    if "=" not in text:
        raise RobustGaitError(f"{OVERRIDE_OPTION} {text}: expected KEY=VALUE, e.g. certify.alpha=0.1")
    key, value = (t.strip() for t in text.split("=", 1))
    info = field_at(Config, key)  # unknown keys: one line naming the key
    try:
        parsed = tomllib.loads(f"v = {value}")["v"]
    except tomllib.TOMLDecodeError:
        parsed = value  # a bare word: a string choice (certify.method=uniform)
    if info.scalar is float and isinstance(parsed, int) and not isinstance(parsed, bool):
        parsed = float(parsed)
    return nest(key, parsed)


def config_from(args: argparse.Namespace, base: Config | None = None) -> Config:
    """The effective configuration of a parsed command: ``base`` (default :class:`Config`), then ``--config``
    FILE, then each ``--override``, then the flags. A bad value fails with one line naming its source: the
    file and field, the override, or the flag."""
    from robustgait.io.configfile import read_config

    config = base or Config()
    if getattr(args, "config_file", None):
        config = read_config(args.config_file, config)
    set_by: dict[str, str] = {}  # each field set on the command line → what set it
    for text in getattr(args, "overrides", None) or []:
        try:
            config = with_overrides(config, _override(text))
        except ConfigError as exc:
            raise RobustGaitError(f"{OVERRIDE_OPTION} {text}: {exc}") from None
        set_by[text.split("=", 1)[0].strip()] = f"{OVERRIDE_OPTION} {text}"
    given: dict[str, Any] = {}
    flag_of: dict[str, str] = {}
    for f in getattr(args, "robustgait_flags", []):
        key = "cfg:" + "|".join(f.paths)
        if key in vars(args):
            for p in f.paths:
                given = merge(given, nest(p, getattr(args, key)))
                flag_of[p] = f.flag
                set_by[p] = f"argument {f.flag}"
    if given:
        try:
            config = with_overrides(config, given)
        except ConfigError as exc:
            text = str(exc)
            field, _, problem = text.partition(": ")
            flag = flag_of.get(field) or next((fl for p, fl in flag_of.items() if field.startswith(p)), None)
            raise RobustGaitError(f"argument {flag}: {problem}" if flag else text) from None
    _check_applies(config, set_by, getattr(args, "certificate", "certify"))
    return config


def _check_applies(config: Config, set_by: Mapping[str, str], certificate: str) -> None:
    """Refuse a certificate option set on the command line that does nothing to the command's certificate
    (``certificate``: ``study``, a study's :attr:`~robustgait.config.Config.study_certify`; else ``certify``):
    one line naming what set it and why (:meth:`~robustgait.config.CertifyConfig.inapplicable`); and a sequential
    budget that cannot hold one verification (:func:`~robustgait.certificate.verification.check_budget`)."""
    from robustgait.certificate.verification import check_budget

    cert = config.study_certify if certificate == "study" else config.certify
    try:
        check_budget(cert)
    except RobustGaitError as exc:
        field, _, problem = str(exc).partition(": ")
        raise RobustGaitError(f"{set_by[field]}: {problem}" if field in set_by else str(exc)) from None
    for path, source in set_by.items():
        head, _, rest = path.partition(".")
        why = cert.inapplicable(rest) if head == "certify" else None
        if why is not None:
            raise RobustGaitError(f"{source}: {why}")


# ----------------------------------------------------------------------------------------------- outputs
def output_path(kind: str) -> Callable[[str], str]:
    """An output file of ``kind`` (json, csv, plot, video, html), checked while parsing
    (:func:`robustgait.io.output.check_output`): before any work."""
    from robustgait.io.output import check_output

    def parse(text: str) -> str:
        try:
            check_output(text, kind)  # type: ignore[arg-type]
        except RobustGaitError as exc:
            raise argparse.ArgumentTypeError(str(exc)) from None
        return text

    parse.__name__ = f"{kind} output"
    return parse


def number_within(doc: Doc) -> Callable[[str], float]:
    """A finite number within a :class:`~robustgait.config.Doc`'s limits (an input that is no config field:
    ``barrier-eval --r``)."""

    def parse(text: str) -> float:
        value = _scalar(text, float)
        if not doc.contains(value):
            raise argparse.ArgumentTypeError(f"must satisfy {doc.text()}, got {text}")
        return float(value)

    parse.__name__ = "number"
    return parse


def numbers_within(doc: Doc, parts: list[str], what: str) -> list[float]:
    """Numbers given as one comma-separated word or several words ("0.1,0.2" or 0.1 0.2 or -0.1 0.2), each
    within ``doc``'s limits; raises :class:`RobustGaitError` naming ``what``."""
    out = []
    for word in " ".join(parts).replace(",", " ").split():
        try:
            value = float(word)
        except ValueError:
            raise RobustGaitError(f"{what}: expected numbers, got {word!r}") from None
        if not math.isfinite(value):
            raise RobustGaitError(f"{what}: expected finite numbers, got {word!r}")
        if not doc.contains(value):
            raise RobustGaitError(f"{what}: must satisfy {doc.text()}, got {word}")
        out.append(value)
    if not out:
        raise RobustGaitError(f"{what}: expected at least one number")
    return out
