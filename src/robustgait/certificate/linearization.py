"""The linearized map at x* as a diagnostic, never a verdict (``docs/certificate.md``, "ρ, a diagnostic").

The step map of a contact simulation is only piecewise smooth: a touchdown is detected on the physics-step grid and a
sole's contact points come and go, so a finite-difference Jacobian may describe the jumps of one grid cell rather than
the orbit. ρ is therefore reported only when it can be trusted:

1. J by finite differences at two steps a decade apart, h and 10 h (:func:`.numerics.fd_jacobian`, one batch of
   2d + 1 states each), corrected for the touchdown found in continuous time (Π J, :func:`.numerics.flow_projection`,
   impact switching); their spectral radii agree within ``orbit.fd_agreement``;
2. a perturbation of size 10 h along the leading eigenvector of the finer one, iterated ``orbit.confirm_steps`` maps
   beside x*, grows or shrinks per map by a factor within ``orbit.confirm_tolerance`` of ρ.

Otherwise: "linearization not defined (contact events)", with the figures that disagree.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from robustgait.certificate.numerics import Jacobian, fd_jacobian, spectral_radius
from robustgait.certificate.orbit import Linearization
from robustgait.certificate.reduced import section_coordinates
from robustgait.certificate.returnmap import FullStateMap
from robustgait.config.certify import OrbitConfig
from robustgait.errors import RobustGaitError

FloatArray = NDArray[np.float64]


def linearize(fmap: FullStateMap, qpos: FloatArray, qvel: FloatArray, cfg: OrbitConfig) -> Linearization:
    """The diagnostic of the module docstring for the map ``fmap`` at the state x* = (``qpos`` (nq,), ``qvel``
    (nv,)), in section coordinates."""
    t = fmap.gait.step_duration
    x = section_coordinates(qpos[None], qvel[None], t)[0]
    F = fmap.section_map(qpos)
    try:
        fine = fd_jacobian(F, x, cfg.fd_step, cfg.fd_jump)
        coarse = fd_jacobian(F, x, 10.0 * cfg.fd_step, cfg.fd_jump)
    except RobustGaitError as exc:
        return Linearization(False, None, None, None, reason=f"a neighbour of x* falls ({exc})")
    proj = fmap.touchdown_projection(x, qpos)

    def matrix(j: Jacobian) -> FloatArray:
        return j.matrix if proj is None else proj @ j.matrix

    rho, moduli = spectral_radius(matrix(fine))
    rho_coarse, _ = spectral_radius(matrix(coarse))
    moduli_t = tuple(float(m) for m in moduli[:6])
    if abs(rho - rho_coarse) > cfg.fd_agreement * max(rho, rho_coarse):
        return Linearization(False, rho, rho_coarse, None, moduli_t,
                             f"ρ = {rho:.3g} at a finite-difference step of {cfg.fd_step:g} and {rho_coarse:.3g} at "
                             f"{10 * cfg.fd_step:g} (more than {100 * cfg.fd_agreement:g} % apart)")
    values, vectors = np.linalg.eig(matrix(fine))
    v = vectors[:, int(np.argmax(np.abs(values)))]
    direction = np.real(v) if np.linalg.norm(np.real(v)) >= np.linalg.norm(np.imag(v)) else np.imag(v)
    delta = 10.0 * cfg.fd_step
    pair = np.vstack([x, x + delta * direction / np.linalg.norm(direction)])
    for _ in range(cfg.confirm_steps):
        pair = F(pair)
        if not np.all(np.isfinite(pair)):
            return Linearization(False, rho, rho_coarse, None, moduli_t,
                                 "the state perturbed along the leading eigenvector fell")
    rate = float((np.linalg.norm(pair[1] - pair[0]) / delta) ** (1.0 / cfg.confirm_steps))
    if abs(rate - rho) > cfg.confirm_tolerance * rho:
        return Linearization(False, rho, rho_coarse, rate, moduli_t,
                             f"ρ = {rho:.3g}, but a perturbation along its eigenvector changed by ×{rate:.3g} per map "
                             f"over {cfg.confirm_steps} maps (more than {100 * cfg.confirm_tolerance:g} % apart)")
    return Linearization(True, rho, rho_coarse, rate, moduli_t)
