"""Check a paper's claims against the run files of a finished sweep.

A claim compares a statistic of one row's metric with a statistic of another row's,
e.g. ("worst run of exp 5 beats the best of exp 2", "max", "5", "position_nrmse",
"<", "min", "2"). Each prints as holds / does not hold with the numbers behind it,
over the ok runs only (a failed run diverged, an errored one is a bug), or n/a saying
why a row has no value (not run, or every run failed or errored).
"""

from __future__ import annotations

import operator
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
