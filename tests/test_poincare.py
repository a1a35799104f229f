import numpy as np
import pytest

from robustgait import CertifyConfig, RobustGaitError
from robustgait.certificate.poincare import FixedPointFailure, ReturnMap
from robustgait.certificate.reduced import reduce_state, section_coordinates, section_state, stance_jacobian
from tests.conftest import ATALANTE_GAIT, search_options


@pytest.fixture(scope="module")
def step_map(robot_gait):
    with ReturnMap(*robot_gait, CertifyConfig(**search_options(robot_gait[1]))) as pmap:
        pmap.find_fixed_point()
        yield pmap


def test_fixed_point_is_a_fixed_point_of_the_map(step_map):
    fp = step_map.fixed_point
    assert fp.residual < 1e-2 and fp.steps >= 10 and len(fp.residuals) == fp.steps
    img = step_map(fp.omega[None])[0]
    assert np.linalg.norm(img - fp.omega) < 0.02


def test_holonomic_reconstruction_keeps_the_stance_sole_twist(step_map):
    robot = step_map.robot
    fp = step_map.fixed_point
    xbar = fp.omega + np.array([[0.3, -0.2, 0.1], [0.0, 0.0, 0.0]])
    qpos, qvel = step_map.reconstruct(xbar)
    np.testing.assert_array_equal(qvel[1], fp.qvel)  # ι(x̄*) = x* exactly
    np.testing.assert_allclose(reduce_state(qpos, qvel, "heading")[0], xbar[0], atol=1e-12)
    js = stance_jacobian(robot, qpos[0], step_map.stance)
    np.testing.assert_allclose(js @ qvel[0], js @ fp.qvel, atol=1e-10)


def test_horizon_maps_k_steps_and_a_fall_in_any_is_a_fall(step_map):
    """P^k: k maps on full states (ι once, Φ at the end — not P ∘ P ∘ P of reduced states, which would rebuild the
    state at every step); a sample that falls in step 1 is NaN at every later iterate."""
    fp = step_map.fixed_point
    x = fp.omega + np.array([[0.05, -0.03, 0.02], [4.0, 0.0, 0.0]])
    one = step_map(x)
    with ReturnMap(step_map.robot, step_map.gait, CertifyConfig(disturbance="state", horizon=3)) as p3:
        p3.set_fixed_point(fp)
        three = p3(x)
        path = p3.last_path
    assert path.shape == (3, 2, 3)
    np.testing.assert_allclose(path[0], one, atol=1e-12)
    np.testing.assert_allclose(three, path[-1])
    q, v = step_map.reconstruct(x[:1])
    for _ in range(3):
        q, v, _ = step_map._advance(q, v)
    np.testing.assert_allclose(reduce_state(q, v, "heading"), three[:1], atol=1e-12)
    assert np.isnan(path[:, 1]).all()


def test_angular_only_changes_only_the_angular_velocity(step_map):
    with ReturnMap(step_map.robot, step_map.gait, CertifyConfig(reconstruction="angular-only")) as pmap:
        fp = pmap.set_fixed_point(step_map.fixed_point)
        qpos, qvel = pmap.reconstruct(fp.omega[None] + 0.25)
    changed = np.flatnonzero(qvel[0] != fp.qvel)
    assert set(changed) <= {3, 4, 5} and np.array_equal(qpos[0], fp.qpos)


@pytest.mark.slow  # rendering / a second map: keeps plain pytest ≤ 60 s; CI runs it
def test_stride_map_fixed_point(robot_gait):
    with ReturnMap(*robot_gait, CertifyConfig(map="stride", **search_options(robot_gait[1]))) as pmap:
        fp = pmap.find_fixed_point()
        assert fp.steps % 2 == 0 and fp.residual < 1e-2
        out = pmap(np.vstack([fp.omega, fp.omega + np.array([3.0, 0, 0])]))
    assert np.linalg.norm(out[0] - fp.omega) < 0.02 and np.isnan(out[1]).all()


def test_fixed_point_errors(robot_gait):
    import dataclasses

    from robustgait.gait import State

    robot, gait = robot_gait
    s = gait.initial_state
    kicked = dataclasses.replace(gait, initial_state=State(s.qpos, s.qvel + np.r_[0, 0, 0, 4.0, 0, 0, np.zeros(12)]))
    with ReturnMap(robot, kicked) as pmap, pytest.raises(RobustGaitError, match="fell within step"):
        pmap.find_fixed_point()
    with ReturnMap(robot, gait, CertifyConfig(fp_tol=1e-9, fp_max_steps=12)) as pmap:
        with pytest.raises(RobustGaitError, match=r"no stable orbit: .* in 12 steps: smallest successive residual"):
            pmap.find_fixed_point()
        with pytest.raises(RobustGaitError, match="find the fixed point first"):
            pmap(np.zeros((1, 3)))
    with pytest.raises(RobustGaitError, match="map: must be one of 'step', 'stride'"):
        CertifyConfig(map="hop")  # type: ignore[arg-type]


def test_section_coordinates_invert_and_the_map_is_equivariant_under_x_y_and_yaw(exo, exo_gait):
    """The section coordinates drop the base's x, y and yaw and lose nothing else (round trip to 1e-15); the map's image
    in them does not depend on x and y (to 1e-9) and depends on the yaw only through MuJoCo's pyramidal friction cone,
    whose facets are fixed in the world: with an elliptic cone the yaw drops out to 1e-9 as well."""
    import mujoco

    from robustgait import load_robot

    t = exo_gait.step_duration
    with ReturnMap(exo, exo_gait) as pmap:
        q, v = pmap.initial_section()
        for _ in range(12):
            q, v, _ = pmap._advance(q, v)
        x = section_coordinates(q, v, t)
        q2, v2 = section_state(x, q[0], t)
        np.testing.assert_allclose(q2[0, :3], q[0, :3], atol=1e-15)
        np.testing.assert_allclose(q2[0, 7:], q[0, 7:], atol=1e-15)
        np.testing.assert_allclose(abs(q2[0, 3:7] @ q[0, 3:7]), 1.0, atol=1e-15)  # the same rotation
        np.testing.assert_allclose(v2, v, atol=1e-14)

        def image(robot, dx, dy, dyaw):  # type: ignore[no-untyped-def]
            ref = q[0].copy()
            ref[0] += dx
            ref[1] += dy
            ref[3:7] = [np.cos(dyaw / 2), 0.0, 0.0, np.sin(dyaw / 2)]  # yaw dyaw (roll and pitch come from x)
            with ReturnMap(robot, exo_gait) as m:
                return m.section_map(ref)(x)[0]

        base = image(exo, 0.0, 0.0, 0.0)
        assert np.abs(image(exo, 0.7, -1.3, 0.0) - base).max() < 1e-9
        pyramid = np.abs(image(exo, 0.0, 0.0, 0.7) - base).max()
        assert 1e-7 < pyramid < 1e-2  # measured 1e-3
    elliptic = load_robot("exo")
    elliptic.model.opt.cone = mujoco.mjtCone.mjCONE_ELLIPTIC
    e0 = image(elliptic, 0.0, 0.0, 0.0)
    assert np.abs(image(elliptic, 0.7, -1.3, 0.7) - e0).max() < 1e-9


@pytest.mark.slow  # ≥ 3.5 s (durations of 2026-11-26): plain pytest ≤ 60 s; CI runs it
def test_the_exo_gait_settles_on_a_stable_orbit(exo, exo_gait):
    """The shipped search on the stored flat-foot gait: a window of 20 iterates within 0.01 at step 27, ρ = 0.79 with
    the touchdown found in continuous time (0.86 at a fixed touchdown step), the fixed point's residual the map's."""
    with ReturnMap(exo, exo_gait) as pmap:
        fp = pmap.find_fixed_point()
    o = fp.orbit
    assert o is not None and o.settled == fp.steps == 27 and o.window_residual <= 1e-2
    assert o.rho == pytest.approx(0.79, abs=0.02) and o.rho_fixed_event == pytest.approx(0.86, abs=0.02)
    assert o.moduli[0] == o.rho and len(o.moduli) == exo.model.nq + exo.model.nv - 4 and o.one_sided == 0
    assert fp.residual == o.map_residual < 1e-2 and not o.newton


@pytest.mark.slow  # ≥ 3.5 s (durations of 2026-11-26): plain pytest ≤ 60 s; CI runs it
def test_orbits_the_search_refuses(exo, exo_mc_gait, request):
    """The stored multi-contact gait never settles (no window of 20 within 0.01 in 100 steps); Atalante's FROST gait
    settles, but on an orbit whose linearization has ρ > 1: perturbations grow (docs/certificate.md)."""
    with ReturnMap(exo, exo_mc_gait) as pmap, pytest.raises(FixedPointFailure) as info:
        pmap.find_fixed_point()
    e = info.value
    assert e.status == "no_stable_orbit" and e.steps == 100 and e.orbit.settled is None and not e.orbit.period_two
    assert e.orbit.window_residual > 1e-2 and e.fixed_point is None and "no stable orbit" in str(e)
    if not ATALANTE_GAIT.is_file():
        pytest.skip("../shared/atalante (AMBER lab model) is not beside the repository")
    atalante, frost = request.getfixturevalue("atalante"), request.getfixturevalue("atalante_gait")
    with ReturnMap(atalante, frost) as pmap, pytest.raises(FixedPointFailure) as info:
        pmap.find_fixed_point()
    e = info.value
    assert e.status == "unstable_orbit" and e.orbit.rho > 1.05 and e.fixed_point is not None
    assert e.orbit.settled == e.steps and "ρ = " in str(e)


@pytest.mark.slow  # three Newton iterations on 67 states: a few seconds
def test_newton_makes_the_settled_iterate_a_fixed_point(exo, exo_gait):
    with ReturnMap(exo, exo_gait, CertifyConfig(fp_newton_iterations=5)) as pmap:
        fp = pmap.find_fixed_point()
        o = fp.orbit
        assert o.newton_converged and o.newton[-1] <= 1e-8 and len(o.newton) <= 5 and o.rho < 0.85
        x = section_coordinates(fp.qpos[None], fp.qvel[None], exo_gait.step_duration)
        np.testing.assert_allclose(pmap.section_map(fp.qpos)(x), x, atol=1e-8)


@pytest.mark.slow  # ≥ 3.5 s (durations of 2026-11-26): plain pytest ≤ 60 s; CI runs it
def test_a_step_map_without_an_orbit_falls_back_to_the_stride_map(exo, exo_gait, monkeypatch):
    """certify.stride_fallback: a step map whose iterates settle on no orbit (a robot whose left and right differ:
    faked here by refusing the step map's search) is replaced by the stride map, searched for real; without the
    fallback, or after another failure, the step map's failure is the answer."""
    from robustgait.certificate.poincare import settle

    real = ReturnMap.find_fixed_point

    status = ["period_two_orbit"]

    def step_refused(self, progress=None):  # type: ignore[no-untyped-def]
        if self.kind == "step":
            raise FixedPointFailure(status[0], 100, f"{status[0]} (faked)")
        return real(self, progress)

    monkeypatch.setattr(ReturnMap, "find_fixed_point", step_refused)
    pmap, found = settle(exo, exo_gait, CertifyConfig())
    with pmap:
        assert pmap.kind == "stride" and pmap.config.map == "stride" and not isinstance(found, FixedPointFailure)
        assert found.steps % 2 == 0 and found.orbit is not None and found.orbit.period == 2
        assert found.orbit.rho is not None and found.orbit.rho < 1
        assert found.orbit.describe().startswith("stride map (two steps): converged")
    status[0] = "unstable_orbit"  # a settled orbit with ρ ≥ 1 is not searched again: the stride map's ρ is its square
    pmap, found = settle(exo, exo_gait, CertifyConfig())
    pmap.close()
    assert pmap.kind == "step" and isinstance(found, FixedPointFailure) and found.status == "unstable_orbit"
    status[0] = "period_two_orbit"
    pmap, found = settle(exo, exo_gait, CertifyConfig(stride_fallback=False))
    pmap.close()
    assert pmap.kind == "step" and isinstance(found, FixedPointFailure) and found.status == "period_two_orbit"
    pmap, found = settle(exo, exo_gait, CertifyConfig(fp_tol=1e-9, fp_max_steps=12, fp_min_steps=10))
    pmap.close()  # the stride map fails too: the step map's status, both findings in the message
    assert isinstance(found, FixedPointFailure) and found.status == "period_two_orbit"
    assert "; the stride map: no stable orbit" in str(found)


def test_a_walk_that_alternates_settles_as_a_stride_map_orbit(exo, exo_gait):
    """walk_orbit: a walk whose left and right steps differ (faked: 0.05 rad/s added to one joint's velocity at every
    event that ends a gait's-stance step) is a period-two orbit of the step map and a period-one orbit of the stride
    map — the events of the gait's own stance, two steps apart."""
    import dataclasses

    from robustgait.sim.walk import walk, walk_orbit

    result = walk(exo, exo_gait, steps=60)
    events = [dataclasses.replace(e, qvel=[v + (0.05 if i == 8 and e.stance == exo_gait.stance else 0.0)
                                           for i, v in enumerate(e.qvel)]) for e in result.events]
    plain = walk_orbit(exo, exo_gait, result.events)
    assert plain.converged and plain.period == 1
    step = walk_orbit(exo, exo_gait, events, CertifyConfig(stride_fallback=False))
    assert not step.converged and step.period_two
    stride = walk_orbit(exo, exo_gait, events)
    assert stride.converged and stride.period == 2 and stride.settled % 2 == 0
    assert events[stride.settled - 1].stance != exo_gait.stance  # x* starts a step of the gait's stance
