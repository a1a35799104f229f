"""Contacts declared as explicit ``<contact><pair>`` elements only (Apptronik Apollo's scene): the model is read as
MuJoCo reads it (``docs/robots.md``, "Soles, floor, URDF"). The shipped exo with its contacts rewritten as pairs — every
geom's contype = conaffinity = 0, one pair of the floor with each geom that touched it, carrying the contact
parameters MuJoCo mixed for those two geoms — must load, walk, certify and validate as exo does."""

from __future__ import annotations

import sys
from pathlib import Path

import mujoco
import numpy as np
import pytest

from robustgait import load_gait, load_robot
from robustgait.certificate.certify import certify_gait
from robustgait.config import CertifyConfig, SimConfig, ValidateConfig
from robustgait.robots import Robot
from robustgait.robots.model import CONTACT_SENSORS
from robustgait.robots.soles import can_touch, collides
from robustgait.sim.walk import walk
from robustgait.validate import Draws, Validator
from robustgait.validate import disturbances as dist
from tests.conftest import EXO_GAIT
from tests.inspection.biped import EXO_XML, SERVO_RULE, biped_xml, run, write

# one worker runs the whole module, so its module fixtures (orbits, certificates, validators) are made once
pytestmark = pytest.mark.xdist_group("pair_contacts_module")

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover - exercised on 3.10 only
    import tomli as tomllib

# exo's geoms that touch its floor (class "collision"): the soles, and those whose floor contact is a fall
EXO_FLOOR_GEOMS = {"left_sole", "right_sole", "pelvis_collision", "trunk_collision", "left_thigh_collision",
                   "right_thigh_collision", "left_shank_collision", "right_shank_collision"}
# the same contacts, made by pairs: bit-identical states under MuJoCo 4.0; a margin for round-off should another
# version order the contacts otherwise
STATE_TOL = 1e-7
STEPS = 20


def floor_pairs_xml(path: Path) -> list[str]:
    """exo's MJCF with its contacts as explicit pairs, written to ``path``; returns the paired geoms' names.

    MuJoCo mixes the contact parameters of two geoms of equal priority: condim and friction (per element) the
    larger, solref and solimp averaged by solmix, margin and gap the larger. An explicit pair does not mix: it takes
    its own attributes (the pair defaults where unset), so each pair is given the mixed values — here exo's floor and
    robot geoms share priority, solref, solimp, solmix, margin and gap (asserted), so those are the floor's."""
    mjs = mujoco.MjSpec.from_file(str(EXO_XML))
    m = mjs.compile()
    floor = m.geom("floor").id
    touching = [g for g in range(m.ngeom) if g != floor and can_touch(m, g, floor)]
    names = [m.geom(g).name for g in touching]
    assert set(names) == EXO_FLOOR_GEOMS
    for g in touching:
        for field in ("geom_priority", "geom_solref", "geom_solimp", "geom_solmix", "geom_margin", "geom_gap"):
            assert np.array_equal(getattr(m, field)[g], getattr(m, field)[floor]), field
    for geom in mjs.geoms:
        geom.contype, geom.conaffinity = 0, 0
    for g, name in zip(touching, names, strict=True):
        mu = np.maximum(m.geom_friction[g], m.geom_friction[floor])  # (slide, spin, roll)
        mjs.add_pair(geomname1="floor", geomname2=name, condim=int(max(m.geom_condim[g], m.geom_condim[floor])),
                     friction=[mu[0], mu[0], mu[1], mu[2], mu[2]], solref=m.geom_solref[floor],
                     solimp=m.geom_solimp[floor], margin=float(m.geom_margin[floor]), gap=float(m.geom_gap[floor]))
    mjs.compile()
    path.write_text(mjs.to_xml())
    return names


@pytest.fixture(scope="module")
def pair_exo(tmp_path_factory: pytest.TempPathFactory) -> Robot:
    """exo loaded from its spec pointed at the pair MJCF."""
    out = tmp_path_factory.mktemp("pair_exo")
    floor_pairs_xml(out / "exo_pairs.xml")
    text = EXO_XML.with_name("spec.toml").read_text()
    assert 'mjcf = "exo.xml"' in text
    (out / "spec.toml").write_text(text.replace('mjcf = "exo.xml"', 'mjcf = "exo_pairs.xml"'))
    return load_robot(out / "spec.toml")


def test_the_pair_model_loads_and_senses_the_floor_as_exo(pair_exo: Robot, exo: Robot) -> None:
    """Every contact is a pair's; the soles, floor, masses and the contact sensors' counts are exo's."""
    m = pair_exo.model
    assert m.npair == len(EXO_FLOOR_GEOMS) and not m.geom_contype.any() and not m.geom_conaffinity.any()
    assert pair_exo.sole_geom_id == exo.sole_geom_id and pair_exo.floor_name == exo.floor_name
    assert pair_exo.mass == exo.mass and {m.geom(g).name for g in range(m.ngeom) if collides(m, g)} == {
        "floor", *EXO_FLOOR_GEOMS}
    gait = load_gait(EXO_GAIT, exo)
    assert gait.initial_state is not None
    counts = []
    for robot in (exo, pair_exo):  # the gait's start 1 mm into the floor (its sole on it), then the pelvis sunk in
        d = robot.new_data()
        d.qpos[:] = gait.initial_state.qpos
        for z in (float(d.qpos[2]) - 0.001, 0.05):
            d.qpos[2] = z
            mujoco.mj_forward(robot.model, d)
            counts.append([float(d.sensordata[robot.sensor_adr[n]]) for n in CONTACT_SENSORS])
    assert counts[2:] == counts[:2]
    stand, sunk = counts[0], counts[1]
    assert stand[0] + stand[1] > 0 and stand[2] == stand[0] + stand[1] and sunk[2] > sunk[0] + sunk[1]


@pytest.mark.slow
def test_the_stored_gait_walks_and_certifies_as_on_exo(pair_exo: Robot, exo: Robot) -> None:
    """exo's stored gait on the pair model: the same switching states over 20 steps (to round-off), and the same
    uniform certificate: its samples fall or not alike — one sample whose outcome round-off decides may differ on
    another machine —, and where they all agree r* is the same."""
    gait = load_gait(EXO_GAIT, pair_exo)
    walks = [walk(r, g, SimConfig(step_cap=STEPS)) for r, g in ((exo, load_gait(EXO_GAIT, exo)), (pair_exo, gait))]
    assert not walks[1].fell and walks[1].steps_taken == walks[0].steps_taken == STEPS
    for a, b in zip(walks[0].events, walks[1].events, strict=True):
        np.testing.assert_allclose(b.qpos, a.qpos, atol=STATE_TOL)
        np.testing.assert_allclose(b.qvel, a.qvel, atol=100 * STATE_TOL)
    config = CertifyConfig(method="uniform", disturbance="state", n_samples=8, r_max=1.0, seed=3)
    certs = [certify_gait(r, load_gait(EXO_GAIT, r), config) for r in (exo, pair_exo)]
    assert certs[1].ok
    a, b = (c.certificate for c in certs)
    assert np.count_nonzero(b.fell != a.fell) <= 1
    if np.array_equal(b.fell, a.fell):
        assert b.radius == pytest.approx(a.radius, abs=1e-6)
    np.testing.assert_allclose(b.x_star, a.x_star, atol=1e-6)


@pytest.fixture(scope="module")
def pair_validator(pair_exo: Robot):  # type: ignore[no-untyped-def]
    gait = load_gait(EXO_GAIT, pair_exo)
    cert = certify_gait(pair_exo, gait, CertifyConfig(method="uniform", disturbance="state", n_samples=4))
    with Validator(pair_exo, gait, ValidateConfig(trials=2, steps_after=2), certificate=cert) as v:
        yield v


def test_terrain_tiles_take_the_floor_pairs_and_carry_the_walk(pair_validator, pair_exo: Robot) -> None:
    """The terrain's tiles replace the floor with its pairs: each tile is paired with every geom the floor was, a
    sole standing on a tile is a footfall (its sensor), the pelvis on a tile a ground contact, and a walk over flat
    tiles does not fall through them."""
    fp = pair_validator.fixed_point
    layout = dist.terrain_layout(pair_exo, fp.qpos, pair_validator.gait.stance, pair_validator.config,
                                 pair_validator.step_length)
    m = dist.terrain_model(pair_exo, layout)
    assert m.npair == len(EXO_FLOOR_GEOMS) * (1 + layout.nx * layout.ny)
    d = mujoco.MjData(m)
    d.qpos[:] = fp.qpos
    d.qpos[0] += layout.rough_from + 1.5 * layout.tile - float(fp.qpos[0])  # the stance foot over the first tiles
    mujoco.mj_forward(m, d)
    sens = [d.sensordata[pair_exo.sensor_adr[n]] for n in ("robustgait_contact_left", "robustgait_contact_right",
                                                          "robustgait_contact_floor")]
    tiles = {m.geom(f"robustgait_tile_{i}_{j}").id for i in range(layout.nx) for j in range(layout.ny)}
    assert sens[0] + sens[1] > 0 and sens[2] == sens[0] + sens[1]
    assert any({int(d.contact[i].geom1), int(d.contact[i].geom2)} & tiles for i in range(d.ncon))
    d.qpos[2] = 0.05  # the pelvis sinks into the tiles: a ground contact that is no footfall
    mujoco.mj_forward(m, d)
    assert d.sensordata[pair_exo.sensor_adr["robustgait_contact_floor"]] > 0
    res = pair_validator.run("terrain", draws=Draws("terrain", np.zeros(2), {"terrain_seed": np.array([1.0, 2.0])}))
    assert res.success.all()


def test_a_slope_trial_walks_like_the_floor_on_the_pair_model(pair_validator) -> None:
    """Slopes tilt gravity over the floor and its pairs: 0° walks as the flat floor, 30° falls."""
    z = Draws("push", np.zeros(1), {"direction": np.zeros(1), "phase": np.zeros(1)})
    flat = pair_validator.run("push", draws=z)
    res = pair_validator.run("slope", draws=Draws("slope", np.array([0.0, 30.0]), {"direction": np.zeros(2)}))
    np.testing.assert_array_equal(res.x_first[0], flat.x_first[0])
    assert res.success[0] and not res.success[1]


# ----------------------------------------------------------------------------------------------- robot init
PAIRS = '<contact><pair geom1="left_sole" geom2="{floor}"/><pair geom1="right_sole" geom2="{floor}"/></contact>'


def pair_biped(floor: str = "ground") -> str:
    """The biped of tests/inspection/biped.py whose geoms all have contype = conaffinity = 0, its soles
    paired with ``floor`` (the other sole: pairs that do not reach the floor)."""
    pairs = PAIRS.format(floor=floor) if floor != "other sole" else (
        '<contact><pair geom1="left_sole" geom2="right_sole"/></contact>')
    return biped_xml(collide=False).replace("</mujoco>", pairs + "</mujoco>")


def test_robot_init_finds_the_soles_paired_with_the_floor(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """A pair-only biped: its soles are the foot geoms paired with the floor; the spec loads, and the robot stands on
    them (robot check's stand)."""
    spec = tmp_path / "biped.toml"
    code, out, err = run(capsys, "robot", "init", write(tmp_path, pair_biped()), "-o", spec, *SERVO_RULE)
    assert code == 0, err
    raw = tomllib.loads(spec.read_text())
    assert raw["legs"]["left"] == {"sole_geom": "left_sole"} and raw["floor_geom"] == "ground"
    code, out, _ = run(capsys, "robot", "check", spec, "--no-timestep")
    assert "stand: ok" in out, out


def test_robot_init_on_exo_as_pairs_finds_its_spec(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    floor_pairs_xml(tmp_path / "exo_pairs.xml")
    spec = tmp_path / "exo.toml"
    code, _, err = run(capsys, "robot", "init", tmp_path / "exo_pairs.xml", "-o", spec, *SERVO_RULE)
    assert code == 0, err
    raw = tomllib.loads(spec.read_text())
    shipped = tomllib.loads(EXO_XML.with_name("spec.toml").read_text())
    assert raw["legs"] == shipped["legs"] and raw["floor_geom"] == "floor" and raw["mirror"] == shipped["mirror"]


@pytest.mark.parametrize(("floor", "message"), [
    ("other sole", "does not collide with the left sole's geoms (contype/conaffinity, or a <pair>)"),
    ("no floor", "add_floor: the soles' geoms touch only what a <pair> names"),
])
def test_pairs_that_miss_the_floor_are_refused(tmp_path: Path, capsys: pytest.CaptureFixture[str], floor: str,
                                               message: str) -> None:
    """Soles paired with each other only, or with no floor in the model: the robot would fall through the floor."""
    xml = pair_biped("other sole")
    if floor == "no floor":
        xml = xml.replace('<geom name="ground" type="plane" size="0 0 0.05"/>', "")
        assert 'type="plane"' not in xml
    spec = tmp_path / "spec.toml"
    code, _, err = run(capsys, "robot", "init", write(tmp_path, xml), "-o", spec, *SERVO_RULE)
    assert code == 2 and err.count("\n") == 1 and message in err, err
    assert not spec.exists()

