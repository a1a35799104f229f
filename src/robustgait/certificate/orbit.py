"""The orbit a gait walks, from what the simulation does (``docs/certificate.md``, "The orbit the gait walks").

A walk's switching states, written for the gait's stance and in band coordinates (:mod:`.band`), are searched for
a **band they enter and stay in**: after each step the last two windows A and B of ``window`` steps each are
compared. For each candidate period k (physical steps: 1, 2, 4 … up to ``max_period``; at least 2 for a robot whose
left and right differ), a phase p holds the states after j steps with j ≡ p (mod k); the shortest period whose
scatter about its phase centres in B is within ``period_ratio`` of the best period's (plus ``floor``) is the orbit's
period. The walk has
**settled** when

* every state of B lies within max(``floor``, κ_s σ_A) of its phase's centre in A (B stays in A's band; σ_A the
  largest deviation of A's states from their phase centres, κ_s = ``settle_multiple``), and
* B's phase centres moved from A's by at most ``drift`` × max(``floor``, σ_B) (the band is not moving: a transient
  still converging moves its centre by more than its last window's own scatter, a noisy band by less).

The band is then B's: per phase its centre and per-coordinate scatter σ (:class:`.band.Band`); x* is B's state of
phase 0 nearest its centre, a state the simulation actually reached (for an even period, a state that starts a
step of the gait's own stance, unmirrored). A walk that falls, or whose band keeps growing or moving until
``max_steps``, has no orbit: :class:`Status` and a reason. Whether perturbed states come back (stability) is the
orbit search's (:mod:`.search`); this module is arithmetic on a sequence, used by the search and by every walk.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from robustgait.certificate.band import Band, band_coordinates
from robustgait.certificate.reduced import reduce_state, section_dimension
from robustgait.config import CertifyConfig
from robustgait.config.base import TextEnum
from robustgait.config.certify import Frame, MapKind, OrbitConfig
from robustgait.errors import RobustGaitError
from robustgait.gait import Gait
from robustgait.robots import Robot
from robustgait.sim.walk import SwitchEvent, WalkResult

FloatArray = NDArray[np.float64]


class Status(TextEnum):
    """What a certificate or an orbit search concluded: ``ok``; ``fell`` (the undisturbed walk fell while its orbit
    was searched); ``unsettled`` (its band kept growing or moving: it drifts, turns or slowly falls); ``undecided``
    (a walk that ended before the rule could tell: too few steps — a walk's, never a certificate's); ``unstable``
    (it settled, but states perturbed from the band did not come back to it); ``unstable_fixed_point`` (a state
    certificate's reduced map falls from x̄* itself: through the reconstruction x̄* is not on a walking orbit)."""

    OK = "ok"
    FELL = "fell"
    UNSETTLED = "unsettled"
    UNDECIDED = "undecided"
    UNSTABLE = "unstable"
    UNSTABLE_FIXED_POINT = "unstable_fixed_point"


def periods(max_period: int, min_period: int = 1) -> tuple[int, ...]:
    """The candidate periods: powers of two from ``min_period`` to ``max_period``."""
    out, k = [], 1
    while k <= max_period:
        if k >= min_period:
            out.append(k)
        k *= 2
    return tuple(out)


def phase_stats(z: FloatArray, steps: NDArray[np.int64], k: int) -> tuple[FloatArray, FloatArray]:
    """Per phase p = steps mod k: the centre (k, d) — the mean of the rows of z (n, d) in that phase — and the
    per-coordinate scatter (k, d), the largest |z − centre| of those rows."""
    d = z.shape[1]
    centres, scatter = np.zeros((k, d)), np.zeros((k, d))
    for p in range(k):
        rows = z[steps % k == p]
        centres[p] = rows.mean(axis=0)
        scatter[p] = np.abs(rows - centres[p]).max(axis=0)
    return centres, scatter


@dataclass(frozen=True)
class Settling:
    """A settled walk: the step (1-based) from which every state lies in the band, the period k, the band, the index
    of x* among the states searched, the number of states searched (``length``) and the figures of the last two
    windows (σ_A, σ_B, the centres' move, and the scatter of each candidate period)."""

    settled: int
    period: int
    band: Band
    x_star: int
    sigma_a: float
    sigma_b: float
    moved: float
    period_scatter: dict[int, float]
    length: int


@dataclass(frozen=True)
class Unsettled:
    """Why the last two windows of a walk that did not settle failed the test: ``growing`` (B left A's band), or the
    band ``moving``; ``too_short`` when the walk had fewer states than two windows."""

    why: str
    sigma_a: float = float("nan")
    sigma_b: float = float("nan")
    excursion: float = float("nan")
    moved: float = float("nan")
    allowed: float = float("nan")


def nearest_of_phase(z: FloatArray, steps: NDArray[np.int64], band: Band) -> int:
    """The index among states z (n, d) (after ``steps`` (n,) steps) of x*: a state of phase 0 nearest the band's
    phase-0 centre — of an even step when there is one, a state that starts a step of the gait's own stance,
    unmirrored."""
    k = band.period
    cand = np.flatnonzero((steps % k == 0) & (steps % 2 == 0))
    if cand.size == 0:
        cand = np.flatnonzero(steps % k == 0)
    return int(cand[int(np.argmin(np.abs(z[cand] - band.centres[0]).max(axis=1)))])


def settle_window(z: FloatArray, first_step: int, cfg: OrbitConfig, min_period: int, radius: float,
                  multiple: float) -> Settling | Unsettled:
    """The settling test (module docstring) on the last 2 × ``window`` states of z (n, d) (band coordinates), z[i]
    the state after ``first_step`` + i steps. ``radius``, ``multiple``: the band's ν and κ (:class:`.band.Band`)."""
    w = cfg.window
    n = z.shape[0]
    if n < 2 * w:
        return Unsettled("too_short")
    steps = first_step + np.arange(n - 2 * w, n)
    both = z[n - 2 * w:]
    a, b = both[:w], both[w:]
    # the period: of the last window, the most settled one (the window before may still hold a transient)
    scatter = {k: float(phase_stats(b, steps[w:], k)[1].max()) for k in periods(cfg.max_period, min_period)}
    best = min(scatter.values())
    k = next(k for k, s in scatter.items() if s <= cfg.period_ratio * best + cfg.floor)
    ca, sa = phase_stats(a, steps[:w], k)
    cb, sb = phase_stats(b, steps[w:], k)
    sigma_a = float(sa.max())
    tol = max(cfg.floor, cfg.settle_multiple * sigma_a)
    excursion = float(np.abs(b - ca[steps[w:] % k]).max())
    moved = float(np.abs(cb - ca).max())
    allowed = cfg.drift * max(cfg.floor, float(sb.max()))
    if excursion > tol:
        return Unsettled("growing", sigma_a, float(sb.max()), excursion, moved, tol)
    if moved > allowed:
        return Unsettled("moving", sigma_a, float(sb.max()), excursion, moved, allowed)
    band = Band(cb, sb, radius, multiple)
    # entered: the first state from which every later one lies within the settling tolerance of its phase centre in B
    all_steps = first_step + np.arange(n)
    within = np.abs(z - cb[all_steps % k]).max(axis=1) <= max(cfg.floor, cfg.settle_multiple * float(sb.max()))
    out = np.flatnonzero(~within)
    entered = int(out[-1]) + 1 if out.size else 0
    near = nearest_of_phase(b, steps[w:], band)
    return Settling(first_step + entered, k, band, n - w + int(near), sigma_a, float(sb.max()), moved, scatter,
                    n)


def unsettled_reason(u: Unsettled, steps: int, window: int) -> str:
    """One line: why a walk of ``steps`` steps settled on no band."""
    if u.why == "too_short":
        return f"{steps} steps are too few to tell whether the walk settles (two windows of {window} steps needed)"
    if u.why == "growing":
        return (f"its band keeps growing: after {steps} steps the last {window} switching states reach "
                f"{u.excursion:.3g} from the centre of the {window} before (allowed {u.allowed:.3g}: their scatter "
                f"{u.sigma_a:.3g} × orbit.settle_multiple; band coordinates)")
    return (f"its band keeps moving: after {steps} steps the centre of the last {window} switching states moved "
            f"{u.moved:.3g} from that of the {window} before (allowed {u.allowed:.3g}: orbit.drift × their scatter "
            f"{u.sigma_b:.3g}; band coordinates) — it drifts, turns, slowly falls or is still converging")


@dataclass(frozen=True)
class Linearization:
    """The linearized map at x* as a diagnostic (:mod:`.linearization`): ``defined`` when ρ is the same within
    ``orbit.fd_agreement`` at two finite-difference steps a decade apart and a perturbation along the leading
    eigenvector grows or shrinks at ρ's rate (``rate``: its per-step factor over ``orbit.confirm_steps`` maps);
    otherwise ``reason`` says why not (contact events make the map non-smooth at that scale)."""

    defined: bool
    rho: float | None
    rho_coarse: float | None
    rate: float | None
    moduli: tuple[float, ...] = ()
    reason: str = ""

    def describe(self) -> str:
        if self.defined and self.rho is not None:
            text = (f"ρ = {self.rho:.3g} (linearization at x*; a perturbation along its eigenvector: "
                    f"×{self.rate:.3g}/map)")
            if self.rho > 1.0:
                # A contact walk can settle in a small band around a repelling x*: the verdict is the band's (the
                # probe's), so say what ρ > 1 does and does not mean.
                text += "; x* itself repels tiny perturbations, which grow until they reach the band's scale"
            return text
        return f"linearization not defined (contact events): {self.reason}"

    def to_dict(self) -> dict[str, Any]:
        return {"defined": self.defined, "rho": self.rho, "rho_coarse": self.rho_coarse, "rate": self.rate,
                "moduli": list(self.moduli), "reason": self.reason}


@dataclass(frozen=True)
class Probe:
    """The stability check: pushes of ``impulse`` [N s] (``orbit.probe_impulse`` × m √(g l), doubled until they take
    the walk out of its band) from x*, each walked ``horizon`` (``orbit.probe_horizon``) steps or until it has been
    back in the band for ``push.recovery_steps`` steps (``recovered``, at step ``steps``; 0: not) or fell (``fell``);
    ``left``: it left the band on the way; ``diverging``: it neither fell nor came back, and its distance from the
    band kept growing (:func:`diverging`). The orbit is stable when no probe diverged and not every probe fell. A
    probe that fell is a push of that size and direction beyond what the gait survives — the size of its basin, which
    J* measures, not the orbit's instability; a probe that settles near the band without entering it (another orbit of
    the same gait, a slow mode) is not a divergence either."""

    impulse: float
    horizon: int
    recovered: tuple[bool, ...]
    steps: tuple[int, ...]
    fell: tuple[bool, ...]
    left: tuple[bool, ...]
    diverging: tuple[bool, ...] = ()

    @property
    def ok(self) -> bool:
        return not any(self.diverging) and not all(self.fell)

    def to_dict(self) -> dict[str, Any]:
        return {"impulse": self.impulse, "horizon": self.horizon, "recovered": list(self.recovered),
                "steps": list(self.steps), "fell": list(self.fell), "left": list(self.left),
                "diverging": list(self.diverging)}

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> Probe:
        """The probe :meth:`to_dict` wrote."""
        return cls(float(d["impulse"]), int(d["horizon"]), tuple(bool(x) for x in d["recovered"]),
                   tuple(int(x) for x in d["steps"]), tuple(bool(x) for x in d["fell"]),
                   tuple(bool(x) for x in d["left"]), tuple(bool(x) for x in d["diverging"]))


def probe_of(size: float, horizon: int, back: NDArray[np.int64], fell: NDArray[np.bool_] | NDArray[np.int64],
             left: NDArray[np.bool_], trace: FloatArray, growth: float) -> Probe:
    """The :class:`Probe` of perturbations of ``size`` from x*, followed ``horizon`` steps (or maps): per probe the
    step it was back in the band (``back``, 0: not), whether it fell (``fell``, or the step it fell in), whether it
    left the band (``left``) and its band distance after every step (``trace`` (n, ≥ horizon), NaN once stopped),
    judged diverging by :func:`moving_away` with ``growth`` (``orbit.probe_growth``)."""
    return Probe(float(size), horizon, tuple(bool(b) for b in back > 0), tuple(int(b) for b in back),
                 tuple(bool(f) for f in np.asarray(fell, dtype=np.int64) > 0), tuple(bool(x) for x in left),
                 moving_away(back, fell, trace, growth))


def unstable_reason(probe: Probe, settled: str, perturbed: str, unit: str) -> str:
    """One line, for an orbit the probe refused: ``settled`` (what settled: "the walk") and, of its probes
    (``perturbed``: "pushes of 12 N s"), how many moved away from the band, fell or stayed near it without entering
    it, and how many came back within its horizon (in ``unit``: "steps")."""
    n, fell, moving, back = len(probe.recovered), sum(probe.fell), sum(probe.diverging), sum(probe.recovered)
    near = n - fell - moving - back
    what = ", ".join([f"{moving} moved away from its band"] * bool(moving) + [f"{fell} fell"] * bool(fell)
                     + [f"{near} stayed near it without entering it"] * bool(near))
    return (f"{settled} settled, but of {n} {perturbed} from x*, {what} and {back} came back within {probe.horizon} "
            f"{unit}")


def moving_away(recovered: NDArray[np.int64], fell: NDArray[np.bool_] | NDArray[np.int64], trace: FloatArray,
                growth: float) -> tuple[bool, ...]:
    """Per probe: neither came back (``recovered`` 0) nor fell (``fell`` false or 0), and :func:`diverging` on its
    row of ``trace`` (K, H)."""
    return tuple(bool(r == 0 and not f and diverging(tr, growth)) for r, f, tr in zip(recovered, fell, trace,
                                                                                        strict=True))


def diverging(trace: FloatArray, growth: float) -> bool:
    """Whether a walk's distance from its orbit's band (one value per step, NaN after it stopped) kept growing: its
    largest value over the last quarter of the steps it walked exceeds ``growth`` × its largest over the first half
    (``orbit.probe_growth``) — a walk that moves away from the band, as a repelling orbit's does, rather than one
    that stays near it or settles on another orbit of the gait."""
    d = trace[np.isfinite(trace)]
    if d.size < 4:
        return False
    return bool(d[-max(1, d.size // 4):].max() > growth * d[:d.size // 2].max())


@dataclass(frozen=True)
class FixedPoint:
    """x*: a switching state the settled walk reached (canonical: it starts a step of the gait's stance), ``qpos``
    (nq,), ``qvel`` (nv,), its base angular velocity ``omega`` (3,) in the certificate's frame, and the ``step`` of
    the walk after which it was reached."""

    qpos: FloatArray
    qvel: FloatArray
    omega: FloatArray
    step: int


@dataclass(frozen=True)
class Orbit:
    """The orbit of a gait's walk: ``status`` and ``reason`` (empty when ok); ``steps`` walked by the search;
    ``settled`` (the step from which every switching state lay in the band; None if it never did); ``period`` k
    (physical steps; the certified map is k steps, mirrored if k is odd); the ``band``; x* (``qpos`` (nq,), ``qvel``
    (nv,): a state the walk reached, at ``x_star_step``); the last windows' figures (``sigma_a``, ``sigma_b``,
    ``moved``, each candidate period's scatter); the stability ``probe`` and the ``linearization`` diagnostic when they
    were computed. ``sides_differ``: the period was searched from 2 (a robot whose left and right differ);
    ``held``: steps the band was watched after it was found; ``band_steps``: the first and last step whose states make
    the band (the settling window and the hold);
    ``physics_steps``: simulated by the search (its walk, the probe, the linearization); ``states``: the band's
    switching states (n, nq + nv), canonical, the first of them after ``states_step`` steps; ``walk_speed`` [m/s] and
    ``sole_turn`` [rad]: the search's walk's mean forward speed and its stance soles' mean turn
    (:class:`~robustgait.sim.walk.WalkResult`'s), None for an orbit not found by walking."""

    status: Status
    reason: str
    steps: int
    window: int
    settled: int | None = None
    period: int = 1
    band: Band | None = None
    qpos: FloatArray | None = field(default=None, repr=False)
    qvel: FloatArray | None = field(default=None, repr=False)
    x_star_step: int | None = None
    sigma_a: float | None = None
    sigma_b: float | None = None
    moved: float | None = None
    period_scatter: dict[int, float] = field(default_factory=dict)
    probe: Probe | None = None
    linearization: Linearization | None = None
    sides_differ: bool = False
    held: int = 0
    band_steps: tuple[int, int] | None = None
    physics_steps: int = 0
    states: FloatArray | None = field(default=None, repr=False)
    states_step: int = 0
    walk_speed: float | None = None
    sole_turn: float | None = None

    @property
    def ok(self) -> bool:
        return self.status == Status.OK

    @property
    def sigma(self) -> float | None:
        """σ: the band's largest scatter (band coordinates), None without a band."""
        return None if self.band is None else self.band.sigma

    def phase_states(self, phase: int) -> FloatArray | None:
        """The last window's switching states (rows of ``states``) of a phase of the orbit."""
        if self.states is None:
            return None
        steps = self.states_step + np.arange(len(self.states))
        return self.states[steps % self.period == phase % self.period]

    def fixed_point(self, frame: Frame) -> FixedPoint:
        """x* as a :class:`FixedPoint` (its base angular velocity in ``frame``)."""
        if self.qpos is None or self.qvel is None or self.x_star_step is None:
            raise RobustGaitError(f"the orbit has no x* ({self.status}: {self.reason})")
        omega = reduce_state(self.qpos[None], self.qvel[None], frame)[0]
        return FixedPoint(self.qpos.copy(), self.qvel.copy(), omega, self.x_star_step)

    @property
    def map_name(self) -> str:
        """The map the orbit is certified on, in words."""
        return {1: "step map (one step, mirrored)", 2: "stride map (two steps)"}.get(
            self.period, f"{self.period}-step map" + (", mirrored" if self.period % 2 else ""))

    def describe(self) -> str:
        """One line: settled (step, period, σ) or why not; the probe; the linearization."""
        if self.band is None or self.settled is None:
            line = f"{self.status}: {self.reason}"
        else:
            line = (f"settled at step {self.settled} on a period-{self.period} orbit ({self.map_name}), in a band of "
                    f"σ = {self.sigma:.2g} (band coordinates) that held {self.held} more steps")
            if self.status != Status.OK:
                line += f"; {self.status}: {self.reason}"
        if self.probe is not None and self.probe.ok:
            back = sum(self.probe.recovered)
            fell = sum(self.probe.fell)
            near = len(self.probe.recovered) - back - fell
            line += (f"; stable: {len(self.probe.recovered)} pushes of {self.probe.impulse:.3g} N s "
                     f"({sum(self.probe.left)} left the band), {back} came back to it within "
                     f"{max(self.probe.steps)} steps" + (f", {near} stayed near it" if near else "")
                     + (f", {fell} fell (a push that size is beyond the gait's basin in its direction: J* lies "
                        "below it)" if fell else ""))
        if self.linearization is not None:
            line += "; " + self.linearization.describe()
        return line

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready (x* as lists)."""
        return {"status": self.status.value, "reason": self.reason, "steps": self.steps, "window": self.window,
                "settled_at_step": self.settled, "period": self.period, "map": self.map_name,
                "sigma": self.sigma, "band": None if self.band is None else self.band.to_dict(),
                "x_star_step": self.x_star_step, "sigma_a": self.sigma_a, "sigma_b": self.sigma_b,
                "moved": self.moved, "period_scatter": {str(k): v for k, v in self.period_scatter.items()},
                "probe": None if self.probe is None else self.probe.to_dict(),
                "linearization": None if self.linearization is None else self.linearization.to_dict(),
                "sides_differ": self.sides_differ, "held": self.held, "physics_steps": self.physics_steps,
                "walk_speed": self.walk_speed, "sole_turn": self.sole_turn}


def orbit_from_dict(d: dict[str, Any], state: dict[str, Any]) -> Orbit:
    """A settled orbit as :meth:`Orbit.to_dict` wrote it, with ``state`` (``qpos``, ``qvel``: x*; ``band_centres``,
    ``band_scatter`` (k, d): its band) — what a push certificate needs of it (:func:`orbit_state`); its band's states
    and window steps are not kept. Raises KeyError, TypeError or ValueError on anything else, and when the record
    holds a linearization (not rebuilt)."""
    if d["linearization"] is not None:
        raise ValueError("an orbit with its linearization is not rebuilt")
    b = d["band"]
    band = Band(np.asarray(state["band_centres"], dtype=float), np.asarray(state["band_scatter"], dtype=float),
                float(b["radius"]), float(b["multiple"]))
    if band.centres.shape != band.scatter.shape or band.period != int(d["period"]):
        raise ValueError("the band's centres and scatter do not match its period")
    return Orbit(status=Status(d["status"]), reason=str(d["reason"]), steps=int(d["steps"]), window=int(d["window"]),
                 settled=d["settled_at_step"], period=int(d["period"]), band=band,
                 qpos=np.asarray(state["qpos"], dtype=float), qvel=np.asarray(state["qvel"], dtype=float),
                 x_star_step=d["x_star_step"], sigma_a=d["sigma_a"], sigma_b=d["sigma_b"], moved=d["moved"],
                 period_scatter={int(k): float(v) for k, v in d["period_scatter"].items()},
                 probe=None if d["probe"] is None else Probe.from_dict(d["probe"]),
                 sides_differ=bool(d["sides_differ"]), held=int(d["held"]), physics_steps=int(d["physics_steps"]),
                 walk_speed=d.get("walk_speed"), sole_turn=d.get("sole_turn"))  # absent from older records


def orbit_state(orbit: Orbit) -> dict[str, Any] | None:
    """What :func:`orbit_from_dict` needs beside :meth:`Orbit.to_dict` (x* and the band's arrays, JSON-ready); None
    for an orbit without them."""
    if orbit.qpos is None or orbit.qvel is None or orbit.band is None:
        return None
    return {"qpos": orbit.qpos.tolist(), "qvel": orbit.qvel.tolist(), "band_centres": orbit.band.centres.tolist(),
            "band_scatter": orbit.band.scatter.tolist()}


class Watch:
    """The orbit rule applied to switching states as a walk produces them (band coordinates, the first after
    ``first_step`` steps): from ``orbit.min_steps`` to ``orbit.max_steps`` steps the last two windows are tested
    (:func:`settle_window`) until they settle; the band found must then **hold** for ``orbit.hold_steps`` more steps —
    every later window of ``orbit.window`` steps keeps its phase centres within ``settle_multiple`` × max(``floor``,
    σ_B) of the band's (a walk that drifts, turns or slowly falls moves its band away). :attr:`done` once the rule
    has its answer; :meth:`orbit` gives it. The one rule of every walk, search and synthetic map."""

    def __init__(self, cfg: OrbitConfig, min_period: int, radius: float, multiple: float, first_step: int = 1):
        self.cfg, self.min_period, self.radius, self.multiple = cfg, min_period, radius, multiple
        self.first_step = first_step
        self.z: list[FloatArray] = []
        self.found: Settling | None = None
        self.last: Settling | Unsettled = Unsettled("too_short")
        self.left: tuple[int, float, float] | None = None  # the window (its first step) that left, its move, allowed

    @property
    def steps(self) -> int:
        """The step after which the newest state was reached."""
        return self.first_step + len(self.z) - 1

    @property
    def held(self) -> int:
        """Steps walked since the band was found (0 before)."""
        return 0 if self.found is None else len(self.z) - self.found.length

    @property
    def done(self) -> bool:
        if self.found is None:
            return self.steps >= self.cfg.max_steps
        return self.left is not None or self.held >= self.cfg.hold_steps

    def add(self, z: FloatArray) -> bool:
        """Take the next state (d,); return :attr:`done`."""
        if self.done:
            return True
        self.z.append(np.asarray(z, dtype=float))
        cfg = self.cfg
        if self.found is None:
            if self.steps >= cfg.min_steps:
                self.last = settle_window(np.array(self.z), self.first_step, cfg, self.min_period, self.radius,
                                          self.multiple)
                if isinstance(self.last, Settling):
                    self.found = self.last
        elif self.held % cfg.window == 0:  # a window of the hold completed: are its centres still the band's?
            steps = self.steps - cfg.window + 1 + np.arange(cfg.window)
            centres, _ = phase_stats(np.array(self.z[-cfg.window:]), steps, self.found.period)
            left = self.hold_window(centres)
            if left is not None:
                self.left = (int(steps[0]), *left)
        return self.done

    def hold_window(self, centres: FloatArray) -> tuple[float, float] | None:
        """The hold test of one completed window, its phase centres (period, d) in band coordinates: None while they
        stay within ``settle_multiple`` × max(``floor``, σ_B) of the band's centres, else (the largest move, that
        bound). The one place the hold is judged (a variant rule overrides it)."""
        assert self.found is not None
        band = self.found.band
        moved = float(np.abs(centres - band.centres).max())
        allowed = self.cfg.settle_multiple * max(self.cfg.floor, band.sigma)
        return (moved, allowed) if moved > allowed else None

    def orbit(self, fell: str | None = None) -> tuple[Orbit, int | None]:
        """The verdict on the states taken (the walk fell in the step after the last when ``fell`` names the reason),
        and the index of x* among them (None without an orbit)."""
        cfg, n, sides = self.cfg, self.steps, self.min_period > 1
        f = self.found
        if f is None:
            if fell is not None and n < cfg.max_steps:
                return Orbit(Status.FELL, f"the gait fell in step {n + 1} ({fell}) before its switching states "
                             "settled", n, cfg.window, sides_differ=sides), None
            if not self.done:
                return Orbit(Status.UNDECIDED, f"the walk ended after {n} steps, before its switching states settled "
                             f"(the rule watches up to {cfg.max_steps} steps for them to settle, then "
                             f"{cfg.hold_steps} more)", n, cfg.window, sides_differ=sides), None
            u = self.last if isinstance(self.last, Unsettled) else Unsettled("too_short")
            return Orbit(Status.UNSETTLED, unsettled_reason(u, n, cfg.window), n, cfg.window,
                         sigma_a=None if np.isnan(u.sigma_a) else u.sigma_a,
                         sigma_b=None if np.isnan(u.sigma_b) else u.sigma_b,
                         moved=None if np.isnan(u.moved) else u.moved, sides_differ=sides), None
        # the band: every state from the settling window on (the hold's too: more of the attractor's scatter)
        start = f.length - cfg.window
        span = np.array(self.z[start:])
        steps = self.first_step + start + np.arange(len(span))
        centres, scatter = phase_stats(span, steps, f.period)
        band = Band(centres, scatter, self.radius, self.multiple)
        x_star = start + nearest_of_phase(span, steps, band)
        orbit = Orbit(Status.OK, "", n, cfg.window, f.settled, f.period, band,
                      x_star_step=self.first_step + x_star, sigma_a=f.sigma_a, sigma_b=f.sigma_b, moved=f.moved,
                      period_scatter=f.period_scatter, sides_differ=sides, held=self.held,
                      band_steps=(int(steps[0]), int(steps[-1])))
        settled_at = self.first_step + f.length - 1
        if self.left is not None:
            start, moved, allowed = self.left
            reason = (f"its switching states settled by step {settled_at}, then left that band: the centre of steps "
                      f"{start}–{start + cfg.window - 1} lies {moved:.3g} from the band's (allowed {allowed:.3g}: "
                      "orbit.settle_multiple × its scatter; band coordinates) — it drifts, turns or slowly falls")
            return dataclasses.replace(orbit, status=Status.UNSETTLED, reason=reason), None
        if self.held < cfg.hold_steps:
            if fell is not None:
                return dataclasses.replace(orbit, status=Status.FELL, reason=(
                    f"the gait fell in step {n + 1} ({fell}), {self.held} steps after its switching states settled "
                    f"by step {settled_at}")), None
            return dataclasses.replace(orbit, status=Status.UNDECIDED, reason=(
                f"its switching states settled by step {settled_at}, but the walk ended {self.held} steps later: "
                f"{cfg.hold_steps} are needed to see the band hold (walk at least {settled_at + cfg.hold_steps} "
                "steps)")), x_star
        return orbit, x_star


def classify(z: FloatArray, cfg: OrbitConfig, *, min_period: int, radius: float, multiple: float,
             fell: str | None = None, first_step: int = 1) -> tuple[Orbit, int | None]:
    """The orbit of a walk's switching states z (n, d) (band coordinates; z[i] after ``first_step`` + i steps; the
    walk fell in the step after the last when ``fell`` names the reason): :class:`Watch` fed the states until it has
    its answer — the states after it are not looked at, so a longer walk of the same gait gives the same orbit —, and
    the index of x* in z (None without a band). The orbit's status is ``ok`` when it settled and held (stability is
    the search's), ``fell``, ``unsettled``, or ``undecided`` for a walk too short to tell."""
    watch = Watch(cfg, min_period, radius, multiple, first_step)
    for row in z:
        if watch.add(row):
            break
    done = watch.done
    return watch.orbit(None if done and len(watch.z) < z.shape[0] else fell)


def min_period(robot: Robot, map_kind: MapKind) -> int:
    """The shortest period the orbit is searched with: 1 for the step map, 2 for the stride map; ``auto``: 2 when the
    robot's left and right differ (:attr:`robustgait.robots.model.Robot.sides_differ`, computed once per robot),
    else 1."""
    if map_kind != "auto":
        return 1 if map_kind == "step" else 2
    return 2 if robot.sides_differ else 1


def classify_walk(robot: Robot, qpos: FloatArray, qvel: FloatArray, config: CertifyConfig,
                  fell: str | None = None) -> Orbit:
    """The orbit (:func:`classify`) of a walk's switching states, written for the gait's stance (qpos (n, nq), qvel
    (n, nv), after steps 1 … n; ``fell``: the reason the walk fell in step n + 1), x* among them, with the band's
    floor and multiple of ``config.push`` (the band a pushed walk must come back to)."""
    z = band_coordinates(robot, qpos, qvel) if len(qpos) else np.empty((0, section_dimension(robot)))
    orbit, i = classify(z, config.orbit, min_period=min_period(robot, config.map), radius=config.push.recovery_radius,
                        multiple=config.push.recovery_scatter, fell=fell)
    if i is None:
        return orbit
    assert orbit.band_steps is not None
    a, b = orbit.band_steps  # the band's states: after steps a … b
    window = np.hstack([qpos[a - 1:b], qvel[a - 1:b]]).astype(float)
    return dataclasses.replace(orbit, qpos=np.array(qpos[i], dtype=float), qvel=np.array(qvel[i], dtype=float),
                               states=window, states_step=a)


def canonical_event_states(robot: Robot, gait: Gait, events: Sequence[SwitchEvent]
                           ) -> tuple[FloatArray, FloatArray]:
    """The states (len(events), nq), (len(events), nv) of a walk's switching events, each written for the gait's own
    stance (an event that starts a step of the other stance is mirrored): the sequence the step map acts on."""
    if not events:
        return np.empty((0, robot.model.nq)), np.empty((0, robot.model.nv))
    qpos, qvel = np.array([e.qpos for e in events]), np.array([e.qvel for e in events])
    # the step that ended was canonical, so the next one is not
    other = np.array([e.stance == gait.stance for e in events])
    mq, mv = robot.mirror_state(qpos, qvel)
    return np.where(other[:, None], mq, qpos), np.where(other[:, None], mv, qvel)


def walk_orbit(robot: Robot, gait: Gait, walked: WalkResult, config: CertifyConfig) -> Orbit:
    """The orbit of a walk's switching states (:func:`robustgait.sim.walk.walk`), written for the gait's stance
    (:func:`canonical_event_states`), by :func:`classify_walk` with the options of ``config.orbit`` and ``config.map``
    — no simulation, and the same orbit the certificate's search finds on the same gait (it walks the same steps and
    stops where they settle), without its stability probe (``robustgait.certificate.search.find_orbit``); with the
    walk's mean forward speed and mean stance-sole turn (``walk_speed``, ``sole_turn``)."""
    qpos, qvel = canonical_event_states(robot, gait, walked.events)
    orbit = classify_walk(robot, qpos, qvel, config, walked.fall_reason if walked.fell else None)
    return dataclasses.replace(orbit, walk_speed=walked.mean_speed, sole_turn=walked.sole_turn)


class SettlingWatch:
    """A stop rule for a walk (``walk(..., until=...)``): true once the orbit rule (:class:`Watch`) has its answer, so
    that the orbit search walks no further than it needs. Called with the walk's events so far (objects with
    ``qpos``, ``qvel`` and the ``stance`` of the step that ended)."""

    def __init__(self, robot: Robot, stance: str, config: CertifyConfig):
        self.robot, self.stance = robot, stance
        p = config.push
        self.watch = Watch(config.orbit, min_period(robot, config.map), p.recovery_radius, p.recovery_scatter)

    def __call__(self, events: Sequence[Any]) -> bool:
        e = events[-1]
        q, v = np.array(e.qpos, dtype=float)[None], np.array(e.qvel, dtype=float)[None]
        if e.stance == self.stance:  # the next step is the other stance's: write it for the gait's
            q, v = self.robot.mirror_state(q, v)
        return self.watch.add(band_coordinates(self.robot, q, v)[0])
