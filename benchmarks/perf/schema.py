"""Schema library for the input layer: pydantic v2 vs msgspec, measured (issue 11).

Both libraries validate the same schema — robustgait's gait JSON (nested objects, lists of lists of numbers,
bounded durations, enums, optional sub-objects) — written the way each is meant to be used (pydantic:
``BaseModel`` with ``strict=True, extra="forbid", allow_inf_nan=False``; msgspec: ``Struct`` with
``forbid_unknown_fields=True`` and ``Meta`` bounds, ``msgspec.convert``). Measured in one run, interleaved:

* import time of the library in a fresh interpreter (after numpy, which robustgait always imports);
* time to a first validated gait in a fresh interpreter: import + define the schema + validate once;
* validation time of one gait dict in a warm process (12 joints × 8 coefficients, 17 × 12 feedforward);
* the error message each produces for the same nested-field defects (printed side by side).

    python benchmarks/perf/schema.py [--repeat 9]

Needs ``pip install pydantic`` (not a dependency of robustgait: only this comparison uses it).
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import textwrap
import timeit

SCHEMAS = {
    "pydantic": '''
from typing import Annotated, Any, Literal
from pydantic import BaseModel, ConfigDict, Field, ValidationError
class _M(BaseModel):
    model_config = ConfigDict(strict=True, extra="forbid", allow_inf_nan=False)
Coef = Annotated[float, Field(ge=-100, le=100)]
class Feedforward(_M):
    tau: Annotated[list[Annotated[float, Field(ge=0, le=1)]], Field(min_length=2)]
    torque: list[list[Annotated[float, Field(ge=-1e5, le=1e5)]]]
class Domain(_M):
    duration: Annotated[float, Field(ge=0.01, le=10)]
    beta: list[Annotated[list[Coef], Field(min_length=8, max_length=8)]]
    name: str = ""
    feedforward: Feedforward | None = None
class State(_M):
    qpos: list[Annotated[float, Field(ge=-1e3, le=1e3)]]
    qvel: list[Annotated[float, Field(ge=-1e3, le=1e3)]]
class Gait(_M):
    schema_version: Literal[1]
    robot: str
    domain_graph: Literal["flat", "multicontact"]
    stance: Literal["left", "right"]
    joints: list[str] = []
    domains: Annotated[list[Domain], Field(min_length=1, max_length=8)]
    initial_state: State | None = None
    pre_impact_state: State | None = None
    params: dict[str, float] | None = None
    solver: dict[str, Any] | None = None
    meta: dict[str, Any] = {}
def validate(raw):
    return Gait.model_validate(raw)
def error(raw):
    try:
        Gait.model_validate(raw)
    except ValidationError as exc:
        e = exc.errors()[0]
        return f"{e['loc']}: {e['msg']} [{exc.error_count()} error(s)]"
    return "accepted"
''',
    "msgspec": '''
from typing import Annotated, Any, Literal
import msgspec
from msgspec import Meta, Struct
Coef = Annotated[float, Meta(ge=-100, le=100)]
class Feedforward(Struct, forbid_unknown_fields=True):
    tau: Annotated[list[Annotated[float, Meta(ge=0, le=1)]], Meta(min_length=2)]
    torque: list[list[Annotated[float, Meta(ge=-1e5, le=1e5)]]]
class Domain(Struct, forbid_unknown_fields=True):
    duration: Annotated[float, Meta(ge=0.01, le=10)]
    beta: list[Annotated[list[Coef], Meta(min_length=8, max_length=8)]]
    name: str = ""
    feedforward: Feedforward | None = None
class State(Struct, forbid_unknown_fields=True):
    qpos: list[Annotated[float, Meta(ge=-1e3, le=1e3)]]
    qvel: list[Annotated[float, Meta(ge=-1e3, le=1e3)]]
class Gait(Struct, forbid_unknown_fields=True):
    schema_version: Literal[1]
    robot: str
    domain_graph: Literal["flat", "multicontact"]
    stance: Literal["left", "right"]
    domains: Annotated[list[Domain], Meta(min_length=1, max_length=8)]
    joints: list[str] = []
    initial_state: State | None = None
    pre_impact_state: State | None = None
    params: dict[str, float] | None = None
    solver: dict[str, Any] | None = None
    meta: dict[str, Any] = {}
def validate(raw):
    return msgspec.convert(raw, Gait)
def error(raw):
    try:
        msgspec.convert(raw, Gait)
    except msgspec.ValidationError as exc:
        return str(exc)
    return "accepted"
''',
}

GAIT = '''
def good():
    return {"schema_version": 1, "robot": "exo", "domain_graph": "flat", "stance": "right",
            "joints": [f"j{i}" for i in range(12)],
            "domains": [{"name": "ss", "duration": 0.7, "beta": [[0.1 * k for k in range(8)] for _ in range(12)],
                         "feedforward": {"tau": [i / 16 for i in range(17)], "torque": [[1.0] * 12] * 17}}],
            "initial_state": {"qpos": [0.0] * 19, "qvel": [0.0] * 18}, "pre_impact_state": None,
            "params": {"step_length": 0.15}, "solver": {"status": "ok"}, "meta": {}}
'''

DEFECTS = {  # name: statement mutating ``d`` (a valid gait dict)
    '"joints": 5': 'd["joints"] = 5',
    '"meta": [..]': 'd["meta"] = [1, 2]',
    'duration "0.7"': 'd["domains"][0]["duration"] = "0.7"',
    "duration true": 'd["domains"][0]["duration"] = True',
    "duration 1e6": 'd["domains"][0]["duration"] = 1e6',
    "duration NaN": 'd["domains"][0]["duration"] = float("nan")',
    "beta cell NaN": 'd["domains"][0]["beta"][3][2] = float("nan")',
    "beta cell 'a'": 'd["domains"][0]["beta"][3][2] = "a"',
    "beta row of 7": 'd["domains"][0]["beta"][3].pop()',
    "torque inf": 'd["domains"][0]["feedforward"]["torque"][4][1] = float("inf")',
    "stance 'middle'": 'd["stance"] = "middle"',
    "typo key": 'd["domains"][0]["durration"] = 0.7',
    "missing duration": 'del d["domains"][0]["duration"]',
}


def _fresh(code: str) -> float:
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    return float(out.stdout.strip())


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=9)
    args = ap.parse_args()
    print(f"python {sys.version.split()[0]}, load {os.getloadavg()[0]:.2f} (1-min average)")
    imp = {lib: [] for lib in SCHEMAS}
    first = {lib: [] for lib in SCHEMAS}
    for _ in range(args.repeat):  # interleaved, so load changes hit both alike
        for lib, schema in SCHEMAS.items():
            imp[lib].append(_fresh(f"import numpy, time\nt = time.perf_counter()\nimport {lib}\n"
                                   + ("from pydantic import BaseModel\n" if lib == "pydantic" else "")
                                   + "print(time.perf_counter() - t)"))
            body = textwrap.indent(schema + GAIT + "validate(good())\n", "    ")
            first[lib].append(_fresh(f"import numpy, time\nt = time.perf_counter()\nif True:\n{body}\n"
                                     "print(time.perf_counter() - t)"))
    warm = {}
    errors: dict[str, dict[str, str]] = {}
    for lib, schema in SCHEMAS.items():
        ns: dict = {}
        # dont_inherit: this module's ``from __future__ import annotations`` must not leak into the schemas
        exec(compile(schema + GAIT, f"<{lib}>", "exec", dont_inherit=True), ns)
        raw = ns["good"]()
        n = 2000
        warm[lib] = min(timeit.repeat(lambda ns=ns, raw=raw: ns["validate"](raw), number=n, repeat=5)) / n
        errors[lib] = {}
        for name, stmt in DEFECTS.items():
            d = ns["good"]()
            exec(compile(stmt, "<defect>", "exec", dont_inherit=True), {"d": d})
            errors[lib][name] = ns["error"](d)
    med = {k: {lib: statistics.median(v) * 1e3 for lib, v in t.items()} for k, t in (("import", imp),
                                                                                     ("first", first))}
    print(f"\n{'median of ' + str(args.repeat):<44} {'pydantic':>10} {'msgspec':>10} {'ratio':>7}")
    for key, label in (("import", "import in a fresh interpreter [ms]"),
                       ("first", "import + schema + first validation [ms]")):
        p, m = med[key]["pydantic"], med[key]["msgspec"]
        print(f"{label:<44} {p:>10.1f} {m:>10.1f} {p / m:>7.1f}")
    p, m = warm["pydantic"] * 1e6, warm["msgspec"] * 1e6
    print(f"{'validate one gait, warm [µs]':<44} {p:>10.1f} {m:>10.1f} {p / m:>7.1f}")
    print("\nerror messages (first error):")
    for name in DEFECTS:
        print(f"- {name}\n    pydantic: {errors['pydantic'][name]}\n    msgspec:  {errors['msgspec'][name]}")


if __name__ == "__main__":
    main()
