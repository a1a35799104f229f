"""The page of a person study (docs/person.md): a small ASGI app (Starlette) served by uvicorn in a thread of the
study's own process, so that it lives and dies with the study — a SIGKILLed ``study run --metric person`` or ``study
serve`` leaves no server behind, and its evaluation workers die with it (``study/executors.py``).

Every URL starts with a random token (``/<token>/``): a request without it or with another gets 403. Routes below it:
``GET /`` the page; ``GET api/state`` what the page shows (the pending batch, earlier answers, the recommendation);
``GET video/<k>/<slot>.mp4`` a gait's looping video; ``POST api/answer`` the person's ranking of the pending batch —
checked (:mod:`robustgait.web.answers`), then stored in the study at once (:func:`robustgait.study.person.
record_answer`), or refused with one line on the page and in the log.
"""

from __future__ import annotations

import errno
import json
import logging
import math
import secrets
import socket
import sys
import threading
import time
from importlib import resources
from pathlib import Path
from typing import Any

from robustgait.config import RunConfig, WebConfig, radius_name
from robustgait.errors import RobustGaitError, input_error
from robustgait.sim.comfort import FIGURES
from robustgait.io.studyfile import load_config
from robustgait.study.person import (
    FLOOR_ATTR,
    AnswerError,
    answer_size,
    pending_iteration,
    recommendation,
    record_answer,
)
from robustgait.study.ranking import requirements
from robustgait.study.run import GAITS_DIR, completed_batches, gait_label, open_store
from robustgait.study.storage import TrialRecord
from robustgait.web.answers import parse_answer

LOG = logging.getLogger("robustgait.web")
VIDEO_FILE = "person.mp4"


def gait_names(n: int) -> list[str]:
    """How the page names a batch's gaits: A, B, C, …"""
    return [chr(ord("A") + i) if i < 26 else f"G{i + 1}" for i in range(n)]


def _finite(v: Any) -> Any:
    return None if isinstance(v, float) and not math.isfinite(v) else v


class PersonPage:
    """The state behind the page of one study directory, and the study's asker
    (:class:`robustgait.study.run.Asker`): :meth:`show` renders the pending batch's videos and shows it,
    :meth:`answered` says whether the page has stored its answer."""

    def __init__(self, directory: str | Path, token: str | None = None):
        self.directory = Path(directory)
        self.setup = load_config(self.directory)
        if self.setup.config.study.metric != "person":
            raise input_error(self.directory, f"study.metric is {self.setup.config.study.metric}: only a study with "
                              "--metric person is ranked on the page")
        self.space = self.setup.action_space()
        self.reqs = requirements(self.setup.config.study, self.space.names)
        self.token = token or secrets.token_urlsafe(18)
        self.store = open_store(self.directory, self.setup, self.space)
        self.lock = threading.Lock()  # the page's threads share one database connection
        self.answer_posted = threading.Event()
        self.final_seen = threading.Event()
        self.ready: int | None = None  # the pending iteration whose videos are rendered
        self.running = False  # a study runner in this process drives the study
        self.errors: list[str] = []
        self.video_errors: dict[tuple[int, int], str] = {}
        self._robot: Any = None

    # ---- the study's side --------------------------------------------------------------------------------
    def show(self, k: int) -> None:
        """Render the videos of iteration k's shown gaits, then show the batch on the page."""
        self.prepare(k)
        self.ready = k
        LOG.info("iteration %d waits for the person's answer", k + 1)

    def answered(self, k: int, timeout: float) -> bool:
        """Whether iteration k's answer is stored, waiting up to ``timeout`` s for the page to post one."""
        self.answer_posted.wait(timeout)
        self.answer_posted.clear()
        with self.lock:
            return "answer" in self.store.iterations().get(k, {})

    def prepare(self, k: int) -> None:
        """Render the videos of iteration k's shown gaits that are not rendered yet (a video that cannot be made: the
        gait is shown without one, and the page says why)."""
        with self.lock:
            rec = self.store.iterations().get(k, {})
            batch = completed_batches(self.store.records()).get(k, [])
        t0, rendered = time.perf_counter(), 0
        for r in batch:
            if r.slot not in rec.get("pending", {}).get("shown", []) or self.video_path(r.index).is_file():
                continue
            gait_file = (self._source(r).result or {}).get("gait_file")
            if gait_file is None:
                raise RobustGaitError(f"trial {r.number}: a shown gait without a gait file")
            try:
                self._render(r.index, gait_file)
                rendered += 1
            except Exception as exc:  # no offscreen GL, a gait that falls in the video's walk: shown without video
                self.video_errors[(k, r.slot)] = f"{type(exc).__name__}: {exc}"
                LOG.warning("iteration %d, gait %s: no video (%s)", k + 1, gait_names(r.slot + 1)[-1],
                            self.video_errors[(k, r.slot)])
        if rendered:
            LOG.info("iteration %d: %d videos rendered in %.1f s", k + 1, rendered, time.perf_counter() - t0)

    def render_ahead(self, index: int, result: dict[str, Any]) -> None:
        """Render the video of grid point ``index``, evaluated ahead of an answer and fit to be shown (``result``: its
        evaluation as the study stores it), so that the next batch shows it without waiting; a video that cannot be
        made is left to :meth:`prepare`, which tells the page why."""
        gait_file = result.get("gait_file")
        if gait_file is None or self.video_path(index).is_file():
            return
        try:
            self._render(index, gait_file)
        except Exception as exc:
            LOG.info("a gait evaluated ahead has no video yet (%s: %s)", type(exc).__name__, exc)

    def _render(self, index: int, gait_file: str) -> None:
        from robustgait.io.gaitfile import load_gait
        from robustgait.io.robotfile import load_robot
        from robustgait.web.media import render_person_video

        if self._robot is None:
            self._robot = load_robot(self.setup.robot)
        cfg = self.setup.config
        gait = load_gait(self.directory / gait_file, self._robot)
        render_person_video(self._robot, gait, self.video_path(index), cfg.person.video_steps, cfg.comfort, cfg.sim)

    def _source(self, r: TrialRecord) -> TrialRecord:
        if r.reused_from is None:
            return r
        with self.lock:
            return next(t for t in self.store.records() if t.number == r.reused_from)

    def video_path(self, index: int) -> Path:
        """Where the looping video of grid point ``index`` is rendered."""
        return self.directory / GAITS_DIR / gait_label(self.space, index) / VIDEO_FILE

    # ---- what the page shows -----------------------------------------------------------------------------
    def state(self) -> dict[str, Any]:
        cfg = self.setup.config
        with self.lock:
            records = self.store.records()
            iterations = self.store.iterations()
            floor = self.store.user_attrs().get(FLOOR_ATTR)
        batches = completed_batches(records)
        by_number = {r.number: r for r in records}
        k = pending_iteration(iterations)
        finished = [i for i in sorted(iterations) if "recommendation" in iterations[i]]
        complete = len(finished) == cfg.study.iterations
        phase = ("complete" if complete else "waiting" if k is not None and self.ready == k else
                 "preparing" if k is not None and self.running else "evaluating" if self.running else "stopped")
        blind = cfg.person.blind
        unit = cfg.study_certify.unit
        out: dict[str, Any] = {
            "study": self.directory.name, "robot": self.setup.robot, "phase": phase, "blind": blind,
            "labels": cfg.person.labels, "iterations": cfg.study.iterations, "iteration": k,
            "iterations_done": len(finished), "trials_done": sum(len(b) for b in batches.values()),
            "trials_planned": cfg.study.trials_planned, "certificate": radius_name(cfg.study_certify.space),
            "unit": unit, "floor": None if floor is None else {"value": floor["value"], "source": floor["source"]},
            "answers": self._answers(iterations, batches)}
        if phase == "waiting" and k is not None:
            out["batch"], out["hidden"] = self._batch(k, batches.get(k, []), iterations[k], blind)
        if complete or not blind:  # blind: only at the end
            value = -math.inf if floor is None else float(floor["value"])
            pick, note = recommendation(iterations, by_number, value, self.reqs)
            if pick is not None:
                out["recommendation"] = self._gait_view(pick, blind=False)
            if note:
                out["recommendation_note"] = note
        if complete:
            self.final_seen.set()
        return out

    def _gait_view(self, r: TrialRecord, *, blind: bool) -> dict[str, Any]:
        res = r.result or {}
        comfort = res.get("comfort") or {}
        view: dict[str, Any] = {"slot": r.slot, "iteration": r.iteration}
        if not blind:
            view["params"] = r.params
            view["r_star"] = res.get("r_star")
            view["figures"] = [{"name": n, "value": _finite(comfort.get(n)), "unit": FIGURES[n][0],
                                "what": FIGURES[n][1]} for n in self.setup.config.person.figures if n in FIGURES]
        return view

    def _batch(self, k: int, batch: list[TrialRecord], rec: dict[str, Any], blind: bool
               ) -> tuple[list[dict[str, Any]], list[dict[str, Any]]]:
        names = gait_names(len(batch))
        shown = rec["pending"]["shown"]
        cards = [{**self._gait_view(r, blind=blind), "name": names[r.slot],
                  "video": f"/{self.token}/video/{k}/{r.slot}.mp4" if self.video_path(r.index).is_file() else None,
                  "no_video": self.video_errors.get((k, r.slot))} for r in batch if r.slot in shown]
        hidden = [{"slot": int(s), "name": names[int(s)], "why": None if blind else why}
                  for s, why in rec["pending"]["hidden"].items()]
        return cards, hidden

    def _answers(self, iterations: dict[int, dict[str, Any]], batches: dict[int, list[TrialRecord]]
                 ) -> list[dict[str, Any]]:
        out = []
        for k in sorted(iterations):
            a = iterations[k].get("answer")
            if a is None:
                continue
            names = gait_names(len(a["ranks"]))
            tiers: dict[int, list[str]] = {}
            for s, rank in enumerate(a["ranks"]):
                if rank is not None:
                    tiers.setdefault(rank, []).append(names[s])
            out.append({"iteration": k, "by": a.get("by"), "tiers": [tiers[t] for t in sorted(tiers)],
                        "labels": {names[s]: lab for s, lab in enumerate(a.get("labels") or []) if lab},
                        "answered_at": a.get("answered_at"), "note": a.get("note")})
        return out

    # ---- answers -----------------------------------------------------------------------------------------
    def submit(self, payload: Any) -> dict[str, Any]:
        """Check and store a posted answer (:class:`AnswerError` with the HTTP status on a bad one)."""
        with self.lock:
            iterations = self.store.iterations()
        k = payload.get("iteration") if isinstance(payload, dict) else None
        if isinstance(k, int) and not isinstance(k, bool) and k not in iterations:
            raise AnswerError(f"iteration {k + 1} is unknown (the study has {len(iterations)} so far)", 409)
        size = answer_size(iterations.get(k, {})) if isinstance(k, int) else 0
        posted = parse_answer(payload, size)
        if posted.iteration == pending_iteration(iterations) and self.ready != posted.iteration:
            raise AnswerError(f"iteration {posted.iteration + 1} is not shown yet", 409)
        with self.lock:
            record_answer(self.store, posted.iteration, {"ranks": posted.ranks, "labels": posted.labels,
                                                         "by": "person"})
        self.answer_posted.set()
        LOG.info("iteration %d: answer stored", posted.iteration + 1)
        return {"ok": True, "iteration": posted.iteration}

    def close(self) -> None:
        with self.lock:
            self.store.close()

    # ---- the ASGI app ------------------------------------------------------------------------------------
    def app(self) -> Any:
        from starlette.applications import Starlette
        from starlette.requests import Request
        from starlette.responses import FileResponse, HTMLResponse, JSONResponse, PlainTextResponse, Response
        from starlette.routing import Route

        page = resources.files("robustgait.web").joinpath("page.html").read_text(encoding="utf-8")

        def refuse(request: Request) -> Response | None:
            if not secrets.compare_digest(request.path_params.get("token", ""), self.token):
                LOG.warning("refused %s %s: no or wrong token", request.method, request.url.path.split("/")[-1])
                return PlainTextResponse("403: this page needs the URL with its token, as the study printed it",
                                         status_code=403)
            return None

        def index(request: Request) -> Response:
            return refuse(request) or HTMLResponse(page.replace("{{TOKEN}}", self.token))

        def state(request: Request) -> Response:
            return refuse(request) or JSONResponse(self.state(), headers={"Cache-Control": "no-store"})

        def video(request: Request) -> Response:
            bad = refuse(request)
            if bad:
                return bad
            k, slot = int(request.path_params["k"]), int(request.path_params["slot"])
            with self.lock:
                rec = self.store.iterations().get(k, {})
                batch = completed_batches(self.store.records()).get(k, [])
            r = next((t for t in batch if t.slot == slot), None)
            shown = rec.get("pending", {}).get("shown", [])
            if r is None or slot not in shown or not self.video_path(r.index).is_file():
                return PlainTextResponse("404: no such video", status_code=404)
            return FileResponse(self.video_path(r.index), media_type="video/mp4")

        async def answer(request: Request) -> Response:
            bad = refuse(request)
            if bad:
                return bad
            try:
                payload = json.loads(await request.body())
            except (json.JSONDecodeError, UnicodeDecodeError):
                return self._error(AnswerError("the answer is not JSON"))
            try:
                from starlette.concurrency import run_in_threadpool

                return JSONResponse(await run_in_threadpool(self.submit, payload))
            except AnswerError as exc:
                return self._error(exc)

        async def other(request: Request) -> Response:
            return PlainTextResponse("403: this page needs the URL with its token, as the study printed it",
                                     status_code=403)

        return Starlette(routes=[
            Route("/{token}/", index), Route("/{token}/api/state", state),
            Route("/{token}/video/{k:int}/{slot:int}.mp4", video),
            Route("/{token}/api/answer", answer, methods=["POST"]),
            Route("/{path:path}", other, methods=["GET", "POST", "PUT", "DELETE", "HEAD"])])

    def _error(self, exc: AnswerError) -> Any:
        from starlette.responses import JSONResponse

        LOG.warning("answer refused: %s", exc)
        self.errors.append(str(exc))
        return JSONResponse({"error": str(exc)}, status_code=exc.status)


def bind(web: WebConfig) -> socket.socket:
    """The page's listening socket on ``web.host``:``web.port`` (0: any free port); a port in use or an address that
    cannot be bound is a one-line error (:class:`RobustGaitError`: exit 2), before a study is created or run."""
    family = socket.AF_INET6 if ":" in web.host else socket.AF_INET
    sock = socket.socket(family, socket.SOCK_STREAM)
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    try:
        sock.bind((web.host, web.port))
        sock.listen(16)
    except OSError as exc:
        sock.close()
        why = ("is in use (another study's page?): pick another with --port" if exc.errno == errno.EADDRINUSE
               else f"cannot be bound ({exc.strerror})")
        raise RobustGaitError(f"--port {web.port}: {web.host}:{web.port} {why}") from None
    except (socket.gaierror, UnicodeError) as exc:
        sock.close()
        raise RobustGaitError(f"--host {web.host}: not an address of this machine ({exc})") from None
    return sock


class PageServer:
    """uvicorn serving a :class:`PersonPage` in a daemon thread of this process, on a bound socket (:func:`bind`)."""

    def __init__(self, page: PersonPage, web: WebConfig, sock: socket.socket | None = None):
        import uvicorn

        self.page, self.web = page, web
        self.sock = sock if sock is not None else bind(web)
        self.port = self.sock.getsockname()[1]
        self.server = uvicorn.Server(uvicorn.Config(page.app(), log_level="warning", lifespan="off",
                                                    access_log=False))
        self.thread = threading.Thread(target=self.server.run, kwargs={"sockets": [self.sock]},
                                       name="robustgait-page", daemon=True)

    @property
    def url(self) -> str:
        host = f"[{self.web.host}]" if ":" in self.web.host else self.web.host
        return f"http://{host}:{self.port}/{self.page.token}/"

    def start(self) -> PageServer:
        self.thread.start()
        t0 = time.monotonic()
        while not self.server.started and self.thread.is_alive() and time.monotonic() - t0 < 10:
            time.sleep(0.02)
        if not self.server.started:
            raise RobustGaitError(f"the page's server did not start on {self.web.host}:{self.port}")
        return self

    def stop(self) -> None:
        self.server.should_exit = True
        self.thread.join(timeout=5)
        self.sock.close()


def log_to_stderr() -> None:
    """The page's log lines on stderr, ``robustgait: page: …``."""
    if not LOG.handlers:
        h = logging.StreamHandler(sys.stderr)
        h.setFormatter(logging.Formatter("robustgait: page: %(message)s"))
        LOG.addHandler(h)
        LOG.setLevel(logging.INFO)
        LOG.propagate = False


def serve_study(directory: str | Path, run: RunConfig, web: WebConfig, *, progress: bool = True,
                verbose: bool = False, announce: Any = print, sock: socket.socket | None = None) -> None:
    """Serve the page of the person study in ``directory`` and run (or resume) it to its budget, its batches waiting
    for the answers given on the page; a complete study: its page (answers, recommendation) until ``web.linger`` has
    passed after the page showed it, or Ctrl-C. ``announce`` gets the URL."""
    from robustgait.study.run import is_running, run_study

    d = Path(directory)
    page = PersonPage(d)
    if is_running(d):
        page.close()
        raise input_error(d, "the study is being run by another process, which serves its page")
    log_to_stderr()
    try:
        server = PageServer(page, web, sock)
    except RobustGaitError:
        page.close()
        raise
    try:
        server.start()
        announce(f"the study's page: {server.url}  (open it in a browser; Ctrl-C stops, `robustgait study serve "
                 f"{d}` comes back to the pending batch)")
        if web.host not in ("127.0.0.1", "localhost", "::1"):
            announce(f"warning: the page is served on {web.host}: anyone who can reach this machine and has the URL "
                     "can answer for the person (docs/person.md)")
        page.running = True
        try:
            run_study(d, run, progress=progress, verbose=verbose, asker=page)
        finally:
            page.running = False
        page.final_seen.wait(web.linger)
        if page.final_seen.is_set():
            time.sleep(min(web.linger, 2.0))  # the page's next poll finds the server still up
    finally:
        server.stop()
        page.close()
