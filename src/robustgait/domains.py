"""Domain graphs (docs/design.md §4): the contact set of each continuous domain of a step, its guard, the transitions.

One definition serves gait generation (which constraints hold in each domain, which impact ends it), the
simulator (which event ends each domain) and the return map (where the Poincaré section is).

Labels are relative to the step: ``stance`` is the leg flat on the ground at the start of the step,
``swing`` the other. A step is the domains in order; after the last one the legs are relabeled (the swing
leg becomes the next step's stance). Contacts:

* ``flat`` — the sole flat on the ground: the sole frame's position and orientation are fixed (6 rows);
  wrench (f, n) ∈ R⁶ at the sole frame, world axes.
* ``toe`` / ``heel`` — a line contact along the toe or heel edge of the sole (FROST's line contact): the
  edge's midpoint is fixed and the edge keeps its direction (the foot's y axis stays the world's y axis),
  so the foot can only pitch about the edge (5 rows: position, and the angular velocity about world x and
  z); wrench (f_x, f_y, f_z, n_x, n_z) at the edge's midpoint, world axes.
* ``line`` — a foot without width (its sole a line heel to toe) standing on that line (FROST's line contact along
  the foot): the sole frame's position is fixed and its x axis stays the world's x axis, so the foot can only roll
  about the line (5 rows: position, and the angular velocity about world y and z); wrench (f_x, f_y, f_z, n_y, n_z)
  at the sole frame, world axes — no roll moment. :func:`on_line_feet` puts a graph's flat soles on it.

Graphs: ``flat`` — one domain, single support with the stance sole flat, ended by the swing sole landing
flat (touchdown). ``multicontact`` (paper Fig. 2b) — single support with the stance sole flat, ended by
the swing heel striking the ground while the stance foot goes onto its toe line; then rolling double
support on the stance toe line and the swing heel line, ended when the swing sole is flat (foot-flat) and
the stance toe leaves the ground (toe-off). The Poincaré section of both graphs is the end of single
support (touchdown / heel strike), the paper's pre-impact surface.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from robustgait.errors import RobustGaitError

Leg = Literal["stance", "swing"]
ContactKind = Literal["flat", "toe", "heel", "line"]
Guard = Literal["touchdown", "foot_flat"]
GRAPH_NAMES = ("flat", "multicontact")
# rows of a frame's 6 × nv (linear; angular, world axes) Jacobian that a contact fixes
CONTACT_ROWS: dict[str, tuple[int, ...]] = {"flat": (0, 1, 2, 3, 4, 5), "toe": (0, 1, 2, 3, 5),
                                            "heel": (0, 1, 2, 3, 5), "line": (0, 1, 2, 4, 5)}


@dataclass(frozen=True)
class Contact:
    """One foot's contact: which leg (in the step's labels) and how (flat sole, toe line, heel line, the line of a
    foot without width)."""

    leg: Leg
    kind: ContactKind

    @property
    def rows(self) -> tuple[int, ...]:
        return CONTACT_ROWS[self.kind]

    @property
    def n_rows(self) -> int:
        return len(self.rows)

    def side(self, stance: str) -> str:
        """The robot side ('left'/'right') of this contact in a step whose stance leg is ``stance``."""
        return stance if self.leg == "stance" else other_side(stance)

    def frame_kind(self) -> str:
        """The foot frame the contact acts at: the sole frame (flat sole, line foot), or the toe / heel edge
        midpoint."""
        return "sole" if self.kind in ("flat", "line") else self.kind

    def relabeled(self) -> Contact:
        return Contact("swing" if self.leg == "stance" else "stance", self.kind)


@dataclass(frozen=True)
class DomainSpec:
    """A continuous domain: its name, the contacts that hold throughout it, and the event that ends it."""

    name: str
    contacts: tuple[Contact, ...]
    guard: Guard


@dataclass(frozen=True)
class DomainGraph:
    """The domains of one step, in order; after the last the legs are relabeled and domain 0 follows."""

    name: str
    domains: tuple[DomainSpec, ...]

    def __len__(self) -> int:
        return len(self.domains)

    def target_contacts(self, d: int) -> tuple[Contact, ...]:
        """The contact set that the impact at the end of domain ``d`` enforces, in the labels of the step
        that domain ``d`` belongs to: the next domain's contacts (relabeled after the last domain)."""
        if d + 1 < len(self.domains):
            return self.domains[d + 1].contacts
        return tuple(c.relabeled() for c in self.domains[0].contacts)


FLAT = DomainGraph("flat", (DomainSpec("single_support", (Contact("stance", "flat"),), "touchdown"),))
MULTICONTACT = DomainGraph("multicontact", (
    DomainSpec("single_support", (Contact("stance", "flat"),), "touchdown"),
    DomainSpec("double_support", (Contact("stance", "toe"), Contact("swing", "heel")), "foot_flat"),
))
GRAPHS = {"flat": FLAT, "multicontact": MULTICONTACT}


def domain_graph(name: str) -> DomainGraph:
    """The domain graph called ``name`` (``flat`` or ``multicontact``)."""
    if name not in GRAPHS:
        raise RobustGaitError(f"unknown domain graph {name!r} (choose from {', '.join(GRAPHS)})")
    return GRAPHS[name]


def on_line_feet(graph: DomainGraph) -> DomainGraph:
    """``graph`` (its name kept) with each flat sole contact a ``line`` contact: the graph of a robot whose feet are
    lines, which can roll about them and take no roll moment."""
    doms = tuple(DomainSpec(d.name, tuple(Contact(c.leg, "line") if c.kind == "flat" else c for c in d.contacts),
                            d.guard) for d in graph.domains)
    return DomainGraph(graph.name, doms)


def other_side(side: str) -> str:
    return "left" if side == "right" else "right"


def step_segments(stance: str, n_domains: int) -> list[tuple[str, int]]:
    """(stance, domain) of one step from a section state that starts a step of ``stance``, in simulation order: the
    previous leg's remaining domains (a multi-contact gait's rolling double support), then ``stance``'s single
    support up to the next section (a flat-foot step: just that). Used by the return map and the validation."""
    return [(other_side(stance), d) for d in range(1, n_domains)] + [(stance, 0)]
