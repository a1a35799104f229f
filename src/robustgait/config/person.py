"""Options of studies with a person as the oracle (``docs/person.md``): the robustness floor that keeps a person from
being shown a gait that is not robust, what the page shows, the simulated persons of tests and benchmarks, and where
the page is served (:mod:`robustgait.web`); and the requirements any study may put on a recorded figure."""

from __future__ import annotations

import dataclasses
import math
import re
from typing import Annotated

from robustgait.config.base import Bool, Doc, FieldProblem, Float, Int, Str, config
from robustgait.config.certify import SEED_LIMIT

# A requirement on a recorded figure: NAME OP NUMBER, e.g. "speed>=0.2" (names: robustgait.study.person.FIGURE_NAMES)
REQUIREMENT = re.compile(r"^\s*([A-Za-z_][A-Za-z0-9_]*)\s*(>=|<=|>|<)\s*([-+]?[0-9.]+(?:[eE][-+]?[0-9]+)?)\s*$")
Speed = Annotated[Float, Doc(ge=0.0, le=5.0)]
Weight = Annotated[Float, Doc(ge=0.0, le=100.0)]


def parse_requirement(text: str) -> tuple[str, str, float]:
    """``"speed>=0.2"`` → ("speed", ">=", 0.2); a ValueError naming the problem otherwise."""
    m = REQUIREMENT.match(text)
    if m is None:
        raise ValueError(f"{text!r} is not FIGURE OP NUMBER with OP one of >= <= > < (e.g. speed>=0.2)")
    value = float(m.group(3))
    if not math.isfinite(value):
        raise ValueError(f"{text!r}: the bound must be finite")
    return m.group(1), m.group(2), value


def _check_range(name: str, r: tuple[float, float]) -> None:
    if not r[0] <= r[1]:
        raise FieldProblem(name, f"the range's low end {r[0]:g} is above its high end {r[1]:g}")


@config
class SimulatedPersonConfig:
    """A simulated person (``--metric simulated-person``, as CoSpar and ROIAL evaluate their learners): a hidden utility
    u = −w_v ((v − v*)/speed_scale)² − w_a (a_z + a_y)/acceleration_scale − w_i i/impact_scale over the walk's speed
    v, vertical and lateral pelvis acceleration RMS a_z, a_y and impact i (body weights), with the preferred speed v*
    and the weights w drawn uniformly from their ranges with ``seed``; it ranks a batch by Plackett–Luce draws
    (pairwise: Bradley–Terry, P(a ≻ b) = σ((u_a − u_b)/noise)) and says "cannot tell" of two neighbours in its
    ranking with probability cannot_tell · exp(−|u_a − u_b|/noise)."""

    seed: Annotated[Int, Doc("the simulated person: its preferred speed, weights and answers are drawn from it", ge=0,
                             le=SEED_LIMIT)] = 0
    preferred_speed: Annotated[tuple[Speed, Speed], Doc("range the preferred walking speed v* is drawn from",
                                                         unit="m/s")] = (0.18, 0.30)
    speed_scale: Annotated[Float, Doc("a speed this far from v* costs w_v", unit="m/s", gt=0.0, le=5.0)] = 0.05
    speed_weight: Annotated[tuple[Weight, Weight], Doc("range of w_v")] = (0.5, 2.0)
    acceleration_scale: Annotated[Float, Doc("pelvis acceleration RMS (vertical + lateral) that costs w_a",
                                             unit="m/s²", gt=0.0, le=100.0)] = 1.0
    acceleration_weight: Annotated[tuple[Weight, Weight], Doc("range of w_a")] = (0.5, 2.0)
    impact_scale: Annotated[Float, Doc("touchdown impact that costs w_i", unit="body weights", gt=0.0,
                                       le=100.0)] = 5.0
    impact_weight: Annotated[tuple[Weight, Weight], Doc("range of w_i")] = (0.0, 1.0)
    noise: Annotated[Float, Doc("Bradley–Terry scale of the answers (utility units): P(a ≻ b) = σ(Δu/noise)", gt=0.0,
                                le=100.0)] = 0.1
    cannot_tell: Annotated[Float, Doc("rate of 'cannot tell' between neighbours of equal utility", ge=0.0,
                                      le=1.0)] = 0.3

    def __post_init__(self) -> None:
        for name in ("preferred_speed", "speed_weight", "acceleration_weight", "impact_weight"):
            _check_range(name, getattr(self, name))


@config
class PersonConfig:
    """A study ranked by a person (``--metric person``, on a web page) or a simulated one (``simulated-person``): only
    gaits certified at or above the robustness ``floor`` and meeting ``study.require`` are shown; the others are ranked
    below every shown gait without asking (among themselves by the certificate's oracle)."""

    floor: Annotated[Float | None, Doc("robustness floor, in the certificate's unit (J*: N s); not set: floor_fraction "
                                       "× the certificate of the grid gait nearest the robot's default gait", ge=0.0,
                                       le=1e6)] = None
    floor_fraction: Annotated[Float, Doc("the floor when not set, as a fraction of the reference gait's certificate "
                                         "(reference_in_batch)",
                                         ge=0.0, le=10.0)] = 0.75
    reference_in_batch: Annotated[Bool, Doc("the floor's reference is the grid point nearest the default gait, the "
                                            "first gait of the first batch (one evaluation fewer before the first "
                                            "question); false: the default gait itself, evaluated beside the first "
                                            "batch")] = True
    blind: Annotated[Bool, Doc("hide the certificate, speed and comfort figures on the page (the person judges the "
                               "videos alone)")] = False
    labels: Annotated[Bool, Doc("ask an ordinal label per gait (bad / neutral / good, as ROIAL)")] = True
    figures: Annotated[tuple[Str, ...], Doc("comfort figures shown beside each gait (not in blind mode)")] = (
        "speed", "cadence", "pelvis_acc_vertical_rms", "pelvis_acc_lateral_rms", "impact_force_ratio",
        "cost_of_transport")
    overdraw: Annotated[Int, Doc("candidates the learner proposes beyond the batch: they are evaluated in its order "
                                 "only while fewer than the iteration's batch (study.batch, study.first_batch) may be "
                                 "shown, so that a batch shown is full", ge=0, le=100)] = 5
    ahead: Annotated[Bool, Doc("while a person answers, evaluate the candidates the learner would propose next if the "
                               "answer were the one its model predicts (reused when they are proposed; discarded "
                               "otherwise)")] = True
    region: Annotated[Bool, Doc("propose only where the gaits are predicted to clear the floor (a model of the "
                                "certificate's figure over the action space, robustgait.learn.floor), as ROIAL asks "
                                "only in a region predicted safe")] = True
    region_lengthscale: Annotated[Float, Doc("that model's kernel lengthscale ℓ, on the action space normalized to "
                                             "[0, 1] per axis", gt=0.0, le=10.0)] = 0.2
    region_prior: Annotated[Float, Doc("that model's prior weight w₀ on a figure of 0 (an unexplored gait is not "
                                       "presumed robust): larger, a smaller region", gt=0.0, le=100.0)] = 0.1
    min_shown: Annotated[Int, Doc("a batch is asked only once at least this many of its gaits may be shown (a "
                                  "ranking of one gait tells the learner nothing): more candidates are proposed "
                                  "until then", ge=1, le=100)] = 2
    video_steps: Annotated[Int, Doc("steps of each gait's looping video (after the comfort figures' skipped steps; "
                                    "2: one stride, which loops seamlessly)", ge=1, le=20)] = 2
    video_fps: Annotated[Int, Doc("the videos' frames per second of walking (they play in real time)", ge=5,
                                  le=60)] = 20
    video_width: Annotated[Int, Doc("the width of one view (a video is the side and the front view side by side)",
                                    unit="px", ge=64, le=1920)] = 288
    video_height: Annotated[Int, Doc("the videos' height", unit="px", ge=64, le=1080)] = 324
    video_shadows: Annotated[Bool, Doc("the videos draw the light's shadows and the floor's reflections (rendered in "
                                       "software, without a GPU, they cost most of each frame)")] = False
    video_antialias: Annotated[Bool, Doc("the videos' frames are multisampled (smoother edges; in software, several "
                                         "times the cost of a frame)")] = False
    simulated: SimulatedPersonConfig = dataclasses.field(default_factory=SimulatedPersonConfig)


@config
class WebConfig:
    """Where the page of a person study is served (not saved with the study). The URL carries a random token: a
    request without it, or with another, is refused (403). Served on 127.0.0.1 by default: ``host = "0.0.0.0"``
    exposes the page — and the study — to the network (``docs/person.md``)."""

    host: Annotated[Str, Doc("address the page is served on (127.0.0.1: this machine only)")] = "127.0.0.1"
    port: Annotated[Int, Doc("TCP port of the page; 0: any free port", ge=0, le=65535)] = 8765
    linger: Annotated[Float, Doc("after the last answer, how long the page stays up for the final recommendation",
                                 unit="s", ge=0.0, le=86400.0)] = 60.0
