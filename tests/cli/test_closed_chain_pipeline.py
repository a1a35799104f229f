"""The whole pipeline on a biped written here, with what Cassie brings: a closed chain per leg (a rod on a ball joint
closing a four-bar through the tarsus), a spring (the shin's) and a line foot (one capsule). robot init → robot check
→ gait generate → walk 300 steps → certify → validate against the certificate → gait convert to FROST and back → a
study and its report, each through the CLI as a user runs it."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import pytest

from tests.inspection.biped import run, write
from tests.robots.test_loops import BENT, chain_xml

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib


@pytest.mark.slow
def test_a_closed_chain_biped_with_a_spring_and_line_feet_goes_through_the_whole_pipeline(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    model = write(tmp_path, chain_xml(BENT, damped=True), "chain.xml")
    spec, gait, cert = tmp_path / "chain.toml", tmp_path / "gait.json", tmp_path / "cert.json"

    code, out, err = run(capsys, "robot", "init", model, "-o", spec)  # the accuracy rule: it walks the default gait
    assert code == 0, err
    raw = tomllib.loads(spec.read_text())
    assert raw["legs"]["left"]["foot"] == raw["legs"]["right"]["foot"] == "line"
    assert raw["springs"]["left_shin_spring"] == [800.0, 0.0] and len(raw["loops"]) == 2
    assert raw["sim"]["timestep"] == pytest.approx(0.002)  # chosen by walking the default gait at 2 ms and 1 ms
    code, out, err = run(capsys, "robot", "check", spec)
    assert code == 0 and "all 7 checks passed" in out, out + err

    code, out, err = run(capsys, "gait", "generate", "--robot", spec, "-o", gait, "--json")
    assert code == 0, err
    generated = json.loads(out)
    assert generated["walk_check"]["fell"] is False

    code, out, err = run(capsys, "walk", "--robot", spec, gait, "--steps", "300", "--json")
    assert code == 0, err
    walked = json.loads(out)
    assert walked["steps_taken"] == 300 and not walked["fell"] and walked["mean_speed"] > 0.2
    assert walked["orbit"]["status"] == "ok"  # its switching states settled and held

    code, out, err = run(capsys, "certify", "--robot", spec, gait, "-o", cert, "--json")
    assert code == 0, err
    certificate = json.loads(cert.read_text())
    assert certificate["status"] == "ok" and certificate["verified"] and certificate["value"] > 0.0

    code, out, err = run(capsys, "validate", "--robot", spec, gait, "--certificate", cert, "--trials", "100",
                         "-o", tmp_path / "validation.json")
    assert code == 0, err
    push = json.loads((tmp_path / "validation.json").read_text())["kinds"]["push"]
    inside = push["certificate_check"]["inside"]
    # the promise: at most 2 % of the pushes below J* fall (95 %); a few dozen pushes land there, none or one falls
    assert inside["n"] >= 20 and inside["k"] <= 1
    assert push["success"]["k"] < push["success"]["n"]  # pushes well past J* do fell it: the test could fail

    frost, back = tmp_path / "gait.yaml", tmp_path / "back.json"
    assert run(capsys, "gait", "convert", "--robot", spec, gait, "--to", "frost", "-o", frost)[0] == 0
    assert run(capsys, "gait", "convert", "--robot", spec, frost, "-o", back)[0] == 0
    a, b = json.loads(gait.read_text()), json.loads(back.read_text())
    np.testing.assert_allclose(np.array(a["domains"][0]["beta"]), np.array(b["domains"][0]["beta"]), atol=1e-9)

    study = tmp_path / "study"
    code, out, err = run(capsys, "study", "run", "--robot", spec, "--iterations", "2", "--batch", "2", "--quiet", study)
    assert code == 0, err
    code, out, err = run(capsys, "study", "report", study)
    assert code == 0, err
    assert (study / "report" / "index.html").is_file()
    statuses = [json.loads(p.read_text())["status"] for p in (study / "gaits").glob("*/certificate.json")]
    assert statuses and all(s == "ok" for s in statuses)  # the study certified what it walked
