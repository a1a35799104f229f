"""Reduced-state logs: a recorded sequence of section states (T, n) from CSV, NPY or NPZ
(``robustgait walk --log`` writes the CSV; ``robustgait barrier-eval`` reads any of the three).

CSV: a header row of names, then rows of values. A column is numeric when every cell is a number and text
when none is (a label column such as ``phase`` = L/R is skipped); a column mixing both, an empty cell, a
ragged row or a NaN/inf value is an error naming its row and column. Default: every numeric column, in file
order; ``columns`` selects and orders them.
NPY: one 2-D numeric array. NPZ: the array named ``x``, or the single array inside. The array header is read
first: a wrong shape or dtype is refused before any data is loaded (a compressed NPZ cannot expand to
gigabytes). Values must be finite and within :data:`robustgait.io.limits.LOG_VALUE`.
"""

from __future__ import annotations

import csv
import io
import zipfile
from collections.abc import Sequence
from pathlib import Path
from typing import IO, Any

import numpy as np
from numpy.typing import NDArray

from robustgait.errors import RobustGaitError, input_error
from robustgait.io import limits as L
from robustgait.io.schema import read_bytes, read_text

FloatArray = NDArray[np.float64]
LOG_FORMATS = (".csv", ".npy", ".npz")


def _cell(text: str) -> float | None:
    try:
        return float(text)
    except ValueError:
        return None


def _read_csv(path: Path, columns: Sequence[str] | None) -> FloatArray:
    text = read_text(path, "log file")
    try:
        rows = [row for row in csv.reader(io.StringIO(text, newline="")) if row and any(c.strip() for c in row)]
    except csv.Error as exc:
        raise input_error(path, f"malformed CSV: {exc}") from None
    if len(rows) < 2:
        raise input_error(path, "expected a header row and at least one data row")
    header = [h.strip() for h in rows[0]]
    body = rows[1:]
    if len(header) > L.MAX_LOG_COLUMNS or len(body) > L.MAX_LOG_ROWS:
        raise input_error(path, f"{len(body)} rows × {len(header)} columns is over the limits "
                          f"({L.MAX_LOG_ROWS} rows, {L.MAX_LOG_COLUMNS} columns)")
    for i, row in enumerate(body, start=2):
        if len(row) != len(header):
            raise input_error(path, f"row {i}: has {len(row)} fields, the header has {len(header)}")

    def parse(j: int, selected: bool) -> list[float] | None:
        """The column's values; None for a text column (unless selected). Empty or mixed cells are errors."""
        cells = [row[j].strip() for row in body]
        values = [_cell(c) for c in cells]
        for i, c in enumerate(cells):
            if not c:
                raise input_error(path, f"row {i + 2}, column {header[j]!r}: empty value")
        numbers = [v for v in values if v is not None]
        if not numbers and not selected:
            return None
        if len(numbers) < len(values):
            i = next(i for i, v in enumerate(values) if v is None)
            raise input_error(path, f"row {i + 2}, column {header[j]!r}: {cells[i][:40]!r} is not a number"
                              + ("" if selected else " (the column's other cells are numbers)"))
        for i, v in enumerate(numbers):
            problem = _value_problem(v)
            if problem:
                raise input_error(path, f"row {i + 2}, column {header[j]!r}: {cells[i][:40]} {problem}")
        return numbers

    if columns is None:
        cols = [c for c in (parse(j, False) for j in range(len(header))) if c is not None]
        if not cols:
            raise input_error(path, "no numeric columns")
    else:
        if len(columns) == 0:
            raise input_error(path, "empty column selection")
        cols = []
        for name in columns:
            if name not in header:
                raise input_error(path, f"no column named {name!r} (have {', '.join(header)})")
            if header.count(name) > 1:
                raise input_error(path, f"column name {name!r} appears {header.count(name)} times in the header")
            col = parse(header.index(name), True)
            assert col is not None
            cols.append(col)
    return np.asarray(cols, dtype=np.float64).T


def _read_npy_stream(fh: IO[bytes], path: Path, what: str) -> FloatArray:
    """One .npy array from an open stream: header checked (2-D, numeric, size) before the data is read."""
    fmt = np.lib.format
    try:
        version = fmt.read_magic(fh)
        if version == (1, 0):
            shape, fortran, dtype = fmt.read_array_header_1_0(fh)
        elif version in ((2, 0), (3, 0)):
            shape, fortran, dtype = fmt.read_array_header_2_0(fh)
        else:
            raise ValueError(f"unsupported .npy version {version}")
    except Exception as exc:  # numpy parses the untrusted header with ast/tokenize: any error means garbage
        raise input_error(path, f"{what}: not a NumPy array file ({type(exc).__name__})") from None
    if dtype.hasobject or dtype.kind not in "iuf" or dtype.fields is not None:
        raise input_error(path, f"{what}: dtype {dtype} is not a real number type")
    if len(shape) != 2 or shape[0] < 1 or shape[1] < 1:
        raise input_error(path, f"{what}: expected an array of shape (T, n) with T, n ≥ 1, got {tuple(shape)}")
    if shape[0] > L.MAX_LOG_ROWS or shape[1] > L.MAX_LOG_COLUMNS:
        raise input_error(path, f"{what}: shape {tuple(shape)} is over the limits ({L.MAX_LOG_ROWS} rows, "
                          f"{L.MAX_LOG_COLUMNS} columns)")
    count = int(shape[0]) * int(shape[1])
    try:
        data = fh.read(count * dtype.itemsize)
        if len(data) != count * dtype.itemsize:
            raise ValueError(f"the file ends early ({len(data)} of {count * dtype.itemsize} data bytes)")
        arr = np.frombuffer(data, dtype=dtype, count=count)
    except (ValueError, OSError, EOFError, zipfile.BadZipFile) as exc:
        raise input_error(path, f"{what}: cannot read the array data: {exc}") from None
    arr = arr.reshape(shape[::-1]).T if fortran else arr.reshape(shape)
    return np.asarray(arr, dtype=np.float64)


def _read_npy(path: Path) -> FloatArray:
    data = read_bytes(path, "log file")
    return _read_npy_stream(io.BytesIO(data), path, "array")


def _read_npz(path: Path) -> FloatArray:
    data = read_bytes(path, "log file")
    try:
        with zipfile.ZipFile(io.BytesIO(data)) as zf:
            names = [n for n in zf.namelist() if n.endswith(".npy")]
            keys = [n[:-4] for n in names]
            if "x" in keys:
                key = "x"
            elif len(keys) == 1:
                key = keys[0]
            else:
                raise input_error(path, f"expected an array named 'x' or a single array, found {keys or 'none'}")
            with zf.open(key + ".npy") as fh:
                return _read_npy_stream(fh, path, f"array {key!r}")
    except RobustGaitError:
        raise
    except (zipfile.BadZipFile, OSError, ValueError, EOFError, RuntimeError, NotImplementedError) as exc:
        raise input_error(path, f"not a valid .npz file ({exc})") from None


def _value_problem(v: float) -> str | None:
    if not np.isfinite(v):
        return "is not a finite number"
    if not L.LOG_VALUE.contains(v):
        return f"is outside the limit {L.LOG_VALUE.text()}"
    return None


def _check_values(x: FloatArray, path: Path) -> None:
    with np.errstate(invalid="ignore"):
        bad = ~np.isfinite(x) | (np.abs(x) > L.LOG_VALUE.high)
    if bad.any():
        i, j = (int(v) for v in np.argwhere(bad)[0])
        v = float(x[i, j])
        raise input_error(path, f"x[{i}, {j}] = {v!r} {_value_problem(v)}")


def load_reduced_log(path: str | Path, columns: Sequence[str] | None = None) -> FloatArray:
    """Read a recorded sequence of reduced states (T, n) from CSV, NPY or NPZ (module docstring).

    Missing or malformed files, NaN or inf values and shapes other than (T, n) with T, n ≥ 1 raise
    :class:`RobustGaitError` naming the file (one line).
    """
    p = Path(path)
    if isinstance(columns, str):
        columns = [columns]
    suffix = p.suffix.lower()
    if suffix not in LOG_FORMATS:
        raise input_error(p, f"unknown log format {suffix or '(no extension)'!r} (expected .csv, .npy or .npz)")
    if columns is not None and suffix != ".csv":
        raise input_error(p, "column names can only be selected in a CSV log")
    readers: dict[str, Any] = {".csv": lambda: _read_csv(p, columns), ".npy": lambda: _read_npy(p),
                               ".npz": lambda: _read_npz(p)}
    x: FloatArray = readers[suffix]()
    if suffix != ".csv":  # CSV cells are checked as they are parsed (row and column names in the message)
        _check_values(x, p)
    return x
