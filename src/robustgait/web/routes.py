"""The page's HTTP routes (docs/person.md): a Starlette app over a :class:`Page`, every route below the page's token.

``GET /<token>/`` the page (``page.html``, its ``{{TOKEN}}`` replaced); ``GET /<token>/api/state`` the page's state
as JSON (``Cache-Control: no-store``); ``GET /<token>/video/<k>/<slot>.mp4`` (:func:`robustgait.web.view.video_url`)
a shown gait's video (Range requests answered: browsers loop and seek videos), 404 for any other; ``POST
/<token>/api/answer`` the person's ranking: 200 ``{"ok": true, "iteration": k}``, or ``{"error": "<one line>"}``
with the refusal's status (400 not JSON or malformed, 409 stale, unknown or answered already), the line also logged
and kept in ``page.errors``. A request without the token, with another, or for any other path (GET, POST, PUT,
DELETE, HEAD): 403 in plain text."""

from __future__ import annotations

import json
import logging
import secrets
from importlib import resources
from pathlib import Path
from typing import Any, Protocol

from starlette.applications import Starlette
from starlette.concurrency import run_in_threadpool
from starlette.requests import Request
from starlette.responses import FileResponse, HTMLResponse, JSONResponse, PlainTextResponse, Response
from starlette.routing import Route

from robustgait.study.person import AnswerError

LOG = logging.getLogger("robustgait.web")
DENIED = "403: this page needs the URL with its token, as the study printed it"


class Page(Protocol):
    """What the routes serve: the page's ``token``, the refusals' lines so far (``errors``, appended to), its state,
    its shown videos and the answers it stores."""

    token: str
    errors: list[str]

    def state(self) -> dict[str, Any]:
        """The JSON the page shows (:func:`robustgait.web.view.page_state`)."""
        ...

    def shown_video(self, k: int, slot: int) -> Path | None:
        """The video file of iteration k's gait in ``slot`` when the page shows it, else None."""
        ...

    def submit(self, payload: Any) -> dict[str, Any]:
        """Store a posted answer; :class:`AnswerError` (with its HTTP status) when it cannot be."""
        ...


class PageRoutes:
    """The route handlers of one :class:`Page` (its ``page.html`` read once, when made); :meth:`app` the ASGI app.
    The synchronous handlers run in Starlette's thread pool, the asynchronous ones on the server's event loop."""

    def __init__(self, page: Page):
        self.page = page
        self.html = resources.files("robustgait.web").joinpath("page.html").read_text(encoding="utf-8")

    def app(self) -> Starlette:
        """The Starlette app: the routes of the module docstring, the catch-all last."""
        return Starlette(routes=[
            Route("/{token}/", self.index), Route("/{token}/api/state", self.state),
            Route("/{token}/video/{k:int}/{slot:int}.mp4", self.video),
            Route("/{token}/api/answer", self.answer, methods=["POST"]),
            Route("/{path:path}", self.other, methods=["GET", "POST", "PUT", "DELETE", "HEAD"])])

    def refuse(self, request: Request) -> Response | None:
        """403 (logged) when the request's token is missing or not the page's, else None."""
        if not secrets.compare_digest(request.path_params.get("token", ""), self.page.token):
            LOG.warning("refused %s %s: no or wrong token", request.method, request.url.path.split("/")[-1])
            return PlainTextResponse(DENIED, status_code=403)
        return None

    def index(self, request: Request) -> Response:
        """The page's HTML, with its token."""
        return self.refuse(request) or HTMLResponse(self.html.replace("{{TOKEN}}", self.page.token))

    def state(self, request: Request) -> Response:
        """The page's state, never cached."""
        return self.refuse(request) or JSONResponse(self.page.state(), headers={"Cache-Control": "no-store"})

    def video(self, request: Request) -> Response:
        """A shown gait's video file; 404 for a trial the batch does not have, a hidden gait or no video."""
        bad = self.refuse(request)
        if bad:
            return bad
        path = self.page.shown_video(int(request.path_params["k"]), int(request.path_params["slot"]))
        if path is None:
            return PlainTextResponse("404: no such video", status_code=404)
        return FileResponse(path, media_type="video/mp4")

    async def answer(self, request: Request) -> Response:
        """Store the posted answer (in the thread pool: the store blocks), or refuse it (:meth:`error`)."""
        bad = self.refuse(request)
        if bad:
            return bad
        try:
            payload = json.loads(await request.body())
        except (json.JSONDecodeError, UnicodeDecodeError):
            return self.error(AnswerError("the answer is not JSON"))
        try:
            return JSONResponse(await run_in_threadpool(self.page.submit, payload))
        except AnswerError as exc:
            return self.error(exc)

    async def other(self, request: Request) -> Response:
        """Any other path: 403."""
        return PlainTextResponse(DENIED, status_code=403)

    def error(self, exc: AnswerError) -> Response:
        """A refused answer: logged, kept in ``page.errors``, ``{"error": line}`` with the refusal's status."""
        LOG.warning("answer refused: %s", exc)
        self.page.errors.append(str(exc))
        return JSONResponse({"error": str(exc)}, status_code=exc.status)


def page_app(page: Page) -> Starlette:
    """The ASGI app serving ``page`` (:class:`PageRoutes`)."""
    return PageRoutes(page).app()
