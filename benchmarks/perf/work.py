"""The worst-case work of every command's defaults, and its limit (robustgait.config.work), on the shipped robot and
the Atalante example, for both domain graphs (issue 28).

For each robot × domain graph, the longest-stepping gait a study can generate (the action space's longest step
duration with its smallest rolling fraction) and the stored gaits (exo's flat and multi-contact test gaits,
Atalante's FROST gait): the physics steps one step may take, then per command (its configuration when given no
option: the command line's parser) the simulated steps, the worst-case physics steps and the limit — the work
checks themselves, no simulation. Prints a markdown table (docs/inputs.md).

    python benchmarks/perf/work.py
"""

from __future__ import annotations

import dataclasses
import sys
from datetime import date
from pathlib import Path

from robustgait import load_gait, load_robot
from robustgait.certificate.certify import certify_steps, check_certify_work
from robustgait.certificate.reduced import section_dimension
from robustgait.cli import build_parser
from robustgait.cli.options import config_from
from robustgait.config import KINDS, CertifyConfig, Config, SimConfig, ValidateConfig, preset
from robustgait.config.work import Work, work_limit
from robustgait.gait import Gait
from robustgait.learn.space import ActionSpace
from robustgait.robots import Robot
from robustgait.sim.engine import step_physics_steps
from robustgait.sim.walk import check_walk_work
from robustgait.study.run import check_evaluation_work, longest_gaits
from robustgait.validate.run import check_validate_work, validate_steps

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # benchmarks/common.py
from common import ATALANTE_GAIT, ATALANTE_SPEC, EXO_GAIT, EXO_MULTICONTACT_GAIT, git_commit

STORED = {("exo", "flat"): EXO_GAIT,
          ("exo", "multicontact"): EXO_MULTICONTACT_GAIT,
          ("atalante", "flat"): ATALANTE_GAIT}


def defaults_of(*argv: str, base: Config | None = None) -> Config:
    return config_from(build_parser().parse_args(list(argv)), base)


def rows(name: str, spec: str, robot: Robot, graph: str, gait: Gait, source: str) -> list[str]:
    dt, sim, dim = robot.dt, SimConfig(), section_dimension(robot)
    step = step_physics_steps(gait, dt, sim)
    out = []

    def row(command: str, work: Work, defaults: Work, checked: int) -> None:
        assert checked == work.physics_steps
        out.append(f"| {name} | {graph} | {source}, {gait.step_duration:.3g} s | {step} | {command} | {work.steps} "
                   f"| {work.physics_steps:.3g} | {work_limit(defaults):.3g} |")

    w = Work(sim.step_cap, step)
    row("walk", w, w, check_walk_work(robot, gait, sim, sim.step_cap).physics_steps)
    c = defaults_of("certify", "g.json", "--robot", spec).certify
    w = Work(certify_steps(c, graph, dim), step)
    row("certify (J*)", w, w, check_certify_work(robot, gait, c, sim))
    for kinds, label in ((1, "validate (one kind, certifying)"),
                         (len(KINDS), f"validate --disturbance all ({len(KINDS)})")):
        v = dataclasses.replace(ValidateConfig(), disturbance="push" if kinds == 1 else "all")
        w = Work(validate_steps(v, kinds, CertifyConfig(), graph, True, dim), step)
        row(label, w, w, check_validate_work(robot, gait, v, sim, kinds=kinds, certifying=True))
    if source == "longest":
        for label, cfg in (("study run: evaluation", defaults_of("study", "run", "d", "--robot", spec, "--domains",
                                                                   graph)),
                           ("demo: evaluation", defaults_of("demo", "--override", f"generate.domains={graph}",
                                                            base=preset("demo")))):
            check_evaluation_work(cfg, robot, ActionSpace.from_robot(robot, graph))  # its walk's and certificate's
            w = Work(certify_steps(cfg.study_certify, graph, dim), step)
            row(f"{label}'s certificate", w, Work(certify_steps(Config().study_certify, graph, dim), step),
                check_certify_work(robot, gait, cfg.study_certify, cfg.sim))
    return out


def main() -> None:
    commit = git_commit()
    print(f"{date.today()}, commit {commit}\n")
    print("| robot | graph | gait | physics steps / step | command (defaults) | simulated steps | worst case "
          "| limit |")
    print("|---|---|---|---|---|---|---|---|")
    robots = [("exo", "exo")] + ([("atalante", str(ATALANTE_SPEC))] if STORED[("atalante", "flat")].is_file() else [])
    for name, spec in robots:
        robot = load_robot(spec)
        for graph in ("flat", "multicontact"):
            study = defaults_of("study", "run", "d", "--robot", spec, "--domains", graph)
            gaits = [(longest_gaits(robot, study, ActionSpace.from_robot(robot, graph))[0], "longest")]
            if (name, graph) in STORED:
                gaits.append((load_gait(STORED[(name, graph)], robot), "stored"))
            for gait, source in gaits:
                print("\n".join(rows(name, spec, robot, graph, gait, source)))
    if len(robots) == 1:
        print("\n(../shared/atalante is absent: Atalante skipped)", file=sys.stderr)


if __name__ == "__main__":
    main()
