"""Property-based tests of every input: valid gait JSON, FROST YAML, robot spec TOML and log files
(CSV, NPY, NPZ) are mutated — types swapped, keys and items deleted or added, NaN/huge/absurd values, text
where numbers belong, truncation, bytes that are not UTF-8, wrong shapes and dtypes — and the command line
runs in-process on them. Every outcome must be exit 0 with a valid result, or exit 2 with exactly one line
on stderr naming the file; never a traceback, never a hang (a time limit per run), never a partial or
temporary file left behind.

Bounded: a fixed number of examples per property (``derandomize`` under CI, so a CI run is reproducible),
the shipped robot ``exo`` and gaits that stand (no solve); the whole file runs in well under two minutes.
``RG_PROPERTY_SCALE=20 pytest tests/cli/test_inputs.py`` searches 20 times deeper.
"""

from __future__ import annotations

import contextlib
import copy
import csv
import io
import json
import math
import os
import re
import signal
import tempfile
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from robustgait import load_gait, load_robot
from robustgait.cli import main
from robustgait.io.gaitfile import save_gait
from robustgait.robots.spec import SHIPPED_DIR
from tests.conftest import standing_gait

TIME_LIMIT_S = 30  # per command: the slowest valid run here (a walk of 2 steps of a 10 s gait) takes ~1 s


def _settings(n: int) -> settings:
    """n examples (times $RG_PROPERTY_SCALE for a deeper local search)."""
    return settings(max_examples=n * int(os.environ.get("RG_PROPERTY_SCALE", "1")), deadline=None,
                    derandomize=bool(os.environ.get("CI")), database=None,
                    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large,
                                           HealthCheck.large_base_example])


class Hang(BaseException):
    """Raised by the per-run alarm (a BaseException: product code catching Exception cannot swallow it)."""


@contextlib.contextmanager
def time_limit(seconds: float) -> Iterator[None]:
    def on_alarm(signum: int, frame: Any) -> None:
        raise Hang(f"no result within {seconds} s")

    old = signal.signal(signal.SIGALRM, on_alarm)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, old)


def run_cli(argv: list[str | Path], workdir: Path, inputs: list[Path], outputs: list[Path]) -> tuple[int, str]:
    """Run ``robustgait argv`` in-process and check the contract; returns (exit status, stdout)."""
    before = set(os.listdir(workdir))
    out, err = io.StringIO(), io.StringIO()
    with time_limit(TIME_LIMIT_S), contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main([str(a) for a in argv])
    stderr = err.getvalue()
    event(f"exit {code}")
    assert "Traceback" not in stderr
    created = set(os.listdir(workdir)) - before
    assert not [n for n in created if n.startswith(".robustgait-") or n.endswith(".tmp")], created
    if code == 0:
        assert created <= {p.name for p in outputs}, created
        assert stderr == "", stderr
    else:
        assert code == 2, (code, stderr)
        lines = stderr.splitlines()
        assert len(lines) == 1 and lines[0].startswith("robustgait: error: "), stderr
        assert any(str(p) in lines[0] for p in inputs), (lines[0], inputs)
        assert created == set(), created
    return code, out.getvalue()


# ------------------------------------------------------------------------------------------ mutations
NASTY = st.one_of(
    st.sampled_from([None, True, False, 0, -1, 1, 3, 12, 2**70, -(2**63), 0.0, -0.0, 0.7, 1e6, -1e6, 1e308,
                     float("nan"), float("inf"), float("-inf"), 5e-324, "", "0.7", "abc", "nan", "1e6", "left",
                     "\x00", "é", [], {}, [1.0], [[1.0]], [0.0] * 7, {"a": 1}, [None], ["a"], [True]]),
    st.floats(allow_nan=True, allow_infinity=True, width=64),
    st.integers(min_value=-(2**64), max_value=2**64),
    st.text(max_size=6),
)


def _paths(tree: Any, prefix: tuple[Any, ...] = ()) -> Iterator[tuple[Any, ...]]:
    if isinstance(tree, dict):
        for k, v in tree.items():
            yield (*prefix, k)
            yield from _paths(v, (*prefix, k))
    elif isinstance(tree, list):
        for i, v in enumerate(tree):
            yield (*prefix, i)
            yield from _paths(v, (*prefix, i))


def _parent(tree: Any, path: tuple[Any, ...]) -> Any:
    for p in path[:-1]:
        tree = tree[p]
    return tree


@st.composite
def mutated(draw: st.DrawFn, tree: Any, max_mutations: int = 3) -> Any:
    """1–max_mutations structural mutations of a JSON-like tree."""
    t = copy.deepcopy(tree)
    for _ in range(draw(st.integers(1, max_mutations))):
        paths = list(_paths(t))
        if not paths:
            break
        path = draw(st.sampled_from(paths))
        parent, key = _parent(t, path), path[-1]
        op = draw(st.sampled_from(["replace", "replace", "replace", "delete", "duplicate", "add_key", "scale"]))
        if op == "replace":
            parent[key] = draw(NASTY)
        elif op == "delete":
            del parent[key]
        elif op == "duplicate" and isinstance(parent, list):
            parent.insert(key, copy.deepcopy(parent[key]))
        elif op == "add_key" and isinstance(parent, dict):
            parent[draw(st.sampled_from(["extra", "durration", "x", str(key) + "_"]))] = draw(NASTY)
        elif op == "scale" and isinstance(parent[key], (int, float)) and not isinstance(parent[key], bool):
            parent[key] = parent[key] * draw(st.sampled_from([-1.0, 1e3, 1e-3, 1e9, 0.0]))
    return t


@st.composite
def corrupted(draw: st.DrawFn, data: bytes) -> bytes:
    """Mostly the bytes as they are; sometimes truncated, with inserted junk or non-UTF-8 bytes, or flipped."""
    op = draw(st.sampled_from(["none"] * 6 + ["truncate", "insert", "flip", "empty"]))
    if op == "truncate" and data:
        return data[:draw(st.integers(0, len(data) - 1))]
    if op == "insert":
        at = draw(st.integers(0, len(data)))
        junk = draw(st.sampled_from([b"\xff", b"\xc3\x28", b"\x00", b"{", b"[", b"]]", b"\n[x\n", b"\"", b","]))
        return data[:at] + junk + data[at:]
    if op == "flip" and data:
        at = draw(st.integers(0, len(data) - 1))
        return data[:at] + bytes([data[at] ^ draw(st.integers(1, 255))]) + data[at + 1:]
    if op == "empty":
        return b""
    return data


def toml_dumps(d: dict[str, Any]) -> str:
    """A small TOML writer for the spec tree (None values cannot be written: they are left out)."""
    def key(k: Any) -> str:
        k = str(k)
        return k if re.fullmatch(r"[A-Za-z0-9_-]+", k) else json.dumps(k)

    def value(v: Any) -> str:
        if isinstance(v, bool):
            return "true" if v else "false"
        if isinstance(v, int):
            return str(v)
        if isinstance(v, float):
            return "nan" if math.isnan(v) else ("inf" if v > 0 else "-inf") if math.isinf(v) else repr(v)
        if isinstance(v, str):
            return json.dumps(v)
        if isinstance(v, list):
            return "[" + ", ".join(value(x) for x in v if x is not None) + "]"
        if isinstance(v, dict):
            return "{" + ", ".join(f"{key(k)} = {value(x)}" for k, x in v.items() if x is not None) + "}"
        raise TypeError(type(v))

    lines: list[str] = []

    def table(t: dict[str, Any], name: str) -> None:
        if name:
            lines.append(f"[{name}]")
        for k, v in t.items():
            if v is not None and not isinstance(v, dict):
                lines.append(f"{key(k)} = {value(v)}")
        for k, v in t.items():
            if isinstance(v, dict):
                table(v, f"{name}.{key(k)}" if name else key(k))

    table(d, "")
    return "\n".join(lines) + "\n"


# ------------------------------------------------------------------------------------------ fixtures
EXO_SPEC_PATH = SHIPPED_DIR / "exo" / "spec.toml"


@pytest.fixture(scope="module")
def exo():
    return load_robot("exo")


@pytest.fixture(scope="module")
def gait_tree(exo) -> dict[str, Any]:
    return json.loads(json.dumps(standing_gait(exo, extras=True).to_dict()))


@pytest.fixture(scope="module")
def frost_tree(exo) -> dict[str, Any]:
    g = standing_gait(exo)
    s = g.initial_state
    return {"coeff_jt": g.domains[0].beta.flatten(order="F").tolist(), "step_dur": 0.7,
            "ffPos": s.qpos[:7].tolist(), "startingPos": s.qpos[7:].tolist(), "ffVel": s.qvel[:6].tolist(),
            "startingVel": s.qvel[6:].tolist(), "coeff_b": [0.0] * 48, "step_len": [0.0, 0.0, 0.0],
            "inputparams": {"desired_stepduration": 0.7, "impact_vel": [-0.8, -0.1]}}


@pytest.fixture(scope="module")
def spec_tree() -> dict[str, Any]:
    from robustgait.io.schema import read_toml

    tree = read_toml(EXO_SPEC_PATH)
    tree["mjcf"] = str(SHIPPED_DIR / "exo" / "exo.xml")
    return tree


@contextlib.contextmanager
def workdir() -> Iterator[Path]:
    with tempfile.TemporaryDirectory(prefix="rg-inputs-") as d:
        yield Path(d)


# ------------------------------------------------------------------------------------------ properties
@pytest.mark.slow  # keeps plain pytest within 60 s; CI runs it
@_settings(60)
@given(data=st.data())
def test_mutated_gait_json_converts_or_fails_cleanly(exo, gait_tree, data):
    tree = data.draw(mutated(gait_tree))
    raw = data.draw(corrupted(json.dumps(tree, allow_nan=True).encode()))
    with workdir() as wd:
        src, out = wd / "gait.json", wd / "out.json"
        src.write_bytes(raw)
        code, _ = run_cli(["gait", "convert", src, "--robot", "exo", "-o", out], wd, [src], [out])
        if code == 0:
            again = load_gait(out, exo)  # the written file is complete and valid
            assert again.to_dict() == load_gait(src, exo).to_dict()


@_settings(25)
@given(data=st.data())
def test_mutated_gait_json_walks_or_fails_cleanly(gait_tree, data):
    tree = data.draw(mutated(gait_tree, max_mutations=2))
    with workdir() as wd:
        src, log = wd / "gait.json", wd / "w.csv"
        src.write_text(json.dumps(tree, allow_nan=True))
        code, out = run_cli(["walk", src, "--robot", "exo", "--steps", "2", "--json", "--log", log], wd, [src], [log])
        if code == 0:
            res = json.loads(out)
            assert 0 <= res["steps_taken"] <= 2 and res["fell"] == (res["fall_reason"] is not None)
            assert len(log.read_text().splitlines()) == 1 + res["steps_taken"]


@pytest.mark.slow  # keeps plain pytest within 60 s; CI runs it
@_settings(40)
@given(data=st.data())
def test_mutated_frost_yaml_converts_or_fails_cleanly(exo, frost_tree, data):
    tree = data.draw(mutated(frost_tree))
    raw = data.draw(corrupted(yaml.safe_dump(tree).encode()))
    with workdir() as wd:
        src, out = wd / "gait.yaml", wd / "out.json"
        src.write_bytes(raw)
        code, _ = run_cli(["gait", "convert", src, "--robot", "exo", "-o", out], wd, [src], [out])
        if code == 0:
            g = load_gait(out, exo)
            assert g.domains[0].beta.shape == (12, 8) and 0.01 <= g.step_duration <= 10


@pytest.mark.slow  # keeps plain pytest within 60 s; CI runs it
@_settings(40)
@given(data=st.data())
def test_mutated_spec_toml_loads_or_fails_cleanly(exo, spec_tree, data):
    tree = data.draw(mutated(spec_tree))
    raw = data.draw(corrupted(toml_dumps(tree).encode()))
    with workdir() as wd:
        spec, gait = wd / "spec.toml", wd / "gait.json"
        spec.write_bytes(raw)
        save_gait(standing_gait(exo), gait)
        mjcf = Path(spec_tree["mjcf"])
        code, out = run_cli(["walk", gait, "--robot", spec, "--steps", "1", "--json"], wd, [spec, gait, mjcf], [])
        if code == 0:
            assert json.loads(out)["max_steps"] == 1


LOG_HEADER = ["wx", "wy", "wz"]
LOG_ROWS = [[0.41, 0.2, 0.3], [0.42, 0.21, 0.3], [0.4, 0.2, 0.31], [0.41, 0.2, 0.3]]


@st.composite
def csv_logs(draw: st.DrawFn) -> bytes:
    rows = [[*LOG_HEADER, "phase"]] + [[repr(v) for v in r] + [draw(st.sampled_from(["L", "R"]))] for r in LOG_ROWS]
    for _ in range(draw(st.integers(0, 3))):
        i = draw(st.integers(0, len(rows) - 1))
        op = draw(st.sampled_from(["cell", "cell", "drop_cell", "add_cell", "drop_row", "dup_header"]))
        if op == "cell" and rows[i]:
            j = draw(st.integers(0, len(rows[i]) - 1))
            rows[i][j] = draw(st.sampled_from(["abc", "", "nan", "inf", "-inf", "1e400", "0x10", "1_000", " 1 ",
                                               "1e6", "1e7", "\"q\"", "L", "0.5"])
                              | st.floats(allow_nan=True).map(repr) | st.text(max_size=4))
        elif op == "drop_cell" and rows[i]:
            rows[i].pop()
        elif op == "add_cell":
            rows[i].append("0.1")
        elif op == "drop_row" and len(rows) > 1:
            rows.pop(i)
        elif op == "dup_header":
            rows[0][1] = rows[0][0]
    buf = io.StringIO()
    csv.writer(buf, lineterminator="\n").writerows(rows)
    return draw(corrupted(buf.getvalue().encode()))


ARRAY_DTYPES = st.sampled_from([np.float64, np.float32, np.float16, np.int32, np.int8, np.uint16, np.bool_,
                                np.complex64, np.dtype("<U3"), np.dtype("datetime64[s]")])


@st.composite
def arrays(draw: st.DrawFn) -> np.ndarray:
    if draw(st.booleans()):  # near-valid: (T, 3) floats with the odd NaN or huge value
        a = np.array(LOG_ROWS, dtype=float)[: draw(st.integers(1, 4))]
        if draw(st.booleans()):
            a[draw(st.integers(0, a.shape[0] - 1)), draw(st.integers(0, 2))] = draw(
                st.sampled_from([np.nan, np.inf, 1e7, -1e300, 0.0]))
        return np.asfortranarray(a) if draw(st.booleans()) else a
    return draw(hnp.arrays(ARRAY_DTYPES, hnp.array_shapes(min_dims=0, max_dims=3, min_side=0, max_side=4)))


@pytest.mark.slow  # keeps plain pytest within 60 s; CI runs it
@_settings(60)
@given(data=st.data())
def test_mutated_logs_evaluate_or_fail_cleanly(data):
    kind = data.draw(st.sampled_from(["csv", "npy", "npz"]))
    with workdir() as wd:
        log = wd / f"log.{kind}"
        if kind == "csv":
            log.write_bytes(data.draw(csv_logs()))
        elif kind == "npy":
            buf = io.BytesIO()
            np.save(buf, data.draw(arrays()), allow_pickle=False)
            log.write_bytes(data.draw(corrupted(buf.getvalue())))
        else:
            keys = data.draw(st.lists(st.sampled_from(["x", "y", "states"]), min_size=0, max_size=2, unique=True))
            buf = io.BytesIO()
            np.savez(buf, **{k: data.draw(arrays()) for k in keys})
            log.write_bytes(data.draw(corrupted(buf.getvalue())))
        plot = wd / "h.png"
        argv: list[str | Path] = ["barrier-eval", log, "--x-star", "0.41,0.2,0.3", "--r", "0.5", "--json"]
        with_plot = data.draw(st.booleans())
        code, out = run_cli(argv + (["--plot", plot] if with_plot else []), wd, [log], [plot])
        if code == 0:
            res = json.loads(out)
            assert len(res["margins"]) == len(res["h"]) - 1 and res["ok"] in (True, False)
            assert plot.exists() == with_plot


NUMBER_TEXT = st.one_of(st.sampled_from(["0", "-1", "1", "1e9", "1000000000", "nan", "inf", "-inf", "0.5", "",
                                         "abc", "2", "10", "10.0001", "1e-300", "9223372036854775808", " 3"]),
                        st.integers(-(2**70), 2**70).map(str), st.floats().map(repr))
OPTIONS = {"walk": ["--steps"], "certify": ["--samples", "--r-max", "--alpha", "--seed", "--orbit-steps",
                                            "--push-horizon", "--epsilon", "--beta", "--budget"],
           "barrier-eval": ["--r", "--alpha"]}


@pytest.mark.slow  # keeps plain pytest within 60 s; CI runs it
@_settings(150)
@given(command=st.sampled_from(sorted(OPTIONS)), data=st.data())
def test_numeric_arguments_are_bounded(command, data):
    """Any text for a numeric option: refused in one line (exit 2) or accepted within its documented limit."""
    from robustgait.cli import build_parser
    from robustgait.config import Config, field_at
    from robustgait.io import limits as L

    option = data.draw(st.sampled_from(OPTIONS[command]))
    text = data.draw(NUMBER_TEXT)
    argv = [command, "in.csv"] + (["--robot", "exo"] if command != "barrier-eval" else ["--x-star", "0", "--r", "1"])
    argv += [f"{option}={text}"]
    err = io.StringIO()
    parser = build_parser()
    try:
        with contextlib.redirect_stderr(err):
            args = parser.parse_args(argv)
    except SystemExit as exc:
        assert exc.code == 2
        lines = err.getvalue().splitlines()
        assert len(lines) == 1 and lines[0].startswith("robustgait: error: argument " + option)
        return
    sub = parser._subparsers._group_actions[0].choices[command]  # type: ignore[union-attr]
    action = next(a for a in sub._actions if option in a.option_strings)
    value = getattr(args, action.dest)
    limit = L.BARRIER_R if option == "--r" else field_at(Config, action.robustgait_paths[0]).doc
    assert math.isfinite(value) and limit.contains(value), (option, text, value)


def test_time_limit_fires() -> None:
    """The per-run limit itself works (a hang would fail the property, not stall the suite)."""
    import time

    with pytest.raises(Hang), time_limit(0.2):
        time.sleep(2)

