"""The orbit search on real gaits (robustgait.certificate.search): the walk the robot has — settled in a band, its
period, x* a state the walk reached, stable under probing pushes — and the same orbit from every walk of the gait
(``robustgait.walk``, ``robustgait walk``, the certificate)."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest

from robustgait import CertifyConfig, walk
from robustgait.certificate import Walked, Walking, find_orbit
from robustgait.certificate.orbit import Status, canonical_event_states, classify_walk, min_period
from robustgait.certificate.search import orbit_speed_note, probe_impulse
from robustgait.config import SimConfig
from robustgait.gait import State
from tests.conftest import EXO_GAIT, ORBITS, walked_orbit

# one worker runs the modules of the group, so their module fixtures are made once and the orbit searches of one gait
# shared (tests.conftest.walked_orbit)
pytestmark = pytest.mark.xdist_group(ORBITS)


@pytest.fixture(scope="module")
def exo_orbit(exo, exo_gait):  # type: ignore[no-untyped-def]
    return walked_orbit(exo, exo_gait)


def test_the_exo_gait_settles_on_a_stable_period_one_orbit(exo, exo_gait, exo_orbit):
    """The stored flat-foot gait: settled within the search's 100 steps, period 1 (exo is its own mirror image), a band
    far below the recovery floor, x* one of the walk's switching states (the one the search names), and every probing
    push came back to the band."""
    o = exo_orbit
    limit = CertifyConfig().orbit
    assert o.status == Status.OK and o.period == 1 and not o.sides_differ and o.held == limit.hold_steps
    assert o.steps < limit.max_steps + limit.hold_steps
    assert o.sigma is not None and o.sigma < 1e-3 and o.settled is not None and o.settled < o.steps
    res = walk(exo, exo_gait, SimConfig(step_cap=o.steps))
    q, v = canonical_event_states(exo, exo_gait, res.events)
    assert o.x_star_step is not None and np.array_equal(q[o.x_star_step - 1], o.qpos)
    assert np.array_equal(v[o.x_star_step - 1], o.qvel)
    assert o.probe is not None and o.probe.ok and any(o.probe.left) and not any(o.probe.fell)
    assert o.probe.impulse == pytest.approx(probe_impulse(exo, CertifyConfig().orbit.probe_impulse) * 2 ** 0, rel=1.01)
    assert o.physics_steps > 0 and o.states is not None and len(o.states) == o.window + o.held
    # the search's walk is that walk: its speed and sole turn are the orbit's
    assert o.walk_speed == pytest.approx(res.mean_speed, rel=1e-12) and o.sole_turn == pytest.approx(res.sole_turn)


def test_the_certificate_notes_a_walk_that_does_not_go_at_its_gaits_speed(exo, exo_gait, exo_orbit):
    """orbit_speed_note: the orbit search's walk against the gait's L / T with sim.speed_agreement — no note for the
    stored gait, which walks at its speed; a note naming both speeds and the sole's turn when the same walk is read
    against a plan three times as fast; none when the walk fell or its speed was not recorded."""
    sim = SimConfig()
    plan = exo_gait.params.step_length / exo_gait.step_duration
    assert abs(exo_orbit.walk_speed - plan) < 0.1 * plan and orbit_speed_note(exo_orbit, exo_gait, sim) == ""
    fast = dataclasses.replace(exo_gait, params=dataclasses.replace(exo_gait.params,
                                                                    step_length=3 * exo_gait.params.step_length))
    note = orbit_speed_note(exo_orbit, fast, sim)
    assert note.startswith(f"the walk advances {exo_orbit.walk_speed:.3f} m/s, ") and "backwards" not in note
    assert f"planned {3 * plan:.3f} m/s" in note and "stance sole ends single support turned" in note
    assert orbit_speed_note(exo_orbit, fast, dataclasses.replace(sim, speed_agreement=2.5)) == ""  # within 250 %
    assert orbit_speed_note(dataclasses.replace(exo_orbit, walk_speed=None), fast, sim) == ""
    assert orbit_speed_note(dataclasses.replace(exo_orbit, status=Status.FELL), fast, sim) == ""


@pytest.mark.slow  # seconds of its own: plain pytest stays ≤ 60 s; CI runs it
def test_walk_and_the_certificate_report_the_same_orbit(exo, exo_gait, exo_orbit, capsys):
    """robustgait.walk (300 steps), `robustgait walk --json` and the certificate's search: one classification of the
    same switching states — the same settled step, period, band and x*."""
    from robustgait.cli import main

    api = find_orbit(Walked(exo, exo_gait, walk(exo, exo_gait, SimConfig(step_cap=300))), CertifyConfig())
    assert api.ok
    for field in ("settled", "period", "steps", "x_star_step"):
        assert getattr(api, field) == getattr(exo_orbit, field), field
    np.testing.assert_array_equal(api.band.centres, exo_orbit.band.centres)
    assert main(["walk", str(EXO_GAIT), "--robot", "exo", "--json", "--steps", "120"]) == 0
    cli = json.loads(capsys.readouterr().out)["orbit"]
    assert cli["settled_at_step"] == exo_orbit.settled and cli["period"] == 1 and cli["status"] == "ok"
    assert cli["sigma"] == pytest.approx(exo_orbit.sigma, rel=1e-12)


@pytest.mark.slow  # two walks of a few seconds
def test_a_walk_says_whether_its_switching_events_settled_on_an_orbit(exo, exo_gait, exo_mc_gait):
    """From the events a walk already has (no simulation): the stored flat-foot gait settles in a band far below the
    recovery floor, the multi-contact gait in a wider one; both hold their band — the orbit the certificate's search
    finds (tests/certificate/test_search.py); a walk too short to see the band hold says so."""
    cfg = CertifyConfig()
    o = find_orbit(Walked(exo, exo_gait, walk(exo, exo_gait, steps=120)), cfg)
    assert o.ok and o.period == 1 and o.sigma < 1e-3 and o.held == cfg.orbit.hold_steps  # held its whole hold
    assert o.to_dict()["settled_at_step"] == o.settled
    mc_walk = walk(exo, exo_mc_gait, steps=120)
    mc = find_orbit(Walked(exo, exo_mc_gait, mc_walk), cfg)
    assert mc_walk.steps_taken == 120 and not mc_walk.fell and mc.ok
    assert mc.sigma > 10 * o.sigma and "settled at step" in mc.describe()
    short = find_orbit(Walked(exo, exo_gait, walk(exo, exo_gait, steps=50)), cfg)
    assert short.status == "undecided" and "are needed to see the band hold" in short.reason


def test_a_walk_too_short_to_tell_says_so(exo, exo_gait):
    o = find_orbit(Walked(exo, exo_gait, walk(exo, exo_gait, SimConfig(step_cap=20))), CertifyConfig())
    assert o.status == Status.UNDECIDED and "before its switching states settled" in o.reason


def test_a_walk_whose_steps_alternate_is_a_period_two_orbit(exo, exo_gait):
    """Left and right steps that differ (faked: 0.05 rad/s added to one joint velocity at every event that ends a
    step of the gait's stance): the period-two orbit of the walk, x* a state that starts a step of the gait's stance;
    the stride map's search (min period 2) finds the same."""
    res = walk(exo, exo_gait, SimConfig(step_cap=130))
    events = [dataclasses.replace(e, qvel=[v + (0.05 if i == 8 and e.stance == exo_gait.stance else 0.0)
                                           for i, v in enumerate(e.qvel)]) for e in res.events]
    q, v = canonical_event_states(exo, exo_gait, events)
    o = classify_walk(exo, q, v, CertifyConfig())
    assert o.ok and o.period == 2 and o.x_star_step is not None and o.x_star_step % 2 == 0
    assert events[o.x_star_step - 1].stance != exo_gait.stance
    assert classify_walk(exo, q, v, CertifyConfig(map="stride")).period == 2
    assert min_period(exo, "auto") == 1 and min_period(exo, "stride") == 2 and min_period(exo, "step") == 1


def test_a_gait_that_falls_in_the_search_is_refused_with_the_step(exo, exo_gait):
    s = exo_gait.initial_state
    kick = np.r_[0, 0, 0, 4.0, 0, 0, np.zeros(12)]
    kicked = dataclasses.replace(exo_gait, initial_state=State(s.qpos, s.qvel + kick))
    o = find_orbit(Walking(exo, kicked))
    assert o.status == Status.FELL and "fell in step" in o.reason and o.band is None and o.probe is None


@pytest.mark.slow  # two finite-difference Jacobians of 67 maps and the eigenvector's 8 maps
def test_the_linearization_is_a_diagnostic_reported_only_where_it_holds(exo, exo_gait):
    """exo's smooth orbit: ρ the same at two finite-difference steps and confirmed along its eigenvector — reported;
    a verdict it never is (the orbit is ok either way)."""
    o = find_orbit(Walking(exo, exo_gait),
                   CertifyConfig(orbit=dataclasses.replace(CertifyConfig().orbit, linearization=True)))
    lin = o.linearization
    assert o.ok and lin is not None and lin.rho is not None and lin.rho_coarse is not None
    assert lin.defined, lin.reason
    assert 0.6 < lin.rho < 0.95 and abs(lin.rho - lin.rho_coarse) <= 0.1 * lin.rho
    assert lin.rate is not None and abs(lin.rate - lin.rho) <= 0.25 * lin.rho and "ρ = " in o.describe()


@pytest.mark.slow  # Booster T1 at 0.5 ms: a search of ~30 strides
def test_a_robot_whose_sides_differ_walks_a_stride_map_orbit(t1):
    """T1's shanks differ by 60 g (beyond the tolerance): its orbit is searched from period two, the stride map."""
    from robustgait import load_gait
    from robustgait.gaitgen import generate_gait

    assert min_period(t1, "auto") == 2
    gen = generate_gait(t1)
    assert gen.gait is not None
    o = find_orbit(Walking(t1, gen.gait))
    assert o.ok and o.period in (2, 4) and o.sides_differ, o.describe()
    del load_gait


@pytest.mark.slow  # a certificate of the AMBER lab's gait: ~15 s
def test_the_atalante_frost_gait_is_certified(atalante, atalante_gait):
    """The paper's own gait walks 300 of 300 steps in a band of ~0.006; a finite-difference ρ of 1.2 (1.21, 2.78 or 1.68
    at three steps) refused it. It settles, holds, comes back from the probe: certified, J* > 0."""
    from robustgait.certificate.certify import certify_gait

    gc = certify_gait(atalante, atalante_gait)
    assert gc.ok, gc.reason
    assert gc.orbit is not None and gc.orbit.period == 1 and gc.orbit.sigma < 0.02 and gc.j_star > 1.0
    assert gc.orbit.probe is not None and gc.orbit.probe.ok


@pytest.mark.slow  # a walk of 245 steps and the search's 63
def test_a_gait_that_falls_after_245_steps_is_refused(exo, exo_gait):
    """exo's stored gait on a 3.5° slope 6° off downhill: it turns away from downhill ever faster and falls,
    undisturbed, after some 245 steps (245 here; a slow divergence, so its step moves with round-off: held to
    200–290). Its switching states look settled for dozens of steps; the band's hold sees them move: refused
    (unsettled), long
    before the fall."""
    from robustgait import load_robot
    from robustgait.certificate.certify import certify_gait

    robot = load_robot("exo")  # a model of its own: gravity tilted
    slope, azimuth = np.radians(3.5), np.radians(6.0)
    robot.model.opt.gravity[:] = 9.81 * np.array([np.sin(slope) * np.cos(azimuth), np.sin(slope) * np.sin(azimuth),
                                                  -np.cos(slope)])
    res = walk(robot, exo_gait, SimConfig(step_cap=300))
    assert res.fell and 200 <= res.steps_taken <= 290
    gc = certify_gait(robot, exo_gait)
    assert gc.status == Status.UNSETTLED and "then left that band" in gc.reason and gc.value == 0
    assert gc.steps_walked < 100 < res.steps_taken
