"""The same results before and after a change that must not change behaviour: a fingerprint of the default gaits,
their certificates and a validation under every disturbance kind.

    python benchmarks/perf/fingerprint.py OUT.json [--compare BEFORE.json] [--renamed OLD=NEW ...] [--added KEY ...]
        [--no-t1] [--t1-spec SPEC]

Records, through the CLI a user runs (``--json`` outputs, every figure to the last digit; wall times and paths
dropped):

* the default ``exo`` gait, flat-foot and multi-contact (``gait generate``): the gait file (its solve times dropped);
* the default ``exo`` certificate of the flat-foot gait (``certify``);
* ``validate --disturbance all --trials 8`` on it (every disturbance kind through the closed loop);
* T1's default gait from ``robots/t1/spec.toml`` and its certificate (skipped without
  ``../shared/robots``, or with ``--no-t1``).

``--compare`` prints each entry as ``same`` or ``DIFFERS`` (with the first differing key) and exits 1 on any
difference. A change that renames keys without changing a figure is compared with ``--renamed OLD=NEW`` (the before's
key OLD read as NEW, at any depth) and ``--added KEY`` (a key the after writes and the before did not, ignored),
each said in the output: e.g. ``--renamed j_star=value --renamed r_star=value --added figure`` for the certificate's
figure named ``value``.
"""
from __future__ import annotations

import argparse
import hashlib
import json
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # benchmarks/common.py
from common import SHARED, T1_SPEC

DROP = ("seconds", "wall", "time_s", "elapsed", "path", "file", "created", "date", "commit", "version", "cpu")


def _clean(v: Any) -> Any:
    """``v`` without the fields that change from run to run (timings, paths, dates)."""
    if isinstance(v, dict):
        return {k: _clean(x) for k, x in v.items() if not any(d in k.lower() for d in DROP)}
    if isinstance(v, list):
        return [_clean(x) for x in v]
    return v


def _run(*args: str, refusal_ok: bool = False) -> str:
    """stdout of ``robustgait ARGS`` (exit 1, a refused certificate or a failed check, is a result when
    ``refusal_ok``)."""
    done = subprocess.run([sys.executable, "-m", "robustgait.cli", *args], capture_output=True, text=True, check=False)
    if done.returncode not in ((0, 1) if refusal_ok else (0,)):
        raise SystemExit(f"robustgait {' '.join(args)} failed ({done.returncode}): {done.stderr.strip()[-400:]}")
    return done.stdout


def _gait(path: Path) -> Any:
    """A gait file's content without its timings, and the SHA-256 of that content (a short line to compare by eye)."""
    gait = _clean(json.loads(path.read_text()))
    return {"sha256": hashlib.sha256(json.dumps(gait, sort_keys=True).encode()).hexdigest(), "content": gait}


def record(t1_spec: Path | None) -> dict[str, Any]:
    out: dict[str, Any] = {}
    with tempfile.TemporaryDirectory() as tmp:
        d = Path(tmp)
        flat, multi = d / "exo_flat.json", d / "exo_multi.json"
        _run("gait", "generate", "--robot", "exo", "-o", str(flat))
        _run("gait", "generate", "--robot", "exo", "--domains", "multicontact", "-o", str(multi))
        out["exo flat gait"] = _gait(flat)
        out["exo multicontact gait"] = _gait(multi)
        cert = _run("certify", str(flat), "--robot", "exo", "--json", refusal_ok=True)
        out["exo certificate"] = _clean(json.loads(cert))
        val = _run("validate", str(flat), "--robot", "exo", "--disturbance", "all", "--trials", "8", "--json",
                   refusal_ok=True)
        out["exo validate all"] = _clean(json.loads(val))
        if t1_spec is not None:
            g = d / "t1.json"
            _run("gait", "generate", "--robot", str(t1_spec), "-o", str(g))
            out["t1 gait"] = _gait(g)
            out["t1 certificate"] = _clean(json.loads(_run("certify", str(g), "--robot", str(t1_spec), "--json",
                                                           refusal_ok=True)))
    return out


def _normalized(v: Any, renamed: dict[str, str], added: set[str]) -> Any:
    """``v`` with the keys of ``renamed`` renamed and those of ``added`` dropped, at every depth."""
    if isinstance(v, dict):
        return {renamed.get(k, k): _normalized(x, renamed, added) for k, x in v.items() if k not in added}
    if isinstance(v, list):
        return [_normalized(x, renamed, added) for x in v]
    return v


def _first_difference(a: Any, b: Any, where: str = "") -> str | None:
    if isinstance(a, dict) and isinstance(b, dict):
        for k in sorted(set(a) | set(b)):
            if k not in a or k not in b:
                return f"{where}.{k} (missing on one side)"
            d = _first_difference(a[k], b[k], f"{where}.{k}")
            if d:
                return d
        return None
    if isinstance(a, list) and isinstance(b, list):
        if len(a) != len(b):
            return f"{where} (length {len(a)} vs {len(b)})"
        for i, (x, y) in enumerate(zip(a, b, strict=True)):
            d = _first_difference(x, y, f"{where}[{i}]")
            if d:
                return d
        return None
    return None if a == b else f"{where}: {a!r} vs {b!r}"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("out", type=Path)
    ap.add_argument("--compare", type=Path)
    ap.add_argument("--renamed", action="append", default=[], metavar="OLD=NEW",
                    help="compare the before's key OLD as NEW (a rename that changes no figure)")
    ap.add_argument("--added", action="append", default=[], metavar="KEY", help="a key new in the after: ignored")
    ap.add_argument("--no-t1", action="store_true")
    ap.add_argument("--t1-spec", type=Path, default=T1_SPEC, help="T1's spec (default: robots/t1/spec.toml)")
    args = ap.parse_args()
    t1 = None if args.no_t1 or not args.t1_spec.exists() or not (SHARED / "robots").exists() \
        else args.t1_spec
    rec = record(t1)
    args.out.write_text(json.dumps(rec, indent=1, sort_keys=True) + "\n")
    print(f"wrote {args.out}: {', '.join(rec)}")
    if args.compare:
        renamed = dict(r.split("=", 1) for r in args.renamed)
        added = set(args.added)
        if renamed or added:
            print(f"compared with keys renamed {renamed} and added keys ignored {sorted(added)}")
        before = _normalized(json.loads(args.compare.read_text()), renamed, added)
        rec = _normalized(rec, renamed, added)
        bad = 0
        for k in sorted(set(before) | set(rec)):
            d = _first_difference(before.get(k), rec.get(k), k)
            print(f"{k}: {'same' if d is None else 'DIFFERS at ' + d}")
            bad += d is not None
        sys.exit(1 if bad else 0)


if __name__ == "__main__":
    main()
