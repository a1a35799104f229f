"""Learners (docs/design.md §7): which gaits to evaluate next, from the comparisons so far.

A learner is a pure function of (action space, its config, the study seed, the history of earlier
iterations, the iteration number): the proposals of iteration k are reproduced exactly from the stored
comparisons, which is what lets a killed study resume. Randomness comes from a torch generator seeded
from (seed, iteration) (:func:`iteration_seed`).

* ``polar`` — POLAR/CoSpar regret minimization (maegant/POLAR, ``@Sampling/ThompsonSampling.m``): the
  first iteration is a uniformly random batch (POLAR draws random actions while the posterior is empty);
  then each new gait of the batch is the argmax of one joint posterior draw of the utility over the grid
  (over a random subset plus the visited gaits and the neighbourhood of the current best when the grid
  has more than ``max_candidates`` points, as LineCoSpar restricts to a subspace through the best);
  a draw whose argmax is already in the batch is redrawn.
* ``eubo`` — qEUBO (Astudillo et al. 2023, BoTorch ``qExpectedUtilityOfBestOption``) over the grid,
  the batch chosen greedily by ``optimize_acqf_discrete(q = batch)``; first iteration random.
* ``random`` — uniformly random distinct gaits every iteration: the baseline.

Every learner recommends the same way: the visited gait with the highest posterior mean of the
preference model (:mod:`robustgait.learn.model`) — POLAR's ``updateBestAction`` — so learners differ
only in what they choose to evaluate.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from typing import Any

import numpy as np
import torch
from numpy.typing import NDArray

from robustgait.config import LearnerConfig, LearnerName, choices_of
from robustgait.errors import RobustGaitError
from robustgait.learn.history import History, iteration_seed
from robustgait.learn.model import (
    cholesky_root,
    posterior_mean,
    posterior_mean_cov,
    preference_model,
    thompson_draws,
    torch_threads,
)
from robustgait.learn.space import ActionSpace

IntArray = NDArray[np.int64]


class Learner:
    """Base: proposals and the recommendation from a :class:`History` (see module docstring)."""

    name: str = ""

    def __init__(self, space: ActionSpace, config: LearnerConfig | None = None, seed: int = 0):
        self.space = space
        self.config = config or LearnerConfig()
        self.seed = seed
        self._x = space.normalized()

    def generator(self, iteration: int, stream: int = 0) -> torch.Generator:
        return torch.Generator().manual_seed(iteration_seed(self.seed, iteration, stream))

    def random_batch(self, iteration: int, batch: int, allowed: NDArray[np.bool_] | None = None) -> list[int]:
        """``batch`` distinct grid indices, uniformly at random (the first iteration of every learner, so
        that learners with one seed start from the same gaits); with ``allowed`` (size,), among those first."""
        if batch > self.space.size:
            raise RobustGaitError(f"a batch of {batch} gaits does not fit in an action space of {self.space.size}")
        order = [int(i) for i in torch.randperm(self.space.size, generator=self.generator(iteration))]
        if allowed is not None:
            order = [i for i in order if allowed[i]] + [i for i in order if not allowed[i]]
        return order[:batch]

    def model(self, history: History, iteration: int = 0) -> Any:
        """The preference model fitted to ``history`` (the prior if it holds no comparison), on one torch thread
        wherever it is fitted (:func:`~robustgait.learn.model.torch_threads`)."""
        visited, comps = history.unique()
        x = self._x[visited] if visited.size else np.zeros((0, self.space.dim))
        with torch_threads(1):
            return preference_model(x, comps, self.config.model, seed=iteration_seed(self.seed, iteration, 7))

    def recommend(self, history: History, iteration: int = 0, model: Any = None) -> int | None:
        """The visited gait with the highest posterior mean (first visited among equals); None before any."""
        visited, _ = history.unique()
        if visited.size == 0:
            return None
        with torch_threads(1):
            m = model if model is not None else self.model(history, iteration)
            mu = posterior_mean(m, self._x[visited])
        return int(visited[int(np.argmax(mu))])

    def grid_utility(self, model: Any) -> NDArray[np.float64]:
        """The posterior mean utility (space.size,) of ``model`` (:meth:`model`) at every grid point."""
        with torch_threads(1):
            return np.asarray(posterior_mean(model, self._x), dtype=float)

    def predicted_utility(self, history: History, indices: Sequence[int], iteration: int = 0) -> NDArray[np.float64]:
        """The preference model's posterior mean utility (len(indices),) of the grid points ``indices`` given
        ``history`` (the prior's, zeros, before any comparison)."""
        with torch_threads(1):
            return np.asarray(posterior_mean(self.model(history, iteration), self._x[list(indices)]), dtype=float)

    def propose(self, history: History, iteration: int, batch: int,
                allowed: NDArray[np.bool_] | None = None) -> list[int]:
        """The ``batch`` distinct grid indices to evaluate in iteration ``iteration`` given ``history`` (the
        iterations before it). ``allowed`` (size,): propose among these grid points (a person study: those predicted
        to clear its floor, :mod:`robustgait.learn.floor`), the others only when fewer than ``batch`` are allowed."""
        if allowed is not None and int(np.count_nonzero(allowed)) >= batch:
            with torch_threads(1):
                return self._propose(history, iteration, batch, allowed)
        with torch_threads(1):
            picks = self._propose(history, iteration, batch, None)
        if allowed is None:
            return picks
        first = [int(i) for i in np.flatnonzero(allowed)]
        return (first + [i for i in picks if i not in set(first)])[:batch]

    def _propose(self, history: History, iteration: int, batch: int,
                 allowed: NDArray[np.bool_] | None) -> list[int]:
        raise NotImplementedError


class RandomLearner(Learner):
    name = "random"

    def _propose(self, history: History, iteration: int, batch: int,
                 allowed: NDArray[np.bool_] | None) -> list[int]:
        return self.random_batch(iteration, batch, allowed)


class PolarLearner(Learner):
    name = "polar"

    def candidates(self, history: History, best: int | None, generator: torch.Generator) -> IntArray:
        """Grid indices the posterior is drawn over: all of them on a small grid; else the visited gaits,
        the box of ``neighbourhood`` steps around the best, and uniformly random others up to
        ``max_candidates``."""
        cap = self.config.max_candidates
        if self.space.size <= cap:
            return np.arange(self.space.size, dtype=np.int64)
        keep = list(dict.fromkeys(list(history.unique()[0]) + (
            list(self.space.neighbours(best, self.config.neighbourhood)) if best is not None else [])))[:cap]
        taken = set(keep)
        perm = torch.randperm(self.space.size, generator=generator).numpy()
        keep += [int(i) for i in perm if int(i) not in taken][:cap - len(keep)]
        return np.array(sorted(keep), dtype=np.int64)

    def _propose(self, history: History, iteration: int, batch: int,
                 allowed: NDArray[np.bool_] | None) -> list[int]:
        if iteration == 0 or not history.actions:
            return self.random_batch(iteration, batch, allowed)
        gen = self.generator(iteration)
        model = self.model(history, iteration)
        best = self.recommend(history, iteration, model)
        cand = self.candidates(history, best, gen)
        if allowed is not None and int(np.count_nonzero(allowed[cand])) >= batch:
            cand = cand[allowed[cand]]
        elif allowed is not None:  # the candidate subset holds too few: every allowed grid point
            cand = np.flatnonzero(allowed).astype(np.int64)
        if batch > cand.size:
            raise RobustGaitError(f"a batch of {batch} gaits does not fit in {cand.size} candidate gaits")
        mean, cov = posterior_mean_cov(model, self._x[cand])
        root = cholesky_root(cov, self.config.model.jitter)
        chosen: list[int] = []
        for _ in range(batch):
            for _ in range(self.config.max_redraws):
                draw = thompson_draws(mean, root, 1, gen)[0]
                pick = int(torch.argmax(draw))
                if pick not in chosen:
                    break
            else:  # every draw repeated a gait of the batch: the best new point of the last draw
                draw[chosen] = -torch.inf
                pick = int(torch.argmax(draw))
            chosen.append(pick)
        return [int(cand[i]) for i in chosen]


class EuboLearner(Learner):
    name = "eubo"

    def _propose(self, history: History, iteration: int, batch: int,
                 allowed: NDArray[np.bool_] | None) -> list[int]:
        if iteration == 0 or not history.actions:
            return self.random_batch(iteration, batch, allowed)
        from botorch.acquisition.preference import qExpectedUtilityOfBestOption
        from botorch.optim import optimize_acqf_discrete
        from botorch.sampling import SobolQMCNormalSampler

        if batch > self.space.size:
            raise RobustGaitError(f"a batch of {batch} gaits does not fit in an action space of {self.space.size}")
        model = self.model(history, iteration)
        sampler = SobolQMCNormalSampler(torch.Size([self.config.eubo_samples]),
                                        seed=iteration_seed(self.seed, iteration, 1) % 2**31)
        acq = qExpectedUtilityOfBestOption(pref_model=model, sampler=sampler)
        index = np.arange(self.space.size) if allowed is None else np.flatnonzero(allowed)
        choices = torch.as_tensor(self._x[index], dtype=torch.float64)
        with torch.no_grad(), warnings.catch_warnings():
            warnings.simplefilter("ignore")
            x, _ = optimize_acqf_discrete(acq, q=batch, choices=choices, unique=True)
        rows = torch.cdist(x.reshape(batch, -1), choices).argmin(dim=1)
        return [int(index[int(i)]) for i in rows]


LEARNER_CLASSES: dict[str, type[Learner]] = {"polar": PolarLearner, "eubo": EuboLearner, "random": RandomLearner}
assert set(LEARNER_CLASSES) == set(choices_of(LearnerName))


def make_learner(name: LearnerName, space: ActionSpace, config: LearnerConfig | None = None, seed: int = 0) -> Learner:
    """The learner called ``name`` (a :data:`~robustgait.config.LearnerName`) over ``space``."""
    return LEARNER_CLASSES[name](space, config, seed)
