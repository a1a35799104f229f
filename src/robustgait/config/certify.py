"""Options of a certificate (:mod:`robustgait.certificate.certify`, :mod:`robustgait.certificate.estimators`,
:mod:`robustgait.certificate.barrier`)."""

from __future__ import annotations

import dataclasses
from typing import Annotated, Any, Literal

from robustgait.config.base import Bool, Doc, FieldProblem, Float, Int, config

Method = Literal["sequential", "uniform"]
Barrier = Literal["ball", "paper"]
MapKind = Literal["auto", "step", "stride"]
Frame = Literal["heading", "world", "body"]
Reconstruction = Literal["holonomic", "angular-only"]
State = Literal["omega", "centroidal", "velocity"]
CertifiedSet = Literal["ball", "ellipsoid"]
CertifyDisturbance = Literal["push", "state"]

# r_max when unset: the paper's 2 rad/s for ``omega``; for the energy states a ball of twice-kinetic-energy radius
# (√J) and for pushes an impulse (N s) — both well beyond what the exo gaits absorb (docs/certificate.md)
DEFAULT_R_MAX = {"omega": 2.0, "centroidal": 10.0, "velocity": 10.0, "push": 100.0}
R_MAX_UNIT = {"omega": "rad/s", "centroidal": "√J", "velocity": "√J", "push": "N s"}
R_MAX_LIMIT = {"omega": 10.0, "centroidal": 1000.0, "velocity": 1000.0, "push": 10_000.0}
# a state certificate's choice when not set: the paper's; a push certificate has exactly these
STATE_CHOICE_DEFAULTS: dict[str, str | int] = {"state": "omega", "set": "ball", "horizon": 1}


# the fields of the fixed-point search and of the fixed push horizon that the orbit search and the recovery band
# replaced: a study or a certificate file that has them is read back without them (io/studyfile.py,
# io/certfile.py), and its orbit is found again by the orbit search
RETIRED_FIELDS = ("fp_tol", "fp_window", "fp_metric", "fp_min_steps", "fp_max_steps", "fp_newton_iterations",
                  "fp_newton_tol", "fp_fd_step", "fp_fd_jump", "fp_rho_max", "stride_fallback")
RETIRED_PUSH_FIELDS = ("steps", "recovery_band_steps", "verify_margin")

# the estimator's options whose default depends on what is certified (SequentialConfig: unset, the disturbance's);
# a push certificate's failing set, in a 2-D disk of impulses, needs less exploration than a state certificate's
ESTIMATOR_DEFAULTS: dict[str, dict[str, int | float]] = {
    "push": {"first_round": 50, "explore": 100, "explore_after_failure": 50, "verify_chunk": 25, "first_share": 0.9},
    "state": {"first_round": 200, "explore": 600, "explore_after_failure": 200, "verify_chunk": 0, "first_share": 0.5},
}
# which estimator options apply to which certificate (``inapplicable``): the rest apply to every sequential one
STATE_ONLY_ESTIMATOR_FIELDS = ("verify_margin",)  # a push certificate's disk comes from its fall curve


def without_retired(certify: dict[str, object]) -> dict[str, object]:
    """A ``[certify]`` table as written by an older version, without :data:`RETIRED_FIELDS` and, in its ``push``
    table, :data:`RETIRED_PUSH_FIELDS`. A table written when the push certificate had its own round sizes (``push``'s
    first_round, explore, explore_after_failure, verify_chunk, first_share) has them moved to ``sequential``: unset
    where both were their defaults, else the values of its disturbance (the rest is read as it is)."""
    out = {k: v for k, v in certify.items() if k not in RETIRED_FIELDS}
    push = out.get("push")
    if isinstance(push, dict):
        keys = ESTIMATOR_DEFAULTS["push"]
        given = out.get("sequential")
        seq: dict[str, object] = dict(given) if isinstance(given, dict) else {}
        out["push"] = {k: v for k, v in push.items() if k not in RETIRED_PUSH_FIELDS and k not in keys}
        if any(k in push for k in keys):  # written before the estimator's options were one table
            is_push = out.get("disturbance", "push") == "push"
            for k, push_default in keys.items():
                v, state_v = push.get(k, push_default), seq.get(k, ESTIMATOR_DEFAULTS["state"][k])
                if v == push_default and state_v == ESTIMATOR_DEFAULTS["state"][k]:
                    seq[k] = None
                else:
                    seq[k] = v if is_push else state_v
            out["sequential"] = seq
    return out


def orbit_options(config: CertifyConfig) -> dict[str, object]:
    """The options that decide a certificate's orbit and x*: ``map`` and every field of ``orbit``."""
    return {"map": config.map, **{f"orbit.{f.name}": getattr(config.orbit, f.name)
                                   for f in dataclasses.fields(config.orbit)}}


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


@config
class SequentialConfig:
    """Options of the sequential estimator (:mod:`robustgait.certificate.estimators`; defaults measured in
    ``docs/certificate.md``)."""

    epsilon: Annotated[Float, Doc("bound on the violating volume fraction of B(r*) to certify", gt=0.0,
                                  lt=1.0)] = 0.02
    budget: Annotated[Int, Doc("most map evaluations in all rounds", ge=1, le=10_000)] = 3000
    first_round: Annotated[Int | None, Doc(
        "round 1: uniform samples in B(r_max) (unset: 50 pushes, 200 states)", ge=1, le=10_000)] = None
    round_size: Annotated[Int, Doc("proposals per exploration round", ge=1, le=10_000)] = 50
    explore: Annotated[Int | None, Doc("exploration samples before the first verification (unset: 100 pushes, 600 "
                                       "states)", ge=0, le=100_000)] = None
    explore_after_failure: Annotated[Int | None, Doc("exploration samples before each further verification (unset: "
                                                     "50 pushes, 200 states)", ge=0, le=100_000)] = None
    local_fraction: Annotated[Float, Doc("share of local proposals (around the violating samples closest to x*)",
                                         ge=0.0, le=1.0)] = 0.5
    spread: Annotated[Float, Doc("σ of the local directions, u = (u_elite + σ g)/‖·‖", gt=0.0, le=10.0)] = 0.15
    elites: Annotated[Int, Doc("violating samples closest to x* that local proposals start from", ge=1,
                               le=1000)] = 8
    min_depth: Annotated[Float, Doc("smallest relative depth 1 − d/r̂ of a local proposal (log-uniform depths)",
                                    gt=0.0, lt=1.0)] = 1e-3
    verify_chunk: Annotated[Int | None, Doc(
        "evaluate a verification batch in chunks of this many samples, farthest from x* first, and abandon it at the "
        "first chunk with a violation inside the radius verified (0: the whole batch at once; unset: 25 pushes, 0 "
        "states)", ge=0, le=10_000)] = None
    verify_margin: Annotated[Float, Doc("state certificates: the radius a verification batch is drawn in, as a "
                                        "fraction of the explored r̂ (below 1: fewer failed batches, a smaller "
                                        "certified radius; a push certificate's disk comes from its fall curve, "
                                        "push.pass_probability)", gt=0.0, le=1.0)] = 1.0
    first_share: Annotated[Float | None, Doc(
        "share of β spent on the first verification attempt (the rest halves over the further attempts; 0.5: β/2, "
        "β/4, …; a larger share, a smaller first batch; unset: 0.9 pushes, 0.5 states)", gt=0.0, lt=1.0)] = None

    def resolved(self, disturbance: str) -> Estimator:
        """The options in effect for a certificate of ``disturbance``: each unset one at its default
        (:data:`ESTIMATOR_DEFAULTS`)."""
        defaults = ESTIMATOR_DEFAULTS[disturbance]
        values: dict[str, Any] = {f.name: getattr(self, f.name) for f in dataclasses.fields(self)}
        values.update({k: v for k, v in defaults.items() if values[k] is None})
        return Estimator(**values)


@dataclasses.dataclass(frozen=True)
class Estimator:
    """The sequential estimator's options in effect for one certificate (:meth:`SequentialConfig.resolved`: every
    option set; the fields are :class:`SequentialConfig`'s)."""

    epsilon: float
    budget: int
    first_round: int
    round_size: int
    explore: int
    explore_after_failure: int
    local_fraction: float
    spread: float
    elites: int
    min_depth: float
    verify_chunk: int
    verify_margin: float
    first_share: float


@config
class EllipsoidConfig:
    """How the shape S of the ellipsoid {δ : δᵀ S δ ≤ r²} is found (:mod:`robustgait.certificate.shape`): a
    least-squares fit of the certified map's linearization A at x* on a small ball, then AᵀSA − S = −I, det S = 1."""

    fit_samples: Annotated[Int, Doc("map evaluations of the fit (uniform in the fit ball)", ge=4, le=10_000)] = 64
    fit_radius: Annotated[Float, Doc("radius of the fit ball, as a fraction of r_max", gt=0.0, le=1.0)] = 0.05
    compare_ball: Annotated[Bool, Doc("also certify the ball of the same state and report the ellipsoid's volume "
                                      "ratio to it (twice the samples)")] = False


@config
class OrbitConfig:
    """How the orbit a gait walks is found and judged (:mod:`robustgait.certificate.orbit`,
    :mod:`robustgait.certificate.search`; ``docs/certificate.md``, "The orbit the gait walks"). Distances are in band
    coordinates: the section state made dimensionless by the leg length l and gravity g (angles in rad, velocities
    over √(g l) or √(g/l))."""

    max_steps: Annotated[Int, Doc("steps walked at most while the switching states are searched for their band",
                                  ge=2, le=1000)] = 100
    min_steps: Annotated[Int, Doc("least steps before the walk may count as settled", ge=1, le=1000)] = 10
    hold_steps: Annotated[Int, Doc("steps walked after the switching states settled, in which every window's centre "
                                   "must stay in the band (a walk that drifts, turns or slowly falls moves it)", ge=0,
                                   le=1000)] = 64
    window: Annotated[Int, Doc("steps of each of the two windows compared (the last against the one before); a "
                               "multiple of max_period", ge=2, le=500)] = 16
    max_period: Annotated[Int, Doc("longest period (physical steps) searched, a power of two: 1 (the step map "
                                   "only), 2 (also the stride map), 4, 8", ge=1, le=8)] = 4
    period_ratio: Annotated[Float, Doc("a shorter period is chosen while its scatter is within this multiple of the "
                                       "best period's", ge=1.0, le=100.0)] = 2.0
    settle_multiple: Annotated[Float, Doc("settled: every state of the last window lies within this multiple of the "
                                          "window before's scatter of its centre", gt=0.0, le=100.0)] = 3.0
    drift: Annotated[Float, Doc("settled: the last window's centre moved at most this multiple of its own scatter",
                                gt=0.0, le=100.0)] = 1.0
    floor: Annotated[Float, Doc("scatter below which two windows are the same (band coordinates)", gt=0.0,
                                le=1.0)] = 1e-3
    probe_impulse: Annotated[Float, Doc("stability: the first impulse of the probing pushes, as a fraction of m √(g l) "
                                        "(the robot's momentum at its pendulum speed; 0: no probe); doubled until "
                                        "they take the walk out of its band", ge=0.0,
                                        le=1.0)] = 0.01
    probe_pushes: Annotated[Int, Doc("stability: probing pushes, at evenly spaced directions; the orbit is stable when "
                                     "none moves away from the band and not all fall (one that falls is a push "
                                     "beyond the basin, for J*)", ge=1, le=100)] = 8
    probe_horizon: Annotated[Int, Doc("stability: steps after the probing push within which it must be back in the "
                                      "band (push.recovery_steps of them in a row)", ge=2, le=100)] = 20
    probe_growth: Annotated[Float, Doc("stability: a probe that neither fell nor came back diverges when its largest "
                                       "distance from the band over the last quarter of its steps exceeds this "
                                       "multiple of its largest over the first half", gt=1.0, le=100.0)] = 1.5
    probe_doublings: Annotated[Int, Doc("stability: most doublings of the probing impulse while no probe leaves the "
                                        "band", ge=0, le=10)] = 3
    linearization: Annotated[Bool, Doc("also compute the linearized map at x* as a diagnostic (ρ; never a verdict): "
                                       "two Jacobians and a perturbation along the leading eigenvector")] = False
    fd_step: Annotated[Float, Doc("linearization: the finer finite-difference step (section coordinates; the coarser "
                                  "is ten times it)", unit="rad/s or m/s", gt=0.0, le=0.01)] = 1e-6
    fd_jump: Annotated[Float, Doc(
        "linearization: a Jacobian column whose forward and backward differences differ by more than this fraction of "
        "the smaller is taken one-sided, the smaller (the map jumps within the step on the other side)", gt=0.0,
        le=100.0)] = 0.5
    fd_agreement: Annotated[Float, Doc("linearization: ρ is defined when its values at the two steps agree within this "
                                       "fraction", gt=0.0, le=1.0)] = 0.1
    confirm_steps: Annotated[Int, Doc("linearization: maps a perturbation along the leading eigenvector is iterated "
                                      "to confirm ρ", ge=1, le=100)] = 8
    confirm_tolerance: Annotated[Float, Doc("linearization: the perturbation's per-map factor must lie within this "
                                            "fraction of ρ", gt=0.0, le=1.0)] = 0.25

    def __post_init__(self) -> None:
        if self.max_period & (self.max_period - 1):
            raise FieldProblem("max_period", f"must be a power of two (1, 2, 4, 8), got {self.max_period}")
        if self.window % self.max_period:
            raise FieldProblem("window", f"must be a multiple of max_period {self.max_period}, got {self.window}")
        if self.max_steps < max(self.min_steps, 2 * self.window):
            raise FieldProblem("max_steps", f"must be at least min_steps ({self.min_steps}) and two windows "
                               f"({2 * self.window}), got {self.max_steps}")


@config
class PushConfig:
    """The push certificate J* (``disturbance = push``, :mod:`robustgait.certificate.push`): when a pushed walk has
    failed — it fell within the pushed step and ``horizon`` more —, when it may stop early — back in its orbit's band
    for ``recovery_steps`` consecutive steps (recovered) —, how exploration pushes are judged, and where its
    verification batch is drawn: in the largest disk the gait's fitted fall curve predicts to pass
    (``pass_probability``, :mod:`robustgait.certificate.fallcurve`). The estimator's options (round sizes, ε, β's
    shares, the budget) are ``sequential``'s, with a push certificate's defaults (:data:`ESTIMATOR_DEFAULTS`). Push
    duration and phases are the validation's (``validate.push_duration``, ``validate.push_phase``)."""

    horizon: Annotated[Int, Doc("steps after the pushed one within which a fall is a failure (the statement's "
                                "horizon)", ge=1, le=100)] = 20
    recovery: Annotated[Bool, Doc("stop a pushed walk once it has recovered (back in its orbit's band for "
                                  "recovery_steps steps); false: every push walks the whole horizon")] = True
    recovery_radius: Annotated[Float, Doc(
        "the band's floor ν: every coordinate of the section state within this distance of x*'s, in band "
        "coordinates (angles in rad, velocities over √(g l) or √(g/l); docs/certificate.md, Recovery)", gt=0.0,
        le=10.0)] = 0.03
    recovery_scatter: Annotated[Float, Doc("the band is at least this multiple of the undisturbed orbit's own "
                                           "scatter in each coordinate", ge=0.0, le=1000.0)] = 3.0
    recovery_steps: Annotated[Int, Doc("consecutive steps in the band that make a pushed walk recovered (it stops)",
                                       ge=1, le=100)] = 2
    r_max_scale: Annotated[Float, Doc(
        "certify.r_max of a push certificate when not set: this multiple of the robot's momentum at its pendulum "
        "speed, m √(g l) (the disk of the first round; J* is at most r_max)", gt=0.0, le=10.0)] = 0.25
    pass_probability: Annotated[Float, Doc(
        "the verification disk is the largest whose batch the gait's fall curve, fitted to the exploration's pushes, "
        "predicts to pass (no fall) with this probability (posterior-predictive; docs/certificate.md): higher, a "
        "smaller J* and fewer failed batches", gt=0.0, lt=1.0)] = 0.9
    explore_horizon: Annotated[Int, Doc("exploration: steps after the pushed one within which an exploration push "
                                        "fails (exploration only places the verified disk; the statement rests on "
                                        "the verification batch, at horizon)", ge=1, le=100)] = 8
    explore_recovery_radius: Annotated[Float, Doc(
        "exploration: the band's floor ν of a recovered exploration push (band coordinates)", gt=0.0,
        le=10.0)] = 0.03
    explore_recovery_steps: Annotated[Int, Doc("exploration: consecutive steps in that band that make an exploration "
                                               "push recovered", ge=1, le=100)] = 1

    def __post_init__(self) -> None:
        if self.recovery and self.recovery_steps > 1 + self.horizon:
            raise FieldProblem("recovery_steps", f"must be at most the pushed step and horizon ({1 + self.horizon} "
                               f"steps), got {self.recovery_steps}")
        if self.recovery and self.explore_recovery_steps > 1 + self.explore_horizon:
            raise FieldProblem("explore_recovery_steps", "must be at most the pushed step and explore_horizon "
                               f"({1 + self.explore_horizon} steps), got {self.explore_recovery_steps}")

    def exploring(self) -> PushConfig:
        """The push rule of exploration pushes: ``explore_horizon``, ``explore_recovery_radius`` and
        ``explore_recovery_steps`` in place of the statement's ``horizon``, ``recovery_radius`` and
        ``recovery_steps``."""
        return dataclasses.replace(self, horizon=self.explore_horizon, recovery_radius=self.explore_recovery_radius,
                                   recovery_steps=self.explore_recovery_steps)


@config
class CertifyConfig:
    """Options of a certificate: the estimator (``sequential``: rounds with a verified bound; ``uniform``: the
    paper's N samples uniform in B(r_max)), the DTBF (barrier, α, r_max), the confidence 1 − β, the seed of the
    perturbations (common random numbers: gaits certified with one seed meet the same perturbations), the map,
    reduced state and reconstruction, and the fixed-point search."""

    method: Annotated[Method, Doc(
        "the estimator of J* or r*: sequential (rounds of exploration, then a fresh batch drawn after the radius is "
        "fixed certifies the violating fraction ≤ epsilon) or uniform (the paper's N samples in B(r_max))"
    )] = "sequential"
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
        "radius of the sampled ball (unset: 2 rad/s for omega, 10 √J for centroidal and velocity, push.r_max_scale × "
        "m √(g l) for push; 100 N s where no robot is given)", gt=0.0, le=10_000.0)] = None
    alpha: Annotated[Float, Doc("DTBF decay rate α", gt=0.0, lt=1.0)] = 0.05
    beta: Annotated[Float, Doc("1 − confidence of the violation bound", gt=0.0, lt=1.0)] = 0.05
    seed: Annotated[Int, Doc("seed of the perturbations", ge=0, le=SEED_LIMIT)] = 0
    barrier: Annotated[Barrier, Doc("ball: H = r² − ‖x − x*‖²; paper: the paper's literal H = r − ‖x − x*‖²")] = "ball"
    map: Annotated[MapKind, Doc(
        "the shortest map the orbit is searched on: step (one step, mirrored), stride (two steps, one on each leg), "
        "auto (stride when the robot's left and right differ, else step); an orbit of period k is certified on the "
        "k-step map")] = "auto"
    reconstruction: Annotated[Reconstruction, Doc("how a full state is rebuilt from a reduced one")] = "holonomic"
    frame: Annotated[Frame, Doc("frame of the base angular velocity (heading: world frame without yaw)")] = "heading"
    sequential: SequentialConfig = dataclasses.field(default_factory=SequentialConfig)
    ellipsoid: EllipsoidConfig = dataclasses.field(default_factory=EllipsoidConfig)
    push: PushConfig = dataclasses.field(default_factory=PushConfig)
    orbit: OrbitConfig = dataclasses.field(default_factory=OrbitConfig)

    @property
    def estimator(self) -> Estimator:
        """The sequential estimator's options in effect: ``sequential``, each unset option at this certificate's
        default (:data:`ESTIMATOR_DEFAULTS`)."""
        return self.sequential.resolved(self.disturbance)

    def inapplicable(self, path: str) -> str | None:
        """Why the option at ``path`` (relative to this config: ``sequential.spread``, ``push.horizon``, ``n_samples``)
        does nothing to this certificate, or None when it applies — an option set for a certificate it does not apply
        to is an error, never ignored (``--override``, flags)."""
        head, _, name = path.partition(".")
        if head == "sequential" and self.method != "sequential":
            return f"the sequential estimator's options do nothing to method = {self.method}"
        if head == "sequential" and name in STATE_ONLY_ESTIMATOR_FIELDS and self.disturbance == "push":
            return ("a push certificate draws its verification disk from its fall curve (push.pass_probability), not "
                    f"sequential.{name}")
        if head == "n_samples" and self.method != "uniform":
            return "n_samples is the uniform estimator's; the sequential estimator's budget is sequential.budget"
        if head == "push" and self.disturbance != "push":
            return "push options do nothing to a state certificate (disturbance = state)"
        if head == "ellipsoid" and (self.disturbance == "push" or self.set != "ellipsoid"):
            return "ellipsoid options do nothing unless set = ellipsoid"
        return None

    def __post_init__(self) -> None:
        if self.disturbance == "push" and self.chooses_a_state:
            raise FieldProblem("disturbance", "a push certificate (J*) has no reduced state, set or horizon (got "
                               f"state {self.state}, set {self.set}, horizon {self.horizon}); for a certificate of "
                               "states set disturbance = state")
        if self.r_max is not None and self.r_max > R_MAX_LIMIT[self.space]:
            raise FieldProblem("r_max", f"must satisfy 0 < x ≤ {R_MAX_LIMIT[self.space]:g} {R_MAX_UNIT[self.space]} "
                               f"when certifying {self.space} (got {self.r_max:g})")

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

    def orbit_steps(self, dim: int) -> int:
        """Most steps the orbit search simulates on a section of ``dim`` coordinates: ``orbit.max_steps`` +
        ``orbit.hold_steps`` steps of the walk, the stability probe's pushes (each the pushed step and
        ``orbit.probe_horizon`` more, at each of up to 1 + ``orbit.probe_doublings`` sizes), and with
        ``orbit.linearization`` two finite-difference batches of 2 dim + 1 maps, the image recorded for the touchdown's
        flow and 2 ``orbit.confirm_steps`` maps along the eigenvector, a map being up to ``orbit.max_period`` steps."""
        o = self.orbit
        probe = (1 + o.probe_doublings) * o.probe_pushes * (1 + o.probe_horizon) if o.probe_impulse > 0 else 0
        lin = o.max_period * (2 * (2 * dim + 1) + 1 + 2 * o.confirm_steps) if o.linearization else 0
        return o.max_steps + o.hold_steps + probe + lin

    @property
    def samples_planned(self) -> int:
        """Most map evaluations of the estimator: N (uniform) or the budget (sequential), plus the ellipsoid's fit."""
        n = self.n_samples if self.method == "uniform" else self.estimator.budget
        if self.set != "ellipsoid" or self.disturbance != "state":
            return n
        return n + self.ellipsoid.fit_samples + (n if self.ellipsoid.compare_ball else 0)

    @property
    def steps_per_sample(self) -> int:
        """Steps simulated per sample at most: a push's (the pushed step and ``push.horizon`` more), or the horizon's
        maps of up to ``orbit.max_period`` steps each."""
        if self.disturbance == "push":
            return 1 + self.push.horizon
        return self.horizon * self.orbit.max_period
