"""Whether a robot's left and right differ (``docs/certificate.md``, "The orbit the gait walks"): the body pairs a
left/right relabeling implies, their masses and inertias, and the soles' sizes. A walk of a robot whose sides differ
is certified on the stride map (two steps: :attr:`robustgait.robots.model.Robot.sides_differ`); ``robot init`` and
``robot check`` say by how much (:mod:`robustgait.inspection.mirror`, :mod:`robustgait.inspection.check`)."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

import mujoco
import numpy as np

from robustgait.errors import input_error
from robustgait.robots.legs import subtree

# the reflection about the base's sagittal (x–z) plane
S = np.diag([1.0, -1.0, 1.0])


def body_name(model: mujoco.MjModel, b: int) -> str:
    """Body ``b``'s name in ``model`` ("" when unnamed)."""
    return str(mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, b) or "")


def body_partners(model: mujoco.MjModel, base: int, partner: Mapping[int, int], d: mujoco.MjData, tolerance: float,
                  source: str | Path | None = None) -> dict[int, int]:
    """Each body's partner below body ``base`` of ``model``: the body of its first joint's partner (``partner``:
    joint id → its partner's); a body without a joint, or whose joints are passive (a closed chain's: not in
    ``partner``): the child of its parent's partner at its reflected position S p within ``tolerance`` [m] (``d``:
    the kinematics with every joint at 0). A body with no mirror image, or several, is an input error naming
    ``source``."""
    out = {base: base}

    def driven(body: int) -> list[int]:
        return [j for j in range(int(model.body_jntadr[body]), int(model.body_jntadr[body] + model.body_jntnum[body]))
                if j in partner]

    for b in subtree(model, base):
        if b == base:
            continue
        joints = driven(b)
        if joints:
            out[b] = int(model.jnt_bodyid[partner[joints[0]]])
            continue
        parent = out.get(int(model.body_parentid[b]))
        found = [c for c in range(model.nbody) if parent is not None and int(model.body_parentid[c]) == parent
                 and not driven(c) and float(np.linalg.norm(d.xpos[c] - S @ d.xpos[b])) <= tolerance]
        if len(found) != 1:
            raise input_error(source, f"the mirror does not reflect the model: body '{body_name(model, b)}' has "
                              f"{len(found) or 'no'} mirror image{'s' if len(found) > 1 else ''}")
        out[b] = found[0]
    return out


# a mass difference at or below this is a model file's rounding, whatever the body's mass [kg]
ROUNDING_MASS = 1e-3


@dataclass(frozen=True)
class MassAsymmetry:
    """The largest difference of mass [kg] between a body and its mirror image (``body`` the lighter), relative to
    the heavier (``relative``), and the largest relative difference of their principal inertias, over every pair of
    :func:`body_partners`."""

    mass: float
    relative: float
    body: int
    partner: int
    inertia: float

    def differs(self, mass_tolerance: float, inertia_tolerance: float) -> bool:
        """Whether left and right differ: a mass difference above ``mass_tolerance`` of the heavier body and above
        :data:`ROUNDING_MASS`, or a principal inertia more than ``inertia_tolerance`` apart."""
        return (self.mass > ROUNDING_MASS and self.relative > mass_tolerance) or self.inertia > inertia_tolerance

    def describe(self, model: mujoco.MjModel, mass_tolerance: float, inertia_tolerance: float) -> str:
        """One clause: how much the two sides differ, and what it means for the certificate."""
        amount = (f"'{body_name(model, self.body)}' is {1000 * self.mass:.3g} g lighter than "
                  f"'{body_name(model, self.partner)}', principal inertias up to {100 * self.inertia:.2g} % apart")
        if self.differs(mass_tolerance, inertia_tolerance):
            return (f"left and right differ: {amount} — certified on the stride map, two steps (certify.map auto)")
        if self.mass <= 0.0 and self.inertia <= 0.0:
            return "left and right have the same masses and inertias"
        return (f"left and right are the same within the tolerance ({amount}; a difference counts above "
                f"{100 * mass_tolerance:g} % of a body's mass and {1000 * ROUNDING_MASS:g} g, or "
                f"{100 * inertia_tolerance:g} % of an inertia) — certified on the step map")


def mass_asymmetry(model: mujoco.MjModel, base: int, body_partner: Mapping[int, int]) -> MassAsymmetry:
    """max |m_b − m_b'| over body pairs (b, b') of the mirror (with |m_b − m_b'| / max(m_b, m_b') of that pair), and
    max_i |I_b,i − I_b',i| / max(I_b,i, I_b',i) of their sorted principal inertias (``body_partner``: body → its
    mirror image, :func:`body_partners`; ``base``: the floating base, named as the pair when none differ): a model
    whose kinematics reflect exactly may still not be its own mirror image in its dynamics (a link's mass may differ
    between the sides), so that the mirrored step map is not the walk's map (``docs/certificate.md``, "The orbit the
    gait walks")."""
    m = model
    mass, relative, body, partner, inertia = 0.0, 0.0, base, base, 0.0
    for b, c in body_partner.items():
        dm = abs(float(m.body_mass[b] - m.body_mass[c]))
        if dm > mass:
            light, heavy = (b, c) if m.body_mass[b] < m.body_mass[c] else (c, b)
            mass, body, partner = dm, light, heavy
            relative = dm / max(float(m.body_mass[heavy]), 1e-12)
        ib, ic = np.sort(m.body_inertia[b]), np.sort(m.body_inertia[c])
        scale = np.maximum(np.maximum(ib, ic), 1e-12)
        inertia = max(inertia, float(np.max(np.abs(ib - ic) / scale)))
    return MassAsymmetry(mass, relative, body, partner, inertia)
