"""The gait NLP's derivatives assembled node kind by node kind (robustgait.gaitgen.derivatives) are the problem's own:
the same values as CasADi's Jacobian and Hessian of the whole problem at random points, on the whole problem's
Jacobian pattern, for the flat and the multi-contact domain graph."""

from __future__ import annotations

import casadi as cs
import numpy as np
import pytest

from robustgait.config import GenerationConfig
from robustgait.dynamics import Dynamics
from robustgait.gaitgen.derivatives import derivative_functions
from robustgait.gaitgen.problem import GaitProblem


@pytest.mark.slow  # CasADi's own derivatives of the whole problem, the reference, take 10-30 s to derive
@pytest.mark.parametrize("domains", ["flat", "multicontact"])
def test_node_derivatives_are_the_whole_problems(exo, domains):  # type: ignore[no-untyped-def]
    prob = GaitProblem(Dynamics(exo.planned), GenerationConfig(domains=domains))
    kinds = {prob.node_kind(nr.d, nr.i) for nr in prob.node_rows}
    assert len(kinds) < len(prob.node_rows) / 3  # each kind derived once, evaluated at its nodes
    jac_g, hess_lag = derivative_functions(prob)
    x, p, g = prob.x, prob.p, prob.g
    lam, sigma = cs.SX.sym("lam", g.numel()), cs.SX.sym("sigma")
    jac_ref = cs.Function("j", [x, p], [g, cs.jacobian(g, x)])
    hess_ref = cs.Function("h", [x, p, sigma, lam], [cs.triu(cs.hessian(sigma * prob.cost + cs.dot(lam, g), x)[0])])
    rng = np.random.default_rng(1)
    for _ in range(2):
        xv = rng.normal(scale=0.2, size=x.numel())
        pv = np.array([0.14, 0.7, 0.24, 0.06, 0.3]) * rng.uniform(0.8, 1.2, 5)
        lv, sv = rng.normal(size=g.numel()), rng.uniform(0.1, 2.0)
        g_mine, j_mine = jac_g(xv, pv)
        g_ref, j_ref = jac_ref(xv, pv)
        assert j_mine.sparsity() == j_ref.sparsity() and j_mine.sparsity() == cs.jacobian_sparsity(g, x)
        np.testing.assert_array_equal(np.asarray(g_mine), np.asarray(g_ref))
        scale = float(cs.mmax(cs.fabs(j_ref)))
        assert float(cs.mmax(cs.fabs(j_mine - j_ref))) <= 1e-12 * scale
        h_mine, h_ref = hess_lag(xv, pv, sv, lv), hess_ref(xv, pv, sv, lv)
        assert h_mine.nnz() == h_ref.nnz()
        scale = float(cs.mmax(cs.fabs(h_ref)))
        assert float(cs.mmax(cs.fabs(cs.DM(h_mine) - cs.DM(h_ref)))) <= 1e-12 * scale
