"""Options of studies (:mod:`robustgait.study`), their learners (:mod:`robustgait.learn`), how they run, and the
commands around them (compare, report)."""

from __future__ import annotations

import dataclasses
import os
from typing import Annotated, Literal

from robustgait.config.base import Bool, Doc, FieldProblem, Float, Int, Str, config
from robustgait.config.certify import SEED_LIMIT
from robustgait.config.person import parse_requirement

Metric = Literal["push", "robustness", "stability", "person", "simulated-person"]
PERSON_METRICS = ("person", "simulated-person")
LearnerName = Literal["polar", "eubo", "random"]
Hyperparameters = Literal["fixed", "fit"]
ExecutorName = Literal["local", "ray"]
Verify = Literal["shown", "all"]
# a gait that walked the cap without a certificate scores cap − this: below every certified gait (cap + r* ≥ cap),
# above every faller (≤ cap − 1)
UNCERTIFIED_PENALTY = 0.5
Lengthscale = Annotated[Float, Doc(gt=0.0, le=1e3)]
FIGURE_ALIASES = {"j_star": "value", "r_star": "value", "certificate_value": "value"}
"""Other names a requirement may give the certificate's figure ``value`` (J* of a push certificate, r* of a state
certificate; ``certificate_value`` as studies wrote it before); a requirement's text keeps the name it was written
with."""
CERTIFICATE_FIGURES = ("value", *FIGURE_ALIASES)  # a requirement's names of the certificate figure
# a study whose grid holds at most this many gaits stores the learner's posterior mean over it after each iteration,
# so that the report draws its map without importing and refitting the preference model
POSTERIOR_STORE_LIMIT = 20_000


@config
class PreferenceModelConfig:
    """Hyperparameters of the preference GP (POLAR: fixed)."""

    lengthscale: Annotated[tuple[Lengthscale, ...], Doc(
        "ℓ per action dimension (or one for all), as a fraction of each axis' range")] = (0.4,)
    outputscale: Annotated[Float, Doc("prior variance s² of the utility, in units of the logistic likelihood's "
                                      "scale", gt=0.0, le=1e6)] = 10.0
    hyperparameters: Annotated[Hyperparameters, Doc(
        "fixed (POLAR: the values above) or fit (BoTorch's priors, Laplace marginal likelihood, every iteration)")] = (
        "fixed")
    jitter: Annotated[Float, Doc("added to covariance diagonals before Cholesky (relative to s²)", gt=0.0,
                                 le=1.0)] = 1e-6

    def __post_init__(self) -> None:
        if not self.lengthscale:
            raise ValueError("lengthscale: needs at least one value")

    def lengthscales(self, dim: int) -> tuple[float, ...]:
        if len(self.lengthscale) == 1:
            return self.lengthscale * dim
        if len(self.lengthscale) != dim:
            raise ValueError(f"{len(self.lengthscale)} lengthscales for a {dim}-dimensional action space")
        return self.lengthscale


@config
class LearnerConfig:
    """Options of the learners: Thompson sampling draws jointly over the whole grid when it has at most
    ``max_candidates`` points, else over that many (visited + neighbourhood of the best + uniformly random)."""

    model: PreferenceModelConfig = dataclasses.field(default_factory=PreferenceModelConfig)
    max_candidates: Annotated[Int, Doc("largest grid drawn jointly by Thompson sampling", ge=2,
                                       le=1_000_000)] = 1000
    neighbourhood: Annotated[Int, Doc("grid steps around the current best kept in the candidate subset", ge=0,
                                      le=100)] = 1
    max_redraws: Annotated[Int, Doc("draws per batch slot before taking the best new point", ge=1,
                                    le=10_000)] = 50
    eubo_samples: Annotated[Int, Doc("quasi-MC samples of qEUBO", ge=1, le=100_000)] = 256


@config
class StudyConfig:
    """A study: the preference oracle (``push``: J* among gaits that walk the step cap; ``robustness``: the state
    certificate r* among them; ``stability``: steps only; ``person``: a person's answers on a web page;
    ``simulated-person``: a simulated person's, ``[person]``), the requirements on recorded figures (a gait that fails
    one ranks below every gait that meets them all), the learner, the budget (iterations × batch gaits), the learner's
    seed (iteration k is seeded from (seed, k); the certificates' seed is ``certify.seed``), where it is stored."""

    metric: Annotated[Metric, Doc("preference oracle: J* (push: the push certificate) among gaits that walk the step "
                                  "cap, r* (robustness: the state certificate), steps only (stability), a person on a "
                                  "web page (person) or a simulated one (simulated-person)")] = "push"
    require: Annotated[tuple[Str, ...], Doc(
        "requirements FIGURE OP NUMBER on recorded figures (speed>=0.2; OP >= <= > <; a comfort figure, "
        "value (the certificate's verified J* or r*; also named j_star or r_star), steps_taken, mean_speed or a gait "
        "parameter), comma-separated: a gait failing one ranks below all that meet them")] = ()
    verify: Annotated[Verify, Doc(
        "which gaits get the verified certificate: shown (the learner ranks every gait on its certificate's estimate "
        "from exploration; verified are each iteration's best, the recommendations, the gaits a person is shown and "
        "the Pareto front) or all (every gait, ranked on its verified value)")] = "shown"
    learner: Annotated[LearnerName, Doc("polar (Thompson sampling), eubo (qEUBO) or random")] = "polar"
    iterations: Annotated[Int, Doc("batches", ge=1, le=1000)] = 10
    batch: Annotated[Int, Doc("gaits per batch (a batch is ranked: at least 2)", ge=2, le=100)] = 5
    first_batch: Annotated[Int | None, Doc(
        "a person study's first batch (the person's first question comes once this many gaits may be shown; later "
        "batches, evaluated while the person answers, hold batch); not set: batch", ge=2, le=100)] = 2
    seed: Annotated[Int, Doc("seed of the learner", ge=0, le=SEED_LIMIT)] = 0
    uncertified_penalty: Annotated[Float, Doc(
        "push and robustness oracles: a gait that walked the step cap without a certificate scores cap − this, "
        "below every certified gait (0: tied with a certified r* = 0, as a study written without this field ranks)",
        ge=0.0, lt=1.0)] = UNCERTIFIED_PENALTY
    storage: Annotated[Str | None, Doc(
        "SQLAlchemy URL of the Optuna database; not set: a SQLite file in the study directory")] = None
    study_name: Annotated[Str, Doc("the Optuna study's name in its database")] = "robustgait"
    learning: LearnerConfig = dataclasses.field(default_factory=LearnerConfig)

    def __post_init__(self) -> None:
        for text in self.require:
            try:
                parse_requirement(text)
            except ValueError as exc:
                raise FieldProblem("require", str(exc)) from None

    def batch_size(self, k: int) -> int:
        """Gaits in iteration k's batch: ``first_batch`` for a person study's first iteration, else ``batch`` (a
        person study's iteration holds this many gaits that may be shown, besides its over-drawn candidates)."""
        if k == 0 and self.asks_a_person and self.first_batch is not None:
            return self.first_batch
        return self.batch

    @property
    def trials_planned(self) -> int:
        return sum(self.batch_size(k) for k in range(self.iterations))

    @property
    def verifies_all(self) -> bool:
        """Every evaluation computes the verified certificate (``verify = all``, or a requirement on the certificate's
        figure, which only a verified value can meet)."""
        return self.verify == "all" or any(parse_requirement(t)[0] in CERTIFICATE_FIGURES for t in self.require)

    @property
    def asks_a_person(self) -> bool:
        """Ranked by a person or a simulated one (``[person]``: the floor, the page)."""
        return self.metric in PERSON_METRICS


@config
class RunConfig:
    """How a study runs (not saved with it: a study may be resumed with other options)."""

    executor: Annotated[ExecutorName, Doc(
        'local worker processes or Ray actors (pip install "robustgait[ray]")')] = "local"
    workers: Annotated[Int | None, Doc("parallel evaluations; not set: min(cores, 2)", ge=1, le=256)] = None
    address: Annotated[Str | None, Doc("Ray cluster address, e.g. auto; not set: start a local Ray")] = None

    @property
    def n_workers(self) -> int:
        return self.workers if self.workers is not None else default_workers()


def default_workers() -> int:
    """min(cores, 2): a study's evaluations in parallel when not set."""
    return max(1, min(os.cpu_count() or 1, 2))


@config
class CompareConfig:
    """``robustgait study compare``: the best gaits of two studies re-certified with fresh seeds."""

    seeds: Annotated[Int, Doc("fresh certificate seeds", ge=1, le=1000)] = 5
    seed_base: Annotated[Int, Doc("first fresh seed", ge=0, le=SEED_LIMIT)] = 1000
    samples: Annotated[Int | None, Doc("uniform certificates: samples N; not set: study A's", ge=1,
                                       le=10_000)] = None


@config
class ReportConfig:
    """Figures: the study report and gait tiles."""

    axes: Annotated[tuple[Str, Str], Doc("the two parameters of the posterior-mean map")] = (
        "step_length", "step_duration")
    video: Annotated[Bool, Doc("render a video of the best gait")] = True
    video_steps: Annotated[Int, Doc("steps the best gait walks in the video, from its initial state", ge=1,
                                    le=50)] = 6
    video_fps: Annotated[Int, Doc("the video's frames per second of walking (it plays in real time)", ge=5,
                                  le=60)] = 25
    video_width: Annotated[Int, Doc("the video's width (as shown on the page)", unit="px", ge=64, le=1920)] = 480
    video_height: Annotated[Int, Doc("the video's height", unit="px", ge=64, le=1080)] = 360
    video_shadows: Annotated[Bool, Doc("the video draws the light's shadows and the floor's reflections (rendered in "
                                       "software, without a GPU, they cost most of each frame)")] = False
    video_antialias: Annotated[Bool, Doc("the video's frames are multisampled (smoother edges; in software, "
                                         "several times the cost of a frame)")] = False
    pareto_figure: Annotated[Str, Doc("comfort figure (a cost: lower is better) of the trade-off front over the "
                                      "certificate, the speed and it (study pareto, the report)")] = (
        "pelvis_acc_vertical_rms")
    tile_frames: Annotated[Int, Doc("gait tiles: frames of one step (each a 320 × 480 tile)", ge=2, le=60)] = 6
    tile_warmup_steps: Annotated[Int, Doc("gait tiles: steps walked before the step shown", ge=0, le=1000)] = 4
