"""The page of a person study in a real browser (docs/person.md), slow: `robustgait study run --metric person` on a tiny
exo study, driven by Playwright in the Chromium of the system's package manager (`apt-get install chromium`; never
`playwright install`): rank a batch, submit, see the next batch; SIGKILL the study while a batch waits — nothing of it
keeps running — and `study serve` comes back at that batch with the first answer kept; SIGKILL `study serve` the
same way; answer the last batch; the study completes with both answers stored once."""

from __future__ import annotations

import os
import queue
import shutil
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

from robustgait.study.status import study_status

REPO = Path(__file__).resolve().parents[2]
CHROMIUM = "/usr/bin/chromium"
CHROMIUM_ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                 "--disable-background-networking", "--disable-component-update", "--disable-sync"]
TINY = ["--iterations", "2", "--batch", "2", "--method", "uniform", "--samples", "10", "--steps", "5", "--seed", "0",
        "--override", "comfort.skip_steps=1", "--override", "comfort.steps=3", "--override", "web.linger=2",
        "--floor", "0", "--port", "0", "--workers", "1", "--quiet"]

pytestmark = [pytest.mark.slow, pytest.mark.skipif(not Path(CHROMIUM).is_file(),
                                                   reason="no /usr/bin/chromium (apt-get install chromium)")]


def start(*args: str) -> tuple[subprocess.Popen, str]:  # type: ignore[type-arg]
    """Start a CLI process in its own session and return it with the page's URL (its first line)."""
    env = {**os.environ, "PYTHONPATH": str(REPO / "src"), "MUJOCO_GL": os.environ.get("MUJOCO_GL", "egl")}
    proc = subprocess.Popen([sys.executable, "-m", "robustgait.cli", *args], env=env, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, start_new_session=True)
    lines: queue.Queue[str] = queue.Queue()
    threading.Thread(target=lambda: [lines.put(x) for x in proc.stdout], daemon=True).start()  # type: ignore[union-attr]
    line = lines.get(timeout=120)
    assert "the study's page: http://127.0.0.1:" in line, line
    return proc, line.split()[3]


def session_processes(sid: int) -> list[int]:
    """Living processes of session ``sid`` (the study and everything it started)."""
    out = []
    for name in os.listdir("/proc"):
        if name.isdigit():
            try:
                fields = Path(f"/proc/{name}/stat").read_text().rsplit(")", 1)[1].split()
            except OSError:
                continue
            if int(fields[3]) == sid and fields[0] != "Z":
                out.append(int(name))
    return out


def kill_and_check(proc: subprocess.Popen) -> None:  # type: ignore[type-arg]
    """SIGKILL the study's process alone; within 5 s nothing it started runs (its workers, the page's server)."""
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait(timeout=10)
    t0 = time.monotonic()
    while session_processes(proc.pid) and time.monotonic() - t0 < 5:
        time.sleep(0.1)
    assert session_processes(proc.pid) == []


def wait_for_batch(page, n: int) -> None:  # type: ignore[no-untyped-def]
    page.wait_for_function(f"() => document.querySelector('[data-testid=status]').textContent.startsWith('Batch {n} ')",
                           timeout=600_000)
    page.wait_for_selector("[data-testid=card-A]")
    # the videos play: decoded frames and time moving (H.264 in Debian's Chromium)
    page.wait_for_function("() => [...document.querySelectorAll('video')].every(v => v.videoWidth > 0 && "
                           "v.currentTime > 0.1 && !v.paused)", timeout=60_000)


def test_rank_submit_kill_resume_in_chromium(tmp_path):
    from playwright.sync_api import sync_playwright

    d = tmp_path / "study"
    run, url = start("study", "run", str(d), "--robot", "exo", "--metric", "person", *TINY)
    with sync_playwright() as p:
        browser = p.chromium.launch_persistent_context(str(tmp_path / "chromium"), executable_path=CHROMIUM,
                                                       args=CHROMIUM_ARGS, headless=True,
                                                       viewport={"width": 1100, "height": 1000})
        try:
            page = browser.new_page()
            page.goto(url)
            wait_for_batch(page, 1)
            # B better than A, A labelled good; submit
            page.click("[data-testid=down-A]")
            page.check("[data-testid=label-A-good]")
            page.click("[data-testid=submit]")
            wait_for_batch(page, 2)
            assert "batch 1: B ≻ A (A: good)" in page.inner_text("[data-testid=answers]")
            page.screenshot(path=str(tmp_path / "page.png"), full_page=True)
            kill_and_check(run)  # `study run` killed while batch 2 waits
            page.wait_for_function("() => document.querySelector('[data-testid=status]').textContent"
                                   ".includes('not reachable')", timeout=15_000)
            serve, url = start("study", "serve", str(d), "--port", "0", "--quiet", "--override", "web.linger=2")
            page.goto(url)
            wait_for_batch(page, 2)  # the pending batch, the first answer kept
            assert "batch 1: B ≻ A (A: good)" in page.inner_text("[data-testid=answers]")
            kill_and_check(serve)  # `study serve` killed the same way
            serve, url = start("study", "serve", str(d), "--port", "0", "--quiet", "--override", "web.linger=2")
            page.goto(url)
            wait_for_batch(page, 2)
            # batch 2: both proposals certified (the second, L 0.22, T 0.8, W 0.28, h 0.08, on a period-4 orbit), both
            # shown; submitted as listed
            assert page.locator("input[data-testid^=tie-]").count() == 1
            assert page.locator("[data-testid^=up-]").count() == 2
            page.click("[data-testid=submit]")
            page.wait_for_function("() => document.querySelector('[data-testid=status]').textContent"
                                   ".startsWith('The study is complete')", timeout=600_000)
            assert page.is_visible("[data-testid=recommendation]")
            assert serve.wait(timeout=60) == 0
        finally:
            browser.close()
            for proc in (run,):
                if proc.poll() is None:
                    os.killpg(proc.pid, signal.SIGKILL)
    st = study_status(d)
    assert st["state"] == "complete" and st["trials_done"] == 4
    answers = st["person"]["answers"]
    assert [a["ranks"] for a in answers] == [[1, 0], [0, 1]] and answers[0]["labels"] == ["good", None]
    assert all(a["by"] == "person" for a in answers)
    if os.environ.get("ROBUSTGAIT_SCREENSHOT"):  # the docs' screenshot: ROBUSTGAIT_SCREENSHOT=docs/person_page.png
        shutil.copy(tmp_path / "page.png", os.environ["ROBUSTGAIT_SCREENSHOT"])
