"""Disturbances of a validation: what is drawn per trial, and how it enters the batched engine.

Every kind draws one scalar *size* per trial (the x axis of "success against disturbance size") and the
other parameters of the trial from ``numpy.random.default_rng((seed, kind index))`` alone — not from the
gait — so validating many gaits with one config puts every gait through the same disturbances (common
random numbers). Realizations that are drawn per physics step or per ground tile (noise, terrain) are laid
out so that a longer step or a longer terrain only appends numbers: the first ones stay the same. Ranges
are fields of :class:`ValidateConfig` (documented in ``docs/validation.md``).

How each kind reaches MuJoCo (:class:`robustgait.sim.StepInputs`):

* ``push``: a horizontal force on the floating base at its centre of mass (``xfrc_applied``) for
  ``push_duration`` seconds, starting at a random phase of the first step. Impulse J ∈ [0, m Δv_max]
  (m = the robot's mass, so Δv_max is the velocity change of the whole robot); F = J / duration. The
  window is cut at the step's switching event (the next step gets no force).
* ``mass``: severity s ∈ [0, 1]; the base body (pelvis + passenger trunk) mass × (1 ± s·mass_max), its
  centre of mass shifted by s·com_offset_max in a random horizontal direction, and every body's inertia
  × (1 + s·inertia_max·u), u ∈ [−1, 1] per body. One model per trial (``mj_setConst`` recomputes the
  derived constants).
* ``friction``: sliding friction μ of every geom and every explicit contact pair.
* ``latency``: the joint command stream delayed by d seconds (whole physics steps): c(t − d) instead of
  c(t), the previous step's command tail for t < d. See ``docs/validation.md`` for why this and not
  MuJoCo's actuator ``delay``.
* ``noise``: joint-encoder noise n_q ~ N(0, σ_q²) and velocity noise n_v ~ N(0, (ratio σ_q)²), i.i.d. per
  physics step and joint, read by the tracking law: in the servo law u = kp (c − q̃) − kd q̃̇ with q̃ = q + n_q,
  q̃̇ = q̇ + n_v it is exactly the control offset −(n_q + (kd/kp) n_v); a state-feedback law (the passivity-based
  one) is evaluated at the noisy joint state.
* ``terrain``: the ground becomes boxes: flat under the start, then square tiles of ``terrain_tile``
  metres, each with a random height and slope, within ±A (A the trial's amplitude) — step changes between
  tiles and slopes on them. Every tile takes the floor's contact properties and its explicit contact pairs (a
  ``<pair>`` of the floor and a sole becomes one per tile), so the ground touches what the floor touched. The
  contact sensors count contacts with any ground box (the world body), so sole–ground contacts are footfalls and
  any other ground contact is a fall, as on the flat floor.
* ``slope``: smooth ground (no edge) inclined by θ ∈ [0, ``slope_max``] whose downhill direction makes the angle
  φ with the heading of the fixed point (φ = 0: downhill ahead; π: uphill; ±π/2: sideways). Simulated exactly as
  a rigid rotation of the world: the floor stays the plane z = 0 and gravity is tilted by θ towards the downhill
  direction, g = |g| (sin θ d − cos θ e_z), so the trial starts from the fixed point's state lying on the slope
  and the fall criteria are measured relative to the ground (base height above it, tilt from its normal).
  One model per trial (only ``opt.gravity`` differs).
"""

from __future__ import annotations

import copy
import math
from dataclasses import dataclass

import mujoco
import numpy as np
from numpy.typing import NDArray

from robustgait.config import KINDS, ValidateConfig
from robustgait.errors import RobustGaitError
from robustgait.robots import Robot
from robustgait.robots.model import CONTACT_SENSORS
from robustgait.robots.soles import paired_names, spec_collides
from robustgait.sim.trials import wrench_window

# name and unit of the size axis of each kind
SIZE_LABELS = {
    "push": ("impulse", "N s"),
    "mass": ("severity", "1"),
    "friction": ("friction coefficient", "1"),
    "latency": ("command delay", "s"),
    "noise": ("encoder noise σ_q", "rad"),
    "terrain": ("terrain amplitude", "m"),
    "slope": ("slope angle", "deg"),
}
FloatArray = NDArray[np.float64]


@dataclass
class Draws:
    """The drawn disturbances of one kind: ``size`` (N,) and named per-trial parameters (arrays, N first)."""

    kind: str
    size: FloatArray
    params: dict[str, FloatArray]


def draw(kind: str, n: int, config: ValidateConfig, robot: Robot) -> Draws:
    """Per-trial parameters of ``kind`` from (seed, kind) alone (module docstring)."""
    if kind not in KINDS:
        raise RobustGaitError(f"unknown disturbance {kind!r} (choose from {', '.join(KINDS)} or all)")
    rng = np.random.default_rng((config.seed, KINDS.index(kind)))
    if kind == "push":
        size = rng.uniform(0.0, robot.mass * config.push_dv_max, n)
        return Draws(kind, size, {"direction": rng.uniform(0.0, 2 * math.pi, n),
                                  "phase": rng.uniform(*config.push_phase, n)})
    if kind == "mass":
        size = rng.uniform(0.0, 1.0, n)
        return Draws(kind, size, {"sign": rng.choice([-1.0, 1.0], n), "com_direction": rng.uniform(0, 2 * math.pi, n),
                                  "inertia_u": rng.uniform(-1.0, 1.0, (n, robot.model.nbody))})
    if kind == "friction":
        return Draws(kind, rng.uniform(*config.friction_range, n), {})
    if kind == "latency":
        return Draws(kind, rng.uniform(0.0, config.latency_max, n), {})
    if kind == "noise":
        return Draws(kind, rng.uniform(0.0, config.noise_q_max, n), {})
    if kind == "slope":
        return Draws(kind, rng.uniform(0.0, config.slope_max, n), {"direction": rng.uniform(0.0, 2 * math.pi, n)})
    seeds = rng.integers(0, 2**31, n).astype(np.float64)
    return Draws(kind, rng.uniform(0.0, config.terrain_max, n), {"terrain_seed": seeds})


def push_wrench(draws: Draws, duration: float, period: float, dt: float, horizon: int) -> FloatArray:
    """Base wrench series (N, horizon, 6) of pushes: force J/duration along the drawn direction over
    round(duration/dt) physics steps from step round(phase·period/dt)."""
    width = max(1, round(duration / dt))
    force = draws.size / (width * dt)
    th = draws.params["direction"]
    start = np.round(draws.params["phase"] * period / dt).astype(int)
    # math.cos/sin per push, not numpy's: the forces stay bit-identical to every stored validation
    xy = np.array([[f * math.cos(t), f * math.sin(t)] for f, t in zip(force, th, strict=True)]).reshape(-1, 2)
    return wrench_window(xy, start, width, horizon)


def physics_spec(robot: Robot) -> mujoco.MjSpec:
    """The robot's MjSpec without geoms that neither collide nor carry mass (visual meshes): per-trial model
    copies stay small. A geom an explicit contact pair names collides (:func:`robustgait.robots.soles.spec_collides`)
    and stays, with its pair. The dynamics are unchanged (checked in :func:`physics_model`)."""
    mjs = robot.mjspec()
    paired = paired_names(mjs)
    for g in list(mjs.geoms):
        if not spec_collides(g, paired):
            mjs.delete(g)
    for mesh in list(mjs.meshes):
        if not any(g.meshname == mesh.name for g in mjs.geoms):
            mjs.delete(mesh)
    return mjs


def physics_model(robot: Robot, mjs: mujoco.MjSpec | None = None) -> mujoco.MjModel:
    """Compile :func:`physics_spec` (or ``mjs``) and check the masses and inertias equal the robot's."""
    m = (mjs or physics_spec(robot)).compile()
    r = robot.model
    for f in ("body_mass", "body_inertia", "body_ipos", "body_iquat"):
        if not np.array_equal(getattr(m, f), getattr(r, f)):
            raise RobustGaitError(f"{robot.name}: removing the visual geoms changed {f}; geoms with "
                                  "contype = conaffinity = 0 and in no <pair> must not carry mass")
    return m


def _set_const(m: mujoco.MjModel) -> mujoco.MjModel:
    mujoco.mj_setConst(m, mujoco.MjData(m))
    return m


def mass_models(base: mujoco.MjModel, robot: Robot, draws: Draws, config: ValidateConfig) -> list[mujoco.MjModel]:
    """One model per trial with the passenger mass, centre of mass and link inertias changed."""
    b = robot.base_body_id
    out = []
    for i, s in enumerate(draws.size):
        m = copy.copy(base)
        ratio = 1.0 + draws.params["sign"][i] * s * config.mass_max
        m.body_mass[b] *= ratio
        m.body_inertia[b] *= ratio
        th = draws.params["com_direction"][i]
        m.body_ipos[b, :2] += s * config.com_offset_max * np.array([math.cos(th), math.sin(th)])
        m.body_sameframe[b] = 0  # the inertial frame no longer coincides with the body frame (if it did)
        u = draws.params["inertia_u"][i]
        m.body_inertia[1:] *= (1.0 + s * config.inertia_max * u[1:])[:, None]
        out.append(_set_const(m))
    return out


def friction_models(base: mujoco.MjModel, draws: Draws) -> list[mujoco.MjModel]:
    """One model per trial with sliding friction μ on every geom and explicit contact pair."""
    out = []
    for mu in draws.size:
        m = copy.copy(base)
        m.geom_friction[:, 0] = mu
        if m.npair:
            m.pair_friction[:, :2] = mu
        out.append(m)
    return out


@dataclass(frozen=True)
class TerrainLayout:
    """Where the ground lies: a flat box with its top at z = 0 for x < ``rough_from`` (the floor geom, so its
    name and contact properties stay), then ``nx`` × ``ny`` square tiles of side ``tile`` [m] covering
    x ∈ [rough_from, rough_from + nx·tile], y ∈ [y0, y0 + ny·tile]; ``x0``: the back end of the flat part."""

    x0: float
    rough_from: float
    y0: float
    tile: float
    nx: int
    ny: int


TILE_HALF_THICKNESS = 0.25
# an explicit contact pair's own contact parameters (it does not mix its geoms'): a tile's copy of a floor pair has them
PAIR_FIELDS = ("condim", "friction", "solref", "solimp", "solreffriction", "margin", "gap", "adhesion")


def terrain_layout(robot: Robot, qpos: FloatArray, stance: str, config: ValidateConfig,
                   step_length: float) -> TerrainLayout:
    """Ground for a walk that starts from ``qpos`` (stance foot ``stance``): flat up to just past the stance
    sole's toe, tiles after it, 2 m wide and long enough for the trial's steps (with margin)."""
    m = robot.model
    d = mujoco.MjData(m)
    d.qpos[:] = qpos
    mujoco.mj_kinematics(m, d)
    g = robot.sole_geom_id[stance]
    sole = d.geom_xpos[g]
    toe = sole[0] + float(np.abs(d.geom_xmat[g].reshape(3, 3)[0, :] * m.geom_size[g]).sum())
    tile = config.terrain_tile
    length = 1.0 + (config.steps_after + 3) * max(step_length, 0.1) * 1.5
    n_y = math.ceil(2.0 / tile)
    return TerrainLayout(x0=float(sole[0]) - 1.0, rough_from=toe + 0.02, y0=float(qpos[1]) - n_y * tile / 2,
                         tile=tile, nx=math.ceil(length / tile), ny=n_y)


def _tile_name(i: int, j: int) -> str:
    return f"robustgait_tile_{i}_{j}"


def terrain_spec(robot: Robot, layout: TerrainLayout) -> mujoco.MjSpec:
    """:func:`physics_spec` on tiled ground (:class:`TerrainLayout`, all tiles flat at z = 0).

    Every ground geom is a box of the world body with the floor geom's contact properties (and its explicit
    contact pairs, repeated per tile); the contact sensors count contacts with the world body instead of
    the floor geom, so sole–ground contacts are footfalls and any other ground contact is a fall, as on the
    flat floor."""
    mjs = physics_spec(robot)
    floor = next(g for g in mjs.geoms if g.name == robot.floor_name)
    t = TILE_HALF_THICKNESS
    flat_half = (layout.rough_from - layout.x0) / 2
    floor.type = mujoco.mjtGeom.mjGEOM_BOX
    floor.size = [flat_half, layout.ny * layout.tile / 2, t]
    floor.pos = [layout.x0 + flat_half, layout.y0 + layout.ny * layout.tile / 2, -t]
    floor.quat = [1, 0, 0, 0]
    pairs = [p for p in mjs.pairs if robot.floor_name in (p.geomname1, p.geomname2)]
    for i in range(layout.nx):
        for j in range(layout.ny):
            name = _tile_name(i, j)
            tile = mjs.worldbody.add_geom(
                name=name, type=mujoco.mjtGeom.mjGEOM_BOX, size=[layout.tile / 2, layout.tile / 2, t],
                pos=[layout.rough_from + (i + 0.5) * layout.tile, layout.y0 + (j + 0.5) * layout.tile, -t],
                contype=floor.contype, conaffinity=floor.conaffinity, condim=floor.condim, friction=floor.friction,
                solref=floor.solref, solimp=floor.solimp, solmix=floor.solmix, priority=floor.priority,
                margin=floor.margin, gap=floor.gap, group=floor.group, rgba=[0.7, 0.7, 0.75, 1.0])
            assert tile is not None
            for p in pairs:
                other = p.geomname2 if p.geomname1 == robot.floor_name else p.geomname1
                twin = mjs.add_pair(geomname1=other, geomname2=name)
                for field in PAIR_FIELDS:
                    if hasattr(p, field):  # adhesion: MuJoCo ≥ 4 only
                        setattr(twin, field, getattr(p, field))
    for sensor in mjs.sensors:
        if sensor.name == CONTACT_SENSORS[2]:
            sensor.objtype, sensor.objname = mujoco.mjtObj.mjOBJ_BODY, "world"
        elif sensor.name in CONTACT_SENSORS:
            sensor.reftype, sensor.refname = mujoco.mjtObj.mjOBJ_BODY, "world"
    return mjs


def terrain_model(robot: Robot, layout: TerrainLayout) -> mujoco.MjModel:
    """The compiled :func:`terrain_spec` (flat)."""
    m = physics_model(robot, terrain_spec(robot, layout))
    # the tiles are compiled unrotated, which MuJoCo marks as "same orientation as the body" and then never
    # reads geom_quat: clear the mark so that per-trial slopes take effect
    for i in range(layout.nx):
        for j in range(layout.ny):
            m.geom_sameframe[m.geom(_tile_name(i, j)).id] = 0
    return m


def terrain_tiles(layout: TerrainLayout, amplitude: float, seed: int) -> tuple[FloatArray, FloatArray]:
    """Per tile (nx, ny): the height of its centre, uniform in ±2A/3, and its slopes (dh/dx, dh/dy), each
    changing the height by up to ±A/3 across the tile (so the ground stays within ±A).

    Tile (i, j) is drawn from the same numbers whatever ``nx`` (which grows with the gait's step length): all
    three values of a tile are drawn together, row by row, so gaits validated with one seed meet the same
    ground in front of them."""
    rng = np.random.default_rng(seed)
    u = rng.uniform(-1.0, 1.0, (layout.nx, layout.ny, 3))
    level = u[..., 0] * (2 * amplitude / 3)
    slope = u[..., 1:] * (amplitude / 3) / layout.tile
    return level, slope


def terrain_models(base: mujoco.MjModel, layout: TerrainLayout, draws: Draws) -> list[mujoco.MjModel]:
    """One model per trial (copies of ``base`` = :func:`terrain_model`) with its tiles raised and tilted."""
    ids = np.array([[base.geom(_tile_name(i, j)).id for j in range(layout.ny)] for i in range(layout.nx)])
    out = []
    for amp, seed in zip(draws.size, draws.params["terrain_seed"], strict=True):
        m = copy.copy(base)
        level, slope = terrain_tiles(layout, float(amp), int(seed))
        normal = np.concatenate([-slope, np.ones((*level.shape, 1))], axis=-1)
        normal /= np.linalg.norm(normal, axis=-1, keepdims=True)
        # rotation taking e_z to the normal: axis e_z × n, angle acos(n_z)
        axis = np.stack([-normal[..., 1], normal[..., 0], np.zeros(level.shape)], axis=-1)
        sin_t = np.linalg.norm(axis, axis=-1, keepdims=True)
        half = np.arccos(np.clip(normal[..., 2:], -1, 1)) / 2
        quat = np.concatenate([np.cos(half), np.sin(half) * axis / np.maximum(sin_t, 1e-12)], axis=-1)
        centre = m.geom_pos[ids].copy()
        centre[..., 2] = level
        m.geom_pos[ids] = centre - TILE_HALF_THICKNESS * normal
        m.geom_quat[ids] = quat
        out.append(m)
    return out


def slope_gravity(gravity: FloatArray, angle_deg: float, direction: float, heading: float) -> FloatArray:
    """Gravity (3,) of a slope of ``angle_deg`` whose downhill direction is ``direction`` [rad] from the heading
    ``heading`` [rad] (world yaw): |g| (sin θ d − cos θ e_z), d = (cos(ψ + φ), sin(ψ + φ), 0)."""
    th = math.radians(angle_deg)
    a = heading + direction
    return np.asarray(float(np.linalg.norm(gravity)) * np.array([math.sin(th) * math.cos(a),
                                                                  math.sin(th) * math.sin(a), -math.cos(th)]))


def slope_models(base: mujoco.MjModel, draws: Draws, heading: float) -> list[mujoco.MjModel]:
    """One model per trial (copies of ``base``) with gravity tilted by its slope (:func:`slope_gravity`)."""
    out = []
    for angle, direction in zip(draws.size, draws.params["direction"], strict=True):
        m = copy.copy(base)
        m.opt.gravity[:] = slope_gravity(base.opt.gravity, float(angle), float(direction), heading)
        out.append(m)
    return out


def latency_offsets(ctrl: FloatArray, prev_ctrl: FloatArray, delay_steps: NDArray[np.int64],
                    prev_at: NDArray[np.int64]) -> FloatArray:
    """Control offsets (K, H, nu) that turn this step's commands c_j (``ctrl`` (H, nu)) into the delayed
    c_{j−D}; for j < D the previous step's command c'_{a+j−D} (``prev_ctrl``, ``prev_at`` = the physics step
    of the previous step's switching event a). D = ``delay_steps`` per sample."""
    h = ctrl.shape[0]
    j = np.arange(h)[None, :] - delay_steps[:, None]  # (K, H)
    cur = ctrl[np.clip(j, 0, h - 1)]
    prev = prev_ctrl[np.clip(prev_at[:, None] + j, 0, prev_ctrl.shape[0] - 1)]
    delayed = np.where((j >= 0)[..., None], cur, prev)
    return np.asarray(delayed - ctrl[None])


def noise_draws(robot: Robot, sigma_q: FloatArray, ratio: float, horizon: int, seed: int, kind_step: int
                ) -> FloatArray:
    """Encoder noise (K, H, 2, nu): n_q ~ N(0, σ_q²) and n_v ~ N(0, (ratio σ_q)²) per trial, physics step and joint,
    from (seed, step) alone — :attr:`~robustgait.sim.engine.StepInputs.sensor_noise`, which the PD servos take as
    the control offset −(n_q + (kd/kp) n_v) and a state-feedback law reads with the joint state.

    The numbers are drawn time-major ((H, 2, K, nu): physics step first), so the noise of trial i at physics
    step j does not depend on the horizon H, which grows with the gait's step duration: gaits validated with
    one seed get the same noise sequence."""
    rng = np.random.default_rng((seed, KINDS.index("noise"), kind_step))
    k, nu = sigma_q.size, robot.model.nu  # every servo: planned and held joints
    white = rng.standard_normal((horizon, 2, k, nu)).transpose(2, 0, 1, 3)  # (K, H, 2, nu)
    scale = np.array([1.0, ratio])[None, None, :, None] * sigma_q[:, None, None, None]
    return np.asarray(scale * white)
