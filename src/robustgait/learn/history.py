"""What a learner knows of a study (:class:`History`) and the seeds of its iterations (:func:`iteration_seed`): plain
data without torch, so that the study's driver can read and rank batches before it loads the learners."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from robustgait.learn.oracle import batch_comparisons

IntArray = NDArray[np.int64]


@dataclass(frozen=True)
class History:
    """What a learner knows: the grid index of every evaluated gait in (iteration, slot) order, its
    iteration, and the comparisons (winner, loser) as positions in ``actions``."""

    actions: tuple[int, ...] = ()
    iterations: tuple[int, ...] = ()
    comparisons: tuple[tuple[int, int], ...] = ()

    @classmethod
    def from_batches(cls, batches: Sequence[Sequence[tuple[int, float]]],
                     extra: Sequence[tuple[tuple[int, int], tuple[int, int]]] = ()) -> History:
        """From the ranked batches of iterations 0, 1, …: per batch, (grid index, oracle score) per slot;
        every batch gives all its pairwise comparisons (:func:`batch_comparisons`). ``extra``: further comparisons
        (winner, loser) between gaits named by (iteration, slot) — a person's labels across batches."""
        actions: list[int] = []
        iters: list[int] = []
        comps: list[tuple[int, int]] = []
        starts: list[int] = []
        for k, batch in enumerate(batches):
            base = len(actions)
            starts.append(base)
            comps += [(base + w, base + lo) for w, lo in batch_comparisons([s for _, s in batch])]
            actions += [int(i) for i, _ in batch]
            iters += [k] * len(batch)
        comps += [(starts[wk] + ws, starts[lk] + ls) for (wk, ws), (lk, ls) in extra
                  if wk < len(batches) and lk < len(batches)]
        return cls(tuple(actions), tuple(iters), tuple(comps))

    def unique(self) -> tuple[IntArray, list[tuple[int, int]]]:
        """Visited grid indices in order of first visit, and the comparisons as positions in that list
        (a repeated gait is one datapoint of the preference model)."""
        order: dict[int, int] = {}
        for a in self.actions:
            order.setdefault(a, len(order))
        comps = [(order[self.actions[w]], order[self.actions[lo]]) for w, lo in self.comparisons
                 if self.actions[w] != self.actions[lo]]
        return np.array(list(order), dtype=np.int64), comps


def iteration_seed(seed: int, iteration: int, stream: int = 0) -> int:
    """A 63-bit seed for (study seed, iteration, stream), independent across its arguments."""
    return int(np.random.SeedSequence([seed, iteration, stream]).generate_state(2, np.uint64)[0] >> np.uint64(1))
