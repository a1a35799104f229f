"""The fixed point's orbit check (issue 28 item 3), measured: ``python benchmarks/bench_certify.py orbit`` (this module
holds the measurement; ``bench_certify.py`` runs it).

Per gait — the default exo gait (tests/data/exo_gait.json or ``--exo-gait``), the stored multi-contact exo gait
(tests/data/exo_multicontact_gait.json), the Atalante FROST gait (../shared), and any ``--extra ROBOT=FILE`` — three
fixed-point rules, each a push certificate J* with ``--seed``:

* ``before``: the rule before the check (``LEGACY_FIXED_POINT``, fp_tol 5e-3 rad/s on the base angular velocity);
* ``window``: the shipped default (a window of fp_window iterates within fp_tol in section coordinates, then ρ);
* ``window+newton``: the same, x* refined by ``--newton`` damped Newton iterations.

Printed: status, the step the orbit settled at, the window residual, Newton's residuals, ρ (touchdown in continuous
time) and ρ at a fixed touchdown step, the top eigenvalue moduli, the fixed-point stage's physics steps and seconds, J*
and the move of x* from the ``before`` x* (section coordinates; ω*). Then, at the settled iterate of the default rule,
the finite-difference check of ρ: ρ for each ``--fd-steps`` (robust central differences) and for forward differences,
the growth of a perturbation along the top eigenvector and of 8 random ones over 8 steps of the map at amplitudes
1e-6 and 1e-4 — the empirical rates (‖δ_8‖ / ‖δ_0‖)^(1/8) and, for the random ones, (‖δ_8‖ / ‖δ_4‖)^(1/4) — against
ρ, and how far 300 iterates of the map from x* wander (steps 100–300, from their mean). Last, a survey of
``--survey ROBOT=FILE`` gaits: the shipped search alone (status, settled step, ρ, moduli, cost; no J*). ``windows``
(``--orbit-parts windows``): for the standard and survey gaits, where windows of several lengths and tolerances first
hold on 150 iterates, and the share of later windows that keep holding.
"""

from __future__ import annotations

import argparse
import dataclasses
import time
from pathlib import Path

import numpy as np

from robustgait import load_gait, load_robot
from robustgait.certificate.certify import GaitCertificate, certify_gait
from robustgait.certificate.numerics import fd_jacobian, settled_at, spectral_radius, window_residual
from robustgait.certificate.poincare import FixedPointFailure, ReturnMap
from robustgait.certificate.reduced import section_coordinates
from robustgait.config import CertifyConfig, SimConfig
from robustgait.config.certify import LEGACY_FIXED_POINT
from robustgait.gait import Gait
from robustgait.robots import Robot

REPO = Path(__file__).resolve().parents[1]
ATALANTE = REPO.parent / "shared" / "atalante"


def named_gaits(items: list[str]) -> dict[str, tuple[Robot, Gait]]:
    """{file stem: (robot, gait)} of ``ROBOT=FILE`` items."""
    out = {}
    for item in items:
        robot_name, _, path = item.partition("=")
        robot = load_robot(robot_name)
        out[Path(path).stem] = (robot, load_gait(path, robot))
    return out


def orbit_gaits(args: argparse.Namespace) -> dict[str, tuple[Robot, Gait]]:
    exo = load_robot("exo")
    out = {"exo flat": (exo, load_gait(args.exo_gait or REPO / "tests" / "data" / "exo_gait.json", exo)),
           "exo multi-contact": (exo, load_gait(REPO / "tests" / "data" / "exo_multicontact_gait.json", exo))}
    if (ATALANTE / "loadedExo.xml").is_file():
        robot = load_robot(REPO / "examples" / "atalante.toml")
        out["Atalante FROST"] = (robot, load_gait(ATALANTE / "jt_bez_2023-09-10.yaml", robot))
    else:
        print("../shared/atalante is missing: the Atalante gait is skipped")
    return out | named_gaits(args.extra)


def _rules(newton: int) -> dict[str, CertifyConfig]:
    legacy = CertifyConfig(**{**LEGACY_FIXED_POINT, "fp_tol": 5e-3})  # type: ignore[arg-type]
    return {"before": legacy, "window": CertifyConfig(), "window+newton": CertifyConfig(fp_newton_iterations=newton)}


def _row(name: str, rule: str, gc: GaitCertificate, base: GaitCertificate | None, t: float) -> str:
    o, fp = gc.orbit, gc.fixed_point
    settled = "—" if o is None or o.settled is None else str(o.settled)
    window = "—" if o is None else f"{o.window_residual:.1e}"
    newton = "—" if o is None or not o.newton else " → ".join(f"{r:.0e}" for r in o.newton)
    rho = "—" if o is None or o.rho is None else f"{o.rho:.3f} ({o.rho_fixed_event:.3f})"
    moduli = "—" if o is None or not o.moduli else " ".join(f"{m:.2f}" for m in o.moduli[:4])
    move = "—"
    if fp is not None and base is not None and base.fixed_point is not None:
        b = base.fixed_point
        dx = np.linalg.norm(section_coordinates(fp.qpos[None], fp.qvel[None], t)
                            - section_coordinates(b.qpos[None], b.qvel[None], t))
        move = f"{dx:.1e} ({np.linalg.norm(fp.omega - b.omega):.1e})"
    j = f"{gc.r_star:.2f}" if gc.ok else "—"
    return (f"| {name} | {rule} | {gc.status} | {settled} | {window} | {newton} | {rho} | {moduli} | "
            f"{gc.fixed_point_physics_steps / 1e3:.0f} k | {gc.seconds['fixed_point']:.2f} s | {j} | {move} |")


def _spread(xs: np.ndarray) -> float:
    """The largest distance of finite iterates (K, d) from their mean."""
    ok = xs[np.isfinite(xs).all(axis=1)]
    return float(np.linalg.norm(ok - ok.mean(axis=0), axis=1).max()) if len(ok) else float("nan")


def _fd_check(robot: Robot, gait: Gait, sim: SimConfig, steps: list[float]) -> list[str]:
    """ρ at the settled iterate for several finite-difference steps, forward differences, the growth of perturbations
    over 8 steps of the map, and how far 300 iterates from x* wander."""
    cfg = CertifyConfig(fp_rho_max=None)
    with ReturnMap(robot, gait, cfg, sim) as pmap:
        try:
            fp = pmap.find_fixed_point()
        except FixedPointFailure as exc:
            return [f"  (no settled iterate: {exc.status})"]
        ref = fp.qpos
        x = section_coordinates(fp.qpos[None], fp.qvel[None], gait.step_duration)[0]
        F = pmap.section_map(ref)
        proj = pmap.touchdown_projection(x, ref)
        lines = []
        for h in steps:
            j = fd_jacobian(F, x, h, cfg.fp_fd_jump)
            rho = spectral_radius(j.matrix if proj is None else proj @ j.matrix)[0]
            lines.append(f"  h = {h:g}: ρ = {rho:.4f}, at a fixed touchdown step {spectral_radius(j.matrix)[0]:.4f}, "
                         f"{len(j.one_sided)} one-sided columns")
        h = cfg.fp_fd_step
        d = x.size
        y = F(np.vstack([x[None], x + h * np.eye(d)]))
        forward = ((y[1:] - y[0]) / h).T
        rho_f = spectral_radius(forward if proj is None else proj @ forward)[0]
        lines.append(f"  forward differences, h = {h:g}: ρ = {rho_f:.4f}")
        a = j.matrix if proj is None else proj @ j.matrix
        lam, vec = np.linalg.eig(a)
        top = vec[:, np.argmax(np.abs(lam))].real
        rng = np.random.default_rng(0)
        for amp in (1e-6, 1e-4):
            u = rng.standard_normal((8, d))
            u = np.vstack([top, u]) / np.linalg.norm(np.vstack([top, u]), axis=1, keepdims=True)
            xs, sep = np.vstack([x, x + amp * u]), [np.full(9, amp)]
            for _ in range(8):
                xs = F(xs)
                sep.append(np.linalg.norm(xs[1:] - xs[0], axis=1))
            r = np.array(sep)
            late = np.median(r[8, 1:] / r[4, 1:]) ** (1 / 4)
            lines.append(f"  perturbation of {amp:g} along the top eigenvector: × {r[8, 0] / amp:.3g} in 8 steps (rate "
                         f"{(r[8, 0] / amp) ** (1 / 8):.3f}); 8 random ones: × {np.median(r[8, 1:]) / amp:.3g} "
                         f"(median; rate over steps 4–8 {late:.3f})")
        xs = [x]
        for _ in range(300):
            xs.append(F(xs[-1][None])[0])
        tail = np.array(xs[100:])
        lines.append(f"  300 iterates of the map from x*: steps 100–300 within {_spread(tail):.2g} of their mean"
                     + ("" if np.isfinite(tail).all() else " (it fell)"))
    return lines


def cmd_orbit(args: argparse.Namespace) -> None:
    sim = SimConfig(n_threads=args.threads)
    parts = set(args.orbit_parts.split(","))
    if "rules" not in parts:
        for name, (robot, gait) in orbit_gaits(args).items() if "fd" in parts else ():
            print(f"{name}: finite-difference check of ρ at the settled iterate")
            print("\n".join(_fd_check(robot, gait, sim, [float(v) for v in args.fd_steps.split(",")])))
        if "survey" in parts:
            _survey(args, sim)
        if "windows" in parts:
            _windows(args, sim)
        return
    print("| gait | rule | status | settled at step | window residual | Newton ‖P(x) − x‖ | ρ (fixed touchdown) | "
          "top moduli | fixed-point physics steps | fixed-point seconds | J* [N s] | x* move from before: section "
          "(ω*) |")
    print("|" + "---|" * 12)
    checks: dict[str, list[str]] = {}
    for name, (robot, gait) in orbit_gaits(args).items():
        base: GaitCertificate | None = None
        for rule, cfg in _rules(args.newton).items():
            t0 = time.perf_counter()
            gc = certify_gait(robot, gait, dataclasses.replace(cfg, seed=args.seed), sim)
            if rule == "before":
                base = gc
            wall = time.perf_counter() - t0
            print(_row(name, rule, gc, base, gait.step_duration) + f"  <!-- {wall:.1f} s -->", flush=True)
        checks[name] = _fd_check(robot, gait, sim, [float(v) for v in args.fd_steps.split(",")])
    for name, lines in checks.items():
        print(f"{name}: finite-difference check of ρ at the settled iterate")
        print("\n".join(lines))
    _survey(args, sim)


def _windows(args: argparse.Namespace, sim: SimConfig, steps: int = 150) -> None:
    """The window's length and tolerance: per gait (the standard ones and ``--survey``), ``steps`` iterates of the step
    map from its start in section coordinates, the step at which a window of W iterates first holds within tol for
    several (W, tol), and the share of the windows of 20 that hold over steps 40–``steps`` (a settled orbit keeps
    them, a scattered one passes one by luck)."""
    combos = ((10, 1e-2), (20, 5e-3), (20, 1e-2), (20, 2e-2), (30, 1e-2))
    print(f"\n| gait | {' | '.join(f'W {w}, tol {t:g}' for w, t in combos)} | windows of 20 within 0.01 that hold, "
          f"steps 40–{steps} | spread of steps 40–{steps} |\n|" + "---|" * (len(combos) + 3))
    for name, (robot, gait) in (orbit_gaits(args) | named_gaits(args.survey)).items():
        with ReturnMap(robot, gait, CertifyConfig(), sim) as pmap:
            q, v = pmap.initial_section()
            xs = [section_coordinates(q, v, gait.step_duration)[0]]
            for _ in range(steps):
                q, v, reason = pmap._advance(q, v)
                if reason[0] is not None:
                    break
                xs.append(section_coordinates(q, v, gait.step_duration)[0])
        a = np.array(xs)
        cells = [str(settled_at(a, w, t, min_index=10)) for w, t in combos]
        held = np.mean([window_residual(a[:k + 1], 20) <= 1e-2 for k in range(40, len(a))])
        print(f"| {name} | {' | '.join(c.replace('None', 'never') for c in cells)} | {held:.0%} | "
              f"{_spread(a[40:]):.2g} |", flush=True)


def _survey(args: argparse.Namespace, sim: SimConfig) -> None:
    """The shipped search alone on the ``--survey`` gaits, and where its window settles with fp_tol 5e-3 and 2e-2."""
    if args.survey:
        print("\n| gait | status | settled at step | window residual | ρ (fixed touchdown) | top moduli | "
              "fixed-point physics steps | fixed-point seconds | settled with fp_tol 5e-3, 2e-2 |\n|" + "---|" * 9)
    for name, (robot, gait) in named_gaits(args.survey).items():
        gc = certify_gait(robot, gait, CertifyConfig(method="uniform", n_samples=1), sim)
        cells = _row(name, "window", gc, None, gait.step_duration).split(" | ")
        other = []
        for tol in (5e-3, 2e-2):
            with ReturnMap(robot, gait, CertifyConfig(fp_tol=tol, fp_rho_max=None), sim) as pmap:
                try:
                    other.append(str(pmap.find_fixed_point().steps))
                except FixedPointFailure as exc:
                    other.append(exc.status)
        print(" | ".join([cells[0], *cells[2:5], *cells[6:10], ", ".join(other)]) + " |", flush=True)
