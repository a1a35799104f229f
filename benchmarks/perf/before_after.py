"""A command's wall time and work before and after a change, in one run: each case is run with this checkout's
``src`` and with ``--before SRC`` (another checkout's ``src``, e.g. a ``git worktree`` of main) first on
``PYTHONPATH``, the two interleaved ``--repeat`` times so that the machine's load hits them alike.

Cases (``--cases``, comma-separated):

* ``certify``: ``robustgait certify tests/data/exo_gait.json --robot exo --json`` — the default exo certificate: wall
  time, J*, its pushes and physics steps (the sampling's, and the orbit's or fixed point's search);
* ``certify-t1``: the same on Booster T1's L 0.08 T 0.8 gait (``--t1-spec``, ``--t1-gait``);
* ``certify-gaits``: the default certificate of ``--limit`` study gaits (``--from-jsonl``, evenly spaced; each
  generated cold with this checkout): per gait the physics steps and seconds of both, and the medians of the ratios;
* ``demo``: ``robustgait demo --dir TMP`` — the main job: wall time.

Printed: per case and side the median (and range) of the wall times, the work figures, and after / before.

    python benchmarks/perf/before_after.py --before /tmp/oldmain/src [--cases certify,demo] [--repeat 3]
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # benchmarks/common.py
from common import EXO_GAIT, REPO, T1_SPEC, git_commit


def command(case: str, args: argparse.Namespace, tmp: Path) -> list[str]:
    exe = [sys.executable, "-m", "robustgait.cli"]
    if case == "certify":
        return [*exe, "certify", str(EXO_GAIT), "--robot", "exo", "--json"]
    if case == "certify-t1":
        return [*exe, "certify", args.t1_gait, "--robot", args.t1_spec, "--json"]
    if case == "demo":
        return [*exe, "demo", "--dir", str(tmp / f"demo-{time.monotonic_ns()}")]
    if case.startswith("gait:"):
        return [*exe, "certify", case.split(":", 1)[1], "--robot", "exo", "--json"]
    raise SystemExit(f"unknown case {case!r}")


def run(case: str, src: str, args: argparse.Namespace, tmp: Path) -> dict[str, Any]:
    env = {**os.environ, "PYTHONPATH": src}
    t0 = time.perf_counter()
    p = subprocess.run(command(case, args, tmp), env=env, capture_output=True, text=True, cwd=tmp)
    out: dict[str, Any] = {"seconds": time.perf_counter() - t0, "code": p.returncode}
    if (case.startswith("certify") or case.startswith("gait:")) and p.stdout.strip():
        res = json.loads(p.stdout)
        search = res.get("orbit_physics_steps", res.get("fixed_point_physics_steps", 0))
        out.update(status=res["status"], j_star=res["r_star"], pushes=res.get("n_samples"),
                   physics=res["physics_steps"], search_physics=search)
    elif p.returncode != 0:
        out["error"] = p.stderr.strip().splitlines()[-1:] or [""]
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--before", required=True, help="the other checkout's src directory")
    ap.add_argument("--cases", default="certify,demo")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--t1-spec", default=str(T1_SPEC))
    ap.add_argument("--t1-gait", default="")
    ap.add_argument("--from-jsonl",
                    default=str(REPO / "benchmarks" / "experiments" / "predictors" / "data" / "exo.jsonl"))
    ap.add_argument("--limit", type=int, default=10)
    args = ap.parse_args()
    commit = git_commit()
    before = git_commit(Path(args.before).parent)
    print(f"# before_after {time.strftime('%Y-%m-%d %H:%M')}: after = {commit}, before = {before}; "
          f"load {os.getloadavg()[0]:.1f}")
    sides = {"before": args.before, "after": str(REPO / "src")}
    with tempfile.TemporaryDirectory(prefix="bench_before_after_") as d:
        tmp = Path(d)
        for case in args.cases.split(","):
            if case == "certify-gaits":
                certify_gaits(args, sides, tmp)
                continue
            rows: dict[str, list[dict[str, Any]]] = {"before": [], "after": []}
            for _ in range(args.repeat):
                for side, src in sides.items():
                    rows[side].append(run(case, src, args, tmp))
            med = {}
            for side, rs in rows.items():
                secs = [r["seconds"] for r in rs]
                med[side] = statistics.median(secs)
                extra = ""
                r = rs[0]
                if "physics" in r:
                    extra = (f"; {r['status']}, J* {r['j_star']:.2f} N s, {r['pushes']} pushes, "
                             f"{(r['physics'] + r['search_physics']) / 1e6:.2f} M physics steps "
                             f"(search {r['search_physics'] / 1e3:.0f} k)")
                elif "error" in r:
                    extra = f"; exit {r['code']}: {r['error'][0]}"
                print(f"{case} {side}: {med[side]:.1f} s median ({min(secs):.1f}–{max(secs):.1f}, {len(secs)} runs)"
                      f"{extra}")
            ratio = med["after"] / med["before"]
            work = ""
            if "physics" in rows["after"][0] and "physics" in rows["before"][0]:
                a, b = rows["after"][0], rows["before"][0]
                steps = (a["physics"] + a["search_physics"]) / (b["physics"] + b["search_physics"])
                work = f", physics steps {steps:.2f}×"
            print(f"{case}: after / before {ratio:.2f}× wall{work}\n")


def certify_gaits(args: argparse.Namespace, sides: dict[str, str], tmp: Path) -> None:
    """The ``certify-gaits`` case (module docstring)."""
    import numpy as np

    from robustgait.config import GaitParams
    from robustgait.gaitgen import GaitGenerator
    from robustgait.io.gaitfile import save_gait
    from robustgait.io.robotfile import load_robot

    rows = [json.loads(line) for line in Path(args.from_jsonl).read_text().splitlines() if line.strip()]
    pick = np.unique(np.linspace(0, len(rows) - 1, args.limit).round().astype(int))
    gen = GaitGenerator(load_robot("exo"))
    phys, secs = [], []
    print("| gait | before: status, J*, M physics steps, s | after: status, J*, M physics steps, s | ratio steps, s |")
    print("|---|---|---|---|")
    for i in pick:
        label = rows[i]["label"]
        res = gen.solve(GaitParams(**{k: rows[i]["params"][k] for k in ("step_length", "step_duration",
                                                                           "step_width", "step_height")}))
        if res.gait is None:
            print(f"| {label} | not generated: {res.reason} | | |")
            continue
        path = tmp / f"{label}.json"
        save_gait(res.gait, path)
        out = {side: run(f"gait:{path}", src, args, tmp) for side, src in sides.items()}
        cells = []
        for side in ("before", "after"):
            r = out[side]
            cells.append(f"{r.get('status')}, {r.get('j_star', 0):.2f}, "
                         f"{(r.get('physics', 0) + r.get('search_physics', 0)) / 1e6:.2f}, {r['seconds']:.1f}")
        b, a = out["before"], out["after"]
        ratio = ""
        if b.get("status") == "ok" and a.get("status") == "ok":
            phys.append((a["physics"] + a["search_physics"]) / (b["physics"] + b["search_physics"]))
            secs.append(a["seconds"] / b["seconds"])
            ratio = f"{phys[-1]:.2f}×, {secs[-1]:.2f}×"
        print(f"| {label} | {cells[0]} | {cells[1]} | {ratio} |")
    if phys:
        print(f"\ncertify-gaits: on the {len(phys)} gaits certified by both, after / before median physics steps "
              f"{np.median(phys):.2f}× ({min(phys):.2f}–{max(phys):.2f}), wall {np.median(secs):.2f}× "
              f"({min(secs):.2f}–{max(secs):.2f})\n")


if __name__ == "__main__":
    main()
