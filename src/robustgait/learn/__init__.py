"""Preference learning over a robot's action space (``docs/studies.md``): the grid (``space``), the oracles
(``oracle``), the preference GP (``model``), the learners (``learners``: POLAR-style Thompson sampling,
qEUBO, random) and the loop against known scores (``offline``).

Submodules load lazily (the learners import torch and BoTorch; the oracles and the grid do not)."""

from typing import TYPE_CHECKING

from robustgait._lazy import lazy_exports

if TYPE_CHECKING:
    from robustgait.learn.history import History, iteration_seed
    from robustgait.learn.learners import EuboLearner, Learner, PolarLearner, RandomLearner, make_learner
    from robustgait.learn.model import thompson_draws
    from robustgait.learn.offline import ReplayResult, replay
    from robustgait.learn.oracle import Outcome, batch_comparisons, prefer, score
    from robustgait.learn.space import ActionSpace

_EXPORTS = {
    **dict.fromkeys(("EuboLearner", "Learner", "PolarLearner", "RandomLearner", "make_learner"), "learners"),
    **dict.fromkeys(("History", "iteration_seed"), "history"),
    "thompson_draws": "model",
    **dict.fromkeys(("Outcome", "batch_comparisons", "prefer", "score"), "oracle"),
    **dict.fromkeys(("ReplayResult", "replay"), "offline"),
    "ActionSpace": "space",
}


__getattr__ = lazy_exports(__name__, _EXPORTS)

__all__ = [
    "ActionSpace",
    "EuboLearner",
    "History",
    "Learner",
    "Outcome",
    "PolarLearner",
    "RandomLearner",
    "ReplayResult",
    "batch_comparisons",
    "iteration_seed",
    "make_learner",
    "prefer",
    "replay",
    "score",
    "thompson_draws",
]
