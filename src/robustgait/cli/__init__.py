"""The ``robustgait`` command: it parses arguments and calls the API, nothing else. One module per verb group:
:mod:`~robustgait.cli.info` (robots, config show), :mod:`~robustgait.cli.robot` (robot init / check),
:mod:`~robustgait.cli.walk` (walk),
:mod:`~robustgait.cli.certify` (certify, barrier-eval), :mod:`~robustgait.cli.gait` (gait convert / generate /
tiles), :mod:`~robustgait.cli.validate` (validate), :mod:`~robustgait.cli.study` (study …, demo). Every option's
default, choices, limits and help come from the configuration (:mod:`robustgait.cli.options`).

Every user-input problem ends in one line on stderr, ``robustgait: error: ...``, and exit status 2.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable, Sequence
from typing import NoReturn

from robustgait.errors import RobustGaitError


class Parser(argparse.ArgumentParser):
    """argparse with the project's error format: one line on stderr, exit status 2."""

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"robustgait: error: {message} (see {self.prog} --help)\n")


def build_parser() -> argparse.ArgumentParser:
    from robustgait.cli import certify, gait, info, robot, study, validate, walk

    p = Parser(prog="robustgait", description="Synthesize and certify robust walking gaits. Every option is a "
               "field of the configuration: `robustgait config show` prints it, --config FILE.toml reads it.")
    sub = p.add_subparsers(dest="command", required=True, parser_class=Parser)
    for module in (info, robot, walk, certify, gait, validate, study):
        module.add_parsers(sub)
    return p


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; returns the exit status (0 ok, 1 a check failed or stdout was closed, 2 bad input
    with one line on stderr, 130 interrupted)."""
    parser = build_parser()
    try:  # a bad argument: argparse printed one line; return its status so that in-process callers get it
        args = parser.parse_args(argv)
    except SystemExit as exc:
        return exc.code if isinstance(exc.code, int) else 2
    func: Callable[[argparse.Namespace], int] = args.func
    try:
        return func(args)
    except RobustGaitError as exc:
        print(f"robustgait: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:  # outputs are written atomically: nothing half-written is left
        print("robustgait: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:  # stdout closed early (``robustgait ... | head``): not an error of ours
        _silence_stdout()
        return 1


def _silence_stdout() -> None:
    """Point stdout at /dev/null so that the interpreter's final flush does not fail again."""
    import os

    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
    except (OSError, ValueError):  # stdout has no file descriptor (captured in-process)
        pass


if __name__ == "__main__":
    sys.exit(main())
