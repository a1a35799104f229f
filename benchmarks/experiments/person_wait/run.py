"""A person never waits for nothing: a person study of exo with the defaults, answered in Chromium, timed from each
click on "submit" to the next batch shown in full (its videos playing), with and without over-drawn batches and
evaluations ahead of the answer — both in one run.

For each configuration (``before``: ``person.overdraw = 0``, ``person.ahead = false``; ``after``: the defaults)
``robustgait study run DIR --robot exo --metric person --iterations N --batch B --port 0`` runs as a subprocess; a
headless Chromium (Debian's, driven by Playwright: never ``playwright install``) opens the page, and for each batch
the person takes ``--think`` seconds (watching the videos) and submits the batch as listed. Printed and appended to
``--out``/results.jsonl: the time from the study's start to the first question, each answer → next question, the
batches asked (a batch with no gait to show is not asked) and the gaits each showed, the candidates evaluated, and
the evaluations made ahead and used.

    python benchmarks/experiments/person_wait/run.py [--iterations 3] [--batch 3] [--think 60] [--out DIR]
"""

from __future__ import annotations

import argparse
import json
import os
import queue
import signal
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path
from typing import Any

from robustgait.study.status import study_status

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))  # benchmarks/common.py
from common import REPO, git_commit

CHROMIUM = "/usr/bin/chromium"
ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
        "--disable-background-networking", "--disable-component-update", "--disable-sync"]
CONFIGS = {"before": ["--override", "person.overdraw=0", "--override", "person.ahead=false"], "after": []}


def start(directory: Path, iterations: int, batch: int, extra: list[str]) -> tuple[subprocess.Popen[str], str]:
    env = {**os.environ, "PYTHONPATH": str(REPO / "src")}
    proc = subprocess.Popen([sys.executable, "-m", "robustgait.cli", "study", "run", str(directory), "--robot", "exo",
                             "--metric", "person", "--iterations", str(iterations), "--batch", str(batch), "--port",
                             "0", "--quiet", "--override", "web.linger=2", *extra], env=env, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, start_new_session=True)
    lines: queue.Queue[str] = queue.Queue()
    threading.Thread(target=lambda: [lines.put(x) for x in proc.stdout], daemon=True).start()  # type: ignore[union-attr]
    line = lines.get(timeout=300)
    if "the study's page: http://" not in line:
        raise RuntimeError(line)
    return proc, line.split()[3]


def wait_question(page: Any, after: int) -> tuple[int, int]:
    """Wait until the page asks about a batch later than ``after`` (1-based; a batch with no gait to show is not
    asked) with every video playing, or says the study is complete; returns (its number, the gaits shown), (0, 0) at
    the end."""
    page.wait_for_function(
        "(after) => { const t = document.querySelector('[data-testid=status]').textContent; const m = "
        "t.match(/^Batch (\\d+) /); return (m && +m[1] > after && document.querySelector('[data-testid^=card-]')) "
        "|| t.startsWith('The study is complete'); }", arg=after, timeout=3_600_000)
    status = page.inner_text("[data-testid=status]")
    if status.startswith("The study is complete"):
        return 0, 0
    page.wait_for_function("() => [...document.querySelectorAll('video')].every(v => v.videoWidth > 0 && "
                           "v.currentTime > 0.1 && !v.paused)", timeout=120_000)
    return int(status.split()[1]), int(page.locator("[data-testid^=card-]").count())


def one(name: str, iterations: int, batch: int, think: float, work: Path) -> dict[str, Any]:
    from playwright.sync_api import sync_playwright

    d = work / name
    t0 = time.monotonic()
    proc, url = start(d, iterations, batch, CONFIGS[name])
    out: dict[str, Any] = {"config": name, "iterations": iterations, "batch": batch, "think_s": think}
    try:
        with sync_playwright() as p:
            browser = p.chromium.launch_persistent_context(str(work / f"chromium-{name}"), executable_path=CHROMIUM,
                                                           args=ARGS, headless=True,
                                                           viewport={"width": 1100, "height": 1000})
            try:
                page = browser.new_page()
                page.goto(url)
                k, n = wait_question(page, 0)
                out["first_question_s"] = time.monotonic() - t0
                asked, shown, waits = [k], [n], []
                while k:
                    time.sleep(think)
                    page.click("[data-testid=submit]")
                    t = time.monotonic()
                    k, n = wait_question(page, k)
                    if k:
                        asked.append(k)
                        shown.append(n)
                        waits.append(time.monotonic() - t)
                        print(f"{name}: answer → batch {k} shown in {waits[-1]:.1f} s ({n} gaits)", flush=True)
            finally:
                browser.close()
        proc.wait(timeout=120)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
    st = study_status(d)
    out.update({"answer_to_next_s": waits, "asked": asked, "shown": shown,
                "evaluated": [len(it["trials"]) for it in st["iterations"]],
                "ahead": st["person"]["ahead"], "floor": st["person"]["floor"]["value"],
                "study_s": time.monotonic() - t0})
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--iterations", type=int, default=3)
    ap.add_argument("--batch", type=int, default=3)
    ap.add_argument("--think", type=float, default=60.0, help="seconds the person takes per batch")
    ap.add_argument("--configs", default="before,after")
    ap.add_argument("--out", type=Path, default=Path(__file__).parent / "data")
    args = ap.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    commit = git_commit()
    with tempfile.TemporaryDirectory() as tmp:
        for name in args.configs.split(","):
            res = {**one(name, args.iterations, args.batch, args.think, Path(tmp)), "commit": commit,
                   "date": time.strftime("%Y-%m-%d %H:%M"), "load": os.getloadavg()[0]}
            print(json.dumps(res), flush=True)
            with (args.out / "results.jsonl").open("a") as fh:
                fh.write(json.dumps(res) + "\n")


if __name__ == "__main__":
    main()
