"""Configuration files (``--config FILE.toml``): a TOML file with any of the sections of
:class:`robustgait.config.Config`; what it does not set keeps the value it had (the defaults, or a preset)."""

from __future__ import annotations

from pathlib import Path

from robustgait.config import Config, with_overrides
from robustgait.errors import input_error
from robustgait.io.schema import read_toml


def read_config(path: str | Path, base: Config | None = None) -> Config:
    """``base`` (default :class:`Config`) with the file's values on top; errors ``FILE: field: problem``."""
    if Path(path).suffix.lower() != ".toml":
        raise input_error(path, f"unknown configuration format {Path(path).suffix or '(no extension)'!r} "
                          "(expected .toml, as robustgait config show writes)")
    raw = read_toml(path, "configuration file")
    return with_overrides(base or Config(), raw, str(path))
