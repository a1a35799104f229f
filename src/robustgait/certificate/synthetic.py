"""Batched maps with known answers, to check an estimator of r* and its confidence statement (docs/design.md §6).

Both maps contract by ``gain`` < √(1 − α) around x* (such a sample never violates the DTBF condition, for
either barrier) except on a violating set where the sample falls (NaN image: violated for every r ≥ d, for
either barrier). Only the volume fraction of the violating set in a ball matters, and it is known exactly:

* :class:`ConeMap` — a thin cone of directions beyond a radius r0: the true r* is r0 (for r0 < r_max).
* :class:`BandMap` — thin bands of directions whose width grows with the distance, so that the violating
  fraction of B(r) is a + c r n/(n + 1) at every r (any dimension n ≥ 2): with c = 0 every ball has fraction a
  and the true r* is 0, which makes every certificate with ε < a wrong — the case that tests a confidence
  statement.
* :class:`PushThresholdMap` — a 2-D impulse disk whose pushes fail beyond a threshold that depends on the push's
  direction and on its hashed phase (:func:`.push.push_phase`): the push certificate's J* (true
  J* and violating fraction of every disk known by quadrature).
* :class:`DivergingPush` — pushes that walk a few steps and fall later beyond a known critical impulse: the push
  certificate's recovery criterion (:mod:`.push`).

Maps with known orbits, for the orbit search (:func:`.search.find_orbit` of an :class:`.search.Iterated` map) and the
linearization (:mod:`.numerics`):

* :class:`LinearMap` — x* + A (x − x*) with a chosen spectrum (ρ known), optionally with a staircase of jumps along
  its first coordinate (piecewise smooth, as the simulated map is where a touchdown crosses a physics step).
* :class:`QuadraticMap` — the logistic map on one coordinate, contracting on the others: converging (r < 3),
  period two (3 < r < 1 + √6), period four (1 + √6 < r < 3.544) or chaotic, wandering past an unstable x* (r = 3.9).
* :class:`NoisyMap` — another map plus bounded uniform noise: a noisy attractor, a band rather than a point (a
  contraction: accepted, with its scatter; an expansion: its band keeps growing).
* :class:`DriftMap` — a slow drift: one coordinate advances by a constant each map, the others follow it.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from robustgait.errors import RobustGaitError

FloatArray = NDArray[np.float64]


def _check_gain(gain: float) -> None:
    if not 0.0 <= gain < 0.97:  # < √(1 − α) for α ≤ 0.05: the contracting part never violates
        raise RobustGaitError(f"gain must be in [0, 0.97), got {gain!r}")


@dataclass(frozen=True)
class ConeMap:
    """P(x) = x* + gain (x − x*), except that x falls when ‖x − x*‖ > r0 and the angle between x − x* and
    ``axis`` is below ``half_angle`` [rad]. True r* = r0; violating fraction of B(r):
    f (1 − (r0/r)^n)₊ with f the cone's share of directions ((1 − cos θ)/2 for n = 3)."""

    x_star: FloatArray
    r0: float
    half_angle: float
    axis: FloatArray = field(default_factory=lambda: np.array([1.0, 2.0, 2.0]) / 3.0)
    gain: float = 0.5

    def __post_init__(self) -> None:
        _check_gain(self.gain)
        if np.asarray(self.x_star).shape != (3,) or np.asarray(self.axis).shape != (3,):
            raise RobustGaitError("ConeMap is 3-D: x_star and axis must have shape (3,)")
        if not (self.r0 > 0.0 and 0.0 < self.half_angle < math.pi / 2):
            raise RobustGaitError("need r0 > 0 and 0 < half_angle < π/2")

    @property
    def radius(self) -> float:
        return float(self.r0)

    @property
    def cone_fraction(self) -> float:
        return (1.0 - math.cos(self.half_angle)) / 2.0

    def violating_fraction(self, r: float) -> float:
        return 0.0 if r <= self.r0 else self.cone_fraction * (1.0 - (self.r0 / r) ** 3)

    def __call__(self, x: ArrayLike) -> FloatArray:
        dx = np.asarray(x, dtype=np.float64) - self.x_star
        d = np.linalg.norm(dx, axis=1)
        axis = np.asarray(self.axis) / np.linalg.norm(self.axis)
        inside_cone = dx @ axis > math.cos(self.half_angle) * d
        out = self.x_star + self.gain * dx
        out[(d > self.r0) & inside_cone] = np.nan
        return np.asarray(out, dtype=np.float64)


@dataclass(frozen=True)
class BandMap:
    """P(x) = x* + gain (x − x*), except that x falls when frac(K t) < a + c ‖x − x*‖, with t = F((u_n + 1)/2), u the
    unit direction of x − x* (K = ``bands``), u_n its last coordinate and F the CDF of (u_n + 1)/2 for uniform
    directions in n dimensions, Beta((n − 1)/2, (n − 1)/2) — the identity for n = 3 (Archimedes) — so t is uniform,
    a fraction a + c d of the sphere of radius d falls and the violating fraction of B(r) is a + c r n/(n + 1)."""

    x_star: FloatArray
    a: float
    c: float = 0.0
    bands: int = 40
    gain: float = 0.5
    r_max: float = 2.0

    def __post_init__(self) -> None:
        _check_gain(self.gain)
        if np.asarray(self.x_star).ndim != 1 or np.asarray(self.x_star).shape[0] < 2:
            raise RobustGaitError("BandMap needs x_star of shape (n,), n ≥ 2")
        if not (0.0 <= self.a and 0.0 <= self.c and self.a + self.c * self.r_max <= 1.0 and self.bands >= 1):
            raise RobustGaitError("need a, c ≥ 0, a + c r_max ≤ 1 and bands ≥ 1")

    @property
    def radius(self) -> float:
        return 0.0 if self.a > 0.0 or self.c > 0.0 else float(self.r_max)

    @property
    def dim(self) -> int:
        return int(np.asarray(self.x_star).shape[0])

    def violating_fraction(self, r: float) -> float:
        n = self.dim
        return self.a + self.c * r * n / (n + 1) if r > 0.0 else self.a

    def __call__(self, x: ArrayLike) -> FloatArray:
        from scipy.special import betainc

        dx = np.asarray(x, dtype=np.float64) - self.x_star
        d = np.linalg.norm(dx, axis=1)
        un = dx[:, -1] / np.where(d > 0.0, d, 1.0)
        h = 0.5 * (self.dim - 1)
        t = betainc(h, h, np.clip((un + 1.0) / 2.0, 0.0, 1.0))
        falls = np.mod(self.bands * t, 1.0) < self.a + self.c * d
        out = self.x_star + self.gain * dx
        out[falls] = np.nan
        return np.asarray(out, dtype=np.float64)


@dataclass(frozen=True)
class PushThresholdMap:
    """A push-failure model on the impulse disk: J = (J_x, J_y) ↦ (0, 0) (absorbed) or NaN (fell), falling when
    |J| > J_c = j0 (1 + a cos θ)(1 − b φ), θ the direction of J and φ ∈ [0, 1) its phase from
    :func:`.push.push_phase` (the certificate's hashed phase). True J* = j0 (1 − a)(1 − b) (the
    infimum over directions and phases); :meth:`violating_fraction` of the disk B(r) by quadrature over θ and φ
    (uniform)."""

    j0: float = 20.0
    a: float = 0.3
    b: float = 0.4

    def __post_init__(self) -> None:
        if not (self.j0 > 0.0 and 0.0 <= self.a < 1.0 and 0.0 <= self.b < 1.0):
            raise RobustGaitError("need j0 > 0, 0 ≤ a < 1 and 0 ≤ b < 1")

    @property
    def radius(self) -> float:
        return float(self.j0 * (1.0 - self.a) * (1.0 - self.b))

    def threshold(self, theta: FloatArray, phase: FloatArray) -> FloatArray:
        return np.asarray(self.j0 * (1.0 + self.a * np.cos(theta)) * (1.0 - self.b * phase))

    def violating_fraction(self, r: float, grid: int = 400) -> float:
        """∫∫ max(0, 1 − J_c(θ, φ)²/r²) dθ/2π dφ: the share of the disk's area beyond the threshold."""
        if r <= 0.0:
            return 0.0
        theta = (np.arange(grid) + 0.5) / grid * 2.0 * math.pi
        phase = (np.arange(grid) + 0.5) / grid
        jc = self.threshold(theta[:, None], phase[None, :])
        return float(np.mean(np.maximum(0.0, 1.0 - (jc / r) ** 2)))

    def __call__(self, x: ArrayLike) -> FloatArray:
        from robustgait.certificate.push import push_phase

        j = np.atleast_2d(np.asarray(x, dtype=np.float64))
        theta = np.arctan2(j[:, 1], j[:, 0])
        falls = np.linalg.norm(j, axis=1) > self.threshold(theta, push_phase(j, 0.0, 1.0))
        out = np.zeros_like(j)
        out[falls] = np.nan
        return out


@dataclass(frozen=True)
class LinearMap:
    """F(x) = x* + A (x − x*) + (β + s ⌊(x_0 − x*_0)/w + ½⌋) e_0 on (N, d): linear with A's spectrum (ρ = :attr:`rho`),
    plus, for ``jump`` s ≠ 0, a staircase along the first coordinate — F jumps by s whenever x_0 crosses a boundary at
    x*_0 ± w/2, ± 3w/2, … (``width`` w), and is linear between them. x* is the fixed point for ``bias`` β = 0; with
    β ≠ 0 and A = a I the linear piece k has its fixed point at x*_0 + (β + s k)/(1 − a) — when that lies outside every
    piece, F jumps across the diagonal and has no fixed point at all."""

    a: FloatArray
    x_star: FloatArray
    jump: float = 0.0
    width: float = 1.0
    bias: float = 0.0

    @classmethod
    def with_spectrum(cls, eigenvalues: ArrayLike, x_star: ArrayLike, skew: float = 0.0, seed: int = 0,
                      jump: float = 0.0, width: float = 1.0, bias: float = 0.0) -> LinearMap:
        """A = V diag(λ) V⁻¹ with V = I + skew · G (G standard normal from ``seed``): the eigenvalues λ (real), normal
        for skew 0, ever less so as skew grows."""
        lam = np.asarray(eigenvalues, dtype=np.float64)
        v = np.eye(lam.size) + skew * np.random.default_rng(seed).standard_normal((lam.size, lam.size))
        a = v @ np.diag(lam) @ np.linalg.inv(v)
        return cls(a, np.asarray(x_star, dtype=np.float64), jump, width, bias)

    @property
    def rho(self) -> float:
        return float(np.max(np.abs(np.linalg.eigvals(self.a))))

    def __call__(self, x: ArrayLike) -> FloatArray:
        dx = np.atleast_2d(np.asarray(x, dtype=np.float64)) - self.x_star
        out = self.x_star + dx @ self.a.T
        out[:, 0] += self.bias + self.jump * np.floor(dx[:, 0] / self.width + 0.5)
        return np.asarray(out, dtype=np.float64)


@dataclass(frozen=True)
class QuadraticMap:
    """x_0 ↦ r x_0 (1 − x_0) (the logistic map), x_i ↦ ``gain`` x_i for i ≥ 1, on (N, ``dim``): smooth, with the fixed
    point x* = (1 − 1/r, 0, …) of eigenvalues 2 − r and ``gain`` (ρ = :attr:`rho`). r < 3: the iterates converge to
    x*; 3 < r < 1 + √6: to the period-two orbit :attr:`period_two` (P∘P has fixed points there, P none: x* repels);
    r = 3.9: chaotic — the iterates wander over (0, 1), now and then passing near the repelling x* (|2 − r| = 1.9)
    and leaving it."""

    r: float
    dim: int = 3
    gain: float = 0.5

    @property
    def x_star(self) -> FloatArray:
        out = np.zeros(self.dim)
        out[0] = 1.0 - 1.0 / self.r
        return out

    @property
    def rho(self) -> float:
        return max(abs(2.0 - self.r), abs(self.gain))

    @property
    def period_two(self) -> tuple[float, float]:
        """The period-two points p± = (r + 1 ± √((r + 1)(r − 3))) / 2r of the first coordinate (r > 3)."""
        if self.r <= 3.0:
            raise RobustGaitError(f"the logistic map has no period-two orbit for r = {self.r} ≤ 3")
        root = math.sqrt((self.r + 1.0) * (self.r - 3.0))
        return (self.r + 1.0 - root) / (2.0 * self.r), (self.r + 1.0 + root) / (2.0 * self.r)

    def preimage(self, y: float, steps: int) -> float:
        """An x_0 whose ``steps``-th iterate is y (first coordinate): the inverse branches x = (1 ± √(1 − 4y/r))/2
        alternated (y ≤ r/4)."""
        x = y
        for k in range(steps):
            root = math.sqrt(max(0.0, 1.0 - 4.0 * x / self.r))
            x = 0.5 * (1.0 + root if k % 2 else 1.0 - root)
        return x

    def __call__(self, x: ArrayLike) -> FloatArray:
        x = np.atleast_2d(np.asarray(x, dtype=np.float64))
        out = self.gain * x
        out[:, 0] = self.r * x[:, 0] * (1.0 - x[:, 0])
        return np.asarray(out, dtype=np.float64)


class NoisyMap:
    """F(x) + η, η uniform in [−``amplitude``, ``amplitude``]^d, drawn from a generator seeded with ``seed`` (the
    noise of successive calls differs; a map with known answers: F's attractor widened by at most
    amplitude / (1 − gain) for a contraction of gain < 1)."""

    def __init__(self, inner: Callable[[FloatArray], FloatArray], amplitude: float, seed: int = 0):
        if amplitude < 0.0:
            raise RobustGaitError(f"amplitude must be ≥ 0, got {amplitude!r}")
        self.inner, self.amplitude = inner, amplitude
        self.rng = np.random.default_rng(seed)

    def __call__(self, x: ArrayLike) -> FloatArray:
        out = np.asarray(self.inner(np.atleast_2d(np.asarray(x, dtype=np.float64))), dtype=np.float64)
        return np.asarray(out + self.rng.uniform(-self.amplitude, self.amplitude, out.shape))


@dataclass(frozen=True)
class DriftMap:
    """x_0 ↦ x_0 + ``velocity``, x_i ↦ x_0 + ``gain`` (x_i − x_0) for i ≥ 1, on (N, ``dim``): every coordinate
    settles onto the first, which moves by a constant each map — no orbit, a walk whose band keeps moving (it turns
    or drifts slowly)."""

    velocity: float
    gain: float = 0.5
    dim: int = 3

    def __call__(self, x: ArrayLike) -> FloatArray:
        x = np.atleast_2d(np.asarray(x, dtype=np.float64))
        out = x[:, :1] + self.gain * (x - x[:, :1])
        out[:, 0] = x[:, 0] + self.velocity
        return np.asarray(out, dtype=np.float64)


def iterates(F: Callable[[FloatArray], FloatArray], x0: ArrayLike, n: int) -> FloatArray:
    """x_0, F(x_0), …, F^n(x_0) (n + 1, d) of a batched map."""
    xs = [np.asarray(x0, dtype=np.float64)]
    for _ in range(n):
        xs.append(np.asarray(F(xs[-1][None]), dtype=np.float64)[0])
    return np.array(xs)


@dataclass(frozen=True)
class DivergingPush:
    """A push model with late falls and a known answer, for the push certificate's recovery criterion
    (:mod:`.recovery`). A push of impulse |J| leaves the walker at distance d₁ = |J| / mass from its orbit
    after the pushed step; each further step maps d ↦ a d + b d² (a < 1: small deviations die out; the unstable
    point d_u = (1 − a) / b separates the pushes that recover from those that diverge); the walker falls in the first
    step whose d exceeds ``d_fall``. Pushes just above the true critical impulse J_u = mass · d_u walk several steps
    before they fall: a certificate that only asks "no fall within k steps" certifies some of them."""

    mass: float = 10.0
    a: float = 0.6
    b: float = 0.4
    d_fall: float = 3.0

    @property
    def critical(self) -> float:
        """J_u [N s]: every push above it eventually falls, every push below it recovers."""
        return self.mass * (1.0 - self.a) / self.b

    def walk(self, impulse: ArrayLike, steps: int) -> tuple[NDArray[np.int64], FloatArray]:
        """Impulses J (N, 2) walked the pushed step and ``steps`` more: the 1-based step each fell in (0: none) and
        its distance d at the end (NaN if it fell)."""
        d = np.linalg.norm(np.atleast_2d(np.asarray(impulse, dtype=float)), axis=1) / self.mass
        fall = np.zeros(d.size, dtype=np.int64)
        for k in range(1, steps + 2):
            if k > 1:  # a fallen walker's d stops (and cannot overflow)
                d = np.where(fall == 0, self.a * d + self.b * d * d, d)
            fall[(fall == 0) & (d > self.d_fall)] = k
        return fall, np.where(fall == 0, d, np.nan)

    def map(self, steps: int, radius: float | None) -> Callable[[FloatArray, object], FloatArray]:
        """The push map of :class:`.push.PushMap` on this model: (0, 0) for a push that neither falls within
        the pushed step and ``steps`` more nor ends farther than ``radius`` from the orbit (None: falls only)."""
        def P(j: FloatArray, progress: object = None) -> FloatArray:
            fall, d = self.walk(j, steps)
            failed = (fall > 0) if radius is None else (fall > 0) | ~(np.nan_to_num(d, nan=np.inf) <= radius)
            out = np.zeros((np.atleast_2d(j).shape[0], 2))
            out[failed] = np.nan
            return out
        return P
