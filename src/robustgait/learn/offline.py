"""The learning loop without simulation: a learner against known scores (a synthetic utility, or a table of
evaluated gaits). What the study loop does, minus evaluation and storage — for tests and benchmarks."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

from robustgait.learn.history import History
from robustgait.learn.learners import Learner


@dataclass
class ReplayResult:
    """Per iteration: the proposed grid indices and the recommendation after its comparisons."""

    proposals: list[list[int]] = field(default_factory=list)
    recommendations: list[int | None] = field(default_factory=list)
    history: History = field(default_factory=History)

    @property
    def unique(self) -> int:
        return len({i for batch in self.proposals for i in batch})


def replay(learner: Learner, score_of: Callable[[int], float], iterations: int, batch: int) -> ReplayResult:
    """Run ``iterations`` × ``batch`` with the oracle score of every grid index given by ``score_of``."""
    out = ReplayResult()
    batches: list[list[tuple[int, float]]] = []
    for k in range(iterations):
        proposal = learner.propose(out.history, k, batch)
        out.proposals.append(proposal)
        batches.append([(i, float(score_of(i))) for i in proposal])
        out.history = History.from_batches(batches)
        out.recommendations.append(learner.recommend(out.history, k))
    return out
