"""Estimators of r* from samples of a batched return map, and the confidence statement each one supports.

``docs/certificate.md`` (derivations). Two estimators, both exact for their samples
(:func:`.barrier.solve_radius`):

* ``uniform`` — the paper's: N i.i.d. samples uniform in B(x*, r_max); the statement is a union bound over
  the N + 1 values r* can take (:func:`.barrier.certify_map`,
  :func:`~.barrier.violation_bound`).
* ``sequential`` (:func:`certify_map_sequential`) — beyond the paper. Exploration proposes r̂, verification
  certifies a radius below it:

  1. round 1: the uniform draw with N = ``first_round`` (the same samples as ``uniform`` with that N and seed);
  2. exploration rounds of ``round_size`` proposals inside B(r̂): a fraction uniform in B(r̂), the rest
     *local* — around the directions of the violating samples closest to x* ("elites"), just inside r̂
     (relative depth log-uniform in [``min_depth``, 1]). After each round r̂ = the exact r* of all samples so
     far; it only shrinks. Exploration may use any distribution and any map — a cheaper one than the map certified
     (``explore``: the push certificate's exploration pushes stop sooner) —: it only proposes;
  3. verification attempt a = 1, 2, …: the radius r_a = ``verify_margin`` × r̂ is fixed (a push certificate's: the
     largest radius whose batch the fall curve fitted to every sample so far predicts to pass with probability
     ``push.pass_probability``, :mod:`.fallcurve`; its estimate is the curve's Ĵ), then a fresh batch of n_a
     samples i.i.d. uniform in B(r_a) is drawn and evaluated on the certified map, with n_a the least n such that
     (1 − ε)^n ≤ β_a (β_1 = s β, β_a = (1 − s) β / 2^(a−1) after, s = ``first_share``). If no sample of the batch
     violates the condition at r_a (and, but for a push certificate, r_a stays the supremum of the feasible radii up
     to r_a over every sample so far) the certificate is r* = r_a; otherwise r̂ shrinks, ``explore_after_failure``
     more exploration samples follow and attempt a + 1 is drawn. With ``verify_chunk`` > 0 the batch is evaluated in
     chunks, the samples farthest from x* first (where a violation is likeliest), and abandoned at the first chunk
     with a violation (it cannot pass then); the whole batch is still drawn, so the streams stay aligned. When the
     next batch would exceed ``budget`` samples the estimator stops and says there is no statement.

  ``verify=False`` stops after exploration: r̂ is an *estimate* (no statement), what a study ranks gaits by.

Guarantee of ``sequential``: P(a certificate is issued and the fraction of the volume of B(r*) where the
condition at radius r* fails exceeds ε) ≤ Σ_a β_a ≤ β, whatever the map of exploration and the exploration itself.
Proof: let V(r) be that violating fraction (on the certified map) and F_{a−1} everything drawn before batch a. r_a is
F_{a−1}-measurable and batch a is i.i.d. uniform in B(r_a) independently of F_{a−1}, so on {V(r_a) > ε}, P(all n_a
samples satisfy | F_{a−1}) ≤ (1 − ε)^{n_a} ≤ β_a. A certificate at attempt a needs that event; a union over a gives
Σ β_a; the order in which a batch's samples are evaluated, and a batch abandoned at its first violating chunk
(``verify_chunk``), issue no certificate, so they change nothing here. Assumptions: the certified map is
deterministic; the condition is evaluated exactly at the verification samples; the pseudo-random streams stand in
for independent uniforms. It says nothing about violating sets of volume fraction ≤ ε, and it is not a proof of
invariance.

Common random numbers: every perturbation is x* + ρ·u with the direction u and the fraction ρ taken from
streams that depend on the seed only (round 1: ``default_rng(seed)``; exploration: ``default_rng([seed, 1])``;
verification: ``default_rng([seed, 2])``), in a fixed order per sample, whatever the map. Two maps certified
with one seed see the same round-1 perturbations, the same exploration draws (scaled by their own r̂ and,
for local proposals, around their own elites) and the same verification directions and radius fractions.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace

import numpy as np
from numpy.typing import ArrayLike, NDArray

from robustgait.certificate.barrier import (
    BatchedMap,
    Certificate,
    RadiusSolution,
    Round,
    _check_point,
    certificate_from_samples,
    distances,
    evaluate_map,
    sample_ball,
    solve_radius,
    violation_end,
)
from robustgait.certificate.fallcurve import FallCurve, fit_fall_curve
from robustgait.certificate.verification import attempt_size, check_budget, verification_bound
from robustgait.config import Barrier, CertifyConfig
from robustgait.config.certify import Estimator
from robustgait.errors import RobustGaitError

__all__ = [
    "Replay",
    "certify_map_sequential",
    "propose_round",
]

FloatArray = NDArray[np.float64]


# ------------------------------------------------------------------------------------- exploration
def _unit(v: FloatArray) -> FloatArray:
    norm = np.linalg.norm(v, axis=1, keepdims=True)
    return np.asarray(v / np.where(norm > 0.0, norm, 1.0), dtype=np.float64)


def propose_round(rng: np.random.Generator, m: int, x_star: FloatArray, r_hat: float, elites: FloatArray,
                  config: Estimator) -> FloatArray:
    """m exploration proposals (m, n) inside B(x*, r̂).

    Draws, in this order and whatever the data (common random numbers): g (m, n) ~ N(0, I) and w (m, 3) ~
    U(0, 1). Proposal i is *local* if w_i0 < local_fraction and there are elites (unit directions (k, n) of
    the violating samples closest to x*): direction (e_j + σ g_i)/‖·‖ with j = ⌊w_i2 k⌋, distance
    r̂ (1 − min_depth^{w_i1}) (relative depth log-uniform in [min_depth, 1]); otherwise *global*: direction
    g_i/‖g_i‖, distance r̂ w_i1^{1/n} (uniform in the ball).
    """
    n = x_star.shape[0]
    g = rng.standard_normal((m, n))
    w = rng.random((m, 3))
    u = _unit(g)
    rho = w[:, 1] ** (1.0 / n)
    if elites.shape[0] > 0:
        local = w[:, 0] < config.local_fraction
        j = np.minimum((w[:, 2] * elites.shape[0]).astype(np.int64), elites.shape[0] - 1)
        u[local] = _unit(elites[j[local]] + config.spread * g[local])
        rho[local] = 1.0 - config.min_depth ** w[local, 1]
    return np.asarray(x_star + r_hat * rho[:, None] * u, dtype=np.float64)


class Replay:
    """A map of exploration that answers from an earlier run's exploration: while it is asked for exactly the samples
    that run evaluated, in the order it evaluated them (``samples`` (N, n) and their ``images`` (N, n), NaN rows: fell),
    it returns their stored images without evaluating ``P``; from the first call that asks for anything else it
    evaluates ``P``, and keeps doing so. The sequential estimator's exploration is a function of the seed and the
    images alone, so a run of the same map, seed and options asks for those samples again and, replayed, goes on
    exactly as if it had evaluated them (a study verifies a gait whose estimate it already explored). ``P``'s calls
    take the samples and an optional progress callback (called with the number of samples answered). ``replayed``:
    samples answered from the stored run."""

    def __init__(self, P: Callable[..., ArrayLike], samples: ArrayLike, images: ArrayLike):
        self.P = P
        self.samples = np.asarray(samples, dtype=np.float64)
        self.images = np.asarray(images, dtype=np.float64)
        if self.samples.shape != self.images.shape or self.samples.ndim != 2:
            raise RobustGaitError(f"replayed exploration: samples {self.samples.shape} and images "
                                  f"{self.images.shape} must be two arrays of one shape (N, n)")
        self.next = 0
        self.replayed = 0

    def __call__(self, x: FloatArray, progress: Callable[[int], None] | None = None) -> FloatArray:
        k, m = self.next, x.shape[0]
        if k + m <= self.samples.shape[0] and np.array_equal(x, self.samples[k:k + m]):
            self.next += m
            self.replayed += m
            if progress is not None:
                progress(m)
            return self.images[k:k + m].copy()
        self.next = self.samples.shape[0]  # the run has left the stored one: never replay after this
        return np.asarray(self.P(x, progress), dtype=np.float64)


class _Pool:
    """All samples so far with their distances, violation ends and rounds; r̂ of all of them. ``P``: the certified
    map (verification rounds); ``explore``: the map of the other rounds."""

    def __init__(self, P: BatchedMap, explore: BatchedMap, x_star: FloatArray, alpha: float, r_max: float,
                 barrier: Barrier):
        self.P, self.explore, self.x_star, self.alpha, self.r_max, self.barrier = P, explore, x_star, alpha, r_max, \
            barrier
        self.x0: list[FloatArray] = []
        self.x1: list[FloatArray] = []
        self.d = np.empty(0)
        self.p = np.empty(0)
        self.s = np.empty(0)
        self.round_of: list[NDArray[np.int64]] = []
        self.rounds: list[Round] = []
        self.r_hat = r_max
        self.verified: RadiusSolution | None = None  # the radius the last passed verification batch certified
        self._curve: tuple[int, FallCurve] | None = None  # the last fall curve and the samples it was fitted to

    @property
    def used(self) -> int:
        return int(self.d.size)

    def _evaluate(self, P: BatchedMap, part: FloatArray) -> None:
        x1 = evaluate_map(P, part)
        d, p = distances(part, x1, self.x_star)
        self.x0.append(part)
        self.x1.append(x1)
        self.d = np.concatenate([self.d, d])
        self.p = np.concatenate([self.p, p])
        self.s = np.concatenate([self.s, violation_end(d, p, self.alpha, self.barrier)])
        self.round_of.append(np.full(d.size, len(self.rounds), dtype=np.int64))

    def _solve(self, r_max: float, since: int = 0) -> RadiusSolution:
        """:func:`.barrier.solve_radius` up to ``r_max`` over the samples from index ``since`` on."""
        return solve_radius(self.d[since:], self.p[since:], alpha=self.alpha, r_max=r_max, barrier=self.barrier)

    def add(self, kind: str, radius: float, x0: FloatArray) -> None:
        """Evaluate the exploration map on x0, add the samples as a round and recompute r̂."""
        self._evaluate(self.explore, x0)
        self.r_hat = self._solve(self.r_max).radius
        self.rounds.append(Round(kind, float(radius), int(x0.shape[0]), self.used, float(self.r_hat), None))

    def verify(self, radius: float, x0: FloatArray, chunk: int = 0, batch_only: bool = False) -> bool:
        """Evaluate a verification batch x0 (uniform in B(radius)) on the certified map and add it as a round. It
        passes when ``radius`` is still the supremum of the feasible radii up to it over every sample so far: no sample
        of the batch violates the condition there (nor chains a violation up to it); with ``batch_only``, when no
        sample of the batch violates the condition at ``radius`` (the earlier samples are the exploration's: a radius
        placed by the fall curve may hold an exploration sample that fell).

        ``chunk`` > 0: evaluate x0 in chunks of that many samples, the farthest from x* first, and abandon the rest
        of the batch at the first chunk that fails it — the batch cannot pass then, and its remaining samples would
        only be simulated to be discarded. The round holds the samples evaluated, in the order evaluated."""
        order = np.argsort(-np.linalg.norm(x0 - self.x_star, axis=1), kind="stable") if chunk > 0 else None
        x0 = x0 if order is None else x0[order]
        step = chunk if chunk > 0 else x0.shape[0]
        n_used = 0
        first = self.used
        sol = self._solve(radius)
        for start in range(0, x0.shape[0], max(step, 1)):
            part = x0[start:start + step]
            self._evaluate(self.P, part)
            n_used += part.shape[0]
            sol = self._solve(radius, since=first if batch_only else 0)
            if sol.radius != radius:
                break
        passed = sol.radius == radius
        self.r_hat = self._solve(self.r_max).radius
        self.verified = sol if passed else None
        self.rounds.append(Round("verify", float(radius), int(n_used), self.used, float(self.r_hat), passed))
        return passed

    def fall_curve(self) -> FallCurve:
        """The fall curve (:func:`.fallcurve.fit_fall_curve`) of every sample so far: its distance from x* as its
        size, violated somewhere (fell) as its outcome, r_max as the cap; fitted again only when samples were added
        since the last fit."""
        if self._curve is None or self._curve[0] != self.used:
            keep = self.d > 0.0
            self._curve = (self.used, fit_fall_curve(self.d[keep], (self.s > self.d)[keep], self.r_max))
        return self._curve[1]

    def elites(self, k: int) -> FloatArray:
        """Unit directions (≤ k, n) of the samples violated somewhere (s > d, falls included) with d ≥ r̂,
        closest to x* first: the frontier of the violating set that r̂ rests on."""
        idx = np.flatnonzero((self.s > self.d) & (self.d >= self.r_hat) & (self.d > 0.0))
        idx = idx[np.argsort(self.d[idx], kind="stable")[:k]]
        x0 = np.concatenate(self.x0)
        return _unit(x0[idx] - self.x_star)


def certify_map_sequential(P: BatchedMap, x_star: ArrayLike, config: CertifyConfig | None = None, *,
                           explore: BatchedMap | None = None,
                           verify: bool | Callable[[float], bool] = True) -> Certificate:
    """The sequential estimator (module docstring): certify a batched map P: (N, n) → (N, n) (NaN rows =
    fell) around its fixed point x_star (n,) with ``config`` (``r_max``, ``alpha``, ``beta``, ``seed``,
    ``barrier`` and the estimator's options ``sequential``). ``explore``: the map the first round and the exploration
    rounds are evaluated on (default P). Returns a :class:`~.barrier.Certificate` with ``method="sequential"``, every
    round (``rounds``: kind, radius, samples, samples used, r̂ after it), ``estimate`` (r̂ after the exploration
    before the first verification) and, if a verification batch passed, r* = its radius and ``violation_bound`` = ε_a
    ≤ ε (:func:`~.verification.verification_bound`) at confidence 1 − β; otherwise ``budget_exhausted`` (bound 1)
    or, if r̂ reached 0, a vacuous certificate. A budget that cannot hold one batch is refused before any sample
    (:func:`~.verification.check_budget`). ``verify=False``: the exploration alone, r* = the estimate r̂, with no
    statement (``verified`` false); a callable decides from the estimate r̂ whether to go on to verification.
    """
    full = config or CertifyConfig()
    check_budget(full)
    cfg = full.estimator
    xs = _check_point("x_star", x_star)
    r, a, b, seed, barrier = full.radius, full.alpha, full.beta, full.seed, full.barrier
    level = full.push.pass_probability if full.disturbance == "push" else None  # the push batch's fall curve
    n = xs.shape[0]
    explore_rng = np.random.default_rng([seed, 1])
    verify_rng = np.random.default_rng([seed, 2])
    pool = _Pool(P, P if explore is None else explore, xs, a, r, barrier)
    pool.add("uniform", r, sample_ball(cfg.first_round, n, r, xs, np.random.default_rng(seed)))
    explore_left, attempt, passed = cfg.explore, 0, False
    estimate: float | None = None
    curve: FallCurve | None = None
    verifying = verify is not False
    while pool.r_hat > 0.0:
        room = cfg.budget - pool.used - (attempt_size(full, attempt + 1) if verifying else 0)
        while explore_left > 0 and room > 0 and pool.r_hat > 0.0:
            m = min(cfg.round_size, explore_left, room)
            pool.add("explore", pool.r_hat, propose_round(explore_rng, m, xs, pool.r_hat, pool.elites(cfg.elites), cfg))
            explore_left -= m
            room -= m
        if level is not None:
            curve = pool.fall_curve()
        if estimate is None:
            estimate = pool.r_hat if curve is None else curve.estimate(cfg.epsilon)
            verifying = verify(estimate) if callable(verify) else verify
        if pool.r_hat == 0.0 or not verifying:
            break
        attempt += 1
        n_a = attempt_size(full, attempt)
        if pool.used + n_a > cfg.budget:
            break
        if level is None:
            radius = cfg.verify_margin * pool.r_hat
        else:
            assert curve is not None  # fitted above whenever there is a level
            radius = curve.verification_radius(n_a, level)
        if radius <= 0.0:
            break
        if pool.verify(radius, sample_ball(n_a, n, radius, xs, verify_rng), cfg.verify_chunk, curve is not None):
            passed = True
            break
        explore_left = cfg.explore_after_failure

    x0_all, x1_all = np.concatenate(pool.x0), np.concatenate(pool.x1)
    solution = pool.verified if passed else None
    if not verifying and curve is not None and estimate is not None:  # the estimate alone is the fitted Ĵ
        solution = RadiusSolution(estimate, True)
    cert = certificate_from_samples(x0_all, x1_all, xs, alpha=a, r_max=r, beta=b, seed=seed, barrier=barrier,
                                    solution=solution)
    assert passed or cert.radius == (pool.r_hat if solution is None else solution.radius)
    cert = replace(cert, method="sequential", rounds=tuple(pool.rounds), sample_round=np.concatenate(pool.round_of),
                   estimate=float(pool.r_hat if estimate is None else estimate), verified=verifying,
                   curve=None if curve is None else pool.fall_curve().summary(cfg.epsilon))
    if passed:
        n_a = pool.rounds[-1].n_samples
        beta_text = "β/2" if cfg.first_share == 0.5 and attempt == 1 else (
            f"{cfg.first_share:g} β" if attempt == 1 else f"β_{attempt}")
        if level is not None:
            basis = (f"a batch of {n_a} fresh samples drawn uniformly in this ball after r* was fixed — the largest "
                     f"ball whose batch the fall curve fitted to the earlier samples predicted to pass with probability"
                     f" {level:g} — all satisfy it (verification attempt {attempt}: (1 − ε)^{n_a} ≤ {beta_text})")
        elif cfg.verify_margin == 1.0:
            basis = (f"a batch of {n_a} fresh samples drawn uniformly in this ball after r* was fixed all satisfy it "
                     f"(verification attempt {attempt}: (1 − ε)^{n_a} ≤ {beta_text}; r* is exact for all "
                     f"{cert.n_samples} samples of {len(pool.rounds)} rounds)")
        else:
            basis = (f"a batch of {n_a} fresh samples drawn uniformly in this ball after r* = {cfg.verify_margin:g} "
                     f"r̂ was fixed all satisfy it (verification attempt {attempt}: (1 − ε)^{n_a} ≤ {beta_text})")
        return replace(cert, violation_bound=verification_bound(n_a, b, attempt, cfg.first_share), basis=basis)
    return replace(cert, violation_bound=1.0, budget_exhausted=verifying and pool.r_hat > 0.0)
