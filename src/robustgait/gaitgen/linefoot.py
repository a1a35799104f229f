"""The stance foot's roll on line feet (``docs/gaitgen.md``, "Line feet"): the gait problem's one unactuated degree of
freedom when the feet are lines (:func:`robustgait.domains.on_line_feet`).

A foot without width stands on a line heel to toe and takes no roll moment (FROST's line contact along the foot). With
every joint a Bézier output, the stance foot's roll φ about that line is the degree of freedom the joints do not fix:
its motion is the zero dynamics, integrated between the nodes. Per node the NLP carries (φ, φ̇, φ̈) as variables tied
to the model (:func:`roll_rows`); consecutive nodes are tied by the linear-acceleration rule (:func:`roll_collocation`);
and the step is periodic in φ after relabeling (:func:`roll_periodicity`). Everything is written in world axes with the
line along world x (the contact rows hold it there), where the foot's rotation is R_x(φ) and its angular velocity
φ̇ e_x.
"""

from __future__ import annotations

import casadi as cs

ROLL_AXIS = 3  # the row of a frame's (linear; angular) world Jacobian that is the angular velocity about world x


def foot_roll(R: cs.SX) -> cs.SX:
    """The roll φ [rad] of a foot whose rotation is R = R_x(φ) (3 × 3; its x axis on world x): φ = atan2(R₃₂, R₃₃)."""
    return cs.atan2(R[2, 1], R[2, 2])


def roll_rows(roll: cs.SX, R: cs.SX, J: cs.SX, Jdot: cs.SX, nu: cs.SX, nud: cs.SX) -> cs.SX:
    """The node's roll variables (φ, φ̇, φ̈) = ``roll`` (3,) [rad, rad/s, rad/s²] tied to the stance sole frame's
    rotation R (3 × 3), Jacobian J and its derivative J̇ (6 × nv, world axes) at the velocity ν and acceleration ν̇
    (nv,): (φ − atan2(R₃₂, R₃₃), φ̇ − (J ν)₄, φ̈ − (J ν̇ + J̇ ν)₄) (3,) — the angular velocity and acceleration about
    world x, the line's direction."""
    return cs.vertcat(roll[0] - foot_roll(R), roll[1] - (J @ nu)[ROLL_AXIS],
                      roll[2] - (J @ nud + Jdot @ nu)[ROLL_AXIS])


def roll_collocation(a: cs.SX, b: cs.SX, h: cs.SX) -> cs.SX:
    """The linear-acceleration rule (Newmark, β = 1/6, γ = 1/2; exact when φ̈ is linear in t between the nodes)
    between consecutive nodes' roll variables a = (φ_i, φ̇_i, φ̈_i) and b (3,) a time h [s] apart (2,) [rad, rad/s]:
    φ_{i+1} − φ_i − h φ̇_i − h² (2 φ̈_i + φ̈_{i+1}) / 6 and φ̇_{i+1} − φ̇_i − h (φ̈_i + φ̈_{i+1}) / 2."""
    return cs.vertcat(b[0] - a[0] - h * a[1] - h**2 * (2 * a[2] + b[2]) / 6, b[1] - a[1] - h * (a[2] + b[2]) / 2)


def roll_periodicity(first: cs.SX, R_swing: cs.SX, J_swing: cs.SX, nu_plus: cs.SX) -> cs.SX:
    """The step's first node's roll and rate ``first`` (2,) [rad, rad/s] mirrored from the landing foot's — the swing
    sole's rotation R_swing (3 × 3) at touchdown and its angular velocity about world x after the impact, from its
    Jacobian J_swing (6 × nv) and ν⁺ (nv,); the mirror (y → −y) flips a roll: (φ_0 + atan2(R₃₂, R₃₃), φ̇_0 +
    (J ν⁺)₄) (2,)."""
    return cs.vertcat(first[0] + foot_roll(R_swing), first[1] + (J_swing @ nu_plus)[ROLL_AXIS])
