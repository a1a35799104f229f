"""The study report (``robustgait study report DIR``): how long a user waits for it, where its seconds go, and what
the video's render settings cost. Three measurements in one run, on one study directory:

1. **The command** as a user runs it (a fresh interpreter: imports, the figures, the video, the page), with this
   checkout's ``src`` and, with ``--before SRC``, another checkout's ``src`` (e.g. a ``git worktree`` of the commit
   before a change) first on ``PYTHONPATH``, interleaved ``--repeat`` times: median (range) wall seconds of each and
   after / before. Both write ``DIR/report/``.
2. **Phase by phase**, this checkout in process, with the configuration's defaults
   (:class:`robustgait.config.ReportConfig`), then with the video settings before them (:data:`OLD_VIDEO`: 8 steps,
   480 × 360, 30 fps, shadows and reflections, the model's multisampling): the study's status, the recommended
   gaits' verification, each figure, the comfort, Pareto and validation parts, the walk for the video, its frames
   (ms each: ``robustgait.sim.walk.video_frames``), their encoding (``write_video`` less the frames drawn inside
   it); the rest of ``write_study_report`` is "other". The report's functions are wrapped with timers; nothing is
   copied from the package. Both come after a warm-up (the report without its video: the imports made inside the
   report's functions, which ``robustgait demo`` has made by its report), timed too.
3. **The video's frames alone** (``video_frames``) on the walks the report renders (the best gait), with
   :data:`OLD_VIDEO` and the configuration's settings, interleaved ``--repeat`` times: frames, median ms a frame,
   and the ratio of the two's seconds per video; and their encoding (this checkout's encoder for both).

A study directory: ``robustgait demo --dir /tmp/demo`` (about 5 min on 2 cores; the demo's report is then the one
measured). ``MUJOCO_GL`` as for the package (``egl`` unless set).

    python benchmarks/perf/report.py DIR [--before /path/to/old/checkout/src] [--repeat 3]
"""

from __future__ import annotations

import argparse
import datetime
import functools
import importlib
import os
import statistics
import subprocess
import sys
import tempfile
import time
from collections import defaultdict
from collections.abc import Callable, Iterator
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # benchmarks/common.py
from common import REPO, git_commit, load_average

if TYPE_CHECKING:
    from robustgait.config import ReportConfig

OLD_VIDEO: dict[str, Any] = {"video_steps": 8, "video_fps": 30, "video_width": 480, "video_height": 360,
                             "video_shadows": True, "video_antialias": True}
"""The report's video settings before the fast rendering (its hard-coded values then), as :class:`ReportConfig`
fields."""

REPORT_CODE = ("import sys; from robustgait.report.study import write_study_report; "
               "write_study_report(sys.argv[1])")


def command_seconds(directory: Path, src: Path) -> float:
    """Wall seconds of the study report in a fresh interpreter with ``src`` first on ``PYTHONPATH`` (NaN if it
    failed; its error is printed)."""
    env = {**os.environ, "PYTHONPATH": str(src), "MUJOCO_GL": os.environ.get("MUJOCO_GL", "egl")}
    t0 = time.perf_counter()
    p = subprocess.run([sys.executable, "-c", REPORT_CODE, str(directory)], env=env, capture_output=True, text=True)
    if p.returncode != 0:
        print(f"  failed with {src}: {p.stderr.strip().splitlines()[-1:]}")
        return float("nan")
    return time.perf_counter() - t0


def median_range(values: list[float]) -> str:
    return f"{statistics.median(values):6.2f} s ({min(values):.2f}–{max(values):.2f})"


def commands(directory: Path, before: Path | None, repeat: int) -> None:
    """Measurement 1: the report in fresh interpreters, after (and before) interleaved."""
    sides = {"after": REPO / "src"} | ({"before": before} if before else {})
    times: dict[str, list[float]] = defaultdict(list)
    for _ in range(repeat):
        for side, src in sides.items():
            times[side].append(command_seconds(directory, src))
    print("1. write_study_report in a fresh interpreter (imports, figures, video, page):")
    for side, src in sides.items():
        print(f"  {side:<7} {median_range(times[side])}  [{git_commit(src)} {src}]")
    if before:
        print(f"  after / before: {statistics.median(times['after']) / statistics.median(times['before']):.2f}")


class Phases:
    """Timers wrapped around module attributes: seconds and calls per phase, nested phases subtracted from the
    phase that called them (``exclusive``)."""

    def __init__(self) -> None:
        self.seconds: dict[str, float] = defaultdict(float)
        self.calls: dict[str, int] = defaultdict(int)
        self._stack: list[float] = []  # the time spent in nested phases, per open phase
        self._undo: list[tuple[object, str, object]] = []

    def wrap(self, module: object, name: str, phase: str | None = None) -> None:
        """Time ``module.name`` as ``phase`` (default: ``name``); a missing attribute is skipped."""
        fn = getattr(module, name, None)
        if fn is None:
            return
        self._undo.append((module, name, fn))
        setattr(module, name, self._timed(fn, phase or name))

    def _timed(self, fn: Callable[..., Any], phase: str) -> Callable[..., Any]:
        @functools.wraps(fn)
        def timed(*args: Any, **kwargs: Any) -> Any:
            self._stack.append(0.0)
            t0 = time.perf_counter()
            try:
                return fn(*args, **kwargs)
            finally:
                self.add(phase, time.perf_counter() - t0)
        return timed

    def add(self, phase: str, total: float) -> None:
        """Book ``total`` seconds (its nested phases' included) to ``phase``, exclusive of them."""
        nested = self._stack.pop()
        self.seconds[phase] += total - nested
        self.calls[phase] += 1
        if self._stack:
            self._stack[-1] += total

    def frames(self, gen: Iterator[Any]) -> Iterator[Any]:
        """``gen`` with each frame's drawing booked to the phase ``frames``."""
        while True:
            self._stack.append(0.0)
            t0 = time.perf_counter()
            try:
                frame = next(gen)
            except StopIteration:
                self.add("frames", time.perf_counter() - t0)
                self.calls["frames"] -= 1
                return
            self.add("frames", time.perf_counter() - t0)
            yield frame

    def undo(self) -> None:
        for module, name, fn in reversed(self._undo):
            setattr(module, name, fn)


def phases(directory: Path, config: ReportConfig, label: str) -> None:
    """Measurement 2: this checkout's report, phase by phase, with ``config``."""
    import robustgait.report.study as rs
    import robustgait.sim as sim
    import robustgait.study.status as st

    sw: Any = importlib.import_module("robustgait.sim.walk")  # the module (robustgait.sim's ``walk`` is a function)

    ph = Phases()
    for name in ("plot_history", "plot_explored", "plot_posterior", "plot_certificate", "person_parts",
                 "_comfort_parts", "pareto_parts", "_validation_parts", "verify_recommended", "_page"):
        ph.wrap(rs, name)
    ph.wrap(st, "study_status")
    ph.wrap(sim, "walk", "walk for the video")
    ph.wrap(sw, "write_video", "encoding")
    frames = sw.video_frames
    sw.video_frames = lambda *a, **k: ph.frames(frames(*a, **k))
    ph.wrap(rs, "write_study_report", "other")
    try:
        t0 = time.perf_counter()
        rs.write_study_report(directory, config)
        total = time.perf_counter() - t0
    finally:
        sw.video_frames = frames
        ph.undo()
    c = config
    print(f"2. write_study_report in process, phase by phase, {label} (video {c.video_steps} steps, {c.video_width} "
          f"× {c.video_height}, {c.video_fps} fps, shadows {c.video_shadows}, antialias {c.video_antialias}): "
          f"{total:.2f} s")
    for name, s in sorted(ph.seconds.items(), key=lambda kv: -kv[1]):
        each = f", {1e3 * s / ph.calls[name]:.1f} ms each" if name == "frames" else ""
        print(f"  {name:<22} {s:6.2f} s  ({ph.calls[name]} calls{each})")


def frames_alone(directory: Path, repeat: int) -> None:
    """Measurement 3: the video's frames with the old and the new settings, on the same walk, interleaved."""
    from robustgait.config import ReportConfig
    from robustgait.io.gaitfile import load_gait
    from robustgait.io.robotfile import load_robot
    from robustgait.sim.walk import video_frames, walk, write_video
    from robustgait.study.status import study_status

    status = study_status(directory)
    robot = load_robot(status["robot"])
    gait = load_gait(directory / status["best"]["gait_file"], robot)
    settings = {"old": replace(ReportConfig(), **OLD_VIDEO), "new": ReportConfig()}
    walks = {}
    for k, c in settings.items():
        trajectory = walk(robot, gait, steps=c.video_steps, keep_trajectory=True).trajectory
        assert trajectory is not None
        walks[k] = trajectory
    draw: dict[str, list[float]] = defaultdict(list)
    encode: dict[str, list[float]] = defaultdict(list)
    count: dict[str, int] = {}
    with tempfile.TemporaryDirectory() as tmp:
        for _ in range(repeat):
            for k, c in settings.items():
                t0 = time.perf_counter()
                images = list(video_frames(robot, walks[k], fps=c.video_fps, width=c.video_width,
                                           height=c.video_height, shadows=c.video_shadows,
                                           antialias=c.video_antialias))
                t1 = time.perf_counter()
                count[k] = write_video(images, Path(tmp) / f"{k}.mp4", c.video_fps)
                draw[k].append((t1 - t0) / count[k])
                encode[k].append(time.perf_counter() - t1)
    print("3. the video's frames alone (video_frames, the renderer's making included), interleaved:")
    for k, c in settings.items():
        print(f"  {k}: {c.video_steps} steps, {c.video_width} × {c.video_height}, {c.video_fps} fps, shadows "
              f"{c.video_shadows}, antialias {c.video_antialias}: {count[k]} frames, "
              f"{1e3 * statistics.median(draw[k]):.1f} ms a frame ({', '.join(f'{1e3 * v:.0f}' for v in draw[k])}), "
              f"{count[k] * statistics.median(draw[k]):.2f} s; encoding {statistics.median(encode[k]):.2f} s")
    per_frame = statistics.median(draw["new"]) / statistics.median(draw["old"])
    per_video = count["new"] * statistics.median(draw["new"]) / (count["old"] * statistics.median(draw["old"]))
    print(f"  new / old: {per_frame:.3f} a frame, {per_video:.3f} a video's frames")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("dir", type=Path, help="a study directory with at least one evaluated gait")
    ap.add_argument("--before", type=Path, help="another checkout's src directory, timed on the same study")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--skip", default="", help="comma-separated measurements to skip: 1, 2, 3")
    args = ap.parse_args()
    os.environ.setdefault("MUJOCO_GL", "egl")
    from robustgait.config import ReportConfig

    skip = set(args.skip.split(","))
    print(f"benchmarks/perf/report.py {args.dir}: {datetime.datetime.now():%Y-%m-%d %H:%M}, commit "
          f"{git_commit()}, MUJOCO_GL={os.environ['MUJOCO_GL']}, {load_average()}")
    if "1" not in skip:
        commands(args.dir, args.before, args.repeat)
    if "2" not in skip:
        from robustgait.report.study import write_study_report

        t0 = time.perf_counter()
        write_study_report(args.dir, replace(ReportConfig(), video=False))  # the imports inside, as in `demo`
        print(f"2. warm-up: write_study_report without its video, in process, first: {time.perf_counter() - t0:.2f} s")
        phases(args.dir, ReportConfig(), "the configuration's defaults")
        phases(args.dir, replace(ReportConfig(), **OLD_VIDEO), "the video settings before")
    if "3" not in skip:
        frames_alone(args.dir, args.repeat)
    print(f"done: {datetime.datetime.now():%H:%M}, {load_average()}")


if __name__ == "__main__":
    main()
