"""Learning (docs/studies.md): action space, oracles, Thompson draws, learners on synthetic utilities."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from robustgait import GaitParams, RobustGaitError, load_robot
from robustgait.config import LearnerConfig
from robustgait.learn import (
    ActionSpace,
    History,
    Outcome,
    batch_comparisons,
    make_learner,
    prefer,
    replay,
    score,
    thompson_draws,
)
from robustgait.learn.model import cholesky_root


@pytest.fixture(scope="module")
def exo_space() -> ActionSpace:
    return ActionSpace.from_robot(load_robot("exo"))


def grid_space(*sizes: int) -> ActionSpace:
    return ActionSpace(tuple(f"x{i}" for i in range(len(sizes))),
                       tuple(tuple(np.linspace(0, 1, n).round(9)) for n in sizes))


def test_exo_action_space_from_spec(exo_space):
    assert exo_space.names == ("step_length", "step_duration", "step_width", "step_height")
    assert exo_space.shape == (7, 6, 5, 4) and exo_space.size == 840
    assert exo_space.values[0] == (0.1, 0.12, 0.14, 0.16, 0.18, 0.2, 0.22)
    pts, x = exo_space.points(), exo_space.normalized()
    assert pts.shape == (840, 4) and x.min() == 0.0 and x.max() == 1.0
    for i in (0, 1, 417, 839):
        p = exo_space.params(i)
        assert isinstance(p, GaitParams) and exo_space.index(p) == i
        np.testing.assert_allclose([p.to_dict()[n] for n in exo_space.names], pts[i])
    # normalization: grid step k of an axis with n values is k / (n − 1)
    np.testing.assert_allclose(exo_space.normalized(exo_space.index(GaitParams(0.12, 1.1, 0.3, 0.04))),
                               [1 / 6, 1.0, 1.0, 0.0])


def test_exo_multicontact_action_space_searches_the_rolling_fraction():
    space = ActionSpace.from_robot(load_robot("exo"), "multicontact")
    assert space.names == ("step_length", "step_duration", "step_width", "step_height", "rolling_fraction")
    assert space.values[1] == (0.8, 0.9, 1.0, 1.1) and space.values[4] == (0.15, 0.2, 0.25)
    p = space.params(space.size - 1)
    assert p.rolling_fraction == 0.25 and space.index(p) == space.size - 1
    with pytest.raises(RobustGaitError, match="domains must be"):
        ActionSpace.from_robot(load_robot("exo"), "hopping")


def test_action_space_rejects_off_grid_and_missing(exo_space):
    with pytest.raises(RobustGaitError, match="not on the action-space grid"):
        exo_space.index(GaitParams(0.13, 0.7, 0.24, 0.06))
    with pytest.raises(RobustGaitError, match="out of range"):
        exo_space.coords(840)
    robot = load_robot("exo")
    from dataclasses import replace

    robot.spec = replace(robot.spec, action_space=None)
    with pytest.raises(RobustGaitError, match=r"no \[action_space\]"):
        ActionSpace.from_robot(robot)
    robot.spec = replace(robot.spec, multicontact_action_space=None)
    with pytest.raises(RobustGaitError, match=r"no \[action_space.multicontact\]"):
        ActionSpace.from_robot(robot, "multicontact")


def test_the_nearest_grid_point_rounds_each_axis_and_a_tie_goes_down(exo_space):
    on = GaitParams(0.16, 0.8, 0.26, 0.06)
    assert exo_space.nearest(on) == exo_space.index(on)  # a grid point is its own nearest
    # exo's default gait lies between grid values on three axes: 0.15 (0.14 | 0.16), 0.25 (0.24 | 0.26), 0.07
    assert exo_space.value(exo_space.nearest(GaitParams().resolved("flat"))) == pytest.approx(
        {"step_length": 0.14, "step_duration": 0.7, "step_width": 0.24, "step_height": 0.06})
    assert exo_space.value(exo_space.nearest({"step_length": 0.151, "step_duration": 5.0, "step_width": 0.0,
                                              "step_height": 0.09})) == pytest.approx(
        {"step_length": 0.16, "step_duration": 1.1, "step_width": 0.22, "step_height": 0.08})
    with pytest.raises(RobustGaitError, match="missing parameter 'step_height'"):
        exo_space.nearest({"step_length": 0.15, "step_duration": 0.7, "step_width": 0.25})


def test_neighbourhood_is_the_clipped_box(exo_space):
    assert len(exo_space.neighbours(0)) == 2**4  # corner: itself and one step up each axis
    centre = exo_space.index(GaitParams(0.16, 0.8, 0.26, 0.06))
    nb = exo_space.neighbours(centre)
    assert len(nb) == 3**4 and centre in nb
    steps = np.abs(exo_space.coords(nb) - exo_space.coords(centre))
    assert steps.max() == 1
    assert len(exo_space.neighbours(centre, radius=2)) == 5 * 5 * 5 * 4


def test_robustness_oracle_rules():
    walker_low, walker_high = Outcome(50, 50, 0.2), Outcome(50, 50, 0.9)
    faller_many, faller_few, failed = Outcome(40, 50, 0.0), Outcome(3, 50, 0.0), Outcome(0, 50, 0.0)
    assert prefer("robustness", walker_low, faller_many) == 1  # walking the cap beats any fall
    assert prefer("robustness", walker_high, walker_low) == 1  # among walkers, r*
    assert prefer("robustness", faller_many, faller_few) == 1  # among fallers, steps
    assert prefer("robustness", faller_few, failed) == 1  # a failed generation is a faller with 0 steps
    assert prefer("robustness", Outcome(50, 50, 0.5), Outcome(50, 50, 0.5)) == 0  # equal: no comparison
    assert prefer("robustness", Outcome(7, 50, 0.0), Outcome(7, 50, 0.3)) == 0  # r* of a faller is ignored
    order = [faller_few, walker_high, failed, walker_low, faller_many]
    ranked = sorted(range(5), key=lambda i: -score("robustness", order[i]))
    assert ranked == [1, 3, 4, 0, 2]


@pytest.mark.parametrize("metric", ["robustness", "push"])
def test_a_gait_that_walked_the_cap_without_a_certificate_ranks_below_every_certified_one(metric):
    """Walked the cap, no certificate (its orbit did not settle, is unstable, …): cap − ½, strictly below a certified
    gait of r* = 0 (before, tied with it: cap) and above every faller; certified scores are unchanged."""
    cap = 50
    uncertified = Outcome(cap, cap, 0.0, certified=False)
    certified_zero, certified = Outcome(cap, cap, 0.0), Outcome(cap, cap, 1.3)
    assert score(metric, uncertified) == cap - 0.5 and score(metric, certified_zero) == cap
    assert score(metric, certified) == cap + 1.3  # as before
    assert prefer(metric, certified_zero, uncertified) == 1 and prefer(metric, uncertified, Outcome(cap - 1, cap)) == 1
    assert score(metric, uncertified, penalty=0.0) == score(metric, certified_zero)  # a study created before
    assert prefer(metric, Outcome(cap, cap, 0.0, False), uncertified) == 0  # two without: no comparison
    assert score(metric, Outcome(12, cap, 0.0, certified=False)) == 12  # a faller's flag does not count
    assert score("stability", uncertified) == cap


def test_stability_oracle_counts_steps_only():
    assert prefer("stability", Outcome(50, 50, 0.1), Outcome(50, 50, 1.5)) == 0
    assert prefer("stability", Outcome(12, 50), Outcome(11, 50, 0.0)) == 1
    with pytest.raises(RobustGaitError, match="unknown metric"):
        score("speed", Outcome(1, 50))


def test_batch_comparisons_all_pairs_ties_none():
    assert len(batch_comparisons([5.0, 4.0, 3.0, 2.0, 1.0])) == 10  # C(5, 2)
    comps = batch_comparisons([1.0, 3.0, 3.0, 0.5])
    assert (1, 2) not in comps and (2, 1) not in comps  # the tie
    assert sorted(comps) == sorted([(1, 0), (2, 0), (0, 3), (1, 3), (2, 3)])
    assert batch_comparisons([2.0, 2.0, 2.0]) == []


def test_history_from_batches_and_unique():
    h = History.from_batches([[(10, 1.0), (11, 2.0)], [(11, 2.0), (12, 0.0)]])
    assert h.actions == (10, 11, 11, 12) and h.iterations == (0, 0, 1, 1)
    assert h.comparisons == ((1, 0), (2, 3))
    visited, comps = h.unique()
    assert visited.tolist() == [10, 11, 12] and comps == [(1, 0), (1, 2)]


def test_thompson_draws_have_the_posterior_covariance_not_its_square():
    """POLAR's ThompsonSampling.m draws mean + Σ z, whose covariance is Σ²; ours must be Σ."""
    cov = torch.tensor([[4.0, 1.2, 0.0], [1.2, 0.25, 0.1], [0.0, 0.1, 0.09]], dtype=torch.float64)
    cov = cov @ cov.T / 4  # positive definite, variances far from 1
    mean = torch.tensor([1.0, -2.0, 0.5], dtype=torch.float64)
    g = torch.Generator().manual_seed(0)
    f = thompson_draws(mean, cholesky_root(cov), 40000, g)
    emp = torch.cov(f.T)
    np.testing.assert_allclose(f.mean(0).numpy(), mean.numpy(), atol=0.03)
    np.testing.assert_allclose(emp.numpy(), cov.numpy(), rtol=0.05, atol=0.01)
    assert not np.allclose(emp.numpy(), (cov @ cov).numpy(), rtol=0.2)


def smooth_utility(space: ActionSpace, seed: int) -> np.ndarray:
    """Two Gaussian bumps of different heights at random places (a smooth utility with a local optimum)."""
    rng = np.random.default_rng(seed)
    x = space.normalized()
    centres, heights = rng.uniform(0, 1, (2, space.dim)), np.array([1.0, 0.6])
    return sum(h * np.exp(-((x - c) ** 2).sum(1) / (2 * 0.3**2)) for h, c in zip(heights, centres, strict=True))


@pytest.mark.slow  # seconds of its own: plain pytest stays ≤ 60 s; CI runs it
@pytest.mark.parametrize("name", ["polar", "eubo", "random"])
def test_same_seed_same_proposals(name):
    space = grid_space(6, 5, 4)
    u = smooth_utility(space, 1)
    runs = [replay(make_learner(name, space, seed=s), lambda i: u[i], 3, 4) for s in (3, 3, 4)]
    assert runs[0].proposals == runs[1].proposals and runs[0].recommendations == runs[1].recommendations
    assert runs[0].proposals != runs[2].proposals
    assert runs[0].proposals[0] == replay(make_learner("random", space, seed=3), lambda i: u[i], 1, 4).proposals[0]
    for batch in runs[0].proposals:
        assert len(set(batch)) == 4


def test_recommendation_is_the_top_of_a_fully_ranked_batch():
    """After one batch, every pair is compared: the posterior mean must rank its winner first."""
    space = grid_space(5, 5)
    u = space.normalized()[:, 0] + 0.5 * space.normalized()[:, 1]
    for seed in range(3):
        res = replay(make_learner("random", space, seed=seed), lambda i: u[i], 1, 5)
        assert res.recommendations[0] == max(res.proposals[0], key=lambda i: u[i])


def test_polar_candidates_on_a_large_grid():
    space = grid_space(10, 10, 10, 10)  # 10 000 points > max_candidates
    learner = make_learner("polar", space, LearnerConfig(max_candidates=300), seed=0)
    u = smooth_utility(space, 2)
    h = replay(learner, lambda i: u[i], 1, 5).history
    best = learner.recommend(h)
    cand = learner.candidates(h, best, torch.Generator().manual_seed(0))  # type: ignore[attr-defined]
    assert cand.size == 300 and len(set(cand.tolist())) == 300
    assert set(space.neighbours(best).tolist()) <= set(cand.tolist()) and set(h.actions) <= set(cand.tolist())
    proposal = learner.propose(h, 1, 5)
    assert len(set(proposal)) == 5 and all(0 <= i < space.size for i in proposal)


@pytest.mark.slow
def test_polar_and_eubo_beat_random_on_a_smooth_utility():
    """Simple regret (normalized) of the recommended gait after 5 iterations × 4 on a 6 × 6 × 4 grid, 40
    utilities: both learners' mean regret is below random's by more than two standard errors (paired)."""
    space = grid_space(6, 6, 4)
    regret: dict[str, list[float]] = {n: [] for n in ("polar", "eubo", "random")}
    for seed in range(40):
        u = smooth_utility(space, 100 + seed)
        for name in regret:
            rec = replay(make_learner(name, space, seed=seed), lambda i, u=u: u[i], 5, 4).recommendations[-1]
            regret[name].append((u.max() - u[rec]) / (u.max() - u.min()))
    r = {n: np.asarray(v) for n, v in regret.items()}
    for name in ("polar", "eubo"):
        diff = r["random"] - r[name]  # paired: same utility, same first batch
        se = diff.std(ddof=1) / np.sqrt(diff.size)
        assert diff.mean() > 2 * se, (name, {n: float(v.mean()) for n, v in r.items()})


# ---- the region predicted to clear a person study's floor (robustgait.learn.floor) ---------------------------------
def test_the_region_around_the_reference_is_the_ball_the_formula_gives() -> None:
    """One observation (the floor's reference, figure v, floor f v): the grid points predicted to clear the floor are
    those within ℓ √(2 ln((1 − f) / (f w₀))) of it, and no point farther."""
    from robustgait.learn.floor import predicted_to_clear

    space = grid_space(21, 21)
    ref = {"x0": 0.5, "x1": 0.5}
    ell, f, w0 = 0.2, 0.75, 0.1
    region = predicted_to_clear(space, [(ref, 20.0)], f * 20.0, ell, w0)
    d = np.linalg.norm(space.normalized() - 0.5, axis=1)
    radius = ell * np.sqrt(2 * np.log((1 - f) / (f * w0)))
    assert region[d < 0.999 * radius].all() and not region[d > 1.001 * radius].any() and region.sum() > 1
    assert predicted_to_clear(space, [], 15.0, ell, w0).all()  # nothing observed: no model, nothing excluded
    assert predicted_to_clear(space, [(ref, 20.0)], 0.0, ell, w0).all()  # floor 0: everything clears it


def test_the_region_around_the_reference_alone_does_not_depend_on_its_value() -> None:
    """A person study proposes its first batch while the reference is still evaluated: with the reference alone and
    the floor a fraction f of its figure, the region is the same for any figure v > 0 (computed with v = 1)."""
    from robustgait.learn.floor import predicted_to_clear

    space = grid_space(21, 21)
    ref = {"x0": 0.3, "x1": 0.6}
    unit = predicted_to_clear(space, [(ref, 1.0)], 0.75, 0.2, 0.1)
    for v in (0.37, 1.9, 13.61, 94.7):
        assert np.array_equal(predicted_to_clear(space, [(ref, v)], 0.75 * v, 0.2, 0.1), unit), v


def test_the_region_follows_the_evaluated_gaits() -> None:
    """Gaits that fell (figure 0) carve their neighbourhood out of the region; robust ones extend it."""
    from robustgait.learn.floor import predicted_to_clear

    space = grid_space(11, 11)
    ref = ({"x0": 0.5, "x1": 0.5}, 20.0)
    grown = predicted_to_clear(space, [ref, ({"x0": 0.9, "x1": 0.5}, 22.0)], 15.0, 0.2, 0.1)
    cut = predicted_to_clear(space, [ref, ({"x0": 0.6, "x1": 0.5}, 0.0)], 15.0, 0.2, 0.1)
    base = predicted_to_clear(space, [ref], 15.0, 0.2, 0.1)
    i = space.index({"x0": 0.9, "x1": 0.5})
    j = space.index({"x0": 0.6, "x1": 0.5})
    assert grown[i] and not base[i] and base[j] and not cut[j] and grown.sum() > base.sum() > cut.sum()


@pytest.mark.parametrize("name", ["random", "polar", "eubo"])
def test_learners_propose_within_the_allowed_grid_points(name: str) -> None:
    """With ``allowed``, every learner proposes among those points (all of them when too few are allowed, the allowed
    first); without it, its proposals are unchanged."""
    space = grid_space(5, 5)
    learner = make_learner(name, space, LearnerConfig(), seed=2)
    history = History.from_batches([[(0, 1.0), (6, 0.5), (24, 0.0)]])
    allowed = np.zeros(space.size, dtype=bool)
    allowed[[6, 7, 8, 11, 12, 13]] = True
    for k, h in ((0, History.from_batches([])), (1, history)):
        picks = learner.propose(h, k, 3, allowed)
        assert len(set(picks)) == 3 and all(allowed[i] for i in picks)
        assert learner.propose(h, k, 3) == learner.propose(h, k, 3, None)
    few = np.zeros(space.size, dtype=bool)
    few[[3]] = True
    picks = learner.propose(history, 1, 3, few)
    assert picks[0] == 3 and len(set(picks)) == 3
