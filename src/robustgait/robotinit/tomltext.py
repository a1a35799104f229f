"""How a spec TOML written by ``robot init`` shows a number, an angle, a key and a string."""

from __future__ import annotations

import json
import re

from robustgait.inspection.scale import sig

BARE_KEY = re.compile(r"^[A-Za-z0-9_-]+$")


def num(x: float, digits: int = 4) -> str:
    """A number as the spec shows it: ``digits`` significant digits, a TOML float."""
    return repr(float(sig(float(x), digits)))


def angle(x: float) -> str:
    """An angle [rad] to 1e-6 (symmetric: angle(−x) is −angle(x), as the loader's mirror check needs)."""
    return repr(round(float(x), 6) + 0.0)


def key(name: str) -> str:
    return name if BARE_KEY.match(name) else json.dumps(name)


def text(s: str) -> str:
    return json.dumps(s, ensure_ascii=False)
