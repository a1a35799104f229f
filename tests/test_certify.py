import json

import numpy as np
import pytest

from robustgait import RobustGaitError
from robustgait.certify import CertifyConfig, certify_gait
from robustgait.cli import main
from robustgait.report import outcome_masks, plot_barrier_trace, plot_certificate
from tests.conftest import ATALANTE_GAIT, ATALANTE_SPEC, EXO_GAIT, needs_atalante


@pytest.fixture(scope="module")
def small_cert(robot_gait):
    return certify_gait(*robot_gait, CertifyConfig(n_samples=24, r_max=1.0, seed=3))


def test_certificate_is_consistent(small_cert):
    c = small_cert.certificate
    assert 0 <= c.r_star <= 1.0 and c.n_samples == 24
    np.testing.assert_array_equal(c.fell, np.isnan(c.images).any(axis=1))
    d = np.linalg.norm(c.samples - c.x_star, axis=1)
    inside = d < c.r_star
    assert np.all(c.margins[inside] >= 0) and inside.sum() <= c.n_inside
    assert np.all(d <= 1.0 + 1e-12)
    assert small_cert.fixed_point.residual < 5e-3 and small_cert.map_residual < 0.02
    assert small_cert.physics_steps > 24 * 500


def test_same_seed_same_json(robot_gait, small_cert):
    again = certify_gait(*robot_gait, CertifyConfig(n_samples=24, r_max=1.0, seed=3))
    a, b = small_cert.to_dict(), again.to_dict()
    a.pop("seconds")
    b.pop("seconds")
    assert json.dumps(a) == json.dumps(b)
    other = certify_gait(*robot_gait, CertifyConfig(n_samples=24, r_max=1.0, seed=4))
    assert other.to_dict()["samples"] != a["samples"]


def test_figures(tmp_path, small_cert):
    from robustgait.barrier import barrier_along

    masks = outcome_masks(small_cert.certificate)
    assert sum(int(m.sum()) for m in masks.values()) == 24
    out = plot_certificate(small_cert.certificate, tmp_path / "cert.png")
    assert out.stat().st_size > 10_000
    xs = small_cert.fixed_point.x_star + np.outer(0.5 ** np.arange(6), [0.1, 0.0, 0.0])
    trace = barrier_along(xs, small_cert.fixed_point.x_star, 0.2, 0.05)
    assert plot_barrier_trace(trace, tmp_path / "trace.png").stat().st_size > 5_000
    with pytest.raises(RobustGaitError, match="output directory does not exist"):
        plot_certificate(small_cert.certificate, tmp_path / "missing" / "cert.png")


@pytest.mark.parametrize("kwargs, message", [
    ({"r_max": 0.0}, "r_max"), ({"r_max": -1.0}, "r_max"), ({"alpha": 0.0}, "alpha"), ({"alpha": 1.0}, "alpha"),
    ({"n_samples": 0}, "samples"),
])
def test_bad_config(kwargs, message):
    with pytest.raises(RobustGaitError, match=message):
        CertifyConfig(**kwargs)


def _cli(capsys, *argv):
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def test_cli_certify_json(capsys, tmp_path):
    code, out, _ = _cli(capsys, "certify", str(EXO_GAIT), "--robot", "exo", "--samples", "12",
                        "--json", "--plot", str(tmp_path / "c.png"), "-o", str(tmp_path / "c.json"))
    res = json.loads(out)
    assert code == 0
    for key in ("r_star", "x_star", "fixed_point_residual", "n_samples", "n_fell", "map", "reconstruction",
                "seconds"):
        assert key in res
    assert res["n_samples"] == 12 and res["map"] == "step" and res["reconstruction"] == "holonomic"
    assert len(json.loads((tmp_path / "c.json").read_text())["samples"]) == 12
    assert (tmp_path / "c.png").stat().st_size > 10_000


@needs_atalante
@pytest.mark.parametrize("extra, message", [
    (["--r-max", "0"], "--r-max"), (["--r-max", "-2"], "--r-max"), (["--alpha", "1.5"], "--alpha"),
    (["--alpha", "0"], "--alpha"), (["--samples", "0"], "--samples"),
    (["--switching", "time"], "before a fixed point was reached"),
    (["--fp-tol", "1e-9", "--fp-max-steps", "12"], "no fixed point within 12 steps"),
])
def test_cli_certify_bad_input(capsys, tmp_path, extra, message):
    out_json = tmp_path / "c.json"
    code, out, err = _cli(capsys, "certify", str(ATALANTE_GAIT), "--robot", str(ATALANTE_SPEC), "--samples", "4",
                          "-o", str(out_json), *extra)
    assert code == 2 and out == "" and message in err and len(err.strip().splitlines()) == 1
    assert not out_json.exists()


def test_cli_walk_log_then_barrier_eval(capsys, tmp_path):
    log = tmp_path / "w.csv"
    assert _cli(capsys, "walk", str(EXO_GAIT), "--robot", "exo", "--steps", "20", "--log",
                str(log))[0] == 0
    rows = log.read_text().splitlines()
    assert rows[0] == "wx,wy,wz" and len(rows) == 21
    xs = np.loadtxt(log, delimiter=",", skiprows=1)
    x_star = ",".join(str(v) for v in xs[-1])
    code, out, _ = _cli(capsys, "barrier-eval", str(log), "--x-star", x_star, "--r", "0.5", "--json",
                        "--plot", str(tmp_path / "t.png"))
    res = json.loads(out)
    assert code == 0 and len(res["h"]) == 20 and len(res["margins"]) == 19
    # a wrong x* (0.3 rad/s off the orbit) puts every logged state outside B(0.05), where H < 0 stays H < 0:
    # H(x_k+1) − (1 − α) H(x_k) = α H < 0, a violation at the first step
    wrong = ",".join(str(v) for v in xs[-1] + [0.3, 0.0, 0.0])
    code, out, _ = _cli(capsys, "barrier-eval", str(log), "--x-star", wrong, "--r", "0.05", "--check")
    assert code == 1 and "violated first at step 0" in out
    code, _, err = _cli(capsys, "barrier-eval", str(log), "--x-star", "0.1,0.2", "--r", "0.5")
    assert code == 2 and "3 columns" in err
