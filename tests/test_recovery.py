"""The recovery criterion of the push certificate (robustgait.certificate.recovery, docs/certificate.md "Recovery"):
distances in the base's Froude-scaled velocity with known answers, the band's radius, and on a synthetic push model
with late falls that a certificate asking only "no fall yet" certifies pushes that fall later, and one asking for
recovery does not."""

from __future__ import annotations

import math

import numpy as np
import pytest

from robustgait.certificate.estimators import certify_map_sequential
from robustgait.certificate.poincare import ReturnMap
from robustgait.certificate.push import NOT_RECOVERED, PushMap
from robustgait.certificate.recovery import OrbitBand, froude_scales, heading_velocity
from robustgait.certificate.synthetic import DivergingPush
from robustgait.config import CertifyConfig, PushConfig, SequentialConfig, ValidateConfig


def _yawed(qpos: np.ndarray, qvel: np.ndarray, psi: float) -> tuple[np.ndarray, np.ndarray]:
    """The state turned by ψ about the vertical (position, orientation and world-frame linear velocity)."""
    c, s = math.cos(psi), math.sin(psi)
    rz = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    q, v = qpos.copy(), qvel.copy()
    q[:3] = rz @ q[:3]
    w, x, y, z = q[3:7]
    q[3:7] = [math.cos(psi / 2) * w - math.sin(psi / 2) * z, math.cos(psi / 2) * x - math.sin(psi / 2) * y,
              math.cos(psi / 2) * y + math.sin(psi / 2) * x, math.cos(psi / 2) * z + math.sin(psi / 2) * w]
    v[:3] = rz @ v[:3]
    return q, v


def test_distance_is_in_froude_units_and_blind_to_heading(exo, exo_gait):
    q, v = exo_gait.initial_state.qpos, exo_gait.initial_state.qvel
    scales = froude_scales(exo)
    assert scales[0] == pytest.approx(math.sqrt(9.81 * exo.leg_length))
    assert scales[3] == pytest.approx(math.sqrt(9.81 / exo.leg_length))
    band = OrbitBand.of(exo, (q, v), np.hstack([q, v])[None], radius=0.3, multiple=3.0)
    assert band.scatter == 0.0 and band.radius == 0.3  # an orbit that does not move: the radius ν
    # a forward velocity 0.2 √(g l) off: distance 0.2, inside; 0.4: outside
    for dv, inside in ((0.2, True), (0.4, False)):
        v2 = v.copy()
        v2[0] += dv * scales[0]
        assert band.distance(q[None], v2[None])[0] == pytest.approx(dv, rel=1e-9)
        assert band.inside(q[None], v2[None])[0] == inside
    # the same deviation seen from another heading: the same distance (heading-frame twist)
    v2 = v.copy()
    v2[0] += 0.2 * scales[0]
    qy, vy = _yawed(q, v2, 0.7)
    assert band.distance(qy[None], vy[None])[0] == pytest.approx(0.2, rel=1e-9)
    tw, twy = heading_velocity(q[None], v2[None])[0], heading_velocity(qy[None], vy[None])[0]
    np.testing.assert_allclose(tw, twy, atol=1e-12)
    # a wandering undisturbed orbit widens the band to κ × its scatter
    v3 = v.copy()
    v3[4] += 0.5 * scales[4]  # its states reach 0.5 (scaled) from x*
    wide = OrbitBand.of(exo, (q, v), np.vstack([np.hstack([q, v]), np.hstack([q, v3])]), radius=0.3, multiple=3.0)
    assert wide.scatter == pytest.approx(0.5) and wide.radius == pytest.approx(1.5)
    assert not band.inside(np.full((1, q.size), np.nan), np.full((1, v.size), np.nan))[0]  # a fall is never inside


def test_recovery_refuses_the_late_falls_a_fall_only_certificate_certifies():
    model = DivergingPush()
    cfg = CertifyConfig(disturbance="push", seed=0, r_max=60.0, sequential=SequentialConfig(budget=3000))
    falls_only = certify_map_sequential(model.map(3, None), np.zeros(2), cfg)
    recovery = certify_map_sequential(model.map(3, 0.5), np.zeros(2), cfg)
    # without recovery J* lies above the true critical impulse: pushes just below it walk 4 steps and fall later
    assert falls_only.r_star > model.critical * 1.05
    j = np.column_stack([np.linspace(0, falls_only.r_star * 0.999, 400), np.zeros(400)])
    late, _ = model.walk(j, 19)
    assert (late > 0).any()
    # with it (a radius below the unstable point d_u = 1) J* stays below J_u: no push under it falls in 20 steps
    assert recovery.r_star < model.critical and recovery.violation_bound <= 0.02
    j = np.column_stack([np.linspace(0, recovery.r_star * 0.999, 400), np.zeros(400)])
    assert (model.walk(j, 19)[0] == 0).all()


@pytest.mark.slow  # ≥ 3.5 s (durations of 2026-11-26): plain pytest ≤ 60 s; CI runs it
def test_a_push_that_ends_off_its_orbit_fails(exo, exo_gait):
    cfg = CertifyConfig(disturbance="push")
    with ReturnMap(exo, exo_gait, cfg) as pmap:
        fp = pmap.find_fixed_point()
        falls_only = PushMap(pmap.engine, fp, ValidateConfig(), PushConfig(recovery=False))
        j = np.array([[0.0, 0.0], [12.0, 0.0], [0.0, 12.0], [-12.0, -6.0]])
        phase = np.full(4, 0.3)
        ok, _, fall, _ = falls_only.walk(j, phase)
        assert ok.all() and (fall == 0).all()
        # the band: the undisturbed walk from x* stays near it; a zero push ends inside
        pm = PushMap(pmap.engine, fp, ValidateConfig(), PushConfig())
        assert pm.band is not None and pm.band.radius == 0.3 and pm.band.scatter < 0.1
        ok, _, _, distance = pm.walk(j, phase)
        assert ok[0] and distance[0] <= pm.band.scatter * 1.5
        # a radius below a push's end distance makes that push a failure, 'not_recovered', and the map NaN there
        k = int(np.argmax(distance))
        tight = PushMap(pmap.engine, fp, ValidateConfig(), PushConfig(recovery_radius=0.9 * distance[k],
                                                                      recovery_scatter=0.0))
        ok2, reasons2, _, distance2 = tight.walk(j, phase)
        np.testing.assert_array_equal(distance2, distance)
        assert not ok2[k] and reasons2[k] == NOT_RECOVERED and ok2[0]
