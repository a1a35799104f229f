"""A tread that is not a rectangle (robustgait.robots.soles.tread_fill and line_chord, docs/robots.md, "Foot
kinds"): the planner keeps a flat sole's centre of pressure in the rectangle around its ground points, so a tread whose
contact polygon covers much less of it — Unitree H1's heel point and toe bar, a triangle — is no flat sole. robot init
plans it as a line foot on its longest chord along the foot (inside the polygon over its whole length), and the loader
refuses it as a flat sole in one line naming the shape and what to change; rectangles, disks and trapezoids are flat
soles."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from robustgait import load_robot
from robustgait.errors import RobustGaitError
from robustgait.robots.soles import LINE_HALF_WIDTH, MIN_TREAD_FILL, line_chord, tread_fill, tread_problem
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


def test_the_longest_chord_lies_inside_the_tread() -> None:
    triangle = np.array([[-0.06, 0.0], [-0.02, 0.0], [0.12, -0.04], [0.12, 0.04]])  # a heel point, a toe bar
    chord = line_chord(triangle)
    assert (chord.start, chord.end, chord.across) == pytest.approx((-0.06, 0.12, 0.0), abs=1e-9)
    # off the heel's line the chord is shorter: it starts where the polygon is that wide
    assert line_chord(triangle + np.array([0.0, 0.01])).across == pytest.approx(0.01, abs=1e-9)
    rectangle = np.array([[0, 0], [0.2, 0], [0, 0.1], [0.2, 0.1]])
    assert tuple(line_chord(rectangle)) == pytest.approx((0.0, 0.2, 0.05), abs=1e-9)  # every chord as long: the middle
    skewed = np.array([[0.0, 0.0], [0.1, 0.0], [0.2, 0.1], [0.0, 0.1]])  # a trapezoid: its long side is the chord
    assert tuple(line_chord(skewed)) == pytest.approx((0.0, 0.2, 0.1), abs=1e-9)
    assert tuple(line_chord(np.array([[0.0, 0.01], [0.1, 0.01], [0.2, 0.01]]))) == pytest.approx((0.0, 0.2, 0.01))


def test_robot_init_plans_a_triangular_tread_as_a_line_foot(tmp_path: Path,
                                                          capsys: pytest.CaptureFixture[str]) -> None:
    model = write(tmp_path, triangle_feet_xml())
    spec = tmp_path / "biped.toml"
    code, _, err = run(capsys, "robot", "init", model, "-o", spec, *SERVO_RULE)
    assert code == 0, err
    text = spec.read_text()
    assert 'foot = "line"  # its contact polygon covers 50 % of the rectangle around it' in text
    assert "planned on its longest chord along the foot, 0.18 m" in text
    robot = load_robot(spec)
    for side in ("left", "right"):  # the sole box is the chord: heel to toe bar on the foot's centre line
        box = robot.sole_boxes[side]
        assert box.half_length == pytest.approx(0.09, abs=1e-6) and box.half_width == pytest.approx(LINE_HALF_WIDTH)
        centre = robot.model.geom_pos[robot.sole_geom_id[side]]
        assert centre[:2] == pytest.approx([0.03, 0.0], abs=1e-6)


def test_the_loader_refuses_it_as_a_flat_sole(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    model = write(tmp_path, biped_xml(foot="capsules"))  # two capsules along the foot: a rectangle
    spec = tmp_path / "biped.toml"
    code, _, err = run(capsys, "robot", "init", model, "-o", spec, *SERVO_RULE)
    assert code == 0, err
    load_robot(spec)
    write(tmp_path, triangle_feet_xml())  # the same file, its feet now triangles
    with pytest.raises(RobustGaitError, match=r"the left sole .* is not a rectangle: its contact polygon covers 50 %"
                       r".*legs\.left\.foot = \"line\""):
        load_robot(spec)
