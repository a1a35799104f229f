"""Contracts in the code, history in git and docs: no file of src/robustgait (code, docstrings, comments, help text,
the page) names an issue, carries a date, tells what the code did before, or quotes a measurement. Measurements and
their dates belong in docs/ and benchmarks/."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

import robustgait

SRC = Path(robustgait.__file__).parent
HISTORY = {
    "an issue number": re.compile(r"\bissues?\s+#?\d+|\(issue\b", re.IGNORECASE),
    "a date": re.compile(r"\b20\d\d-[01]\d-[0-3]\d\b"),
    "history phrasing": re.compile(r"\b(?:of before|as before|than before|the rule before|durations of "
                                   r"20\d\d|before 20\d\d|used to be|formerly|previously)\b", re.IGNORECASE),
    # what a developer measured: "(measured: …", "measured, docs/…", timings before → after, "~5 µs", "5× slower"
    "a measurement": re.compile(r"\(measured\b|\bmeasured[:;]|\bmeasured, (?:docs|benchmarks)\b|\bwas measured \d"
                                r"|\d\s*(?:s|ms|µs)\s*→\s*\d|[~≈]\s*\d+(?:\.\d+)?\s*(?:ms|µs)\b"
                                r"|\d+(?:\.\d+)?\s*(?:ms|µs) (?:per|for|each)\b|\d(?:–\d+)?\s*× (?:faster|slower)"
                                r"|\d\.\d+ (?:and \d\.\d+ )?kg\b", re.IGNORECASE),
}


def findings(text: str) -> list[tuple[int, str, str]]:
    """(line, what, the match) for every history pattern in ``text``."""
    out = []
    for n, line in enumerate(text.splitlines(), 1):
        for what, rx in HISTORY.items():
            out += [(n, what, m.group(0)) for m in rx.finditer(line)]
    return out


def test_the_patterns_catch_what_they_name():
    assert [w for _, w, _ in findings('_STREAM = 29  # (issue 29)\n"the rule before 2026-11-25"')] == [
        "an issue number", "a date", "history phrasing"]
    assert [w for _, w, _ in findings("# ≥ 3.5 s (durations of 2026-11-26), as before")] == [
        "a date", "history phrasing", "history phrasing"]
    assert findings('a study written before over-drawn batches; "#fff" colour; issued 3 times; before the solve') == []
    measured = ['# (measured: 620 s → 549 s)', '"""ran at ~0.6 of a step; ~5 µs per sample"""', "# 4–5× faster",
                "# measured, docs/gaitgen.md", "# the shanks weigh 1.73 and 1.79 kg", "# was measured 5× slower"]
    assert [{w for _, w, _ in findings(t)} for t in measured] == [{"a measurement"}] * len(measured)
    assert findings("steps measured after the skipped ones; the measured lateral growth; 1 ms of 0.308 s; "
                    "0.8^200 ≈ 1e-20; flat_approach × the height") == []


@pytest.mark.parametrize("path", sorted(p for p in SRC.rglob("*") if p.suffix in (".py", ".html", ".toml")),
                         ids=lambda p: str(p.relative_to(SRC)))
def test_src_holds_contracts_not_history(path):
    found = findings(path.read_text(encoding="utf-8"))
    assert not found, "; ".join(f"{path.relative_to(SRC)}:{n}: {what} ({m!r})" for n, what, m in found)
