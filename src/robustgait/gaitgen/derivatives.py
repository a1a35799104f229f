"""The exact constraint Jacobian and Lagrangian Hessian of the gait NLP (:mod:`.problem`), derived node by node.

A node's rows depend on its own variables and, linearly, on its domain's β and on its neighbours at a domain's ends
(continuity, periodicity): the Jacobian of g is block-sparse and the Hessian of the Lagrangian block-diagonal.
Nodes of one kind (:meth:`.GaitProblem.node_kind`) add the same rows as functions of their variables and Bézier
basis values (:meth:`.GaitProblem.node_function`), so each kind's derivatives are derived once, symbolically, on one
node, and evaluated at every node of that kind. Deriving them over the whole problem instead costs the whole
expression graph once per colour of the sparsity pattern. The values are the same derivatives (IPOPT receives them
through ``nlpsol``'s ``jac_g`` and ``hess_lag`` options); only the time to build the solver changes.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as cs
import numpy as np

from robustgait.gaitgen.problem import GaitProblem, trapezoid_weights


@dataclass(frozen=True)
class NodeDerivatives:
    """One node kind's derivatives, functions of (z, p, c) as :meth:`.GaitProblem.node_function`'s: ``jacobian``
    → ∂g_node/∂z (rows × |z|); ``hessian`` of (z, p, c, λ, σ) → triu ∇²_z (σ T_d ‖u‖² + λᵀ g_node) (|z| × |z|),
    λ the node rows' multipliers, σ the cost's (times the node's trapezoid weight)."""

    jacobian: cs.Function
    hessian: cs.Function

    @classmethod
    def of(cls, node: cs.Function) -> NodeDerivatives:
        z, p, c = (cs.SX.sym(node.name_in(k), node.sparsity_in(k)) for k in range(3))
        rows, cost = node(z, p, c)
        lam, sigma = cs.SX.sym("lam", rows.numel()), cs.SX.sym("sigma")
        hess = cs.triu(cs.hessian(sigma * cost + cs.dot(lam, rows), z)[0])
        return cls(cs.Function(f"jac_{node.name()}", [z, p, c], [cs.jacobian(rows, z)]),
                   cs.Function(f"hess_{node.name()}", [z, p, c, lam, sigma], [hess]))


def node_columns(prob: GaitProblem, sparsity: cs.Sparsity) -> list[list[int]]:
    """For each node of ``prob.node_rows``, the variables (columns of x, increasing) its rows depend on: the
    structural pattern ``sparsity`` of ∂g/∂x on its rows."""
    rows, cols = (np.asarray(a) for a in sparsity.get_triplet())
    return [sorted(set(cols[(rows >= nr.start) & (rows < nr.stop)].tolist())) for nr in prob.node_rows]


class _Blocks:
    """Sparse blocks (local row and column indices mapped to global ones) summed into one n × m MX matrix."""

    def __init__(self, n: int, m: int):
        self.n, self.m = n, m
        self.rows: list[int] = []
        self.cols: list[int] = []
        self.values: list[cs.MX] = []

    def add(self, block: cs.MX, sparsity: cs.Sparsity, row_of: list[int], col_of: list[int]) -> None:
        r, c = sparsity.get_triplet()
        self.rows += [row_of[k] for k in r]
        self.cols += [col_of[k] for k in c]
        self.values.append(block.nz[:])

    def matrix(self) -> cs.MX:
        sp, mapping = cs.Sparsity.triplet(self.n, self.m, self.rows, self.cols, True)  # entry k → its nonzero
        total = len(self.rows)  # entries that land on one nonzero are summed
        gather = cs.DM(cs.Sparsity.triplet(sp.nnz(), total, mapping, list(range(total))), 1.0)
        return cs.MX(sp, cs.mtimes(gather, cs.vertcat(*self.values)))


def derivative_functions(prob: GaitProblem) -> tuple[cs.Function, cs.Function]:
    """``nlpsol``'s ``jac_g`` ((x, p) → (g, ∂g/∂x)) and ``hess_lag`` ((x, p, λ_f, λ_g) → triu ∇²_x (λ_f f + λ_gᵀ
    g)) for ``prob``, assembled from one :class:`NodeDerivatives` per node kind; the rows after the last node
    (position periodicity) are derived directly."""
    nx, ng = int(prob.x.numel()), int(prob.g.numel())
    X, P = cs.MX.sym("x", nx), cs.MX.sym("p", int(prob.p.numel()))
    lam_f, lam_g = cs.MX.sym("lam_f"), cs.MX.sym("lam_g", ng)
    jac, hess = _Blocks(ng, nx), _Blocks(nx, nx)
    kinds: dict[tuple[int, bool, bool, bool, bool], tuple[int, NodeDerivatives]] = {}
    weights = [trapezoid_weights(len(taus)) for taus in prob.domain_taus]
    pattern = cs.jacobian_sparsity(prob.g, prob.x)
    for nr, cols in zip(prob.node_rows, node_columns(prob, pattern), strict=True):
        key = prob.node_kind(nr.d, nr.i)
        if key not in kinds:
            kinds[key] = (len(cols), NodeDerivatives.of(prob.node_function(nr.d, nr.i, cols)))
        width, der = kinds[key]
        if width != len(cols):
            raise AssertionError(f"node {nr.i} of domain {nr.d} depends on {len(cols)} variables, its kind on {width}")
        z, c = X[cols], cs.DM(prob.node_basis(nr.d, nr.i))
        rows = list(range(nr.start, nr.stop))
        jac.add(der.jacobian(z, P, c), der.jacobian.sparsity_out(0), rows, cols)
        hess.add(der.hessian(z, P, c, lam_g[nr.start:nr.stop], lam_f * weights[nr.d][nr.i]),
                 der.hessian.sparsity_out(0), cols, cols)
    tail = prob.node_rows[-1].stop
    if tail < ng:
        g_tail, lam = prob.g[tail:], cs.SX.sym("lam", ng - tail)
        tail_jac = cs.Function("jac_tail", [prob.x, prob.p], [cs.jacobian(g_tail, prob.x)])
        tail_hess = cs.Function("hess_tail", [prob.x, prob.p, lam],
                                [cs.triu(cs.hessian(cs.dot(lam, g_tail), prob.x)[0])])
        everything = list(range(nx))
        jac.add(tail_jac(X, P), tail_jac.sparsity_out(0), list(range(tail, ng)), everything)
        hess.add(tail_hess(X, P, lam_g[tail:]), tail_hess.sparsity_out(0), everything, everything)
    g = cs.Function("g", [prob.x, prob.p], [prob.g])(X, P)
    # a node kind's Jacobian keeps entries that vanish at some of its nodes (a Bézier basis value of 0): IPOPT gets
    # the whole problem's own pattern, whose structure its linear solver's pivoting follows
    return (cs.Function("nlp_jac_g", [X, P], [g, cs.project(jac.matrix(), pattern)], ["x", "p"], ["g", "jac_g_x"]),
            cs.Function("nlp_hess_l", [X, P, lam_f, lam_g], [hess.matrix()], ["x", "p", "lam_f", "lam_g"],
                        ["triu_hess_gamma_x_x"]))
