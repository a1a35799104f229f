"""The maps on the switching surface (robustgait.certificate.returnmap, .reducedmap): k physical steps from a canonical
state, mirrored when k is odd; the reduced map P^K = Φ ∘ Δ^K ∘ ι at x*, the reconstruction ι; the section coordinates
the map is equivariant in."""

import numpy as np
import pytest

from robustgait import CertifyConfig, RobustGaitError
from robustgait.certificate.reduced import (
    ReducedState,
    reduce_state,
    section_coordinates,
    section_state,
    stance_jacobian,
)
from robustgait.certificate.reducedmap import ReducedMap
from robustgait.certificate.returnmap import FullStateMap
from robustgait.certificate.search import initial_section
from tests.conftest import ORBITS, walked_orbit

# one worker runs the modules of the group, so their module fixtures are made once and the orbit searches of one gait
# shared (tests.conftest.walked_orbit)
pytestmark = pytest.mark.xdist_group(ORBITS)


@pytest.fixture(scope="module")
def step_map(robot_gait):  # type: ignore[no-untyped-def]
    """The reduced map (omega, holonomic) at the orbit's x* of each flat-foot gait, and the orbit."""
    robot, gait = robot_gait
    cfg = CertifyConfig(disturbance="state")
    orbit = walked_orbit(robot, gait, cfg)
    assert orbit.ok, orbit.describe()
    with FullStateMap(robot, gait, orbit.period) as fmap:
        yield ReducedMap(fmap, ReducedState.at("omega", robot, orbit.qpos, orbit.qvel, gait.stance, cfg), 1), orbit


def test_x_star_maps_into_the_orbits_band(step_map):
    """x* is a state of the settled walk: its image lies within a few times the band's scatter of x*'s centre."""
    pmap, orbit = step_map
    x = pmap.reduced.x_star
    img = pmap(x[None])[0]
    assert np.linalg.norm(img - x) < 0.05
    assert orbit.period == 1 and pmap.fmap.mirrored


def test_holonomic_reconstruction_keeps_the_stance_sole_twist(step_map):
    pmap, orbit = step_map
    robot = pmap.fmap.robot
    x_star = pmap.reduced.x_star
    xbar = x_star + np.array([[0.3, -0.2, 0.1], [0.0, 0.0, 0.0]])
    qpos, qvel = pmap.reconstruct(xbar)
    np.testing.assert_array_equal(qvel[1], orbit.qvel)  # ι(x̄*) = x* exactly
    np.testing.assert_allclose(reduce_state(qpos, qvel, "heading")[0], xbar[0], atol=1e-12)
    js = stance_jacobian(robot, qpos[0], pmap.fmap.gait.stance)
    np.testing.assert_allclose(js @ qvel[0], js @ orbit.qvel, atol=1e-10)


def test_horizon_maps_k_steps_and_a_fall_in_any_is_a_fall(step_map):
    """P^K: K maps on full states (ι once, Φ at the end — not P ∘ P ∘ P of reduced states, which would rebuild the
    state at every step); a sample that falls in step 1 is NaN at every later iterate."""
    pmap, _ = step_map
    x = pmap.reduced.x_star + np.array([[0.05, -0.03, 0.02], [4.0, 0.0, 0.0]])
    one = pmap(x)
    p3 = ReducedMap(pmap.fmap, pmap.reduced, 3)
    three = p3(x)
    path = p3.last_path
    assert path is not None and path.shape == (3, 2, 3)
    np.testing.assert_allclose(path[0], one, atol=1e-12)
    np.testing.assert_allclose(three, path[-1])
    q, v = pmap.reconstruct(x[:1])
    for _ in range(3):
        q, v, _ = pmap.fmap(q, v)
    np.testing.assert_allclose(reduce_state(q, v, "heading"), three[:1], atol=1e-12)
    assert np.isnan(path[:, 1]).all()


def test_angular_only_changes_only_the_angular_velocity(step_map):
    pmap, orbit = step_map
    cfg = CertifyConfig(disturbance="state", reconstruction="angular-only")
    red = ReducedState.at("omega", pmap.fmap.robot, orbit.qpos, orbit.qvel, pmap.fmap.gait.stance, cfg)
    qpos, qvel = red.iota(red.x_star[None] + 0.25)
    changed = np.flatnonzero(qvel[0] != orbit.qvel)
    assert set(changed) <= {3, 4, 5} and np.array_equal(qpos[0], orbit.qpos)


@pytest.mark.slow
def test_a_two_step_map_is_two_steps_unmirrored_and_a_one_step_map_mirrors(exo, exo_gait):
    """The stride map (k = 2) of a symmetric robot is the step map applied twice (each mirrored: the mirrors cancel),
    to rounding; a map of no steps is refused."""
    orbit = walked_orbit(exo, exo_gait)
    q, v = orbit.qpos[None], orbit.qvel[None]
    with FullStateMap(exo, exo_gait, 1) as step, FullStateMap(exo, exo_gait, 2) as stride:
        q1, v1, _ = step(*step(q, v)[:2])
        q2, v2, _ = stride(q, v)
        assert not stride.mirrored and step.mirrored
        assert len(stride.phases()) == 2 and stride.phases()[0][0] != stride.phases()[1][0]
    np.testing.assert_allclose(q2, q1, atol=1e-6)
    np.testing.assert_allclose(v2, v1, atol=1e-4)
    with pytest.raises(RobustGaitError, match="at least one step"):
        FullStateMap(exo, exo_gait, 0)
    with pytest.raises(RobustGaitError, match="map: must be one of 'auto', 'step', 'stride'"):
        CertifyConfig(map="hop")  # type: ignore[arg-type]


def test_section_coordinates_invert_and_the_map_is_equivariant_under_x_y_and_yaw(exo, exo_gait):
    """The section coordinates drop the base's x, y and yaw and lose nothing else (round trip to 1e-15); the map's image
    in them does not depend on x and y (to 1e-9) and depends on the yaw only through MuJoCo's pyramidal friction cone,
    whose facets are fixed in the world: with an elliptic cone the yaw drops out to 1e-9 as well."""
    import mujoco

    from robustgait import load_robot

    t = exo_gait.step_duration
    with FullStateMap(exo, exo_gait, 1) as fmap:
        q, v = initial_section(exo, exo_gait, fmap.engine)
        for _ in range(12):
            q, v, _ = fmap(q, v)
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
        with FullStateMap(robot, exo_gait, 1) as m:
            return m.section_map(ref)(x)[0]

    base = image(exo, 0.0, 0.0, 0.0)
    assert np.abs(image(exo, 0.7, -1.3, 0.0) - base).max() < 1e-9
    pyramid = np.abs(image(exo, 0.0, 0.0, 0.7) - base).max()
    assert 1e-7 < pyramid < 1e-2  # measured 1e-3
    elliptic = load_robot("exo")
    elliptic.model.opt.cone = mujoco.mjtCone.mjCONE_ELLIPTIC
    e0 = image(elliptic, 0.0, 0.0, 0.0)
    assert np.abs(image(elliptic, 0.7, -1.3, 0.7) - e0).max() < 1e-9
