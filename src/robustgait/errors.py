"""Errors that carry a one-line, user-facing message.

Every problem caused by user input (a file, a parameter, a state) raises :class:`RobustGaitError`.
The CLI prints its message on one line and exits with status 2; anything else is a bug.
"""

from __future__ import annotations

from pathlib import Path


class RobustGaitError(ValueError):
    """A problem with user input; ``str(err)`` is a complete one-line message."""


def input_error(source: str | Path | None, problem: str) -> RobustGaitError:
    """Build an error naming the offending file (or object) and the problem, on one line."""
    msg = " ".join(problem.split())
    return RobustGaitError(f"{source}: {msg}" if source is not None else msg)
