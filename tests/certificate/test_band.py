"""The band of an orbit and recovery to it (robustgait.certificate.band, .push; docs/certificate.md "Recovery"): band
coordinates with known answers — dimensionless by the robot's leg length and gravity, blind to position and heading —,
the half-widths max(ν, κ σ), phases; and on a synthetic push model with late falls, that a certificate asking only "no
fall yet" certifies pushes that fall later, and one asking for recovery does not."""

from __future__ import annotations

import math

import numpy as np
import pytest

from robustgait.certificate.band import Band, band_coordinates, band_scales
from robustgait.certificate.estimators import certify_map_sequential
from robustgait.certificate.synthetic import DivergingPush
from robustgait.config import CertifyConfig, SequentialConfig


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


def test_band_coordinates_are_froude_scaled_and_blind_to_position_and_heading(exo, exo_gait):
    q, v = exo_gait.initial_state.qpos, exo_gait.initial_state.qvel
    s = band_scales(exo)
    leg, g = exo.leg_length, exo.scale.gravity
    d = exo.model.nq + exo.model.nv - 4
    assert s.shape == (d,) and s[0] == pytest.approx(leg) and s[1] == s[2] == s[3] == 1.0
    npos = exo.model.nq - 4
    assert s[npos] == pytest.approx(math.sqrt(g * leg)) and s[npos + 3] == pytest.approx(math.sqrt(g / leg))
    assert s[-1] == pytest.approx(math.sqrt(g / leg))  # joint velocities: rad/s over √(g/l)
    z = band_coordinates(exo, q[None], v[None])[0]
    assert z[0] == pytest.approx(q[2] / leg)
    # a forward velocity 0.2 √(g l) off is 0.2 in its coordinate, from any heading and position
    v2 = v.copy()
    v2[0] += 0.2 * math.sqrt(g * leg)
    z2 = band_coordinates(exo, q[None], v2[None])[0]
    assert np.linalg.norm(z2[npos:npos + 3] - z[npos:npos + 3]) == pytest.approx(0.2, rel=1e-9)  # heading frame
    qy, vy = _yawed(q, v2, 0.7)
    qy[:2] += [3.0, -1.0]
    np.testing.assert_allclose(band_coordinates(exo, qy[None], vy[None])[0], z2, atol=1e-12)


def test_a_band_is_a_box_of_half_widths_max_nu_kappa_sigma_per_phase():
    c = np.array([[0.0, 0.0], [1.0, 1.0]])
    sigma = np.array([[0.0, 0.02], [0.0, 0.0]])
    band = Band(c, sigma, radius=0.03, multiple=3.0)
    assert band.period == 2 and band.sigma == 0.02
    np.testing.assert_allclose(band.half_width, [[0.03, 0.06], [0.03, 0.03]])
    z = np.array([[0.029, 0.059], [0.031, 0.0], [1.0, 1.029], [0.0, 0.0]])
    np.testing.assert_allclose(band.distance(z, np.array([0, 0, 1, 1])), [0.059 / 0.06, 0.031 / 0.03, 0.029 / 0.03,
                                                                         1.0 / 0.03])
    np.testing.assert_array_equal(band.inside(z, np.array([0, 0, 1, 1])), [True, False, True, False])
    assert band.inside(z[:1], 2)[0]  # the phase of step j is j mod k
    nan = np.array([[np.nan, 0.0]])
    assert np.isnan(band.distance(nan, 0)[0]) and not band.inside(nan, 0)[0]
    assert band.to_dict() == {"radius": 0.03, "multiple": 3.0, "sigma": 0.02, "period": 2, "phase_sigma": [0.02, 0.0]}


def test_the_floor_needed_is_the_smallest_nu_that_puts_a_state_in_the_band():
    c = np.array([[0.0, 0.0], [1.0, 1.0]])
    sigma = np.array([[0.0, 0.02], [0.0, 0.0]])
    z = np.array([[0.029, 0.059], [0.031, 0.07], [1.0, 1.029], [0.0, 0.0], [np.nan, 0.0]])
    phase = np.array([0, 0, 1, 1, 0])
    need = Band(c, sigma, radius=0.03, multiple=3.0).floor_needed(z, phase)
    # coordinates within κσ count as 0; the others by their deviation, whatever the band's own ν
    np.testing.assert_allclose(need[:4], [0.029, 0.07, 0.029, 1.0])
    assert np.isnan(need[4])
    for nu in (0.02, 0.03, 0.05, 0.08):
        band = Band(c, sigma, radius=nu, multiple=3.0)
        np.testing.assert_array_equal(band.inside(z, phase), need <= nu)

def test_recovery_refuses_the_late_falls_a_fall_only_certificate_certifies():
    model = DivergingPush()
    cfg = CertifyConfig(disturbance="push", seed=0, r_max=60.0, sequential=SequentialConfig(budget=3000))
    falls_only = certify_map_sequential(model.map(3, None), np.zeros(2), cfg)
    recovery = certify_map_sequential(model.map(3, 0.5), np.zeros(2), cfg)
    # without recovery J* lies above the true critical impulse: pushes just below it walk 4 steps and fall later
    assert falls_only.radius > model.critical * 1.05
    j = np.column_stack([np.linspace(0, falls_only.radius * 0.999, 400), np.zeros(400)])
    late, _ = model.walk(j, 19)
    assert (late > 0).any()
    # with it (a radius below the unstable point d_u = 1) J* stays below J_u: no push under it falls in 20 steps
    assert recovery.radius < model.critical and recovery.violation_bound <= 0.02
    j = np.column_stack([np.linspace(0, recovery.radius * 0.999, 400), np.zeros(400)])
    assert (model.walk(j, 19)[0] == 0).all()


def test_band_coordinates_of_a_closed_chain_count_a_ball_joints_four_coordinates_and_three_rates(tmp_path):
    # the inline biped of tests/robots/test_loops.py: a rod on a ball joint per leg (nq − 7 = nv − 6 + 2)
    from robustgait import load_robot
    from robustgait.cli import main
    from tests.inspection.biped import SERVO_RULE, write
    from tests.robots.test_loops import chain_xml

    model, spec = write(tmp_path, chain_xml(), "chain.xml"), tmp_path / "chain.toml"
    assert main(["robot", "init", str(model), "-o", str(spec), *SERVO_RULE]) == 0
    robot = load_robot(spec)
    m = robot.model
    assert m.nq - 7 == m.nv - 6 + 2
    z = band_coordinates(robot, m.qpos0, np.ones(m.nv))
    assert z.shape == (1, m.nq + m.nv - 4) and np.all(np.isfinite(z))
    rate = math.sqrt(robot.scale.gravity / robot.leg_length)
    assert np.allclose(z[0, -(m.nv - 3):], 1.0 / rate)  # every rate (base angular and joints) over √(g/l)
