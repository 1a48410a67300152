"""Check a paper's claims against the run files of a finished sweep.

A claim compares a statistic of one row's metric with a statistic of another row's,
e.g. ("worst run of exp 5 beats the best of exp 2", "max", "5", "position_nrmse",
"<", "min", "2"). Each prints as holds / does not hold with the numbers behind it,
over the ok runs only (a failed run diverged, an errored one is a bug), or n/a saying
why a row has no value (not run, or every run failed or errored).

:func:`tally` counts the verdicts of the project's table of every claim
(docs/results/claims.md) per reading of the thesis's unstated settings, so the counts the
page states are the table's: ``python -m skinny_mj.experiments.claims docs/results/claims.md``.
"""

from __future__ import annotations

import operator
import re
import sys
from collections import Counter
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from skinny_mj.engine.stats import load_runs

_STATS = {"min": np.min, "max": np.max, "mean": np.mean, "median": np.median}
_OPS = {"<": operator.lt, ">": operator.gt, "<=": operator.le, ">=": operator.ge}

Claim = tuple[str, str, str, str, str, str, str]


def values(out_dir: Path, row: str, metric: str,
           runs: Sequence[dict[str, Any]] | None = None) -> list[float]:
    """The finite values of ``metric`` over the ok runs of ``row`` (failed runs diverged
    and errored runs are bugs: neither has metrics). ``runs``: the records, if loaded."""
    out = []
    for run in load_runs(out_dir) if runs is None else runs:
        if run.get("row") == row and run.get("status") == "ok":
            v = run.get("metrics", {}).get(metric)
            if isinstance(v, int | float) and np.isfinite(v):
                out.append(float(v))
    return out


def _why_empty(runs: Sequence[dict[str, Any]], row: str) -> str:
    counts = Counter(r.get("status") for r in runs if r.get("row") == row)
    if not counts:
        return f"row {row} was not run"
    return (f"no ok run with a value for row {row} ({counts['failed']} failed, "
            f"{counts['error']} errored of {sum(counts.values())})")


def check(out_dir: Path, claim: Claim, runs: Sequence[dict[str, Any]] | None = None
          ) -> tuple[bool | None, str]:
    """(holds, line); holds is None when a row has no ok run with a value (not run,
    e.g. left out by ``--rows``, or every run failed or errored)."""
    runs = load_runs(out_dir) if runs is None else runs
    text, stat_a, row_a, metric, op, stat_b, row_b = claim
    a, b = values(out_dir, row_a, metric, runs), values(out_dir, row_b, metric, runs)
    if not a or not b:
        return None, f"- [n/a] {text}: {_why_empty(runs, row_a if not a else row_b)}"
    va, vb = float(_STATS[stat_a](a)), float(_STATS[stat_b](b))
    holds = bool(_OPS[op](va, vb))
    mark = "holds" if holds else "does NOT hold"
    return holds, (f"- [{mark}] {text}: {stat_a} {metric}[{row_a}] = {va:.4g} {op} "
                   f"{stat_b} {metric}[{row_b}] = {vb:.4g} (n = {len(a)}, {len(b)}; "
                   "ok runs only)")


def claim_lines(out_dir: Path, claims: Sequence[Claim]) -> str:
    runs = load_runs(out_dir)
    return "\n".join(check(out_dir, c, runs)[1] for c in claims)


# -- the claims table's count ---------------------------------------------------------
#: A claim's id in the claims table: its paper's letter (S: paper E §5.1) and its number.
CLAIM_ID = re.compile(r"^[ABCDES]\d+$")
#: Verdict words, in the order they are counted (weak is a kind of holds).
VERDICTS = ("holds", "weak", "does not hold", "not run")


def _cells(line: str) -> list[str]:
    """A Markdown table row's cells (an escaped ``\\|`` stays inside its cell)."""
    return [c.strip() for c in re.split(r"(?<!\\)\|", line.strip().strip("|"))]


def _verdict(cell: str) -> str:
    word = cell.strip().rstrip(".").lower()
    if word not in VERDICTS:
        raise ValueError(f"unknown verdict {cell!r} (verdicts: {', '.join(VERDICTS)})")
    return word


def tally(markdown: str, readings: tuple[str, ...] = ("default", "thesis reading")
          ) -> dict[str, Counter]:
    """The verdicts of the claims table in ``markdown`` (docs/results/claims.md), counted
    per reading: a table whose verdict column is ``verdict (default; thesis reading)``
    gives one verdict per reading (``holds; weak``); a table with one ``verdict`` column is
    of studies the readings do not change, so its verdict counts under each. Rows are
    those whose first cell is a claim id (``E4``, ``S7``, ``D10``)."""
    counts = {r: Counter() for r in readings}
    column, per_reading = None, False
    for line in markdown.splitlines():
        if not line.lstrip().startswith("|"):
            column = None
            continue
        cells = _cells(line)
        if column is None:
            column = next((i for i, c in enumerate(cells) if c.startswith("verdict")), None)
            per_reading = column is not None and ";" in cells[column]
            continue
        if not CLAIM_ID.match(cells[0]):
            continue
        words = [_verdict(w) for w in cells[column].split(";")] if per_reading \
            else [_verdict(cells[column])] * len(readings)
        if len(words) != len(readings):
            raise ValueError(f"claim {cells[0]}: {len(words)} verdicts for "
                             f"{len(readings)} readings")
        for reading, word in zip(readings, words, strict=True):
            counts[reading][word] += 1
    return counts


def tally_lines(counts: dict[str, Counter]) -> list[str]:
    """One line per reading: how many claims hold (of them weak), do not hold, were not
    run, of how many."""
    return [f"{reading}: {c['holds'] + c['weak']} of {sum(c.values())} hold "
            f"({c['weak']} of them weak), {c['does not hold']} do not hold, "
            f"{c['not run']} not run" for reading, c in counts.items()]


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit("usage: python -m skinny_mj.experiments.claims CLAIMS_MD")
    print("\n".join(tally_lines(tally(Path(sys.argv[1]).read_text(encoding="utf-8")))))
