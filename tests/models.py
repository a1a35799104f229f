"""Robot variants built for tests and benchmarks from ../shared (never shipped): a user's robot with narrow feet."""

from __future__ import annotations

from pathlib import Path

# outer width of the narrow soles [m] and radius of their contact spheres [m]: the kind of sole a Menagerie humanoid
# brings (four small spheres per foot, 0.19 × 0.04 m)
NARROW_WIDTH = 0.04
SPHERE_RADIUS = 0.005
SPHERE_X = 0.095


def narrow_t1_xml(t1_xml: Path, out_dir: Path, width: float = NARROW_WIDTH) -> Path:
    """Booster T1 with each sole box replaced by four contact spheres (radius :data:`SPHERE_RADIUS`) at the corners of
    a 0.19 × ``width`` m footprint under the box (0.015: a line foot, its spheres 5 mm apart); writes
    ``out_dir/t1.xml`` and returns it."""
    import mujoco

    spec = mujoco.MjSpec.from_file(str(t1_xml))
    y = width / 2.0 - SPHERE_RADIUS
    for side in ("left", "right"):
        box = spec.geom(f"{side}_foot_box")
        x0, z = box.pos[0], box.pos[2] - box.size[2] + SPHERE_RADIUS
        for i, (dx, dy) in enumerate((a, b) for a in (-SPHERE_X, SPHERE_X) for b in (-y, y)):
            box.parent.add_geom(name=f"{side}_sole_ball{i}", type=mujoco.mjtGeom.mjGEOM_SPHERE,
                                size=[SPHERE_RADIUS, 0.0, 0.0], pos=[x0 + dx, dy, z])
        spec.delete(box)
    out_dir.mkdir(parents=True, exist_ok=True)
    path = out_dir / "t1.xml"
    path.write_text(spec.to_xml())
    return path
