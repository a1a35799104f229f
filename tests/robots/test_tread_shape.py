"""A tread that is not a rectangle (robustgait.robots.soles.tread_problem, docs/robots.md, "Soles, floor, URDF"): the
planner keeps the centre of pressure in the rectangle around the sole's ground points, so a tread whose contact
polygon covers much less of it — Unitree H1's heel point and toe bar, a triangle — is refused in one line naming
the shape and what to change, by robot init and by the loader; rectangles, disks and trapezoids are kept."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from robustgait import load_robot
from robustgait.errors import RobustGaitError
from robustgait.robots.soles import MIN_TREAD_FILL, tread_fill, tread_problem
from tests.inspection.biped import FEET, SERVO_RULE, biped_xml, run, write

# Unitree H1's foot in small: a short heel capsule on the foot's centre line and a toe bar across it
TRIANGLE = ('<geom class="foot" type="capsule" size="0.01" fromto="-0.06 0 -0.05 -0.02 0 -0.05"/>'
            '<geom class="foot" type="capsule" size="0.01" fromto="0.12 -0.04 -0.05 0.12 0.04 -0.05"/>')


def triangle_feet_xml() -> str:
    return biped_xml(foot="capsules").replace(FEET["capsules"], TRIANGLE)


def test_the_fill_of_shapes() -> None:
    corners = np.array([[0, 0], [0.2, 0], [0, 0.1], [0.2, 0.1], [0.1, 0.05]])
    assert tread_fill(corners) == pytest.approx(1.0)
    assert tread_fill(np.array([[0, 0.05], [0.2, 0], [0.2, 0.1]])) == pytest.approx(0.5)
    rim = [(math.cos(a), math.sin(a)) for a in np.linspace(0, 2 * math.pi, 8, endpoint=False)]
    assert tread_fill(np.array(rim)) > MIN_TREAD_FILL  # a disk's rim points, whatever their phase
    assert tread_fill(np.array([(math.cos(a), math.sin(a)) for a, _ in zip(np.linspace(0.39, 7, 8), rim,
                                                                             strict=True)])) > MIN_TREAD_FILL
    trapezoid = np.array([[0, 0.0375], [0, 0.0625], [0.2, 0], [0.2, 0.1]])  # the heel a quarter of the toe's width
    assert tread_fill(trapezoid) == pytest.approx(0.625) and tread_problem("left", "x", trapezoid) is None
    assert tread_fill(np.array([[0, 0], [0.1, 0], [0.2, 0]])) == 0.0  # a line: no area (refused elsewhere)


def test_robot_init_refuses_a_triangular_tread_in_one_line(tmp_path: Path,
                                                          capsys: pytest.CaptureFixture[str]) -> None:
    model = write(tmp_path, triangle_feet_xml())
    spec = tmp_path / "biped.toml"
    code, _, err = run(capsys, "robot", "init", model, "-o", spec, *SERVO_RULE)
    line = err.strip()
    assert code == 2 and not spec.exists() and "\n" not in line
    assert "the left sole (2 geoms of body 'left_foot') is not a rectangle: its contact polygon covers 50 %" in line
    assert "add a box geom under the foot spanning its tread" in line and "legs.left.sole_geom" in line


def test_the_loader_refuses_it_too(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    model = write(tmp_path, biped_xml(foot="capsules"))  # two capsules along the foot: a rectangle
    spec = tmp_path / "biped.toml"
    code, _, err = run(capsys, "robot", "init", model, "-o", spec, *SERVO_RULE)
    assert code == 0, err
    load_robot(spec)
    write(tmp_path, triangle_feet_xml())  # the same file, its feet now triangles
    with pytest.raises(RobustGaitError, match=r"the left sole .* is not a rectangle: its contact polygon covers 50 %"):
        load_robot(spec)
