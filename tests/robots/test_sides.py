"""Whether a robot's left and right differ (robustgait.robots.sides, Robot.sides_differ): the body pairs' masses and
inertias, and the soles' sizes, on the synthetic biped of tests/inspection/biped.py."""

from __future__ import annotations

from pathlib import Path

import pytest

from robustgait import load_robot
from robustgait.cli import main
from robustgait.config import RobotConfig
from robustgait.inspection.mirror import find_mirror
from robustgait.inspection.model import open_model
from robustgait.robots.sides import mass_asymmetry
from tests.inspection.biped import SERVO_RULE, biped_xml, write

SHIN = 'mass="2.0" diaginertia="0.02 0.02 0.002"'


def shin(xml: str, side: str, replacement: str) -> str:
    """``xml`` with the ``side`` shin's mass and inertia replaced."""
    at = xml.index(SHIN, xml.index(f'name="{side}_shin"'))
    return xml[:at] + replacement + xml[at + len(SHIN):]


def test_mass_asymmetry_finds_the_side_that_differs(tmp_path: Path) -> None:
    """A model whose kinematics reflect exactly can still differ left to right in its masses (T1's shanks, 60 g):
    found pair by pair, the lighter body named — and a difference at the level of a model file's rounding (half a
    milligram, an inertia 0.5 % apart) is not a difference: certified on the step map."""
    tol = (RobotConfig().side_mass_tolerance, RobotConfig().side_inertia_tolerance)
    xml = biped_xml()
    r = open_model(write(tmp_path, xml))
    same = mass_asymmetry(r.model, r.base, find_mirror(r, 1e-3).body_partner)
    assert same.mass == 0 and same.inertia == 0 and "same masses" in same.describe(r.model, *tol)
    assert not same.differs(*tol)
    at = xml.index('name="right_shin"')
    at = xml.index('mass="2.0"', at)
    rounding = xml[:at] + 'mass="2.0000005" diaginertia="0.0201 0.02 0.002"' + xml[
        at + len('mass="2.0" diaginertia="0.02 0.02 0.002"'):]
    r = open_model(write(tmp_path, rounding, "rounding.xml"))
    tiny = mass_asymmetry(r.model, r.base, find_mirror(r, 1e-3).body_partner)
    assert tiny.mass == pytest.approx(5e-7) and tiny.inertia == pytest.approx(0.0001 / 0.0201)
    assert not tiny.differs(*tol) and "the same within the tolerance" in tiny.describe(r.model, *tol)
    assert "certified on the step map" in tiny.describe(r.model, *tol)
    at = xml.index('name="right_shin"')
    at = xml.index('mass="2.0"', at)
    heavier = xml[:at] + 'mass="2.06" diaginertia="0.021 0.02 0.002"' + xml[at + len('mass="2.0" diaginertia="0.02 '
                                                                                       '0.02 0.002"'):]
    r = open_model(write(tmp_path, heavier, "heavier.xml"))
    asym = mass_asymmetry(r.model, r.base, find_mirror(r, 1e-3).body_partner)
    assert asym.mass == pytest.approx(0.06) and asym.inertia == pytest.approx(0.001 / 0.021)
    assert r.body_name(asym.body) == "left_shin" and r.body_name(asym.partner) == "right_shin"
    assert asym.differs(*tol) and "'left_shin' is 60 g lighter than 'right_shin'" in asym.describe(r.model, *tol)
    assert "certified on the stride map" in asym.describe(r.model, *tol)


def test_the_loaded_robot_says_whether_its_sides_differ(tmp_path: Path) -> None:
    """Robot.sides_differ, what the certificate's orbit search reads: the biped's sides are alike; a shin 60 g heavier
    than its partner, or a right sole box 1 cm wider than the left, makes them differ (the defaults read the right
    sole for both)."""
    xml = biped_xml()
    cases = {"same": xml, "heavier": shin(xml, "right", 'mass="2.06" diaginertia="0.021 0.02 0.002"'),
             "wider": xml.replace('<geom name="right_sole" type="box" size="0.1 0.05 0.01"',
                                  '<geom name="right_sole" type="box" size="0.1 0.055 0.01"')}
    assert cases["wider"] != xml
    for name, text in cases.items():
        spec = tmp_path / f"{name}.toml"
        assert main(["robot", "init", str(write(tmp_path, text, f"{name}.xml")), "-o", str(spec), *SERVO_RULE]) == 0
        assert load_robot(spec).sides_differ == (name != "same"), name
