"""``robustgait study serve | pareto`` and the person studies of ``study run | resume`` (docs/person.md): they parse
arguments and call :mod:`robustgait.web` and :mod:`robustgait.study`."""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

from robustgait.cli.common import command
from robustgait.cli.options import FlagTable, config_from
from robustgait.config import Config, RunConfig, radius_name

WEB: FlagTable = {"--host": "web.host", "--port": "web.port"}


def is_person_study(directory: str | Path) -> bool:
    """A study ranked on the page (``--metric person``)."""
    from robustgait.io.studyfile import load_config

    return load_config(directory).config.study.metric == "person"


def serve(directory: str, run: RunConfig, config: Config, args: argparse.Namespace, sock: Any = None) -> bool:
    """Serve the page and run the study to its budget; False on Ctrl-C (after saying how to come back). ``sock``: the
    page's socket, bound before the study was created (:func:`robustgait.web.server.bind`)."""
    from robustgait.web.server import serve_study

    try:
        serve_study(directory, run, config.web, progress=not getattr(args, "quiet", False),
                    verbose=getattr(args, "verbose", False), announce=lambda s: print(s, flush=True), sock=sock)
    except KeyboardInterrupt:
        print(f"\nrobustgait: interrupted; the answers given are stored: robustgait study serve {directory}",
              file=sys.stderr)
        return False
    return True


def _figure(row: dict[str, Any]) -> str:
    """A front row's certificate figure: the verified value, or "≈ estimate" for one only estimated."""
    return f"{row['value']:.3f}" if row["verified"] else f"≈ {row['estimate']:.3f}"


def _study_pareto(args: argparse.Namespace) -> int:
    from robustgait.study.pareto import study_pareto

    out = study_pareto(args.dir, config_from(args).report.pareto_figure)
    if args.json:
        print(json.dumps(out, allow_nan=False))
        return 0
    name, fig = radius_name(out["certificate"]), out["figure"]
    print(f"{len(out['front'])} of {len(out['gaits'])} certified gaits are non-dominated over {name} (higher), speed "
          f"(higher) and {fig} (lower):")
    print(f"  {'trial':>5}  {'L, T, W, h':<24} {name + ' [' + out['certificate_unit'] + ']':>10} "
          f"{'speed [m/s]':>11}  {fig} [{out['unit']}]")
    for r in out["front"]:
        params = ", ".join(f"{v:g}" for v in r["params"].values())
        print(f"  {r['trial']:>5}  {params:<24} {_figure(r):>10} {r['speed']:>11.3f}  {r[fig]:.3g}")
    return 0


def add_parsers(ssub: argparse._SubParsersAction[argparse.ArgumentParser], run_flags: FlagTable,
                study_serve: Callable[[argparse.Namespace], int]) -> None:
    sv = command(ssub, "serve", "serve the page of a person study (--metric person) and run it: each batch waits for "
                 "the person's ranking", study_serve, {**run_flags, **WEB})
    sv.add_argument("dir", help="study directory")
    sv.add_argument("--quiet", action="store_true", help="no progress bar")
    sv.add_argument("--verbose", action="store_true", help="print IPOPT's iteration log of every gait")
    pa = command(ssub, "pareto", "the non-dominated gaits of a study over the certificate, the speed and a comfort "
                 "figure", _study_pareto, {"--figure": "report.pareto_figure"})
    pa.add_argument("dir", help="study directory")
    pa.add_argument("--json", action="store_true", help="print one JSON object")
