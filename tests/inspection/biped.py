"""The synthetic bipeds the inspection and robot init tests write (MJCF and URDF), and their shared helpers."""

from __future__ import annotations

import sys
import textwrap
from pathlib import Path

import pytest

from robustgait.cli import main

if sys.version_info >= (3, 11):
    pass
else:  # pragma: no cover - exercised on 3.10 only
    pass

REPO = Path(__file__).resolve().parents[2]
T1 = REPO.parent / "shared" / "robots" / "booster_t1" / "t1.xml"
EXO_XML = REPO / "src" / "robustgait" / "robots" / "exo" / "exo.xml"
# robot init's servo timestep rule, which walks no gait (the accuracy rule's tests: tests/robotinit/test_timestep.py),
# and robot check without the timestep check (which generates the default gait)
SERVO_RULE = ("--timestep-rule", "servo")
needs_t1 = pytest.mark.skipif(not T1.is_file(), reason="../shared/robots/booster_t1 (Booster T1) is not beside the "
                              "repository")

FEET = {
    "box": '<geom name="{s}_sole" type="box" size="0.1 0.05 0.01" pos="0.03 0 -0.05"/>',
    "unnamed_box": '<geom type="box" size="0.1 0.05 0.01" pos="0.03 0 -0.05"/>',
    "spheres": "".join(f'<geom class="foot" type="sphere" size="0.01" pos="{x} {y} -0.05"/>'
                       for x in (-0.06, 0.12) for y in (-0.04, 0.04)),
    "capsules": "".join(f'<geom class="foot" type="capsule" size="0.01" fromto="-0.06 {y} -0.05 0.12 {y} -0.05"/>'
                        for y in (-0.04, 0.04)),
    # two cylinders lying along the foot (PNDbotics Adam Lite's feet): their lowest lines are the sole
    "cylinders": "".join(f'<geom class="foot" type="cylinder" size="0.01" fromto="-0.06 {y} -0.05 0.12 {y} -0.05"/>'
                         for y in (-0.04, 0.04)),
    # one cylinder standing on its end: its bottom disk is the sole
    "puck": '<geom class="foot" type="cylinder" size="0.05 0.01" pos="0.03 0 -0.05"/>',
    # a box sole and a higher cylinder (an ankle guard) of another class: the sole is the box's class
    "box_and_cylinder": ('<geom class="foot" type="box" size="0.1 0.05 0.01" pos="0.03 0 -0.05"/>'
                         '<geom type="cylinder" size="0.03 0.02" pos="0 0 0"/>'),
    # a mesh (a pyramid on its base): the sole is its convex hull's bottom face
    "mesh": '<geom type="mesh" mesh="footmesh"/>',
    "ellipsoid": '<geom type="ellipsoid" size="0.1 0.05 0.01" pos="0.03 0 -0.05"/>',
    # the box sole pitched 0.01 rad in its foot's frame (a CAD export's foot plate)
    "tilted_box": '<geom name="{s}_sole" type="box" size="0.1 0.05 0.01" pos="0.03 0 -0.05" euler="0 0.01 0"/>',
    # a toe on its own hinge, its box level with the foot's
    "toe": ('<geom name="{s}_sole" type="box" size="0.06 0.05 0.01" pos="-0.01 0 -0.05"/>'
            '<body name="{s}_toe" pos="0.05 0 0"><joint name="{s}_toe" axis="0 1 0" range="-0.5 0.5"/>'
            '<inertial pos="0.03 0 -0.05" mass="0.1" diaginertia="0.0001 0.0001 0.0001"/>'
            '<geom type="box" size="0.04 0.05 0.01" pos="0.04 0 -0.05"/></body>'),
    "none": "",
}


def body(name: str, joint: str, axis: str, limits: str, mass: float, com: str, inertia: str, inner: str = "",
         pos: str = "0 0 0", extra: str = "") -> str:
    """One MJCF body on one hinge: its inertial, then ``inner`` (geoms, child bodies)."""
    return (f'<body name="{name}" pos="{pos}"><joint name="{joint}" axis="{axis}" range="{limits}" {extra}/>'
            f'<inertial pos="{com}" mass="{mass}" diaginertia="{inertia}"/>{inner}</body>')


def leg(s: str, y: float, foot: str, roll_axis: str, short: float = 0.0, ankle_roll: bool = True) -> str:
    """A 6-joint leg (hip yaw, roll, pitch, knee, ankle pitch, roll) hanging from the waist at lateral offset y;
    without ``ankle_roll`` 5 joints, the foot on the ankle pitch (its body and the foot's as one, 1 kg)."""
    def frc(limit: int) -> str:
        return f'actuatorfrcrange="-{limit} {limit}"'

    if ankle_roll:
        foot_body = body(f"{s}_foot", f"{s}_ankle_roll", "1 0 0", "-0.5 0.5", 0.8, "0.02 0 -0.03",
                         "0.002 0.004 0.004", FEET[foot].format(s=s), extra=frc(40))
        ankle = body(f"{s}_ankle", f"{s}_ankle_pitch", "0 1 0", "-1 1", 0.2, "0 0 0", "0.0002 0.0002 0.0002",
                     foot_body, pos="0 0 -0.3", extra=frc(50))
    else:
        ankle = body(f"{s}_ankle", f"{s}_ankle_pitch", "0 1 0", "-1 1", 1.0, "0.02 0 -0.03", "0.002 0.004 0.004",
                     FEET[foot].format(s=s), pos="0 0 -0.3", extra=frc(50))
    shin = body(f"{s}_shin", f"{s}_knee", "0 1 0", "0 2.2", 2.0, "0 0 -0.15", "0.02 0.02 0.002",
                '<geom type="capsule" fromto="0 0 -0.02 0 0 -0.26" size="0.035"/>' + ankle, pos=f"0 0 {-0.3 + short}",
                extra=frc(100))
    thigh = body(f"{s}_thigh", f"{s}_hip_pitch", "0 1 0", "-1.5 1.5", 3.0, "0 0 -0.15", "0.03 0.03 0.004",
                 '<geom type="capsule" fromto="0 0 0 0 0 -0.3" size="0.04"/>' + shin,
                 extra=frc(80) + ' armature="0.01"')
    hip2 = body(f"{s}_hip2", f"{s}_hip_roll", roll_axis, "-0.5 0.5", 0.5, "0 0 0", "0.001 0.001 0.001", thigh,
                extra=frc(80))
    return body(f"{s}_hip", f"{s}_hip_yaw", "0 0 1", "-0.5 0.5", 1.0, "0 0 0", "0.002 0.002 0.002", hip2,
                pos=f"0 {y} -0.05", extra=frc(60))


def arm(s: str, y: float) -> str:
    forearm = body(f"{s}_forearm", f"{s}_elbow", "0 1 0", "-2 0", 0.6, "0 0 -0.1", "0.002 0.002 0.0005",
                   '<geom type="capsule" fromto="0 0 0 0 0 -0.2" size="0.025"/>', pos="0 0 -0.25")
    return body(f"{s}_upper_arm", f"{s}_shoulder", "0 1 0", "-2 2", 1.0, "0 0 -0.12", "0.005 0.005 0.001",
                '<geom type="capsule" fromto="0 0 0 0 0 -0.24" size="0.03"/>' + forearm, pos=f"0 {y} 0.25")


def biped_xml(*, foot: str = "box", floor: bool = True, keyframe: bool = True, freejoint: bool = True,
              legs: tuple[str, ...] = ("left", "right"), right_short: float = 0.0, waist: float = 0.0,
              collide: bool = True, ankle_roll: bool = True) -> str:
    """A 20 kg humanoid: torso with a head (neck yaw) and two 2-joint arms, a waist (yaw) carrying two 6-joint legs
    (``ankle_roll`` false: 5-joint legs, as Unitree H1's). The right hip roll's axis points the other way (-x), as
    some models have it. Torque limits: the legs' from actuatorfrcrange, the arms' and neck's from motors' ctrlrange,
    the waist's from a position actuator's forcerange × gear."""
    sides = {"left": 0.09, "right": -0.09}
    axes = {"left": "1 0 0", "right": "-1 0 0"}
    legs_xml = "".join(leg(s, sides[s], foot, axes[s], right_short if s == "right" else 0.0, ankle_roll)
                       for s in legs)
    pose = "0 0 -0.3 0.6 -0.3" + (" 0" if ankle_roll else "")
    key = (f'<keyframe><key name="stand" qpos="0 0 0.9 1 0 0 0  0  0.3 -0.5 0.3 -0.5  {waist}  '
           f'{pose}  {pose}"/></keyframe>') if keyframe and len(legs) == 2 else ""
    return textwrap.dedent(f"""\
        <mujoco model="Test Biped">
          <compiler angle="radian" autolimits="true"/>
          <option timestep="0.002" integrator="implicitfast"/>
          <asset><mesh name="footmesh" vertex="-0.08 -0.05 -0.06 0.12 -0.05 -0.06 0.12 0.05 -0.06 -0.08 0.05 -0.06
                                              0 0 -0.01"/></asset>
          <default>{'' if collide else '<geom contype="0" conaffinity="0"/>'}
            <default class="foot"><geom friction="1 0.005 0.0001"/></default></default>
          <worldbody>
            {'<geom name="ground" type="plane" size="0 0 0.05"/>' if floor else ''}
            <body name="torso" pos="0 0 0.9">
              {'<freejoint name="root"/>' if freejoint else ''}
              <inertial pos="0 0 0.15" mass="8.0" diaginertia="0.15 0.12 0.08"/>
              <geom type="box" size="0.08 0.12 0.15" pos="0 0 0.15"/>
              {body("head", "neck_yaw", "0 0 1", "-1 1", 1.0, "0 0 0.08", "0.004 0.004 0.004",
                    '<geom type="sphere" size="0.08" pos="0 0 0.08"/>', pos="0 0 0.32")}
              {arm("left", 0.15)}{arm("right", -0.15)}
              {body("waist", "waist_yaw", "0 0 1", "-1 1", 2.0, "0 0 0", "0.01 0.01 0.01", legs_xml,
                    pos="0 0 -0.05")}
            </body>
          </worldbody>
          <actuator>
            <motor joint="neck_yaw" ctrlrange="-5 5"/>
            <motor joint="left_shoulder" ctrlrange="-20 20"/>
            <motor joint="right_shoulder" ctrlrange="-20 20"/>
            <motor joint="left_elbow" ctrlrange="-10 10" gear="2"/>
            <motor joint="right_elbow" ctrlrange="-10 10" gear="2"/>
            <position joint="waist_yaw" kp="100" forcerange="-30 30"/>
          </actuator>
          {key}
        </mujoco>""")


def write(tmp_path: Path, text: str, name: str = "biped.xml") -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


def run(capsys: pytest.CaptureFixture[str], *argv: str | Path) -> tuple[int, str, str]:
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


LEFT_LEG = ["left_hip_yaw", "left_hip_roll", "left_hip_pitch", "left_knee", "left_ankle_pitch", "left_ankle_roll"]
