"""Check a paper's claims against the run files of a finished sweep.

A claim compares a statistic of one row's metric with a statistic of another row's,
e.g. ("worst run of exp 5 beats the best of exp 2", "max", "5", "position_nrmse",
"<", "min", "2"). Each prints as holds / does not hold with the numbers behind it.
"""

from __future__ import annotations

import operator
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from skinny_mj.sweep.stats import load_runs

_STATS = {"min": np.min, "max": np.max, "mean": np.mean, "median": np.median}
_OPS = {"<": operator.lt, ">": operator.gt, "<=": operator.le, ">=": operator.ge}

Claim = tuple[str, str, str, str, str, str, str]


def values(out_dir: Path, row: str, metric: str) -> list[float]:
    """The finite values of ``metric`` over the ok runs of ``row``."""
    out = []
    for run in load_runs(out_dir):
        if run.get("row") == row and run.get("status") == "ok":
            v = run.get("metrics", {}).get(metric)
            if isinstance(v, int | float) and np.isfinite(v):
                out.append(float(v))
    return out


def check(out_dir: Path, claim: Claim) -> tuple[bool | None, str]:
    """(holds, line); holds is None when a row has no finished runs."""
    text, stat_a, row_a, metric, op, stat_b, row_b = claim
    a, b = values(out_dir, row_a, metric), values(out_dir, row_b, metric)
    if not a or not b:
        return None, f"- [n/a] {text}: no finished runs for row {row_a if not a else row_b}"
    va, vb = float(_STATS[stat_a](a)), float(_STATS[stat_b](b))
    holds = bool(_OPS[op](va, vb))
    mark = "holds" if holds else "does NOT hold"
    return holds, (f"- [{mark}] {text}: {stat_a} {metric}[{row_a}] = {va:.4g} {op} "
                   f"{stat_b} {metric}[{row_b}] = {vb:.4g} (n = {len(a)}, {len(b)})")


def claim_lines(out_dir: Path, claims: Sequence[Claim]) -> str:
    return "\n".join(check(out_dir, c)[1] for c in claims)
