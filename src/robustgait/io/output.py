"""The one output writer: every file robustgait writes goes through :func:`atomic_output`.

Before any work, :func:`check_output` refuses a target that could not be written or must not be replaced:
an unknown extension for that kind of output, a missing or non-writable directory, a path that is a
directory, a symbolic link, a device, FIFO or socket, or that lies under ``/proc``, ``/sys`` or ``/dev``.
Writing goes to a temporary file in the target's directory (same file system) that is renamed over the
target only when complete, so a reader never sees a half-written file; on any failure — an exception, a
full disk, Ctrl-C — the temporary file is removed and the target is untouched.

Kinds of output and their extensions: :data:`FORMATS`. The command line checks its output arguments while
parsing (:func:`robustgait.io.args.output_path`), i.e. before the seconds-long work starts.
"""

from __future__ import annotations

import csv
import io
import json
import os
import stat
import tempfile
from collections.abc import Iterable, Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import Any, Literal

from robustgait.errors import RobustGaitError, input_error

OutputKind = Literal["json", "gait", "csv", "plot", "video", "html", "toml"]
FORMATS: dict[str, tuple[str, ...]] = {
    "json": (".json",),
    "gait": (".json", ".yaml", ".yml"),
    "csv": (".csv",),
    "plot": (".png", ".pdf", ".svg"),
    "video": (".mp4", ".gif"),
    "html": (".html",),
    "toml": (".toml",),
}
_LABELS = {"json": "JSON output", "gait": "gait file", "csv": "CSV output", "plot": "plot", "video": "video",
           "html": "HTML report", "toml": "spec TOML"}
FORBIDDEN_ROOTS = (Path("/proc"), Path("/sys"), Path("/dev"))
_TMP_PREFIX = ".robustgait-"


def kind_of(path: str | Path) -> OutputKind:
    """The output kind an extension belongs to (for callers that only have a path)."""
    suffix = Path(path).suffix.lower()
    for kind, exts in FORMATS.items():
        if suffix in exts:
            return kind  # type: ignore[return-value]
    known = ", ".join(e for exts in FORMATS.values() for e in exts)
    raise input_error(path, f"unknown output format {suffix or '(no extension)'!r} (robustgait writes {known})")


def _exts(kind: str) -> str:
    exts = FORMATS[kind]
    return exts[0] if len(exts) == 1 else ", ".join(exts[:-1]) + " or " + exts[-1]


def check_output(path: str | Path, kind: OutputKind) -> Path:
    """Raise a one-line :class:`RobustGaitError` if ``path`` cannot or must not be written as ``kind``.

    Returns the path. Cheap (a few ``stat`` calls): call it before the work, :func:`atomic_output` calls it
    again right before writing.
    """
    text = os.fspath(path)
    if text in ("", "-"):
        raise input_error(text or "''", f"not a file name (robustgait writes {_LABELS[kind]} to files; "
                          "use --json to print results on stdout)")
    if "\0" in text:
        raise input_error(repr(text), "a file name cannot contain a NUL byte")
    p = Path(text)
    if len(os.fsencode(p.name)) > 200:
        raise input_error(p, "file name longer than 200 bytes")
    try:
        st: os.stat_result | None = os.lstat(p)
    except FileNotFoundError:
        st = None
    except OSError as exc:
        raise input_error(p, f"cannot inspect the output path: {exc.strerror or exc}") from None
    if st is not None:
        if stat.S_ISLNK(st.st_mode):
            raise input_error(p, "is a symbolic link: refusing to replace it (write to its target's path instead)")
        if stat.S_ISDIR(st.st_mode):
            raise input_error(p, "is a directory: give a file name")
        if not stat.S_ISREG(st.st_mode):
            raise input_error(p, "is a device, FIFO or socket: refusing to replace it")
    parent = p.parent
    try:
        real_parent = parent.resolve(strict=True)
    except (FileNotFoundError, NotADirectoryError):
        raise input_error(p, "output directory does not exist") from None
    except (OSError, RuntimeError) as exc:
        raise input_error(p, f"output directory cannot be used: {getattr(exc, 'strerror', None) or exc}") from None
    for root in FORBIDDEN_ROOTS:
        if real_parent == root or root in real_parent.parents:
            raise input_error(p, f"refusing to write under {root} (kernel or device files)")
    if p.suffix.lower() not in FORMATS[kind]:
        raise input_error(p, f"unknown {_LABELS[kind]} format {p.suffix or '(no extension)'!r} "
                          f"(expected {_exts(kind)})")
    if not real_parent.is_dir():
        raise input_error(p, "output directory does not exist (its parent is a file)")
    if not os.access(real_parent, os.W_OK | os.X_OK):
        raise input_error(p, "output directory is not writable")
    return p


def check_outputs(outputs: Iterable[tuple[str | Path | None, OutputKind]]) -> None:
    """:func:`check_output` for each (path, kind) whose path is not None — for commands with several outputs."""
    for path, kind in outputs:
        if path is not None:
            check_output(path, kind)


def _mode_for(path: Path) -> int:
    try:
        return stat.S_IMODE(os.stat(path).st_mode)
    except OSError:
        umask = os.umask(0)
        os.umask(umask)
        return 0o666 & ~umask


@contextmanager
def atomic_output(path: str | Path, kind: OutputKind) -> Iterator[Path]:
    """Yield a temporary path (same directory, same extension) to write; rename it over ``path`` on success.

    On any exception (including KeyboardInterrupt) the temporary file is removed and ``path`` is untouched.
    """
    target = check_output(path, kind)
    fd, name = tempfile.mkstemp(prefix=_TMP_PREFIX, suffix=target.suffix, dir=target.parent)
    os.close(fd)
    tmp = Path(name)
    try:
        yield tmp
        if not tmp.is_file() or tmp.is_symlink():
            raise RobustGaitError(f"{target}: the writer produced no file")
        os.chmod(tmp, _mode_for(target))
        check_output(target, kind)  # again: the target may have changed during the work
        os.replace(tmp, target)
    finally:
        try:
            tmp.unlink()
        except FileNotFoundError:
            pass


def write_bytes(path: str | Path, data: bytes, kind: OutputKind) -> Path:
    with atomic_output(path, kind) as tmp:
        with open(tmp, "wb") as fh:
            fh.write(data)
            fh.flush()
            os.fsync(fh.fileno())
    return Path(path)


def write_text(path: str | Path, text: str, kind: OutputKind) -> Path:
    """Write UTF-8 text atomically (see module docstring)."""
    return write_bytes(path, text.encode("utf-8"), kind)


def write_json(path: str | Path, obj: Any) -> Path:
    """Write an object as JSON (indent 1, no NaN/Infinity: they are not JSON) atomically."""
    return write_text(path, json.dumps(obj, indent=1, allow_nan=False), "json")


def write_csv(path: str | Path, header: Sequence[str], rows: Iterable[Sequence[float]]) -> Path:
    """Write a header row and rows of numbers (``repr``: exact round trip) as CSV, atomically."""
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(header)
    w.writerows([[repr(float(v)) for v in row] for row in rows])
    return write_text(path, buf.getvalue(), "csv")
