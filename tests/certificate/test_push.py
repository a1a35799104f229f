"""The push map of J* (robustgait.certificate.push): the validation's walk, on flat-foot and multi-contact gaits."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from robustgait.certificate.certify import certify_gait
from robustgait.certificate.push import PushMap, push_phase, recovered_steps
from robustgait.config import CertifyConfig, PushConfig, SimConfig, ValidateConfig
from robustgait.report import plot_certificate
from robustgait.rotations import quat_to_mat
from robustgait.sim.engine import FALL_REASONS
from robustgait.sim.factory import make_engine
from robustgait.sim.trials import pushed_first_step, simulate_trials
from robustgait.validate import Validator
from robustgait.validate.disturbances import Draws
from tests.conftest import ORBITS, walked_orbit

# one worker runs the modules of the group, so their module fixtures are made once and the orbit searches of one gait
# shared (tests.conftest.walked_orbit: the engines here run the default simulation options, as the search's own does)
pytestmark = pytest.mark.xdist_group(ORBITS)


@pytest.fixture(scope="module")
def mc_pushes(exo, exo_mc_gait):  # type: ignore[no-untyped-def]
    engine = make_engine(exo, exo_mc_gait, SimConfig())
    orbit = walked_orbit(exo, exo_mc_gait)
    assert orbit.ok, orbit.describe()
    # falls only, the pushed step and 3 more: the map is then the validation's walk to the letter (recovery: its own
    # test)
    falls_only = PushConfig(recovery=False, horizon=3)
    yield PushMap(engine, orbit.qpos, orbit.qvel, orbit.band, ValidateConfig(), falls_only), orbit
    engine.close()


@pytest.fixture(scope="module")
def exo_pushes(exo, exo_gait):  # type: ignore[no-untyped-def]
    engine = make_engine(exo, exo_gait, SimConfig())
    orbit = walked_orbit(exo, exo_gait)
    yield engine, orbit
    engine.close()


def test_push_phase_is_a_function_of_the_impulse_uniform_over_the_range():
    j = np.random.default_rng(0).uniform(-30, 30, (4000, 2))
    phi = push_phase(j, 0.1, 0.7)
    np.testing.assert_array_equal(phi, push_phase(j.copy(), 0.1, 0.7))
    assert phi.min() >= 0.1 and phi.max() < 0.7
    counts = np.histogram(phi, bins=6, range=(0.1, 0.7))[0]
    assert counts.min() > 4000 / 6 * 0.85  # uniform within sampling noise (σ ≈ 3 %)


@pytest.mark.slow  # seconds of its own: plain pytest stays ≤ 60 s; CI runs it
def test_multicontact_zero_push_walks_and_the_push_map_is_the_validation_walk(mc_pushes, exo, exo_mc_gait):
    """A multi-contact step is double support then single support: a zero impulse walks all four steps; pushes of
    the same impulse, direction (heading frame → world) and phase fall in the same step under the push map as under
    ``validate --disturbance push`` (one code path), in either domain."""
    pm, orbit = mc_pushes
    fp = orbit.fixed_point("heading")
    assert len(pm.engine.graph) == 2 and pm.window == sum(pm.engine.horizons)
    out = pm(np.zeros((1, 2)))
    assert np.all(out == 0) and pm.fall_step[-1][0] == 0
    j = np.array([[0.0, 0.0], [25.0, 0.0], [0.0, -40.0], [-60.0, 10.0], [90.0, 90.0], [0.0, 120.0]])
    out = pm(j)
    falls = pm.fall_step[-1]
    assert np.all(np.isnan(out[falls > 0])) and np.all(out[falls == 0] == 0)
    assert falls[0] == 0 and falls[-1] > 0  # no push walks; 120 N s (≈ 1.7 m/s on 70 kg) falls
    alive, reasons, steps, recovered = pm.walk(j, push_phase(j, 0.0, 0.6))  # the map is the walk at the hashed phases
    assert np.all(recovered == 0)  # no band: nothing to come back to, every walk goes to the horizon
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
                   certificate=certify_gait(exo, exo_mc_gait, CertifyConfig(method="uniform", n_samples=2)),
                   start=fp) as v:
        res = v.run("push", draws=draws)
    np.testing.assert_array_equal(res.fall_step, falls)


@pytest.mark.slow  # seconds of its own: plain pytest stays ≤ 60 s; CI runs it
def test_multicontact_push_certificate(exo, exo_mc_gait, tmp_path):
    gc = certify_gait(exo, exo_mc_gait, CertifyConfig(disturbance="push", method="uniform", n_samples=10, seed=2,
                                                      push={"horizon": 1}))
    c = gc.certificate
    assert gc.ok and c.samples.shape == (10, 2) and gc.config.unit == "N s"
    d = np.linalg.norm(c.samples, axis=1)
    assert c.radius == pytest.approx(d[c.fell].min() if c.fell.any() else 100.0)
    engine = make_engine(exo, exo_mc_gait)  # at most the pushed step and one more, each two domains
    assert 0 < gc.physics_steps <= 10 * 2 * sum(engine.horizons)
    engine.close()
    # its figure: the impulse disk, the fall fraction by |J|, the rounds — in N s, not a state's coordinates
    out = plot_certificate(c, tmp_path / "j.png", coordinates=gc.coordinates)
    assert out.stat().st_size > 10_000 and gc.coordinates.space == "push"


def test_a_pushed_walk_stops_once_back_in_the_band_and_fails_when_it_is_not(exo, exo_gait, exo_pushes):
    """A zero push is in the band from the first step on: recovered at step push.recovery_steps (2), having walked
    only those; pushes of 12 N s come back later; with a band too narrow to come back to (ν tiny, no scatter
    multiple) the same pushes never stop early: they walk the whole horizon, and — not falling — do not fail. The step
    each came back at is the one recovered_steps finds on the recorded sections of a full walk (validate's check of
    the promise)."""
    engine, orbit = exo_pushes
    j = np.array([[0.0, 0.0], [12.0, 0.0], [0.0, 12.0], [-12.0, -6.0]])
    phase = np.full(4, 0.3)
    pm = PushMap(engine, orbit.qpos, orbit.qvel, orbit.band, ValidateConfig(), PushConfig())
    ok, _, fall, back = pm.walk(j, phase)
    assert ok.all() and (fall == 0).all() and back[0] == 2 and (back[1:] > 2).all() and (back <= 21).all()
    assert pm.farthest is not None and pm.farthest[0] <= 1.0 and (pm.farthest[1:] > 1.0).all()
    # the same walks, recorded to the horizon: the recovery rule on their sections gives the same steps
    window = sum(engine.horizons)
    from robustgait.certificate.push import push_series

    heading = math.atan2(*reversed(quat_to_mat(orbit.qpos[3:7])[:2, 0]))
    wrench = push_series(j, phase, heading, 0.1, exo_gait.step_duration, exo.dt, window)
    sections = np.full((4, 21, exo.model.nq + exo.model.nv), np.nan)
    simulate_trials(engine, np.tile(orbit.qpos, (4, 1)), np.tile(orbit.qvel, (4, 1)), 21, 21,
                    pushed_first_step(engine, wrench), first_at=0, sections=sections)
    np.testing.assert_array_equal(recovered_steps(orbit.band, exo, sections, 2), back)
    narrow = dataclasses.replace(orbit.band, multiple=0.0)  # its floor ν is the push rule's
    tight = PushMap(engine, orbit.qpos, orbit.qvel, narrow, ValidateConfig(), PushConfig(horizon=4,
                                                                                       recovery_radius=1e-6))
    ok2, reasons2, fall2, back2 = tight.walk(j, phase)
    assert ok2.all() and all(r is None for r in reasons2) and (back2[1:] == 0).all() and (fall2 == 0).all()
    assert tight.physics_steps > 3 * 5 * 500  # the three walked the whole horizon
