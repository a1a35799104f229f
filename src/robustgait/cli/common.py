"""Pieces every command uses: the robot and gait arguments, the error context of an input file."""

from __future__ import annotations

import argparse
from collections.abc import Iterator
from contextlib import contextmanager
from typing import TYPE_CHECKING

from robustgait.cli.options import FlagTable, add_config_file, add_flags, config_from, flags
from robustgait.errors import RobustGaitError

if TYPE_CHECKING:
    from robustgait.config import Config
    from robustgait.gait import Gait
    from robustgait.robots import Robot

ROBOT_HELP = "shipped robot name or path to a spec .toml"
GAIT_HELP = "gait file: .json (robustgait) or .yaml (FROST/ambersim)"


def command(sub: argparse._SubParsersAction[argparse.ArgumentParser], name: str, help: str, func: object,
            table: FlagTable | None = None) -> argparse.ArgumentParser:
    """A subcommand with ``--config``/``--override`` and the config flags of ``table``."""
    p: argparse.ArgumentParser = sub.add_parser(name, help=help, description=help)
    add_flags(p, flags(table or {}))
    add_config_file(p)
    p.set_defaults(func=func)
    return p


@contextmanager
def naming_file(path: str) -> Iterator[None]:
    """Report a problem found while running an input (a gait that cannot start, has no fixed point, ...)
    against its file: every bad-input message names the file."""
    try:
        yield
    except RobustGaitError as exc:
        msg = str(exc)
        raise RobustGaitError(msg if msg.startswith(f"{path}: ") else f"{path}: {msg}") from None


def inputs(args: argparse.Namespace) -> tuple[Config, Robot, Gait]:
    """The effective configuration, the robot (``--robot``) and the gait (the ``gait`` argument) of a command."""
    from robustgait.io.gaitfile import load_gait
    from robustgait.io.robotfile import load_robot

    config = config_from(args)
    robot = load_robot(args.robot)
    return config, robot, load_gait(args.gait, robot)
