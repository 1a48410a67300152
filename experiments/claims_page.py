"""The claims page's computed section, written from a scoring (:mod:`claims_score`).

Between :data:`claims_score.BEGIN` and :data:`claims_score.END` of a results page: the
count per reading column, the sweeps scored (one line per study: each reading with the
command that made its sweep, the runs), then per paper one line per claim (its short
statement, the thesis's sentence and line, its verdict under each reading column, the
counted one in bold) and one line per claim and column with the deciding comparison's
numbers and, for each claim that does not hold or is not testable, the measured reason.
Nothing in it is typed: the page test recomputes it from the committed extracts and
compares.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

from skinny_mj.experiments.claims_rules import ALPHA, READINGS
from skinny_mj.experiments.claims_score import BEGIN, END, counts

from skinny_mj import io
from skinny_mj.engine.stats import SMOKE_NOTE

PAPERS = {"E": "Paper E — the new β training method (2D, Cartesian)",
          "S": "Paper E §5.1 — why the new method works (Figs. 7–10)",
          "D": "Paper D — 3D, true target (TT) and feedback controller (FEL)",
          "A": "Paper A — delayed sensory feedback (2D, joint angles)",
          "B": "Paper B — bimanual coordination (2D, joint angles)",
          "C": "Paper C — generalization (2D, joint angles)"}
EXTRACTS = "docs/results/claims-runs"
_ESC = str.maketrans({"|": "\\|", "\n": " "})


def _cell(text: str) -> str:
    return str(text).translate(_ESC)


def _fmt(v: float | None) -> str:
    return "—" if v is None else f"{v:.3g}"


def _verdict(col: Mapping[str, Any]) -> str:
    return col["outcome"] + (" (weak)" if col["weak"] else "")


def numbers(col: Mapping[str, Any]) -> str:
    """The deciding comparison's numbers: the first failing, else the largest p."""
    comps = [c for c in col["comparisons"] if c["outcome"] != "not testable"]
    if not comps:
        return "—"
    failing = [c for c in comps if c["outcome"] == "does not hold"]
    c = failing[0] if failing else max(comps, key=lambda c: -1 if c["p"] is None else c["p"])
    n = ", ".join(map(str, c["n"]))
    held = sum(x["outcome"] == "holds" for x in col["comparisons"])
    p = "" if c["p"] is None else f", p {_fmt(c['p'])}"
    return (f"{c['comparison']}: {c['statistic']} {_fmt(c['stat_a'])} vs "
            f"{_fmt(c['stat_b'])} (n {n}{p}); {held} of {len(col['comparisons'])} "
            "comparisons hold")


def count_table(scored: Mapping[str, Any]) -> list[str]:
    lines = ["| reading | status | hold | do not hold (weak among them) | not testable |",
             "|---|---|---|---|---|"]
    for name, c in counts(scored).items():
        if name == "counted":
            label, status = "**counted** (each claim under its counted reading)", "—"
        else:
            label = name
            readings = [READINGS[r] for r in name.split("+")]
            status = ", ".join(dict.fromkeys(r.status for r in readings))
            if not all(r.counted for r in readings):
                status += "; not counted"
        lines.append(f"| {label} | {status} | {c['holds']} | {c['does not hold']} "
                     f"({c['weak']}) | {c['not testable']} |")
    return lines


def readings_table() -> list[str]:
    """Every reading: its status, what it sets, the thesis's words it rests on."""
    lines = ["| reading | status | what it sets | rests on |", "|---|---|---|---|"]
    for r in READINGS.values():
        words = f"“{r.quote}” (L{r.line})" if r.quote else ""
        rests = "; ".join(x for x in (words, r.note) if x) or "—"
        lines.append("| " + " | ".join(_cell(x) for x in (
            r.name, r.status + ("" if r.counted else ": not counted"), r.settings, rests))
            + " |")
    return lines


def sources_table(scored: Mapping[str, Any]) -> list[str]:
    """One line per study: each reading with the command(s) that made its sweep(s), and
    the runs (``k sweeps, each ok / failed / errored`` when every sweep counted the same)."""
    if not scored["sources"]:
        return ["No sweep was given: every claim is not testable."]
    lines = ["| study | reading: the command that made each sweep "
             "| runs: ok / failed / errored |", "|---|---|---|"]
    studies = dict.fromkeys(s["study"] for s in scored["sources"])
    for study in studies:
        mine = [s for s in scored["sources"] if s["study"] == study]
        made: dict[str, list[str]] = {}
        for s in mine:
            made.setdefault(s["key"], []).append(f"`{s['command']}`")
        runs = [f"{s['runs'].get('ok', 0)} / {s['runs'].get('failed', 0)} / "
                f"{s['runs'].get('error', 0)}" for s in mine]
        same = len(runs) > 1 and len(set(runs)) == 1
        runs_cell = f"{len(runs)} sweeps, each {runs[0]}" if same else ", ".join(runs)
        sweeps = "<br>".join(f"{key}: {', '.join(cmds)}" for key, cmds in made.items())
        lines.append(f"| {study} | {sweeps} | {runs_cell} |")
    return lines


def paper_tables(scored: Mapping[str, Any], paper: str) -> list[str]:
    claims = [c for c in scored["claims"] if c["paper"] == paper]
    names = list(dict.fromkeys(col["column"] for c in claims for col in c["columns"]))
    lines = [f"### {PAPERS[paper]}", "",
             "| claim | the thesis | " + " | ".join(names) + " |",
             "|---|---|" + "---|" * len(names)]
    for c in claims:
        cols = {col["column"]: col for col in c["columns"]}
        cells = [f"**{c['id']}** {c['claim']}", f"“{c['quote']}” (L{c['line']})"]
        for name in names:
            col = cols.get(name)
            cells.append("" if col is None else
                         f"**{_verdict(col)}**" if col["counted"] else _verdict(col))
        lines.append("| " + " | ".join(_cell(x) for x in cells) + " |")
    lines += ["", "| claim | reading | verdict | numbers | reason |", "|---|---|---|---|---|"]
    for c in claims:
        for col in c["columns"]:
            reading = col["column"] + (" (counted)" if col["counted"] else "")
            cells = [c["id"], reading, _verdict(col), numbers(col), col["reason"] or "—"]
            lines.append("| " + " | ".join(_cell(x) for x in cells) + " |")
    return lines + [""]


def markdown(scored: Mapping[str, Any]) -> str:
    """The computed section, markers included."""
    lines = [BEGIN, ""]
    if scored["smoke"]:
        lines += [SMOKE_NOTE, ""]
    lines += [f"Computed by `skinny claims` (Welch's t-test, α = {ALPHA:g}, the mean; "
              "weak never counts). Count per reading column:", "", *count_table(scored), "",
              "The readings (experiments/claims_rules.py):", "", *readings_table(), "",
              f"Sweeps scored (each one's extract in `{EXTRACTS}/`: "
              "`<study>.<reading>.json`, a band's point i `<study>.<reading>.<i>.json`):", "",
              *sources_table(scored), ""]
    for paper in PAPERS:
        lines += paper_tables(scored, paper)
    return "\n".join(lines + [END]) + "\n"


def page_section(page: str) -> str | None:
    """The computed section of a results page (markers included), None without one."""
    return io.page_section(page, BEGIN, END)


def page_matches(page: str, scored: Mapping[str, Any]) -> bool:
    """Does the page's computed section equal the table scored from the runs?"""
    return page_section(page) == markdown(scored)


def write_page(path: Path, scored: Mapping[str, Any]) -> None:
    """Replace the computed section of the page at ``path`` (it must have the markers)."""
    io.write_page_section(path, BEGIN, END, markdown(scored))
