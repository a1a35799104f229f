"""The page of a person study (docs/person.md): a small ASGI app (Starlette) served by uvicorn in a thread of the
study's own process, so that it lives and dies with the study — a SIGKILLed ``study run --metric person`` or ``study
serve`` leaves no server behind, and its evaluation workers die with it (``study/executors.py``).

Every URL starts with a random token (``/<token>/``): a request without it or with another gets 403. Routes below it:
``GET /`` the page; ``GET api/state`` what the page shows (the pending batch, earlier answers, the recommendation);
``GET video/<k>/<slot>.mp4`` a gait's looping video; ``POST api/answer`` the person's ranking of the pending batch —
checked (:mod:`robustgait.web.answers`), then stored in the study at once (:func:`robustgait.study.person.
record_answer`), or refused with one line on the page and in the log.

Its parts: :class:`PersonPage` (the study's asker, coordinating the others), :mod:`robustgait.web.records` (the
store behind one lock), :mod:`robustgait.web.media` (the videos), :mod:`robustgait.web.view` (the state's JSON),
:mod:`robustgait.web.answers` (checking and storing answers), :mod:`robustgait.web.routes` (the ASGI app); here also
:func:`bind`, :class:`PageServer` and :func:`serve_study`.
"""

from __future__ import annotations

import errno
import logging
import secrets
import socket
import sys
import threading
import time
from pathlib import Path
from typing import Any

from robustgait.config import RunConfig, WebConfig
from robustgait.errors import RobustGaitError, input_error
from robustgait.io.studyfile import load_config
from robustgait.study.ranking import requirements
from robustgait.study.run import open_store
from robustgait.study.storage import TrialRecord
from robustgait.web.answers import store_answer
from robustgait.web.media import VIDEO_FILE as VIDEO_FILE
from robustgait.web.media import GaitVideos
from robustgait.web.records import StudyRecords
from robustgait.web.view import gait_names as gait_names
from robustgait.web.view import page_state, video_url

LOG = logging.getLogger("robustgait.web")


class PersonPage:
    """The state behind the page of one study directory, and the study's asker
    (:class:`robustgait.study.policies.Asker`): :meth:`show` renders the pending batch's videos and shows it,
    :meth:`answered` says whether the page has stored its answer. A coordinator: the videos are
    :class:`~robustgait.web.media.GaitVideos`', the state it shows is :func:`~robustgait.web.view.page_state`'s, the
    answers are stored by :func:`~robustgait.web.answers.store_answer`, the routes are
    :mod:`robustgait.web.routes`'.

    Made for a study whose ``study.metric`` is ``person`` (else a one-line input error); it opens the study's store
    until :meth:`close`. What callers set or read: ``ready`` (the pending iteration whose videos are rendered, None:
    none), ``running`` (a study runner in this process drives the study), ``setup`` (read anew by every state and
    render), ``errors`` (the refused answers' lines), ``final_seen`` (set once the page was served a complete study's
    state), ``answer_posted`` (set by each stored answer), ``video_errors`` (``(iteration, slot) -> why`` a shown gait
    has no video)."""

    def __init__(self, directory: str | Path, token: str | None = None):
        self.directory = Path(directory)
        self.setup = load_config(self.directory)
        if self.setup.config.study.metric != "person":
            raise input_error(self.directory, f"study.metric is {self.setup.config.study.metric}: only a study with "
                              "--metric person is ranked on the page")
        self.space = self.setup.action_space()
        self.reqs = requirements(self.setup.config.study, self.space.names)
        self.token = token or secrets.token_urlsafe(18)
        self.records = StudyRecords(open_store(self.directory, self.setup, self.space))
        self.answer_posted = threading.Event()
        self.final_seen = threading.Event()
        self.ready: int | None = None  # the pending iteration whose videos are rendered
        self.running = False  # a study runner in this process drives the study
        self.errors: list[str] = []
        self.videos = GaitVideos(self.directory, self.space, self.records)
        self.video_errors = self.videos.errors

    # ---- the study's side: the asker ---------------------------------------------------------------------
    def show(self, k: int) -> None:
        """Render the videos of iteration k's shown gaits, then show the batch on the page."""
        self.prepare(k)
        self.ready = k
        LOG.info("iteration %d waits for the person's answer", k + 1)

    def answered(self, k: int, timeout: float) -> bool:
        """Whether iteration k's answer is stored, waiting up to ``timeout`` s for the page to post one."""
        self.answer_posted.wait(timeout)
        self.answer_posted.clear()
        return "answer" in self.records.iterations().get(k, {})

    def prepare(self, k: int) -> None:
        """Render the videos of iteration k's shown gaits that are not rendered yet (a video that cannot be made: the
        gait is shown without one, and the page says why); :meth:`GaitVideos.prepare
        <robustgait.web.media.GaitVideos.prepare>`."""
        self.videos.prepare(k, self.setup)

    def render_ahead(self, index: int, result: dict[str, Any]) -> None:
        """Render the video of grid point ``index``, evaluated ahead of an answer and fit to be shown (``result``: its
        evaluation as the study stores it), so that the next batch shows it without waiting; a video that cannot be
        made is left to :meth:`prepare`, which tells the page why."""
        self.videos.render_ahead(index, result, self.setup)

    def video_path(self, index: int) -> Path:
        """Where the looping video of grid point ``index`` is rendered."""
        return self.videos.path(index)

    # ---- the page's side ---------------------------------------------------------------------------------
    def state(self) -> dict[str, Any]:
        """What the page shows (:func:`robustgait.web.view.page_state`); sets ``final_seen`` for a complete study."""
        out = page_state(self.setup, self.records.snapshot(), study=self.directory.name, reqs=self.reqs,
                         ready=self.ready, running=self.running, video_url=self._video_url,
                         video_errors=self.video_errors)
        if out["phase"] == "complete":
            self.final_seen.set()
        return out

    def _video_url(self, k: int, r: TrialRecord) -> str | None:
        return video_url(self.token, k, r.slot) if self.videos.path(r.index).is_file() else None

    def shown_video(self, k: int, slot: int) -> Path | None:
        """The video file of iteration k's gait in ``slot`` when the page shows it, else None."""
        return self.videos.shown(k, slot)

    def submit(self, payload: Any) -> dict[str, Any]:
        """Check and store a posted answer (:class:`AnswerError` with the HTTP status on a bad one;
        :func:`robustgait.web.answers.store_answer`): ``{"ok": True, "iteration": k}``."""
        posted = store_answer(self.records, payload, lambda: self.ready)
        self.answer_posted.set()
        LOG.info("iteration %d: answer stored", posted.iteration + 1)
        return {"ok": True, "iteration": posted.iteration}

    def close(self) -> None:
        """Close the study's store."""
        self.records.close()

    def app(self) -> Any:
        """The ASGI app serving this page (:func:`robustgait.web.routes.page_app`)."""
        from robustgait.web.routes import page_app

        return page_app(self)


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
