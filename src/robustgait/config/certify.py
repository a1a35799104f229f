"""Options of a certificate (:mod:`robustgait.certificate.certify`, :mod:`robustgait.certificate.estimators`,
:mod:`robustgait.certificate.barrier`)."""

from __future__ import annotations

import dataclasses
import math
from typing import Annotated, Literal

from robustgait.config.base import Bool, Doc, FieldProblem, Float, Int, config

Method = Literal["sequential", "uniform"]
Barrier = Literal["ball", "paper"]
MapKind = Literal["step", "stride"]
Frame = Literal["heading", "world", "body"]
Reconstruction = Literal["holonomic", "angular-only"]
State = Literal["omega", "centroidal", "velocity"]
CertifiedSet = Literal["ball", "ellipsoid"]
CertifyDisturbance = Literal["push", "state"]
OrbitMetric = Literal["section", "omega"]

# r_max when unset: the paper's 2 rad/s for ``omega``; for the energy states a ball of twice-kinetic-energy radius
# (√J) and for pushes an impulse (N s) — both well beyond what the exo gaits absorb (docs/certificate.md)
DEFAULT_R_MAX = {"omega": 2.0, "centroidal": 10.0, "velocity": 10.0, "push": 100.0}
R_MAX_UNIT = {"omega": "rad/s", "centroidal": "√J", "velocity": "√J", "push": "N s"}
R_MAX_LIMIT = {"omega": 10.0, "centroidal": 1000.0, "velocity": 1000.0, "push": 10_000.0}
# a state certificate's choice when not set: the paper's; a push certificate has exactly these
STATE_CHOICE_DEFAULTS: dict[str, str | int] = {"state": "omega", "set": "ball", "horizon": 1}


# the fixed-point search of results written before the orbit check (2026-11-25): the first iterate after
# fp_min_steps whose base angular velocity moved by less than fp_tol, no Newton step, no spectral radius — how a
# study or a certificate file that predates these fields is read back (study/config.py, io/certfile.py), so that it
# reproduces its x*
LEGACY_FIXED_POINT: dict[str, object] = {"fp_window": 1, "fp_metric": "omega", "fp_newton_iterations": 0,
                                         "fp_rho_max": None}


# the step fractions a damped Newton iteration tries at once (one batch of the map), the smallest residual taken
NEWTON_DAMPING = (1.0, 0.5, 0.25, 0.125)


def fixed_point_options(config: CertifyConfig) -> dict[str, object]:
    """Every ``fp_*`` field of ``config``: the options that decide its fixed point x*."""
    return {f.name: getattr(config, f.name) for f in dataclasses.fields(config) if f.name.startswith("fp_")}


def study_disturbance(metric: str, disturbance: CertifyDisturbance) -> CertifyDisturbance:
    """What a study's evaluation certifies: pushes for the ``push`` metric, states for ``robustness``, otherwise the
    configured ``certify.disturbance`` (``stability`` ranks by steps and only reports the certificate)."""
    if metric == "push":
        return "push"
    return "state" if metric == "robustness" else disturbance


def radius_name(space: str) -> str:
    """The certified radius's name: J* for pushes (``space`` push), r* for a set of states."""
    return "J*" if space == "push" else "r*"


SEED_LIMIT = 2**63 - 1  # a seed fits a signed 64-bit integer (study storage)


def verification_beta(beta: float, attempt: int) -> float:
    """β_a = β / 2^a: the share of β spent on verification attempt a ≥ 1 of the sequential estimator (Σ_a β_a = β)."""
    if attempt < 1:
        raise ValueError(f"verification attempts count from 1, got {attempt}")
    return beta * 0.5**attempt


def verification_size(epsilon: float, beta: float, attempt: int) -> int:
    """n_a = ⌈ln β_a / ln(1 − ε)⌉: the least batch with (1 − ε)^{n_a} ≤ β_a (:func:`verification_beta`)."""
    n = math.log(verification_beta(beta, attempt)) / math.log1p(-epsilon)
    return max(1, math.ceil(n - 1e-9))  # the slack absorbs rounding when n is an integer


@config
class SequentialConfig:
    """Options of the sequential estimator (:mod:`robustgait.certificate.estimators`; defaults measured in
    ``docs/certificate.md``)."""

    epsilon: Annotated[Float, Doc("bound on the violating volume fraction of B(r*) to certify", gt=0.0,
                                  lt=1.0)] = 0.02
    budget: Annotated[Int, Doc("most map evaluations in all rounds", ge=1, le=10_000)] = 3000
    first_round: Annotated[Int, Doc("round 1: uniform samples in B(r_max)", ge=1, le=10_000)] = 200
    round_size: Annotated[Int, Doc("proposals per exploration round", ge=1, le=10_000)] = 50
    explore: Annotated[Int, Doc("exploration samples before the first verification", ge=0, le=100_000)] = 600
    explore_after_failure: Annotated[Int, Doc("exploration samples before each further verification", ge=0,
                                              le=100_000)] = 200
    local_fraction: Annotated[Float, Doc("share of local proposals (around the violating samples closest to x*)",
                                         ge=0.0, le=1.0)] = 0.5
    spread: Annotated[Float, Doc("σ of the local directions, u = (u_elite + σ g)/‖·‖", gt=0.0, le=10.0)] = 0.15
    elites: Annotated[Int, Doc("violating samples closest to x* that local proposals start from", ge=1,
                               le=1000)] = 8
    min_depth: Annotated[Float, Doc("smallest relative depth 1 − d/r̂ of a local proposal (log-uniform depths)",
                                    gt=0.0, lt=1.0)] = 1e-3
    verify_chunk: Annotated[Int, Doc("evaluate a verification batch in chunks of this many samples and abandon it at "
                                     "the first chunk that shrinks r̂ (0: the whole batch at once)", ge=0,
                                     le=10_000)] = 0


@config
class EllipsoidConfig:
    """How the shape S of the ellipsoid {δ : δᵀ S δ ≤ r²} is found (:mod:`robustgait.certificate.shape`): a
    least-squares fit of the certified map's linearization A at x* on a small ball, then AᵀSA − S = −I, det S = 1."""

    fit_samples: Annotated[Int, Doc("map evaluations of the fit (uniform in the fit ball)", ge=4, le=10_000)] = 64
    fit_radius: Annotated[Float, Doc("radius of the fit ball, as a fraction of r_max", gt=0.0, le=1.0)] = 0.05
    compare_ball: Annotated[Bool, Doc("also certify the ball of the same state and report the ellipsoid's volume "
                                      "ratio to it (twice the samples)")] = False


@config
class PushConfig:
    """The push certificate J* (``disturbance = push``, :mod:`robustgait.certificate.push`): the steps after the
    pushed one within which a fall is a failure, and the sizes of the sequential estimator's first round and
    exploration — smaller than a state certificate's, since the failing set of a 2-D impulse disk needs less
    exploration (the statement does not depend on it; ε, β, the budget and the rest are ``sequential``'s). Push
    duration and phases are the validation's (``validate.push_duration``, ``validate.push_phase``)."""

    steps: Annotated[Int, Doc("steps after the pushed one within which a fall, or not being back near the orbit at "
                              "their end, is a failure", ge=1, le=100)] = 3
    recovery: Annotated[Bool, Doc("a pushed walk must also end those steps back near its orbit (recovery_radius); "
                                  "false: a fall is the only failure")] = True
    recovery_radius: Annotated[Float, Doc(
        "the orbit's neighbourhood: distance from x* in the base's Froude-scaled velocity (v/√(g l), ω/√(g/l), "
        "heading frame; docs/certificate.md, Recovery)", ge=0.0, le=100.0)] = 0.3
    recovery_scatter: Annotated[Float, Doc("the recovery radius is at least this multiple of the undisturbed orbit's "
                                           "own scatter about x*", ge=0.0, le=1000.0)] = 3.0
    recovery_band_steps: Annotated[Int, Doc("undisturbed steps from x* whose scatter sets that floor", ge=1,
                                            le=1000)] = 10
    first_round: Annotated[Int, Doc("round 1: uniform pushes in the disk of radius r_max", ge=1, le=10_000)] = 50
    explore: Annotated[Int, Doc("exploration pushes before the first verification", ge=0, le=100_000)] = 100
    explore_after_failure: Annotated[Int, Doc("exploration pushes before each further verification", ge=0,
                                              le=100_000)] = 50
    verify_chunk: Annotated[Int, Doc("verification pushes simulated per chunk; a batch is abandoned at the first "
                                     "chunk with a fall inside the disk verified (0: the whole batch at once)", ge=0,
                                     le=10_000)] = 25


@config
class CertifyConfig:
    """Options of a certificate: the estimator (``sequential``: rounds with a verified bound; ``uniform``: the
    paper's N samples uniform in B(r_max)), the DTBF (barrier, α, r_max), the confidence 1 − β, the seed of the
    perturbations (common random numbers: gaits certified with one seed meet the same perturbations), the map,
    reduced state and reconstruction, and the fixed-point search."""

    method: Annotated[Method, Doc(
        "r* estimator: sequential (rounds inside B(r̂) until a fresh batch certifies the violating fraction ≤ "
        "epsilon) or uniform (the paper's N samples in B(r_max))")] = "sequential"
    state: Annotated[State, Doc(
        "reduced state certified: omega (the paper's base angular velocity, rad/s), centroidal (centroidal momentum, "
        "kinetic-energy metric) or velocity (every contact-consistent velocity, kinetic-energy metric)")] = "omega"
    set: Annotated[CertifiedSet, Doc(
        "certified set: ball (in the state's metric) or ellipsoid (shaped by the map's linearization at x*)")] = "ball"
    horizon: Annotated[Int, Doc("steps k between a sample and the iterate the DTBF condition is checked on (no fall "
                                "within the k steps)", ge=1, le=10)] = 1
    disturbance: Annotated[CertifyDisturbance, Doc(
        "what is certified: push (a disk of push impulses at the validation's push duration and phases, J*: the "
        "choice that ranks gaits by their push robustness, docs/validation.md) or state (a set of perturbed "
        "states, r*; setting state, set or horizon without disturbance implies it)")] = "push"
    n_samples: Annotated[Int, Doc("uniform: number of sampled perturbations N", ge=1, le=10_000)] = 200
    r_max: Annotated[Float | None, Doc(
        "radius of the sampled ball (unset: 2 rad/s for omega, 10 √J for centroidal and velocity, 100 N s for push)",
        gt=0.0, le=10_000.0)] = None
    alpha: Annotated[Float, Doc("DTBF decay rate α", gt=0.0, lt=1.0)] = 0.05
    beta: Annotated[Float, Doc("1 − confidence of the violation bound", gt=0.0, lt=1.0)] = 0.05
    seed: Annotated[Int, Doc("seed of the perturbations", ge=0, le=SEED_LIMIT)] = 0
    barrier: Annotated[Barrier, Doc("ball: H = r² − ‖x − x*‖²; paper: the paper's literal H = r − ‖x − x*‖²")] = "ball"
    map: Annotated[MapKind, Doc("step (one step, mirrored) or stride (two steps) return map")] = "step"
    stride_fallback: Annotated[Bool, Doc(
        "step map only: when its iterates settle on no orbit (wandering or period two), search the stride map's — "
        "two physical steps, one on each leg, unmirrored: the orbit of a robot whose left and right differ — and "
        "certify that map if it settles (the certificate says so)")] = True
    reconstruction: Annotated[Reconstruction, Doc("how a full state is rebuilt from a reduced one")] = "holonomic"
    frame: Annotated[Frame, Doc("frame of the base angular velocity (heading: world frame without yaw)")] = "heading"
    fp_tol: Annotated[Float, Doc("fixed point: the orbit has settled when the last fp_window iterates all lie within "
                                 "this distance of the newest (fp_metric)", unit="rad/s or m/s", gt=0.0,
                                 le=1.0)] = 1e-2
    fp_window: Annotated[Int, Doc("fixed point: iterates before the newest that must lie within fp_tol of it (1: "
                                  "the one before, the rule before 2026-11-25; longer than fp_max_steps: never "
                                  "settles)", ge=1, le=100)] = 20
    fp_metric: Annotated[OrbitMetric, Doc(
        "fixed point: distance of two iterates in section coordinates (the canonical state without base x, y and "
        "yaw, positions divided by the step duration) or omega (the base angular velocity in frame)")] = "section"
    fp_min_steps: Annotated[Int, Doc("fixed point: least steps before stopping (at most fp_max_steps)", ge=1,
                                     le=1000)] = 10
    fp_max_steps: Annotated[Int, Doc("fixed point: give up after this many steps", ge=1, le=1000)] = 100
    fp_newton_iterations: Annotated[Int, Doc(
        "fixed point: most damped Newton iterations on P(x) = x from the settled iterate (0: x* is that iterate)",
        ge=0, le=50)] = 0
    fp_newton_tol: Annotated[Float, Doc("fixed point: Newton has converged when ‖P(x) − x‖ is below this (section "
                                        "coordinates)", unit="rad/s or m/s", gt=0.0, le=1.0)] = 1e-8
    fp_fd_step: Annotated[Float, Doc("fixed point: finite-difference step of the map's Jacobian (section "
                                     "coordinates)", unit="rad/s or m/s", gt=0.0, le=0.1)] = 1e-6
    fp_fd_jump: Annotated[Float, Doc(
        "fixed point: a Jacobian column whose forward and backward differences differ by more than this fraction of "
        "the smaller is taken one-sided, the smaller (the map jumps within the step on the other side)", gt=0.0,
        le=100.0)] = 0.5
    fp_rho_max: Annotated[Float | None, Doc(
        "fixed point: refuse an orbit whose linearized map has a spectral radius ρ ≥ this (not set: ρ is not "
        "computed)", gt=0.0, le=10.0)] = 1.0
    sequential: SequentialConfig = dataclasses.field(default_factory=SequentialConfig)
    ellipsoid: EllipsoidConfig = dataclasses.field(default_factory=EllipsoidConfig)
    push: PushConfig = dataclasses.field(default_factory=PushConfig)

    @property
    def estimator(self) -> SequentialConfig:
        """The sequential estimator's options in effect: ``sequential``, with the push certificate's round sizes for
        ``disturbance = push``."""
        if self.disturbance != "push":
            return self.sequential
        p = self.push
        return dataclasses.replace(self.sequential, first_round=p.first_round, explore=p.explore,
                                   explore_after_failure=p.explore_after_failure, verify_chunk=p.verify_chunk)

    def __post_init__(self) -> None:
        if self.disturbance == "push" and self.chooses_a_state:
            raise FieldProblem("disturbance", "a push certificate (J*) has no reduced state, set or horizon (got "
                               f"state {self.state}, set {self.set}, horizon {self.horizon}); for a certificate of "
                               "states set disturbance = state")
        if self.r_max is not None and self.r_max > R_MAX_LIMIT[self.space]:
            raise FieldProblem("r_max", f"must satisfy 0 < x ≤ {R_MAX_LIMIT[self.space]:g} {R_MAX_UNIT[self.space]} "
                               f"when certifying {self.space} (got {self.r_max:g})")
        seq = self.estimator
        need = seq.first_round + verification_size(seq.epsilon, self.beta, 1)
        if self.method == "sequential" and seq.budget < need:
            raise FieldProblem("sequential.budget", f"{seq.budget} samples cannot hold the first round "
                               f"({seq.first_round}) and one verification batch ({need - seq.first_round} for "
                               f"epsilon = {seq.epsilon:g}, beta = {self.beta:g})")

    def state_choice(self) -> tuple[str, str, int]:
        """(state, set, horizon): what a state certificate certifies."""
        return self.state, self.set, self.horizon

    @property
    def chooses_a_state(self) -> bool:
        """Whether state, set or horizon differ from :data:`STATE_CHOICE_DEFAULTS` (which a push certificate has)."""
        return self.state_choice() != tuple(STATE_CHOICE_DEFAULTS.values())

    @property
    def space(self) -> str:
        """What the certified radius measures: the reduced state's name, or ``push``."""
        return "push" if self.disturbance == "push" else self.state

    @property
    def radius(self) -> float:
        """r_max in effect: the field, or the default of the space (:data:`DEFAULT_R_MAX`)."""
        return self.r_max if self.r_max is not None else DEFAULT_R_MAX[self.space]

    @property
    def unit(self) -> str:
        """Unit of r* and of the certificate's coordinates."""
        return R_MAX_UNIT[self.space]

    @property
    def period(self) -> int:
        """Steps of one iterate of the map: 1 (step map) or 2 (stride map)."""
        return 2 if self.map == "stride" else 1

    def fixed_point_steps(self, dim: int) -> int:
        """Most steps the fixed-point search simulates on a section of ``dim`` coordinates: ``fp_max_steps`` steps of
        iterates, then per Newton iteration a finite-difference batch (2 dim + 1 maps) and its damped steps, then the
        Jacobian at x* and the image recorded for the touchdown's flow (2 dim + 2 maps), a map being :attr:`period`
        steps; with ``stride_fallback``, the step map's search that found no orbit and then the stride map's."""
        fd = 2 * dim + 1
        rho = fd + 1 if self.fp_rho_max is not None else 0
        own = self.fp_max_steps + self.period * (self.fp_newton_iterations * (fd + len(NEWTON_DAMPING)) + rho)
        if self.map == "step" and self.stride_fallback:  # the step map's search gave up, then the stride map's
            return self.fp_max_steps + dataclasses.replace(self, map="stride").fixed_point_steps(dim)
        return own

    @property
    def min_steps(self) -> int:
        """Least fixed-point steps in effect: fp_min_steps, or fp_max_steps if that is smaller."""
        return min(self.fp_min_steps, self.fp_max_steps)

    @property
    def samples_planned(self) -> int:
        """Most map evaluations of the estimator: N (uniform) or the budget (sequential), plus the ellipsoid's fit."""
        n = self.n_samples if self.method == "uniform" else self.estimator.budget
        if self.set != "ellipsoid" or self.disturbance != "state":
            return n
        return n + self.ellipsoid.fit_samples + (n if self.ellipsoid.compare_ball else 0)

    @property
    def steps_per_sample(self) -> int:
        """Steps simulated per sample at most: the horizon (× 2 for the stride map), or a push's steps."""
        if self.disturbance == "push":
            return 1 + self.push.steps
        return self.horizon * (2 if self.map == "stride" else 1)
