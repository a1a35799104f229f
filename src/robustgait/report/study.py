"""The report of a study (``robustgait study report DIR``): one self-contained HTML page (figures and video
embedded) plus the PNG files, in ``DIR/report/``.

Figures: the best r* and steps per iteration (the learner's recommendation after each iteration, and every
evaluated gait), the explored parameters coloured by outcome, the posterior mean of the preference model
over two parameters (the others at the best gait's values), the best gait's invariant set
(:func:`plot_certificate`), the certificate against the comfort figures of every evaluated gait
(:func:`robustgait.report.comfort.plot_comfort`, with their table), when ``robustgait study validate`` has results,
the success of every gait under the same disturbances against r* and steps taken (:func:`plot_study_validation`),
and a short video of the best gait walking (:func:`render_video`).
"""

from __future__ import annotations

import base64
import html
from itertools import combinations
from pathlib import Path
from typing import TYPE_CHECKING, Any

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.ticker import MaxNLocator
from numpy.typing import NDArray

from robustgait.certificate.certify import certificate_from_record
from robustgait.certificate.reduced import Coordinates
from robustgait.config import ReportConfig, radius_name
from robustgait.errors import RobustGaitError, input_error
from robustgait.io.output import write_text
from robustgait.io.schema import read_json
from robustgait.report.figures import _save, plot_certificate
from robustgait.report.marks import (
    OUTCOME_COLORS,
    OUTCOME_LABELS,
    OUTCOME_MARKERS,
    labelled,
    plot_marked,
    plotted_figure,
)
from robustgait.report.person import pareto_parts, person_parts
from robustgait.study.outcome import EvaluationStatus, status_of
from robustgait.study.status import figure_text

if TYPE_CHECKING:
    from robustgait.config import StudyConfig
    from robustgait.learn.history import History
    from robustgait.learn.space import ActionSpace

REPORT_DIR = "report"


def plot_history(status: dict[str, Any], path: Path) -> Path:
    """Per iteration: the certificate's figure (verified, or the estimate, marked as one) and the steps of every
    evaluated gait (by outcome) and of the learner's best after the iteration (line)."""
    fig, (a1, a2) = plt.subplots(2, 1, figsize=(8, 6), sharex=True)
    for t in status["trials"]:
        if t["state"] != "COMPLETE":
            continue
        st = t["status"]
        kw = {"c": OUTCOME_COLORS.get(st, "k"), "marker": OUTCOME_MARKERS.get(st, "o"), "s": 18, "alpha": 0.7}
        a1.scatter(t["iteration"] + 1, plotted_figure(t), **kw)
        a2.scatter(t["iteration"] + 1, t["steps_taken"], **kw)
    its = [it for it in status["iterations"] if it["best"] is not None]
    x = [it["iteration"] + 1 for it in its]
    plot_marked(a1, x, [it["best"] for it in its], label="learner's best (posterior mean)", color="tab:blue")
    a2.plot(x, [it["best"]["steps_taken"] for it in its], "-", color="tab:blue", lw=2)
    observed, best_so_far = [], None  # the highest oracle score evaluated up to each iteration
    for it in status["iterations"]:
        b = it["batch_best"]
        if b is not None and (best_so_far is None or (b["score"] or 0) > (best_so_far["score"] or 0)):
            best_so_far = b
        if best_so_far is not None and it["best"] is not None:
            observed.append((it["iteration"] + 1, best_so_far))
    plot_marked(a1, [i for i, _ in observed], [b for _, b in observed], label="best evaluated so far", color="0.4",
                ls="--")
    a2.plot([i for i, _ in observed], [b["steps_taken"] for _, b in observed], "--", color="0.4", lw=1.2)
    for name, c in OUTCOME_COLORS.items():
        a1.scatter([], [], c=c, marker=OUTCOME_MARKERS[name], label=OUTCOME_LABELS[name])
    a1.set_ylabel(labelled(radius_name(status["certificate"]), status.get("unit", "rad/s")))
    a1.legend(fontsize=8, loc="best")
    cap = status["config"]["sim"]["step_cap"]
    a2.axhline(cap, color="0.6", ls="--", lw=0.8)
    a2.set_ylabel(f"steps (cap {cap})")
    a2.set_xlabel("iteration")
    a2.xaxis.set_major_locator(MaxNLocator(integer=True))
    fig.suptitle(f"{status['learner']} on {status['metric']}: best gait per iteration")
    return _save(fig, path)


def plot_explored(status: dict[str, Any], path: Path) -> Path:
    """Every pair of parameters: the evaluated gaits coloured by outcome (marker size ∝ r* or J*, the largest the
    study's largest)."""
    trials = [t for t in status["trials"] if t["state"] == "COMPLETE" and t["reused_from"] is None]
    top = max((plotted_figure(t) for t in trials), default=0.0) or 1.0
    names = list(trials[0]["params"]) if trials else []
    pairs = list(combinations(range(len(names)), 2))
    cols = min(3, max(1, len(pairs)))
    rows = max(1, -(-len(pairs) // cols))
    fig, axes = plt.subplots(rows, cols, figsize=(4 * cols, 3.4 * rows), squeeze=False)
    best = status["best"]
    for ax, (i, j) in zip(axes.ravel(), pairs, strict=False):
        for t in trials:
            st = t["status"]
            ax.scatter(t["params"][names[i]], t["params"][names[j]], c=OUTCOME_COLORS.get(st, "k"),
                       marker=OUTCOME_MARKERS.get(st, "o"), s=20 + 120 * plotted_figure(t) / top,
                       alpha=0.6)
        if best is not None:
            ax.scatter(best["params"][names[i]], best["params"][names[j]], s=260, facecolors="none",
                       edgecolors="tab:blue", linewidths=2)
        ax.set_xlabel(names[i])
        ax.set_ylabel(names[j])
    for ax in axes.ravel()[len(pairs):]:
        ax.axis("off")
    for name, c in OUTCOME_COLORS.items():
        axes.ravel()[0].scatter([], [], c=c, marker=OUTCOME_MARKERS[name], label=OUTCOME_LABELS[name])
    axes.ravel()[0].scatter([], [], s=120, facecolors="none", edgecolors="tab:blue", label="best")
    axes.ravel()[0].legend(fontsize=7)
    fig.suptitle(f"Explored gait parameters (marker size ∝ {radius_name(status['certificate'])})")
    return _save(fig, path)


def plot_posterior(directory: Path, status: dict[str, Any], axes_names: tuple[str, str], path: Path) -> Path:
    """Posterior mean of the learner's preference model over two parameters; the others at the best gait's
    grid values; evaluated gaits on that slice marked."""
    from robustgait.io.studyfile import load_config
    from robustgait.study.ranking import history_before, requirements
    from robustgait.study.run import completed_batches, open_store

    setup = load_config(directory)
    cfg = setup.config.study
    space = setup.action_space()
    for name in axes_names:
        if name not in space.names:
            raise RobustGaitError(f"report.axes: {name!r} is not a parameter of the action space "
                                  f"({', '.join(space.names)})")
    store = open_store(directory, setup, space)
    try:
        batches = completed_batches(store.records())
        iterations = store.iterations()
        stored = store.posterior()
    finally:
        store.close()
    # the last iteration ranked (a person study's pending batch has no answer yet: the one before it)
    k = max((i for i in range(cfg.iterations) if len(batches.get(i, [])) >= cfg.batch_size(i)
             and (not cfg.asks_a_person or "answer" in iterations.get(i, {}))), default=-1)
    history = history_before(k + 1, batches, cfg, iterations, requirements(cfg, space.names))
    a, b = (space.names.index(n) for n in axes_names)
    base = space.coords(status["best"]["grid_index"]) if status["best"] else np.zeros(space.dim, dtype=np.int64)
    na, nb = space.shape[a], space.shape[b]
    idx = np.empty((nb, na), dtype=np.int64)
    for ia in range(na):
        for ib in range(nb):
            c = base.copy()
            c[a], c[b] = ia, ib
            idx[ib, ia] = space.index_of_coords(c)
    mu = _grid_posterior(space, cfg, history, k, stored)[idx.ravel()].reshape(nb, na)
    fig, ax = plt.subplots(figsize=(6.5, 5))
    im = ax.imshow(mu, origin="lower", aspect="auto", cmap="viridis",
                   extent=(-0.5, na - 0.5, -0.5, nb - 0.5))
    fig.colorbar(im, ax=ax, label="posterior mean utility")
    ax.set_xticks(range(na), [f"{v:g}" for v in space.values[a]])
    ax.set_yticks(range(nb), [f"{v:g}" for v in space.values[b]])
    on_slice = set(idx.ravel().tolist())
    visited = {i for i in history.actions if i in on_slice}
    for i in visited:
        c = space.coords(i)
        ax.plot(c[a], c[b], "wo", mfc="none", ms=10)
    if status["best"]:
        ax.plot(base[a], base[b], "r*", ms=14, label="best")
        ax.legend(fontsize=8)
    fixed = ", ".join(f"{n} = {space.values[j][base[j]]:g}" for j, n in enumerate(space.names) if j not in (a, b))
    ax.set_xlabel(axes_names[0])
    ax.set_ylabel(axes_names[1])
    ax.set_title(f"Posterior mean after {k + 1} iterations ({fixed}); ○ evaluated", fontsize=9)
    return _save(fig, path)


def _grid_posterior(space: ActionSpace, cfg: StudyConfig, history: History, k: int,
                    stored: tuple[int, NDArray[np.float64]] | None) -> NDArray[np.float64]:
    """The learner's posterior mean (space.size,) after iteration ``k``: the one the study stored when it closed the
    iteration, else (a study run before it was stored, a grid past the storing limit, no iteration closed) the
    preference model fitted again to ``history``."""
    if stored is not None and stored[0] == k:
        return stored[1]
    from robustgait.learn.learners import make_learner  # torch and BoTorch: only when nothing is stored

    learner = make_learner(cfg.learner, space, cfg.learning, cfg.seed)
    return learner.grid_utility(learner.model(history, max(k, 0)))


def render_best_video(directory: Path, status: dict[str, Any], path: Path, steps: int | None = None,
                      config: ReportConfig | None = None) -> Path:
    """Walk the best gait ``steps`` steps from its initial state (not set: ``config.video_steps``) and render it
    (:func:`~robustgait.sim.walk.render_video`, MuJoCo offscreen) with the video settings of ``config`` (default
    :class:`ReportConfig`): ``video_fps``, ``video_width`` × ``video_height``, ``video_shadows``,
    ``video_antialias``."""
    from robustgait.io.gaitfile import load_gait
    from robustgait.io.robotfile import load_robot
    from robustgait.sim import render_video, walk

    config = config or ReportConfig()
    robot = load_robot(status["robot"])
    gait = load_gait(directory / status["best"]["gait_file"], robot)
    res = walk(robot, gait, steps=config.video_steps if steps is None else steps, keep_trajectory=True)
    if res.trajectory is None:
        raise RobustGaitError("the best gait produced no trajectory to render")
    render_video(robot, res.trajectory, path, fps=config.video_fps, width=config.video_width,
                 height=config.video_height, shadows=config.video_shadows, antialias=config.video_antialias)
    return path


def _img(path: Path) -> str:
    return f'<img src="data:image/png;base64,{base64.b64encode(path.read_bytes()).decode()}" alt="{path.name}">'


def _table(rows: list[list[Any]], header: list[str] | None = None) -> str:
    th = "<tr>" + "".join(f"<th>{html.escape(h)}</th>" for h in header) + "</tr>" if header else ""
    body = "".join("<tr>" + "".join(f"<td>{html.escape(str(c))}</td>" for c in r) + "</tr>" for r in rows)
    return f"<table>{th}{body}</table>"


def _fmt(v: Any, nd: int = 3) -> str:
    if v is None:
        return "—"
    if isinstance(v, float):
        return f"{v:.{nd}f}"
    return str(v)


def write_study_report(directory: str | Path, config: ReportConfig | None = None, *,
                       video_steps: int | None = None) -> Path:
    """Write ``DIR/report/index.html`` and its PNGs (and ``best.mp4`` when ``config.video``: ``video_steps`` steps of
    the best gait, not set: ``config.video_steps``; :func:`render_best_video`); returns the HTML path.
    ``config.axes``: the two parameters of the posterior-mean map. Parts that cannot be made (no certified gait,
    no offscreen GL for the video) are replaced by a note."""
    from robustgait.study.status import study_status

    config = config or ReportConfig()
    axes, video = config.axes, config.video
    video_steps = config.video_steps if video_steps is None else video_steps

    d = Path(directory)
    status = study_status(d)
    if status["trials_done"] == 0:
        raise input_error(d, "the study has no evaluated gait yet")
    if verify_recommended(d, status, config.pareto_figure):  # what the report recommends is verified
        status = study_status(d)
    out = d / REPORT_DIR
    out.mkdir(exist_ok=True)
    parts: list[str] = []
    notes: list[str] = []
    best = status["best"]
    figs = [("Best gait per iteration", lambda p: plot_history(status, p), "history.png"),
            ("Explored parameters", lambda p: plot_explored(status, p), "explored.png")]
    if best is not None:  # for a person study: the learned utility of the person over the parameters
        figs.append((f"{'Learned utility (posterior mean)' if status['person'] else 'Posterior mean'} over "
                     f"{axes[0]} × {axes[1]}",
                     lambda p: plot_posterior(d, status, axes, p), "posterior.png"))
    for title, make, name in figs:
        parts.append(f"<h2>{html.escape(title)}</h2>{_img(make(out / name))}")
    cert_file = best.get("certificate_file") if best else None
    if cert_file:
        raw = read_json(d / cert_file, "certificate file")
        cert = certificate_from_record(raw)
        coords = Coordinates.from_dict(raw["coordinates"]) if isinstance(raw.get("coordinates"), dict) else None
        name = radius_name("push" if raw.get("disturbance") == "push" else "state")
        what = f"{raw.get('state', 'omega')} {raw.get('set', 'ball')}" if name == "r*" else "pushes"
        p = plot_certificate(cert, out / "certificate.png", coordinates=coords,
                             title=f"best gait: {name} = {cert.radius:.4g} {raw.get('unit', 'rad/s')} ({what})")
        parts.append(f"<h2>Certificate of the best gait</h2>{_img(p)}"
                     f"<p>{html.escape(str(raw.get('statement') or cert.statement()))}</p>")
    else:
        notes.append("The best gait has no certificate (no gait walked the step cap and was certified).")
    parts += person_parts(status, _table)
    parts += _comfort_parts(status, out, notes)
    parts += pareto_parts(status, out, config.pareto_figure, _table, _img)
    parts += _validation_parts(d, status, out, notes)
    if video and best is not None and best.get("gait_file"):
        try:
            v = render_best_video(d, status, out / "best.mp4", video_steps, config)
            b64 = base64.b64encode(v.read_bytes()).decode()
            parts.append(f"<h2>The best gait walking ({video_steps} steps)</h2><video controls loop muted "
                         f'width="{config.video_width}" src="data:video/mp4;base64,{b64}"></video>')
        except RobustGaitError as exc:
            notes.append(f"No video: {exc}")
    return write_text(out / "index.html", _page(status, parts, notes), "html")


def verify_recommended(directory: Path, status: dict[str, Any], figure: str) -> bool:
    """Verify, on demand, every gait the report recommends whose certificate is an estimate: the learner's best, the
    best evaluated gait, each iteration's and the Pareto front's (:func:`~robustgait.study.pareto.study_pareto`).
    Returns whether any was verified."""
    from robustgait.study.pareto import study_pareto
    from robustgait.study.verify import verify_now

    entries = [status["best"], status["best_observed"], *(e for it in status["iterations"]
                                                         for e in (it["best"], it["batch_best"]))]
    indices = [e["grid_index"] for e in entries if e is not None and status_of(e) == EvaluationStatus.ESTIMATED]
    done = verify_now(directory, indices) > 0
    try:
        front = study_pareto(directory, figure, verify=False)["front"]
    except RobustGaitError:  # no front to recommend (the figure is the report's to refuse, below)
        return done
    if any(not r["verified"] for r in front):
        study_pareto(directory, figure)
        done = True
    return done


def _comfort_parts(status: dict[str, Any], out: Path, notes: list[str]) -> list[str]:
    """What the passenger feels on each evaluated gait (``docs/comfort.md``): the figure and the table; a note when no
    gait has comfort figures (a study evaluated before they existed, or no gait walked past the skipped steps)."""
    from robustgait.report.comfort import comfort_rows, measured_trials, plot_comfort

    if not measured_trials(status):
        notes.append("No comfort figures: no evaluated gait has them (evaluated before robustgait measured them, or "
                     "no gait walked past comfort.skip_steps).")
        return []
    header, rows = comfort_rows(status)
    c = status["config"]["comfort"]
    return [f"<h2>What the passenger feels</h2>{_img(plot_comfort(status, out / 'comfort.png'))}"
            f"<p>Steps {c['skip_steps'] + 1}–{c['skip_steps'] + c['steps']} of each gait's walk; pelvis acceleration "
            f"low-passed at {c['cutoff']:g} Hz (gravity excluded); impact: the landing sole's peak normal force within "
            f"{1e3 * c['impact_window']:g} ms of touchdown; definitions in docs/comfort.md.</p>"
            + _table(rows, header)]


def _validation_parts(d: Path, status: dict[str, Any], out: Path, notes: list[str]) -> list[str]:
    """One section per disturbance kind that ``study validate`` has results for (none: no section): the
    scatter of success against r* and steps taken, the correlations and one row per gait."""
    from robustgait.report.validation import plot_study_validation
    from robustgait.study.validate import load_summaries
    from robustgait.validate.stats import correlation_text

    try:
        summaries = load_summaries(d)
    except RobustGaitError as exc:
        notes.append(f"Validation results not shown: {exc}")
        return []
    parts = []
    for kind, s in summaries.items():
        png = plot_study_validation(s, out / f"validation_{kind}.png")
        cfg = s["config"]
        rows = [[r["label"], r["status"], _fmt(r["value"], 4), f"{r['steps_taken']}/{r['step_cap']}",
                 f"{r['success']['k']}/{r['success']['n']} = {r['success']['rate']:.2f} [{r['success']['low']:.2f}, "
                 f"{r['success']['high']:.2f}]",
                 "—" if r["critical"]["s50"] is None else f"{r['critical']['s50']:.4g} {s['unit']}"]
                for r in s["gaits"]]
        rows += [[k["label"], k["status"], "", "", f"skipped: {k['why']}", ""] for k in s["skipped"]]
        corr = "".join(f"<li>{html.escape(correlation_text(c))}</li>" for c in s["correlations"].values())
        parts.append(
            f"<h2>Validation: {html.escape(kind)} (robustgait study validate)</h2>{_img(png)}<ul>{corr}</ul>"
            f"<p>{cfg['trials']} trials per gait, seed {cfg['seed']} (the same disturbances for every gait), success "
            f"= no fall in {cfg['steps_after']} steps after the first switching event; certified gaits start on "
            "their fixed point, the others from their initial state.</p>"
            + _table(rows, ["gait", "study outcome", radius_name(status["certificate"]), "steps", "success [95 % CI]",
                            f"half fail at ({s['size']})"]))
        if s["study"]["unique_gaits"] != status["unique_gaits"]:
            notes.append(f"The {kind} validation covers the {s['study']['unique_gaits']} unique gaits the study had "
                         f"then; it has {status['unique_gaits']} now: run robustgait study validate again (stored "
                         "gaits are reused).")
    return parts


def _certify_text(cfg: dict[str, Any]) -> str:
    c = cfg["certify"]
    how = (f"sequential estimator (ε = {c['sequential']['epsilon']:g}, budget {c['sequential']['budget']}: rounds "
           "until a fresh uniform batch certifies the violating fraction)"
           if c.get("method") == "sequential" else f"uniform estimator (the paper's N = {c['n_samples']} samples)")
    if cfg["study"].get("metric") == "push" or c.get("disturbance") == "push":
        what = f"push certificate J* ({c.get('push', {}).get('horizon', 20)} steps after the push)"
    if cfg["study"].get("verify", "all") == "shown":
        how += ("; the learner ranks every gait on its estimate from exploration, and the best of each iteration, the "
                "recommendations, the gaits shown to a person and the Pareto front are verified")
    else:
        what = (f"{c.get('state', 'omega')} {c.get('set', 'ball')}, horizon {c.get('horizon', 1)}")
    return f"{what}; {how}, seed {c['seed']}, step cap {cfg['sim']['step_cap']}"


def _page(status: dict[str, Any], parts: list[str], notes: list[str]) -> str:
    best = status["best"]
    cfg = status["config"]
    name = radius_name(status["certificate"])
    summary = [["study", status["directory"]], ["robot", status["robot"]], ["metric", status["metric"]],
               ["learner", status["learner"]], ["seed", status["seed"]],
               ["budget", f"{cfg['study']['iterations']} iterations × {cfg['study']['batch']} gaits"],
               ["trials done", f"{status['trials_done']} / {status['trials_planned']} ({status['unique_gaits']} unique "
                               f"gaits)"], ["state", status["state"]],
               ["certificate", _certify_text(cfg)]]
    if best is not None:
        summary += [["best gait (learner)", ", ".join(f"{k} = {v:g}" for k, v in best["params"].items())],
                    [f"best {name} / steps", f"{figure_text(best, status.get('unit', 'rad/s'))} / "
                                        f"{best['steps_taken']}"],
                    ["best gait file", best["gait_file"] or "—"]]
    obs = status["best_observed"]
    if obs is not None and (best is None or obs["trial"] != best["trial"]):
        summary += [["best evaluated gait", ", ".join(f"{k} = {v:g}" for k, v in obs["params"].items())
                     + f": {name} {figure_text(obs, status.get('unit', 'rad/s'))}, "
                     f"{obs['steps_taken']} steps (trial {obs['trial']}; the "
                     "learner's best is the highest posterior mean, from comparisons only)"]]
    unit = status.get("unit", "rad/s")
    it_rows = [[it["iteration"] + 1, figure_text(it["best"], unit) if it["best"] else "—",
                it["best"]["steps_taken"] if it["best"] else "—",
                ", ".join(f"{v:g}" for v in it["best"]["params"].values()) if it["best"] else "—",
                len(it["comparisons"] or [])] for it in status["iterations"]]
    tr_rows = [[t["number"], t["iteration"] + 1, t["state"], ", ".join(f"{v:g}" for v in t["params"].values()),
                t["status"] or "—", t["steps_taken"] if t["steps_taken"] is not None else "—",
                figure_text(t, unit),
                (t["reason"] or "")[:90] + (f" (same gait as trial {t['reused_from']})" if t["reused_from"] is not None
                                            else "")] for t in status["trials"]]
    note_html = "".join(f"<p class=note>{html.escape(n)}</p>" for n in notes)
    return f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>robustgait study report</title>
<style>body{{font-family:sans-serif;max-width:1100px;margin:2em auto;color:#222}}img{{max-width:100%}}
table{{border-collapse:collapse;font-size:13px;margin:1em 0}}
td,th{{border:1px solid #ccc;padding:3px 7px;text-align:left}}
th{{background:#eee}}.note{{color:#a60}}</style></head><body>
<h1>robustgait study: {html.escape(status['learner'])} on {html.escape(status['metric'])},
{html.escape(status['robot'])}</h1>
{_table(summary)}{note_html}
{''.join(parts)}
<h2>Iterations</h2>{_table(it_rows, ["iteration", f"best {name}", "best steps", "best gait params", "comparisons"])}
<h2>Trials</h2>{_table(tr_rows, ["trial", "iteration", "state", "params", "outcome", "steps", name, "reason"])}
<p>Parameters in order: {html.escape(", ".join(best["params"]) if best else "")}. Generated by robustgait.</p>
</body></html>
"""
