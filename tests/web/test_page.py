"""The page of a person study (robustgait.web, docs/person.md), fast: a real server on a free port of 127.0.0.1 in
this process, over a study whose first batch waits for an answer — its trials stored as a run would store them (the
evaluations written as data: the page reads records, it does not evaluate). Every fault case: no or a
wrong token (403), an answer for a stale or unknown batch, a ranking that omits or repeats a gait or ranks a hidden
one, a double submit (409, stored once), a port in use (one line, exit 2)."""

from __future__ import annotations

import json
import os
import shutil
import socket
import subprocess
import sys
import urllib.error
import urllib.request
from pathlib import Path

import pytest

from robustgait.config import Config, PersonConfig, StudyConfig, WebConfig
from robustgait.errors import RobustGaitError
from robustgait.io.studyfile import load_config
from robustgait.study.person import FLOOR_ATTR, pending_record, record_answer
from robustgait.study.ranking import requirements
from robustgait.study.run import completed_batches, create_study, gait_label, open_store
from robustgait.web.answers import parse_answer
from robustgait.web.server import PageServer, PersonPage

REPO = Path(__file__).resolve().parents[2]
COMFORT = {"speed": 0.2, "cadence": 86.0, "pelvis_acc_vertical_rms": 1.4, "pelvis_acc_lateral_rms": 1.3,
           "impact_force_ratio": 5.5, "cost_of_transport": 0.24}


def result(value: float, status: str = "certified") -> dict:  # type: ignore[type-arg]
    return {"status": status, "reason": "", "steps_taken": 50, "step_cap": 50, "fell": False, "fall_reason": None,
            "mean_speed": 0.2, "value": value if status == "certified" else None, "estimate": value,
            "verified": status == "certified", "comfort": COMFORT, "gait_file": None,
            "certificate_file": None, "seconds": {}}


def pending_study(d: Path, r_stars: tuple[float, ...] = (20.0, 15.0, 5.0), floor: float = 10.0) -> Path:
    """A person study (batch 3, floor 10 N s) whose iteration 0 is evaluated and waits for the person: gaits A and B
    are certified above the floor, C below it."""
    cfg = Config(study=StudyConfig(metric="person", iterations=2, batch=len(r_stars)), person=PersonConfig(floor=floor))
    create_study(d, "exo", cfg)
    setup = load_config(d)
    space = setup.action_space()
    store = open_store(d, setup, space)
    try:
        proposals = [3, 100, 500][: len(r_stars)]
        store.set_iteration(0, {"proposals": proposals})
        for slot, index in enumerate(proposals):
            store.enqueue(0, slot, index)
        for r in r_stars:
            t = store.start()
            assert t is not None
            store.complete(t.number, result(r), 50 + r, {})
        store.study.set_user_attr(FLOOR_ATTR, {"value": floor, "source": "person.floor"})
        batch = completed_batches(store.records())[0]
        rec = dict(store.iterations()[0])
        rec["pending"] = pending_record(batch, floor, requirements(setup.config.study, space.names), "N s")
        store.set_iteration(0, rec)
    finally:
        store.close()
    return d


@pytest.fixture(scope="module")
def template(tmp_path_factory):  # type: ignore[no-untyped-def]
    return pending_study(tmp_path_factory.mktemp("template") / "study")


@pytest.fixture
def served(tmp_path, template):  # type: ignore[no-untyped-def]
    """A copy of the pending study (its own database), served on a free port."""
    page = PersonPage(shutil.copytree(template, tmp_path / "study"))
    page.ready = 0  # the videos of batch 0 are "rendered": the page shows it
    server = PageServer(page, WebConfig(port=0)).start()
    yield page, server
    server.stop()
    page.close()


def call(url: str, body: object | None = None) -> tuple[int, dict | str]:  # type: ignore[type-arg]
    data = None if body is None else json.dumps(body).encode()
    req = urllib.request.Request(url, data=data, headers={"Content-Type": "application/json"},
                                 method="GET" if body is None else "POST")
    try:
        with urllib.request.urlopen(req, timeout=10) as r:
            text = r.read().decode()
            status = r.status
    except urllib.error.HTTPError as exc:
        text, status = exc.read().decode(), exc.code
    try:
        return status, json.loads(text)
    except json.JSONDecodeError:
        return status, text


def stored_answers(d: Path) -> dict:  # type: ignore[type-arg]
    setup = load_config(d)
    store = open_store(d, setup, setup.action_space())
    try:
        return {k: v["answer"] for k, v in store.iterations().items() if "answer" in v}
    finally:
        store.close()


def test_the_page_needs_its_token(served):
    page, server = served
    base = f"http://127.0.0.1:{server.port}"
    assert call(server.url)[0] == 200
    assert call(server.url + "api/state")[0] == 200
    for url in (base + "/", base + "/api/state", base + "/not-the-token/api/state", base + "/not-the-token/",
                f"{base}/{page.token}x/api/state"):
        status, text = call(url)
        assert status == 403, url
        assert "token" in str(text)
    assert call(base + "/wrong/api/answer", {"iteration": 0, "ranking": [[0], [1]]})[0] == 403
    assert stored_answers(page.directory) == {}


def test_the_pending_batch_shows_only_gaits_above_the_floor(served):
    page, server = served
    status, st = call(server.url + "api/state")
    assert status == 200 and st["phase"] == "waiting" and st["iteration"] == 0
    assert [g["name"] for g in st["batch"]] == ["A", "B"]  # C (J* 5 < floor 10) is not shown
    assert st["hidden"] == [{"slot": 2, "name": "C", "why": "certified 5 N s, below the floor 10 N s"}]
    assert st["batch"][0]["value"] == 20.0 and st["batch"][0]["verified"]
    assert st["batch"][0]["figures"][0]["name"] == "speed"
    assert st["batch"][0]["video"] is None  # not rendered (the fixture renders none)
    video = page.directory / "gaits" / gait_label(page.space, 3) / "person.mp4"
    video.parent.mkdir(parents=True)
    video.write_bytes(bytes(range(256)) * 8)
    st = call(server.url + "api/state")[1]
    assert st["batch"][0]["video"] == f"/{page.token}/video/0/0.mp4"  # type: ignore[index]
    req = urllib.request.Request(server.url + "video/0/0.mp4", headers={"Range": "bytes=100-199"})
    with urllib.request.urlopen(req, timeout=10) as r:  # browsers loop and seek videos with Range requests
        assert r.status == 206 and r.headers["Content-Type"] == "video/mp4" and r.read() == video.read_bytes()[100:200]
    assert call(server.url + "video/0/2.mp4")[0] == 404  # a hidden gait has no video


def test_an_answer_is_stored_once_and_ranks_the_hidden_gait_last(served):
    page, server = served
    body = {"iteration": 0, "ranking": [[1], [0]], "labels": {"1": "good", "0": "bad"}}
    status, out = call(server.url + "api/answer", body)
    assert status == 200 and out == {"ok": True, "iteration": 0}
    ans = stored_answers(page.directory)
    assert ans[0]["ranks"] == [1, 0, None] and ans[0]["labels"] == ["bad", "good", None] and ans[0]["by"] == "person"
    # a double submit: refused, nothing stored twice
    status, out = call(server.url + "api/answer", body)
    assert status == 409 and "answered already" in out["error"]
    assert stored_answers(page.directory)[0]["answered_at"] == ans[0]["answered_at"]
    assert page.errors and "answered already" in page.errors[-1]
    # the batch's scores: B ≻ A ≻ C (C hidden, below every shown gait)
    from robustgait.study.ranking import batch_scores

    setup = load_config(page.directory)
    store = open_store(page.directory, setup, setup.action_space())
    try:
        batch = completed_batches(store.records())[0]
        scores = batch_scores(setup.config.study, batch, store.iterations()[0], [])
    finally:
        store.close()
    assert scores[1] > scores[0] > scores[2]


@pytest.mark.parametrize(("body", "status", "message"), [
    ({"iteration": 0, "ranking": [[0]]}, 400, "gait 2 is shown and not ranked"),  # omits B
    ({"iteration": 0, "ranking": [[0], [1], [0]]}, 400, "gait 1 is ranked twice"),
    ({"iteration": 0, "ranking": [[0], [1], [2]]}, 400, "gait 3 is not shown"),  # ranks the hidden one
    ({"iteration": 0, "ranking": [[0], [7]]}, 400, "gait 8 is not in the batch of 3"),
    ({"iteration": 0, "ranking": [[0], []]}, 400, "tier 2 must be a non-empty list"),
    ({"iteration": 0, "ranking": [[0, 1]], "labels": {"0": "great"}}, 400, "'great' is not one of bad"),
    ({"iteration": 0, "ranking": [[0, 1]], "labels": {"2": "good"}}, 400, "for a shown gait"),
    ({"iteration": 0, "ranking": [["0"], [1]]}, 400, "expected an integer"),
    ({"iteration": 0, "ranking": [[0], [1]], "token": "x"}, 400, "unknown key(s) token"),
    ({"ranking": [[0], [1]]}, 400, "needs 'iteration' and 'ranking'"),
    ({"iteration": 1, "ranking": [[0], [1]]}, 409, "iteration 2 is unknown"),  # not proposed yet
    ("not an object", 400, "JSON object"),
])
def test_bad_answers_are_refused_with_one_line_and_nothing_is_stored(served, body, status, message):
    page, server = served
    got, out = call(server.url + "api/answer", body)
    assert got == status and message in out["error"], out
    assert stored_answers(page.directory) == {}
    assert message in page.errors[-1]


def test_a_stale_batch_is_refused(served):
    page, server = served
    assert call(server.url + "api/answer", {"iteration": 0, "ranking": [[0, 1]]})[0] == 200  # cannot tell A from B
    assert stored_answers(page.directory)[0]["ranks"] == [0, 0, None]
    setup = load_config(page.directory)
    store = open_store(page.directory, setup, setup.action_space())
    try:
        store.set_iteration(1, {"proposals": [7, 8, 9]})  # the next batch, evaluating: not pending
    finally:
        store.close()
    status, out = call(server.url + "api/answer", {"iteration": 1, "ranking": [[0], [1], [2]]})
    assert status == 409 and "does not wait for an answer" in out["error"]
    status, out = call(server.url + "api/answer", {"iteration": 0, "ranking": [[1], [0]]})  # the old batch again
    assert status == 409 and "answered already" in out["error"]


def test_not_json_is_refused(served):
    _page, server = served
    req = urllib.request.Request(server.url + "api/answer", data=b"{ranking", method="POST")
    with pytest.raises(urllib.error.HTTPError) as exc:
        urllib.request.urlopen(req, timeout=10)
    assert exc.value.code == 400 and "not JSON" in json.loads(exc.value.read())["error"]


def test_record_answer_checks_the_pending_batch(tmp_path, template):
    d = shutil.copytree(template, tmp_path / "s")
    setup = load_config(d)
    store = open_store(d, setup, setup.action_space())
    try:
        with pytest.raises(RobustGaitError, match="ranks must be 0, 1"):
            record_answer(store, 0, {"ranks": [0, 2, None], "labels": [None] * 3, "by": "person"})
        with pytest.raises(RobustGaitError, match="does not wait"):
            record_answer(store, 1, {"ranks": [0, 1, None], "labels": [None] * 3, "by": "person"})
        record_answer(store, 0, {"ranks": [0, 1, None], "labels": [None] * 3, "by": "person"})
    finally:
        store.close()


def test_parse_answer_tiers_are_ranks():
    a = parse_answer({"iteration": 2, "ranking": [[2], [0, 3], [1]], "labels": {"3": "neutral"}}, 5)
    assert a.iteration == 2 and a.ranks == [1, 2, 0, 1, None] and a.labels == [None, None, None, "neutral", None]


@pytest.mark.slow  # seconds of its own: plain pytest stays ≤ 60 s; CI runs it
def test_a_port_in_use_is_one_line_and_exit_2(tmp_path):
    busy = socket.socket()
    busy.bind(("127.0.0.1", 0))
    busy.listen(1)
    port = busy.getsockname()[1]
    try:
        env = {**os.environ, "PYTHONPATH": str(REPO / "src")}
        d = tmp_path / "study"
        res = subprocess.run([sys.executable, "-m", "robustgait.cli", "study", "run", str(d), "--robot", "exo",
                              "--metric", "person", "--port", str(port)], env=env, capture_output=True, text=True,
                             timeout=120)
    finally:
        busy.close()
    assert res.returncode == 2
    assert res.stderr.strip().splitlines() == [f"robustgait: error: --port {port}: 127.0.0.1:{port} is in use "
                                                "(another study's page?): pick another with --port"]
    assert not d.exists()  # refused before the study was created


def test_serve_refuses_a_study_that_is_not_ranked_by_a_person(tmp_path):
    d = tmp_path / "push"
    create_study(d, "exo", Config(study=StudyConfig(iterations=1, batch=2)))
    with pytest.raises(RobustGaitError, match="only a study with --metric person"):
        PersonPage(d)


@pytest.mark.slow  # seconds of its own: plain pytest stays ≤ 60 s; CI runs it
def test_status_and_report_show_the_answers(served, capsys):
    from robustgait.cli.study import print_summary
    from robustgait.config import ReportConfig
    from robustgait.report.study import write_study_report
    from robustgait.study.status import study_status

    page, server = served
    print_summary(page.directory)
    assert "person: robustness floor J* ≥ 10 N s; 0 batches answered; batch 1 waits for an answer" in \
        capsys.readouterr().out
    assert call(server.url + "api/answer", {"iteration": 0, "ranking": [[1], [0]], "labels": {"0": "good"}})[0] == 200
    st = study_status(page.directory)
    assert st["person"]["pending"] is None and st["person"]["floor"]["value"] == 10.0
    assert [a["ranks"] for a in st["person"]["answers"]] == [[1, 0, None]]
    html = write_study_report(page.directory, ReportConfig(video=False)).read_text()
    assert "The person&#x27;s answers" in html or "The person's answers" in html
    assert "<td>1</td><td>B (0.1, 1.1, 0.22, 0.04) ≻ A (0.1, 0.6, 0.22, 0.1)</td><td>A: good</td><td>1</td>" in html


def test_blind_mode_hides_the_figures(served):
    from dataclasses import replace

    page, server = served
    cfg = page.setup.config
    page.setup = replace(page.setup, config=replace(cfg, person=replace(cfg.person, blind=True)))
    st = call(server.url + "api/state")[1]
    assert st["blind"] is True  # type: ignore[index]
    assert [set(g) for g in st["batch"]] == [{"slot", "iteration", "name", "video", "no_video"}] * 2  # type: ignore[index]
    assert st["hidden"] == [{"slot": 2, "name": "C", "why": None}]  # type: ignore[index]


@pytest.mark.slow  # rendering: keeps plain pytest ≤ 60 s; CI runs it
def test_a_person_video_is_what_the_configuration_says(tmp_path, exo, exo_gait):
    """A gait's looping video (render_person_video, the defaults of PersonConfig): the last ``steps`` steps after the
    comfort figures' skipped ones, a frame every 1/video_fps s of them, the side and the front views side by side
    (2·video_width × video_height), H.264 yuv420p with its index first — what the page's <video> plays and loops."""
    from robustgait.config import ComfortConfig
    from robustgait.web.media import render_person_video
    from tests.sim.test_engine import mp4_facts

    cfg = PersonConfig()
    out = tmp_path / "person.mp4"
    try:
        frames = render_person_video(exo, exo_gait, out, cfg.video_steps, ComfortConfig(skip_steps=1))
    except RobustGaitError as exc:  # no EGL/OSMesa on this machine: the message says what to do
        assert "MUJOCO_GL" in str(exc)
        return
    assert frames == pytest.approx(cfg.video_steps * exo_gait.params.step_duration * cfg.video_fps, abs=1.5)
    assert mp4_facts(out) == {"codec": "h264", "pix_fmt": "yuv420p", "size": (2 * cfg.video_width, cfg.video_height),
                              "fps": float(cfg.video_fps), "frames": frames, "index_first": True}
