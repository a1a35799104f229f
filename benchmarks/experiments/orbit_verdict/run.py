"""ρ, a diagnostic and never a gate, measured: ``python benchmarks/experiments/orbit_verdict/run.py``.

Per gait — the default exo gait (tests/data/exo_gait.json or ``--exo-gait``), the stored multi-contact exo gait
(tests/data/exo_multicontact_gait.json), the Atalante FROST gait (robots/atalante/spec.toml with
../shared/atalante/jt_bez_2023-09-10.yaml; skipped with a message when absent), and any ``--extra ROBOT=FILE``;
``--only`` picks some of them by name (``exo``, ``multicontact``, ``atalante``, an extra's file stem) —
:func:`robustgait.certificate.search.find_orbit` with ``orbit.linearization`` on, and printed:

* the orbit's verdict: status, period (physical steps), σ (the band's scatter, band coordinates), the step it settled
  at, the steps walked and the probe's impulse (with how many probing pushes came back);
* the diagnostic (:mod:`robustgait.certificate.linearization`): ρ at ``orbit.fd_step`` and at 10× it, whether they
  agree within ``orbit.fd_agreement`` (10 %), the per-map rate of a perturbation along the leading eigenvector, the top
  eigenvalue moduli, whether ρ is defined and if not why;
* the search's seconds and physics steps (its walk, the stability probe and the linearization together).

``--fd-steps h1,h2,…``: then, per gait whose orbit was found, ρ at each finite-difference step h (one
:func:`robustgait.certificate.numerics.fd_jacobian` batch of the map of the orbit's period in section coordinates at
x*, times the touchdown projection when there is one), ρ at a fixed touchdown step (without it), the one-sided
columns, and the per-map rate of a perturbation of 10 h along that Jacobian's leading eigenvector over
``orbit.confirm_steps`` maps.

What the old version measured and this one does not: the fixed-point rules (the rule before the orbit check, the
window of ``fp_window`` iterates within ``fp_tol``, Newton refinement of x*), their J* and the move of x* between
them, the survey of the shipped search with other ``fp_tol`` (``--survey``), and the window-length study
(``--orbit-parts windows``) — the fixed-point search and its options were replaced by the orbit search
(:mod:`robustgait.certificate.search`), whose verdict no longer depends on ρ. Gaits that used to go to ``--survey``
go to ``--extra``; the finite-difference check of ρ at several steps survives as ``--fd-steps``.

    python benchmarks/experiments/orbit_verdict/run.py [--only exo] [--extra ROBOT=FILE …] [--fd-steps \\
        1e-7,1e-6,1e-5] [--threads N]
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np

from robustgait import load_gait, load_robot
from robustgait.certificate import Walking, find_orbit
from robustgait.certificate.numerics import fd_jacobian, spectral_radius
from robustgait.certificate.orbit import Orbit
from robustgait.certificate.reduced import section_coordinates
from robustgait.certificate.returnmap import FullStateMap
from robustgait.config import CertifyConfig, SimConfig
from robustgait.config.certify import OrbitConfig
from robustgait.errors import RobustGaitError
from robustgait.gait import Gait
from robustgait.robots import Robot

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))  # benchmarks/common.py
from common import ATALANTE_SPEC, EXO_GAIT, EXO_MULTICONTACT_GAIT, SHARED

ATALANTE = SHARED / "atalante"


def named_gaits(items: list[str]) -> dict[str, tuple[Robot, Gait]]:
    """{file stem: (robot, gait)} of ``ROBOT=FILE`` items."""
    out = {}
    for item in items:
        robot_name, _, path = item.partition("=")
        robot = load_robot(robot_name)
        out[Path(path).stem] = (robot, load_gait(path, robot))
    return out


def orbit_gaits(args: argparse.Namespace) -> dict[str, tuple[Robot, Gait]]:
    """The gaits measured (module docstring), restricted to ``--only`` when given; loaded only when picked."""
    only = set(args.only.split(",")) if args.only else None

    def wanted(name: str) -> bool:
        return only is None or name in only

    out: dict[str, tuple[Robot, Gait]] = {}
    if wanted("exo") or wanted("multicontact"):
        exo = load_robot("exo")
        if wanted("exo"):
            out["exo"] = (exo, load_gait(args.exo_gait or EXO_GAIT, exo))
        if wanted("multicontact"):
            out["multicontact"] = (exo, load_gait(EXO_MULTICONTACT_GAIT, exo))
    if wanted("atalante"):
        if (ATALANTE / "loadedExo.xml").is_file():
            robot = load_robot(ATALANTE_SPEC)
            out["atalante"] = (robot, load_gait(ATALANTE / "jt_bez_2023-09-10.yaml", robot))
        else:
            print(f"{ATALANTE} is missing: the Atalante FROST gait is skipped")
    extra = named_gaits(args.extra)
    return out | {k: v for k, v in extra.items() if wanted(k)}


def _f(v: float | None, fmt: str = ".4f") -> str:
    return "—" if v is None else format(v, fmt)


def orbit_row(name: str, orbit: Orbit, agreement: float, seconds: float) -> str:
    """One Markdown row: the orbit's verdict, the linearization diagnostic and the cost."""
    settled = "—" if orbit.settled is None else str(orbit.settled)
    sigma = "—" if orbit.sigma is None else f"{orbit.sigma:.2g}"
    probe = "—"
    if orbit.probe is not None:
        p = orbit.probe
        probe = f"{p.impulse:.3g} N s ({sum(p.recovered)}/{len(p.recovered)} back)"
    lin = orbit.linearization
    if lin is None:
        cells = ["—"] * 5 + ["not computed (no orbit)" if not orbit.ok else "not computed"]
    else:
        agree = "—"
        if lin.rho is not None and lin.rho_coarse is not None:
            gap = abs(lin.rho - lin.rho_coarse) / max(lin.rho, lin.rho_coarse, 1e-300)
            agree = f"{'yes' if gap <= agreement else 'no'} ({100 * gap:.1f} %)"
        moduli = " ".join(f"{m:.3f}" for m in lin.moduli[:4]) or "—"
        defined = "yes" if lin.defined else f"no: {lin.reason}"
        cells = [_f(lin.rho), _f(lin.rho_coarse), agree, _f(lin.rate), moduli, defined]
    return (f"| {name} | {orbit.status} | {orbit.period} | {sigma} | {settled} | {orbit.steps} | {probe} | "
            + " | ".join(cells) + f" | {seconds:.1f} s | {orbit.physics_steps / 1e3:.0f} k |")


def fd_check(robot: Robot, gait: Gait, orbit: Orbit, cfg: OrbitConfig, sim: SimConfig,
             steps: list[float]) -> list[str]:
    """ρ at x* for each finite-difference step h (module docstring), with and without the touchdown projection, the
    one-sided columns, and the per-map rate of a perturbation of 10 h along the leading eigenvector."""
    assert orbit.qpos is not None and orbit.qvel is not None
    t0 = time.perf_counter()
    lines = []
    with FullStateMap(robot, gait, orbit.period, sim) as fmap:
        x = section_coordinates(orbit.qpos[None], orbit.qvel[None], gait.step_duration)[0]
        F = fmap.section_map(orbit.qpos)
        proj = fmap.touchdown_projection(x, orbit.qpos)
        starts, rows = [x], []
        for h in steps:
            try:
                j = fd_jacobian(F, x, h, cfg.fd_jump)
            except RobustGaitError as exc:
                lines.append(f"  h = {h:g}: no Jacobian ({exc})")
                continue
            a = j.matrix if proj is None else proj @ j.matrix
            rho, _ = spectral_radius(a)
            values, vectors = np.linalg.eig(a)
            v = vectors[:, int(np.argmax(np.abs(values)))]
            u = np.real(v) if np.linalg.norm(np.real(v)) >= np.linalg.norm(np.imag(v)) else np.imag(v)
            starts.append(x + 10.0 * h * u / np.linalg.norm(u))
            rows.append((h, rho, spectral_radius(j.matrix)[0], len(j.one_sided)))  # a count of one-sided columns
        # the perturbations along each step's leading eigenvector, iterated beside x* in one batch
        xs = np.vstack(starts)
        for _ in range(cfg.confirm_steps):
            xs = F(xs)
        for i, (h, rho, rho_fixed, n_one_sided) in enumerate(rows, start=1):
            sep = float(np.linalg.norm(xs[i] - xs[0]))
            rate = (sep / (10.0 * h)) ** (1.0 / cfg.confirm_steps) if np.isfinite(sep) else float("nan")
            lines.append(f"  h = {h:g}: ρ = {rho:.4f} (at a fixed touchdown step {rho_fixed:.4f}), {n_one_sided} "
                         f"one-sided columns; a perturbation of {10 * h:g} along its leading eigenvector: "
                         + (f"×{rate:.4f}/map over {cfg.confirm_steps} maps" if np.isfinite(rate) else "fell"))
        lines.append(f"  ({'touchdown projection' if proj is not None else 'no touchdown projection'}; "
                     f"{fmap.physics_steps / 1e3:.0f} k physics steps, {time.perf_counter() - t0:.1f} s)")
    return lines


def cmd_orbit(args: argparse.Namespace) -> None:
    """The measurement of the module docstring."""
    sim = SimConfig(n_threads=args.threads)
    cfg = CertifyConfig(orbit=OrbitConfig(linearization=True))
    o = cfg.orbit
    print(f"## orbit: find_orbit with orbit.linearization (fd_step {o.fd_step:g} and {10 * o.fd_step:g}, agreement "
          f"{100 * o.fd_agreement:g} %, {o.confirm_steps} maps along the eigenvector, tolerance "
          f"{100 * o.confirm_tolerance:g} %); threads {sim.threads}; load average "
          + " ".join(f"{v:.2f}" for v in os.getloadavg()))
    print("| gait | status | period | σ | settled at step | steps walked | probe | ρ (h) | ρ (10 h) | agree within "
          f"{100 * o.fd_agreement:g} % | rate/map along the eigenvector | top moduli | ρ defined | seconds | "
          "physics steps |")
    print("|" + "---|" * 15)
    orbits: dict[str, tuple[Robot, Gait, Orbit]] = {}
    for name, (robot, gait) in orbit_gaits(args).items():
        t0 = time.perf_counter()
        orbit = find_orbit(Walking(robot, gait, sim), cfg)
        print(orbit_row(name, orbit, o.fd_agreement, time.perf_counter() - t0), flush=True)
        orbits[name] = (robot, gait, orbit)
    for name, (_, _, orbit) in orbits.items():
        print(f"{name}: {orbit.describe()}")
    if not args.fd_steps:
        return
    steps = [float(v) for v in args.fd_steps.split(",")]
    for name, (robot, gait, orbit) in orbits.items():
        print(f"{name}: ρ at x* for finite-difference steps {args.fd_steps} (period-{orbit.period} map)")
        if not orbit.ok or orbit.qpos is None:
            print(f"  (no orbit: {orbit.status})")
            continue
        print("\n".join(fd_check(robot, gait, orbit, o, sim, steps)), flush=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--exo-gait", help="the exo gait file (default tests/data/exo_gait.json)")
    ap.add_argument("--threads", type=int, default=0, help="0 = one per core")
    ap.add_argument("--only", default="",
                    help="only these gaits, comma-separated (exo, multicontact, atalante, an extra's file stem)")
    ap.add_argument("--extra", action="append", default=[], help="more gaits, ROBOT=FILE (repeatable)")
    ap.add_argument("--fd-steps", default="",
                    help="also ρ at these finite-difference steps, comma-separated (e.g. 1e-7,1e-6,1e-5)")
    cmd_orbit(ap.parse_args())


if __name__ == "__main__":
    main()
