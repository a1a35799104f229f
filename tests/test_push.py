"""The push map of J* (robustgait.certificate.push): the validation's walk, on flat-foot and multi-contact gaits."""

from __future__ import annotations

import math

import numpy as np
import pytest

from robustgait.certificate.certify import certify_gait
from robustgait.certificate.poincare import ReturnMap
from robustgait.certificate.push import PushMap, push_phase
from robustgait.config import CertifyConfig, PushConfig, ValidateConfig
from robustgait.report import plot_certificate
from robustgait.rotations import quat_to_mat
from robustgait.sim.engine import FALL_REASONS
from robustgait.validate import Validator
from robustgait.validate.disturbances import Draws
from tests.conftest import search_options


@pytest.fixture(scope="module")
def mc_pushes(exo, exo_mc_gait):  # type: ignore[no-untyped-def]
    cfg = CertifyConfig(disturbance="push", **search_options(exo_mc_gait))
    with ReturnMap(exo, exo_mc_gait, cfg) as pmap:
        fp = pmap.find_fixed_point()
        # falls only: the map is then the validation's walk to the letter (recovery: its own test)
        yield PushMap(pmap.engine, fp, ValidateConfig(), PushConfig(recovery=False)), fp


def test_push_phase_is_a_function_of_the_impulse_uniform_over_the_range():
    j = np.random.default_rng(0).uniform(-30, 30, (4000, 2))
    phi = push_phase(j, 0.1, 0.7)
    np.testing.assert_array_equal(phi, push_phase(j.copy(), 0.1, 0.7))
    assert phi.min() >= 0.1 and phi.max() < 0.7
    counts = np.histogram(phi, bins=6, range=(0.1, 0.7))[0]
    assert counts.min() > 4000 / 6 * 0.85  # uniform within sampling noise (σ ≈ 3 %)


@pytest.mark.slow  # ≥ 3.5 s (durations of 2026-11-26): plain pytest ≤ 60 s; CI runs it
def test_multicontact_zero_push_walks_and_the_push_map_is_the_validation_walk(mc_pushes, exo, exo_mc_gait):
    """A multi-contact step is double support then single support: a zero impulse walks all four steps; pushes of
    the same impulse, direction (heading frame → world) and phase fall in the same step under the push map as under
    ``validate --disturbance push`` (one code path), in either domain."""
    pm, fp = mc_pushes
    assert len(pm.engine.graph) == 2 and pm.window == sum(pm.engine.horizons)
    out = pm(np.zeros((1, 2)))
    assert np.all(out == 0) and pm.fall_step[-1][0] == 0
    j = np.array([[0.0, 0.0], [25.0, 0.0], [0.0, -40.0], [-60.0, 10.0], [90.0, 90.0], [0.0, 120.0]])
    out = pm(j)
    falls = pm.fall_step[-1]
    assert np.all(np.isnan(out[falls > 0])) and np.all(out[falls == 0] == 0)
    assert falls[0] == 0 and falls[-1] > 0  # no push walks; 120 N s (≈ 1.7 m/s on 70 kg) falls
    alive, reasons, steps, distance = pm.walk(j, push_phase(j, 0.0, 0.6))  # the map is the walk at the hashed phases
    assert np.array_equal(np.isnan(distance), ~alive) and np.all(distance[alive] == 0)  # no band: 0
    np.testing.assert_array_equal(steps, falls)
    assert np.array_equal(alive, falls == 0)
    assert all((r is None) == ok for r, ok in zip(reasons, alive, strict=True))
    assert all(r in FALL_REASONS for r, ok in zip(reasons, alive, strict=True) if not ok)
    r = quat_to_mat(fp.qpos[3:7])
    heading = math.atan2(r[1, 0], r[0, 0])
    draws = Draws("push", np.linalg.norm(j, axis=1),
                  {"direction": heading + np.arctan2(j[:, 1], j[:, 0]), "phase": push_phase(j, 0.0, 0.6)})
    ds = exo_mc_gait.domains[1].duration / exo_mc_gait.step_duration
    assert draws.params["phase"].min() < ds < draws.params["phase"].max()  # pushes start in both domains
    with Validator(exo, exo_mc_gait, ValidateConfig(trials=6, steps_after=3),
                   certificate=certify_gait(exo, exo_mc_gait, CertifyConfig(method="uniform", n_samples=2,
                                                                            **search_options(exo_mc_gait))),
                   start=fp) as v:
        res = v.run("push", draws=draws)
    np.testing.assert_array_equal(res.fall_step, falls)


@pytest.mark.slow  # ≥ 3.5 s (durations of 2026-11-26): plain pytest ≤ 60 s; CI runs it
def test_multicontact_push_certificate(exo, exo_mc_gait, tmp_path):
    gc = certify_gait(exo, exo_mc_gait, CertifyConfig(disturbance="push", method="uniform", n_samples=10, seed=2,
                                                      push={"steps": 1}, **search_options(exo_mc_gait)))
    c = gc.certificate
    assert gc.ok and c.samples.shape == (10, 2) and gc.config.unit == "N s"
    d = np.linalg.norm(c.samples, axis=1)
    assert c.r_star == pytest.approx(d[c.fell].min() if c.fell.any() else 100.0)
    with ReturnMap(exo, exo_mc_gait) as pmap:  # at most the pushed step and one more, each two domains
        assert 0 < gc.physics_steps <= 10 * 2 * sum(pmap.engine.horizons)
    # its figure: the impulse disk, the fall fraction by |J|, the rounds — in N s, not a state's coordinates
    out = plot_certificate(c, tmp_path / "j.png", coordinates=gc.coordinates)
    assert out.stat().st_size > 10_000 and gc.coordinates.space == "push"
