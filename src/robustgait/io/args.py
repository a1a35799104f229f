"""argparse types for the command line: numbers within the documented limits, output paths checked while
parsing (before any work). A bad value makes argparse print one line and exit 2.

Use them in any command (``robustgait.cli`` and the commands other modules add)::

    p.add_argument("--samples", type=int_in(limits.SAMPLES), default=200)
    p.add_argument("-o", "--output", type=output_path("json"))
"""

from __future__ import annotations

import argparse
import math
from collections.abc import Callable

from robustgait.errors import RobustGaitError
from robustgait.io.limits import Limit
from robustgait.io.output import OutputKind, check_output


def int_in(limit: Limit) -> Callable[[str], int]:
    """An integer within ``limit`` (plain digits: ``1e9`` and ``0.5`` are refused)."""

    def parse(text: str) -> int:
        try:
            value = int(text.strip())
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected an integer, got {text!r}") from None
        if not limit.contains(value):
            raise argparse.ArgumentTypeError(f"must satisfy {limit.text()}, got {value}")
        return value

    parse.__name__ = "integer"
    return parse


def finite_float(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"expected a finite number, got {text!r}")
    return value


def float_in(limit: Limit) -> Callable[[str], float]:
    """A finite number within ``limit`` (``nan`` and ``inf`` are refused)."""

    def parse(text: str) -> float:
        value = finite_float(text)
        if not limit.contains(value):
            raise argparse.ArgumentTypeError(f"must satisfy {limit.text()}, got {text}")
        return value

    parse.__name__ = "number"
    return parse


def output_path(kind: OutputKind) -> Callable[[str], str]:
    """An output file of ``kind``, checked now (:func:`robustgait.io.output.check_output`)."""

    def parse(text: str) -> str:
        try:
            check_output(text, kind)
        except RobustGaitError as exc:
            raise argparse.ArgumentTypeError(str(exc)) from None
        return text

    parse.__name__ = f"{kind} output"
    return parse


def floats_in(limit: Limit, parts: list[str], what: str) -> list[float]:
    """Numbers given as one comma-separated word or several words ("0.1,0.2" or 0.1 0.2 or -0.1 0.2), each
    finite and within ``limit``; raises :class:`RobustGaitError` naming ``what``."""
    text = " ".join(parts).replace(",", " ")
    out = []
    for word in text.split():
        try:
            value = float(word)
        except ValueError:
            raise RobustGaitError(f"{what}: expected numbers, got {word!r}") from None
        if not math.isfinite(value):
            raise RobustGaitError(f"{what}: expected finite numbers, got {word!r}")
        if not limit.contains(value):
            raise RobustGaitError(f"{what}: must satisfy {limit.text()}, got {word}")
        out.append(value)
    if not out:
        raise RobustGaitError(f"{what}: expected at least one number")
    return out
