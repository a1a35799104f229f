"""The study report (``robustgait study report DIR``): how long a user waits for it, where its seconds go, and what
the video's render settings cost. Three measurements in one run, on one study directory:

1. **The command** as a user runs it (a fresh interpreter: imports, the figures, the video, the page), with this
   checkout's ``src`` and, with ``--before SRC``, another checkout's ``src`` (e.g. a ``git worktree`` of the commit
   before a change) first on ``PYTHONPATH``, interleaved ``--repeat`` times: median (range) wall seconds of each and
   after / before. Both write ``DIR/report/``.
2. **Phase by phase**, this checkout in process, with the configuration's defaults
   (:class:`robustgait.config.ReportConfig`), then with the video settings before them (:data:`OLD_VIDEO`: 8 steps,
   480 × 360, 30 fps, shadows and reflections, the model's multisampling): the public functions the report is made
   of, each called alone in the report's order — the study's status, the recommended gaits' verification
   (``verify_recommended``), the three figures (``plot_history``, ``plot_explored``, ``plot_posterior``), the walk
   for the video, its frames (ms each: ``robustgait.sim.walk.video_frames``) and their encoding (``write_video``) —
   then ``write_study_report`` without its video; its seconds less the status's and the three figures' are "the
   rest" (the certificate figure, the person, comfort, Pareto and validation parts, the page; the verification is
   done by then), and the report's total is its seconds without the video plus the video's parts. Nothing in the
   package is wrapped or replaced. Both come after a warm-up (the report without its video: the imports made
   inside the report's functions, which ``robustgait demo`` has made by its report), timed too.
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
import os
import statistics
import subprocess
import sys
import tempfile
import time
from collections import defaultdict
from collections.abc import Callable
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


def timed(seconds: dict[str, float], phase: str, fn: Callable[..., Any], *args: Any, **kwargs: Any) -> Any:
    """``fn(*args, **kwargs)``, its wall seconds added to ``seconds[phase]``."""
    t0 = time.perf_counter()
    try:
        return fn(*args, **kwargs)
    finally:
        seconds[phase] += time.perf_counter() - t0


def phases(directory: Path, config: ReportConfig, label: str) -> None:
    """Measurement 2: this checkout's report, phase by phase, with ``config``: each public function the report is
    made of, called alone in the report's order, then the report without its video; its seconds less the status's
    and the figures' are "the rest" (the verification is done by then). Nothing in the package is wrapped or
    replaced."""
    from robustgait.report.study import (
        plot_explored,
        plot_history,
        plot_posterior,
        verify_recommended,
        write_study_report,
    )
    from robustgait.study.status import study_status

    seconds: dict[str, float] = defaultdict(float)
    frames = 0
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp)
        status = timed(seconds, "status", study_status, directory)
        if timed(seconds, "verification", verify_recommended, directory, status, config.pareto_figure):
            status = timed(seconds, "status", study_status, directory)
        timed(seconds, "plot_history", plot_history, status, out / "history.png")
        timed(seconds, "plot_explored", plot_explored, status, out / "explored.png")
        if status["best"] is not None:
            timed(seconds, "plot_posterior", plot_posterior, directory, status, config.axes, out / "posterior.png")
        if config.video and status["best"] is not None and status["best"].get("gait_file"):
            from robustgait.io.gaitfile import load_gait
            from robustgait.io.robotfile import load_robot
            from robustgait.sim.walk import video_frames, walk, write_video

            robot = load_robot(status["robot"])
            gait = load_gait(directory / status["best"]["gait_file"], robot)
            w = timed(seconds, "walk for the video", walk, robot, gait, steps=config.video_steps,
                      keep_trajectory=True)
            images = timed(seconds, "frames", lambda: list(video_frames(
                robot, w.trajectory, fps=config.video_fps, width=config.video_width, height=config.video_height,
                shadows=config.video_shadows, antialias=config.video_antialias)))
            frames = timed(seconds, "encoding", write_video, images, out / "best.mp4", config.video_fps)
    t0 = time.perf_counter()
    write_study_report(directory, replace(config, video=False))
    without = time.perf_counter() - t0
    video = sum(seconds[k] for k in ("walk for the video", "frames", "encoding"))
    rest = without - sum(v for k, v in seconds.items() if k in ("status", "plot_history", "plot_explored",
                                                                "plot_posterior"))
    c = config
    print(f"2. write_study_report in process, {label} (video {c.video_steps} steps, {c.video_width} × "
          f"{c.video_height}, {c.video_fps} fps, shadows {c.video_shadows}, antialias {c.video_antialias}): "
          f"{without + video:.2f} s = the report without its video {without:.2f} s + the video's parts "
          f"{video:.2f} s; its public parts alone, in its order:")
    for name, v in [*seconds.items(), ("the rest", rest)]:
        each = f", {1e3 * v / frames:.1f} ms each ({frames} frames)" if name == "frames" and frames else ""
        print(f"  {name:<22} {v:6.2f} s{each}")


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
