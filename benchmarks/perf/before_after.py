"""A command's wall time, CPU time and work before and after a change, in one run: each case is run with this
checkout's ``src`` and with ``--before SRC`` (another checkout's ``src``, e.g. a ``git worktree`` of main) first on
``PYTHONPATH``, the two interleaved ``--repeat`` times so that the machine's load hits them alike. Each run's CPU time
(the command's processes, every thread) is also given in **yardsticks**: the CPU time of a fixed raw
``mujoco.rollout`` workload (:func:`common.yardstick`) measured in the same run, beside it — a figure comparable
across machines and load.

Cases (``--cases``, comma-separated). A robot's spec is the side's own (``robots/…/spec.toml`` of each checkout, or
``--g1-before`` / ``--g1-after``): a spec change, such as a timestep, is part of what is compared.

* ``certify``: ``robustgait certify tests/data/exo_gait.json --robot exo --json`` — the default exo certificate: wall
  and CPU time, J*, its pushes and physics steps (the sampling's, and the orbit search's);
* ``certify-mc``: the same on exo's default multi-contact gait (``tests/data/exo_multicontact_gait.json``);
* ``certify-atalante``: the Atalante FROST gait (``../shared/atalante``);
* ``certify-t1``: T1's default gait, generated once with this checkout (``../shared/robots/booster_t1``);
* ``certify-t1-slow``: T1's L 0.08 T 0.8 W 0.2 h 0.03 gait, generated once;
* ``certify-g1``: ``--g1-gait`` with ``--g1-before`` / ``--g1-after`` (a Menagerie G1 made as
  ``benchmarks/experiments/menagerie_humanoids`` says);
* ``certify-gaits``: the default certificate of ``--limit`` study gaits (``--from-jsonl``, evenly spaced; each
  generated cold with this checkout): per gait the physics steps and seconds of both, and the medians of the ratios;
* ``demo``: ``robustgait demo --dir TMP`` — the main job;
* ``study-exo``, ``study-t1``: ``robustgait study run DIR --robot R`` with the defaults (10 × 5);
* ``person-first``: ``robustgait study run DIR --robot exo --metric person --port 0`` with the defaults: the seconds
  from its start to its first question (the study's first pending batch, read from its database), how many gaits
  it shows and how many were evaluated to fill it; the study is then stopped.

Printed: per case and side the median (and range) of the wall times, the CPU time in yardsticks, the work figures,
and after / before.

    python benchmarks/perf/before_after.py --before /tmp/oldmain/src [--cases certify,demo] [--repeat 3]
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import signal
import sqlite3
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # benchmarks/common.py
from common import ATALANTE_GAIT, EXO_GAIT, EXO_MULTICONTACT_GAIT, REPO, git_commit

T1_MODEL_GAITS = {"certify-t1": {}, "certify-t1-slow": {"step_length": 0.08, "step_duration": 0.8,
                                                         "step_width": 0.2, "step_height": 0.03}}


def spec_of(side_src: str, robot: str, args: argparse.Namespace, side: str) -> str:
    """A robot's spec on a side: that checkout's ``robots/<robot>/spec.toml``, or the G1's given spec."""
    if robot == "g1":
        return str(args.g1_before if side == "before" else args.g1_after)
    return str(Path(side_src).parent / "robots" / robot / "spec.toml")


def command(case: str, side: str, src: str, args: argparse.Namespace, tmp: Path) -> list[str]:
    exe = [sys.executable, "-m", "robustgait.cli"]
    run_dir = str(tmp / f"{case}-{side}-{time.monotonic_ns()}")
    if case == "certify":
        return [*exe, "certify", str(EXO_GAIT), "--robot", "exo", "--json"]
    if case == "certify-mc":
        return [*exe, "certify", str(EXO_MULTICONTACT_GAIT), "--robot", "exo", "--json"]
    if case == "certify-atalante":
        return [*exe, "certify", str(ATALANTE_GAIT), "--robot", spec_of(src, "atalante", args, side), "--json"]
    if case in T1_MODEL_GAITS:
        return [*exe, "certify", str(tmp / f"{case}.json"), "--robot", spec_of(src, "t1", args, side), "--json"]
    if case == "certify-g1":
        return [*exe, "certify", str(args.g1_gait), "--robot", spec_of(src, "g1", args, side), "--json"]
    if case == "demo":
        return [*exe, "demo", "--dir", run_dir]
    if case == "study-exo":
        return [*exe, "study", "run", run_dir, "--robot", "exo"]
    if case == "study-t1":
        return [*exe, "study", "run", run_dir, "--robot", spec_of(src, "t1", args, side)]
    if case == "person-first":
        return [*exe, "study", "run", run_dir, "--robot", "exo", "--metric", "person", "--port", "0"]
    if case.startswith("gait:"):
        return [*exe, "certify", case.split(":", 1)[1], "--robot", "exo", "--json"]
    raise SystemExit(f"unknown case {case!r}")


def children_cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def first_question(p: subprocess.Popen[str], directory: Path, timeout: float) -> dict[str, Any]:
    """Wait for a person study's first pending batch (its iteration record in the database), then stop the study:
    seconds to it, gaits shown and evaluated."""
    t0 = time.perf_counter()
    db = directory / "study.db"
    while time.perf_counter() - t0 < timeout and p.poll() is None:
        time.sleep(0.5)
        if not db.exists():
            continue
        try:
            with sqlite3.connect(f"file:{db}?mode=ro", uri=True, timeout=5) as con:
                rows = con.execute("SELECT value_json FROM study_user_attributes "
                                   "WHERE key = 'iteration_000'").fetchall()
        except sqlite3.Error:
            continue
        rec = json.loads(rows[0][0]) if rows else {}
        if "pending" in rec:
            seconds = time.perf_counter() - t0
            p.send_signal(signal.SIGINT)  # the study stops as after a person's Ctrl-C
            try:
                p.wait(timeout=30)
            except subprocess.TimeoutExpired:
                p.kill()
                p.wait()
            return {"first_question": seconds, "shown": len(rec["pending"]["shown"]),
                    "evaluated": rec["pending"]["size"]}
    p.kill()
    return {"first_question": None, "error": "no question within the timeout"}


def run(case: str, side: str, src: str, args: argparse.Namespace, tmp: Path) -> dict[str, Any]:
    env = {**os.environ, "PYTHONPATH": src}
    cmd = command(case, side, src, args, tmp)
    cpu0, t0 = children_cpu(), time.perf_counter()
    if case == "person-first":
        p = subprocess.Popen(cmd, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, text=True, cwd=tmp)
        extra = first_question(p, Path(cmd[cmd.index("run") + 1]), args.timeout)
        return {"seconds": time.perf_counter() - t0, "cpu": children_cpu() - cpu0, "code": 0, **extra}
    p2 = subprocess.run(cmd, env=env, capture_output=True, text=True, cwd=tmp)
    out: dict[str, Any] = {"seconds": time.perf_counter() - t0, "cpu": children_cpu() - cpu0, "code": p2.returncode}
    if (case.startswith("certify") or case.startswith("gait:")) and p2.stdout.strip():
        res = json.loads(p2.stdout)
        search = res.get("orbit_physics_steps", res.get("fixed_point_physics_steps", 0))
        j_star = res["j_star"] if "j_star" in res else res["r_star"]  # J*: written as r_star before it was named
        out.update(status=res["status"], j_star=j_star, pushes=res.get("n_samples"), physics=res["physics_steps"],
                   search_physics=search, attempts=sum(r["kind"] == "verify" for r in res.get("rounds") or []))
    elif p2.returncode != 0:
        out["error"] = p2.stderr.strip().splitlines()[-1:] or [""]
    return out


def yardstick_cpu(src: str) -> float:
    """The yardstick's CPU seconds, in a fresh process on ``src``."""
    code = f"import sys; sys.path.insert(0, {str(REPO / 'benchmarks')!r}); from common import yardstick; " \
           "print(yardstick())"
    p = subprocess.run([sys.executable, "-c", code], env={**os.environ, "PYTHONPATH": src}, capture_output=True,
                       text=True, check=True)
    return float(p.stdout.strip().splitlines()[-1])


def prepare(cases: list[str], tmp: Path) -> None:
    """The gaits the T1 cases certify, generated once with this checkout (``tmp/<case>.json``)."""
    from robustgait.config import GaitParams
    from robustgait.gaitgen import generate_gait
    from robustgait.io.gaitfile import save_gait
    from robustgait.io.robotfile import load_robot

    for case in cases:
        if case in T1_MODEL_GAITS:
            robot = load_robot(REPO / "robots" / "t1" / "spec.toml")
            params = GaitParams(**T1_MODEL_GAITS[case]) if T1_MODEL_GAITS[case] else robot.default_params
            res = generate_gait(robot, params)
            if res.gait is None:
                raise SystemExit(f"{case}: the gait was not generated ({res.status}: {res.reason})")
            save_gait(res.gait, tmp / f"{case}.json")


def describe(r: dict[str, Any], stick: float) -> str:
    """The work figures of one run."""
    out = f"; CPU {r['cpu']:.1f} s = {r['cpu'] / stick:.1f} yardsticks"
    if "physics" in r:
        out += (f"; {r['status']}, J* {r['j_star']:.3f} N s, {r['pushes']} pushes, {r['attempts']} verification "
                f"batch(es), {(r['physics'] + r['search_physics']) / 1e6:.2f} M physics steps "
                f"(search {r['search_physics'] / 1e3:.0f} k)")
    elif "first_question" in r:
        out += (f"; first question after {r['first_question']:.1f} s, {r['shown']} gaits shown of "
                f"{r['evaluated']} evaluated" if r["first_question"] is not None else f"; {r.get('error')}")
    elif "error" in r:
        out += f"; exit {r['code']}: {r['error'][0]}"
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--before", required=True, help="the other checkout's src directory")
    ap.add_argument("--cases", default="certify,demo")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--g1-gait", default="")
    ap.add_argument("--g1-before", default="")
    ap.add_argument("--g1-after", default="")
    ap.add_argument("--timeout", type=float, default=1800.0, help="person-first: the longest wait [s]")
    ap.add_argument("--from-jsonl",
                    default=str(REPO / "benchmarks" / "experiments" / "predictors" / "data" / "exo.jsonl"))
    ap.add_argument("--limit", type=int, default=10)
    ap.add_argument("--out", default="", help="append each run as a JSON line")
    ap.add_argument("--sides", default="before,after",
                    help="which sides to run (one side alone: its figures, no ratio — the other's from an earlier "
                         "run of the same day and machine, with its --out line)")
    args = ap.parse_args()
    commit = git_commit()
    before = git_commit(Path(args.before).parent)
    print(f"# before_after {time.strftime('%Y-%m-%d %H:%M')}: after = {commit}, before = {before}; "
          f"load {os.getloadavg()[0]:.1f}", flush=True)
    sides = {k: v for k, v in {"before": args.before, "after": str(REPO / "src")}.items()
             if k in args.sides.split(",")}
    cases = args.cases.split(",")
    with tempfile.TemporaryDirectory(prefix="bench_before_after_") as d:
        tmp = Path(d)
        prepare(cases, tmp)
        for case in cases:
            if case == "certify-gaits":
                certify_gaits(args, sides, tmp)
                continue
            rows: dict[str, list[dict[str, Any]]] = {side: [] for side in sides}
            sticks: list[float] = []
            for _ in range(args.repeat):
                sticks.append(yardstick_cpu(sides["after"]))
                for side, src in sides.items():
                    r = run(case, side, src, args, tmp)
                    rows[side].append(r)
                    if args.out:
                        with open(args.out, "a") as f:
                            f.write(json.dumps({"case": case, "side": side, **r, "yardstick": sticks[-1],
                                                "commit": commit if side == "after" else before,
                                                "date": time.strftime("%Y-%m-%d %H:%M")}) + "\n")
            stick = statistics.median(sticks)
            med = {}
            for side, rs in rows.items():
                secs = [r["seconds"] for r in rs]
                med[side] = statistics.median(secs)
                print(f"{case} {side}: {med[side]:.1f} s median ({min(secs):.1f}–{max(secs):.1f}, {len(secs)} runs)"
                      f"{describe(rs[0], stick)}", flush=True)
            if len(rows) < 2:
                continue
            ratio = med["after"] / med["before"]
            work = ""
            a, b = rows["after"][0], rows["before"][0]
            if "physics" in a and "physics" in b:
                steps = (a["physics"] + a["search_physics"]) / (b["physics"] + b["search_physics"])
                work = f", physics steps {steps:.2f}×"
            print(f"{case}: after / before {ratio:.2f}× wall, CPU {a['cpu'] / b['cpu']:.2f}×{work} "
                  f"(yardstick {stick:.2f} CPU s)\n", flush=True)


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
        out = {side: run(f"gait:{path}", side, src, args, tmp) for side, src in sides.items()}
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
