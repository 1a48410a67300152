"""Check a paper's claims against the run files of a finished sweep.

A claim compares a statistic of one row's metric with a statistic of another row's,
e.g. ("worst run of exp 5 beats the best of exp 2", "max", "5", "position_nrmse",
"<", "min", "2"). Each prints as holds / does not hold with the numbers behind it,
over the ok runs only (a failed run diverged, an errored one is a bug), or n/a saying
why a row has no value (not run, or every run failed or errored).

Two measures behind paper C's claims are here too: ``python -m
skinny_mj.experiments.claims c7 PAPER_C_SWEEP DOF`` (where the Y-trained networks' YM error
lies) and ``... claims mirrors`` (how far each mirror movement leaves the joint ranges YMCA
covers, 2D and 3D). The thesis's claims are scored by ``skinny claims``
(:mod:`claims_score`).
"""

from __future__ import annotations

import operator
import sys
from collections import Counter
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
from skinny_mj.experiments.paper_c import study as paper_c

from skinny_mj.engine.stats import load_runs
from skinny_mj.plant import body

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


# -- measured reasons (paper C's C1 and C7 in the claims table) ---------------------------
def error_split(produced: np.ndarray, desired: np.ndarray, steps: np.ndarray
                ) -> dict[str, Any]:
    """Where a test's error lies. produced, desired: (T, n) normalized signals in [-1, 1];
    steps: (T,) bool. Returns each signal's share of the squared error (``share``, (n,),
    sums to 1), and the NRMSE (RMS error / 2) on the selected steps and on the others."""
    e2 = (np.asarray(produced, float) - np.asarray(desired, float)) ** 2
    steps = np.asarray(steps, bool)
    return {"share": e2.sum(axis=0) / e2.sum(),
            "nrmse_selected": float(np.sqrt(e2[steps].mean()) / 2.0),
            "nrmse_other": float(np.sqrt(e2[~steps].mean()) / 2.0)}


def range_excursion(angles: np.ndarray, reference: np.ndarray, tol: float = np.radians(1.0)
                    ) -> tuple[np.ndarray, np.ndarray]:
    """How far each joint of ``angles`` (T, n) rad leaves the range [min, max] the same
    joint covers in ``reference`` (T', n) rad: (the largest excursion (n,) rad, the
    fraction of steps (n,) beyond ``tol`` rad)."""
    a, ref = np.asarray(angles, float), np.asarray(reference, float)
    out = np.maximum(a - ref.max(axis=0), 0.0) + np.maximum(ref.min(axis=0) - a, 0.0)
    return out.max(axis=0), (out > tol).mean(axis=0)


def _measure_c7(out_dir: Path, dof: int) -> list[str]:
    """C7: the Y-trained networks' YM error per joint (their kept ``angles__ym``), and
    on the steps where YM's elbows have folded by more than 5 degrees vs the rest."""
    ym = paper_c.load(paper_c.MOVEMENTS["ym"], dof).angles
    elbows = paper_c.elbow_dofs(dof)
    folded = np.abs(ym[:, elbows] - ym[0, elbows]).max(axis=1) > np.radians(5.0)
    lines = []
    for run in load_runs(out_dir):
        if run.get("row") != "y" or "angles__ym" not in run.get("metrics", {}):
            continue
        produced = np.asarray(run["metrics"]["angles__ym"], float)
        n = min(len(produced), len(ym))
        split = error_split(body.body_of(dof).normalize_angles(produced[:n]),
                            body.body_of(dof).normalize_angles(ym[:n]), folded[:n])
        lines.append(f"seed {run['seed']}: elbows' share of the YM error "
                     f"{split['share'][elbows].sum():.3f}; NRMSE where YM's elbows have "
                     f"folded ({folded[:n].mean():.0%} of steps) {split['nrmse_selected']:.4f}, "
                     f"elsewhere {split['nrmse_other']:.4f}")
    return lines


def _measure_mirrors() -> list[str]:
    """C1 in 3D: how far each mirror movement's arms leave the ranges YMCA covers."""
    lines = []
    for dof in (4, 8):
        ymca = paper_c.load(paper_c.MOVEMENTS["ymca"], dof).angles
        for name in ("mirror-right", "mirror-left"):
            most, frac = range_excursion(paper_c.load(paper_c.MOVEMENTS[name], dof).angles,
                                         ymca)
            beyond = [f"{j} {np.degrees(most[i]):.1f} deg ({frac[i]:.0%} of steps)"
                      for i, j in enumerate(body.body_of(dof).dof_names) if most[i] > 0]
            lines.append(f"{dof} DOF, {name}: beyond YMCA's range: "
                         f"{', '.join(beyond) if beyond else 'none'}")
    return lines


USAGE = "usage: python -m skinny_mj.experiments.claims c7 PAPER_C_SWEEP DOF | mirrors"


def _existing(path: str) -> Path:
    if not Path(path).exists():
        raise SystemExit(f"no such file or folder: {path}")
    return Path(path)


def main(args: list[str]) -> str:
    """The command line: one of the measured reasons."""
    if args == ["mirrors"]:
        return "\n".join(_measure_mirrors())
    if len(args) == 3 and args[0] == "c7" and args[2] in ("4", "8"):
        return "\n".join(_measure_c7(_existing(args[1]), int(args[2])))
    raise SystemExit(USAGE)


if __name__ == "__main__":
    try:
        print(main(sys.argv[1:]))
    except SystemExit as e:
        print(e, file=sys.stderr)
        sys.exit(2)
