"""The mirror (robustgait.inspection.mirror): partners by name, signs by axes, asymmetries of the model, on synthetic
bipeds written here (tests/inspection/biped.py)."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

from robustgait.config import RobotConfig
from robustgait.errors import RobustGaitError
from robustgait.inspection.mirror import Mirror, find_mirror, fk_residual, name_partner
from robustgait.inspection.model import open_model
from robustgait.robotinit.draft import draft_spec

if sys.version_info >= (3, 11):
    pass
else:  # pragma: no cover - exercised on 3.10 only
    pass
from tests.inspection.biped import biped_xml, body, write


def test_name_partners() -> None:
    names = ["Left_Hip_Pitch", "Right_Hip_Pitch", "LL_HR", "LR_HR", "leg_left_1_joint", "leg_right_1_joint",
             "l_hip", "r_hip", "AL1", "AR1", "waist"]
    assert name_partner("Left_Hip_Pitch", names) == ("Right_Hip_Pitch", "left")
    assert name_partner("LR_HR", names) == ("LL_HR", "right")
    assert name_partner("leg_left_1_joint", names) == ("leg_right_1_joint", "left")
    assert name_partner("r_hip", names) == ("l_hip", "right")
    assert name_partner("AL1", names) == ("AR1", "left")
    assert name_partner("waist", names) is None


def test_a_model_files_rounding_is_not_an_asymmetry(tmp_path: Path) -> None:
    """Both legs 0.7 mm to the left (PNDbotics Adam Lite's torso sits 0.5 mm off the plane): each hip roll's axis line
    1.4 mm from the other's reflection, within robot.mirror_tolerance (2 mm); 5 mm is refused, saying the
    tolerance."""
    def shifted(dy: float) -> str:
        return biped_xml().replace('pos="0 0.09 -0.05"', f'pos="0 {0.09 + dy:g} -0.05"').replace(
            'pos="0 -0.09 -0.05"', f'pos="0 {-0.09 + dy:g} -0.05"')
    assert 'pos="0 0.0907 -0.05"' in shifted(0.0007)
    draft_spec(write(tmp_path, shifted(0.0007)), RobotConfig())
    with pytest.raises(RobustGaitError, match=r"anchor 10.00 mm from the reflected one, tolerance 2 mm"):
        draft_spec(write(tmp_path, shifted(0.005), "far.xml"), RobotConfig())


def test_mirror_signs_follow_the_axes_and_reflect_the_model(tmp_path: Path) -> None:
    r = open_model(write(tmp_path, biped_xml()))
    mirror = find_mirror(r, 1e-3)
    sign = {r.joint_name(j): mirror.sign[j] for j in r.joints}
    partner = {r.joint_name(j): r.joint_name(k) for j, k in mirror.partner.items()}
    # yaw: a z axis reflects to −S z = −z, the partner's axis is +z: −1; the right roll axis is −x = −S x: +1
    assert sign["left_hip_yaw"] == -1 and sign["left_hip_roll"] == 1 and sign["left_hip_pitch"] == 1
    assert sign["waist_yaw"] == -1 and partner["waist_yaw"] == "waist_yaw" and sign["left_shoulder"] == 1
    assert partner["left_knee"] == "right_knee" and partner["right_elbow"] == "left_elbow"
    res = fk_residual(r, mirror, 10, 0)
    assert res.position < 1e-12 and res.angle < 1e-6
    # a wrong sign moves bodies far from their partners' reflections
    knee = next(j for j in r.joints if r.joint_name(j) == "left_knee")
    bad = Mirror(mirror.partner, {**mirror.sign, knee: -1.0, mirror.partner[knee]: -1.0}, mirror.body_partner)
    assert fk_residual(r, bad, 10, 0).position > 0.05


def test_a_joint_on_the_plane_is_its_own_partner_wherever_its_frame_sits(tmp_path: Path) -> None:
    """A head's tilt hinge mounted on one side of its bracket (Robotis OP3): its frame 2 cm off the sagittal plane,
    its axis along y — the line S maps onto itself, so the joint is its own partner, and the reflection is verified
    (the frame's offset is a constant of the body); a wrong sign is still caught. The neck's yaw shares its vertical
    line with the waist's: each is its own partner, not the other's."""
    tilt = body("head_tilt_link", "head_tilt", "0 -1 0", "-1 1", 0.3, "0 -0.019 0.03", "0.001 0.001 0.001",
                '<geom type="sphere" size="0.06" pos="0 -0.019 0.03"/>', pos="0.01 0.019 0.03")
    r = open_model(write(tmp_path, biped_xml().replace('<geom type="sphere" size="0.08" pos="0 0 0.08"/>', tilt)))
    mirror = find_mirror(r, 1e-3)
    ids = {r.joint_name(j): j for j in r.joints}
    assert mirror.partner[ids["head_tilt"]] == ids["head_tilt"] and mirror.sign[ids["head_tilt"]] == 1
    assert mirror.partner[ids["neck_yaw"]] == ids["neck_yaw"] and mirror.partner[ids["waist_yaw"]] == ids["waist_yaw"]
    res = fk_residual(r, mirror, 10, 0)
    assert res.position < 1e-9 and res.angle < 1e-6
    bad = Mirror(mirror.partner, {**mirror.sign, ids["head_tilt"]: -1.0}, mirror.body_partner)
    assert fk_residual(r, bad, 10, 0).angle > 0.1                   # tilted the other way
