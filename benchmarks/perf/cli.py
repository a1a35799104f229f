"""Start-up of the command line: what a user waits for before ``robustgait --help`` (or any command) answers.

Each figure is the median over ``--repeat`` fresh interpreters, the variants interleaved so that the machine's
load hits them alike:

* ``robustgait --help`` and ``robustgait certify --help`` (building the whole parser from the configuration);
* ``import robustgait`` (the lazy package), ``import robustgait.config`` (the configuration: pydantic + the
  sections), and the schema libraries alone, after numpy: pydantic (the one robustgait uses) and, when
  installed, msgspec (the one it used before; ``pip install msgspec``);
* with ``--before SRC``: the same command lines with another checkout's ``src`` first on ``PYTHONPATH`` (e.g.
  a worktree of the commit before the configuration tree), and the ratios.

    python benchmarks/perf/cli.py [--repeat 15] [--before /path/to/old/checkout/src]
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # benchmarks/common.py
from common import REPO

CASES = {
    "robustgait --help": "import sys; sys.argv=['robustgait', '--help']\ntry:\n from robustgait.cli import main; "
                         "main()\nexcept SystemExit: pass",
    "robustgait certify --help": "import sys\ntry:\n from robustgait.cli import main; main(['certify', '--help'])\n"
                                 "except SystemExit: pass",
    "import robustgait": "import robustgait",
    "import robustgait.config": "import robustgait.config",
    "numpy + pydantic": "import numpy, pydantic, pydantic.dataclasses",
    "numpy + msgspec": "import numpy, msgspec",
    "numpy": "import numpy",
    "python": "pass",
}


def run(code: str, src: Path) -> float:
    """Wall time of a fresh interpreter running ``code`` (NaN if it fails: a module the checkout lacks)."""
    env = {**os.environ, "PYTHONPATH": str(src), "MUJOCO_GL": "egl"}
    t0 = time.perf_counter()
    done = subprocess.run([sys.executable, "-c", code], env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return time.perf_counter() - t0 if done.returncode == 0 else float("nan")


def available(module: str) -> bool:
    return subprocess.run([sys.executable, "-c", f"import {module}"], capture_output=True).returncode == 0


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=15)
    ap.add_argument("--before", type=Path, help="another checkout's src directory, timed on the same command lines")
    args = ap.parse_args()
    cases = {k: v for k, v in CASES.items() if "msgspec" not in v or available("msgspec")}
    srcs = {"now": REPO / "src"} | ({"before": args.before} if args.before else {})
    times: dict[tuple[str, str], list[float]] = {}
    for _ in range(args.repeat):
        for name, code in cases.items():
            for tag, src in srcs.items():
                if tag == "before" and "robustgait" not in code:
                    continue
                times.setdefault((tag, name), []).append(run(code, src))
    print(f"machine: {os.cpu_count()} cores, load {os.getloadavg()[0]:.2f}; python {sys.version.split()[0]}; "
          f"median of {args.repeat} fresh interpreters, interleaved")
    print("| what | now [ms] |" + (" before [ms] | now / before |" if args.before else ""))
    print("|---|---|" + ("---|---|" if args.before else ""))
    for name in cases:
        now = statistics.median(times[("now", name)]) * 1e3
        row = f"| {name} | {now:.0f} |"
        before = statistics.median(times[("before", name)]) * 1e3 if ("before", name) in times else float("nan")
        if before == before:  # not NaN: the other checkout has it
            row += f" {before:.0f} | {now / before:.2f} |"
        elif args.before:
            row += " | |"
        print(row, flush=True)


if __name__ == "__main__":
    main()
