"""Ridge vs new: does a ridge readout (lambda chosen per fit on a validation cycle) with
the original FEL method match paper E's new β method?

Rows, on each of two movements (``ymca-*``: the YMCA of paper E; ``md02-*``: CMU
modern dance md_02, seconds 3 to 9.26, the length of one YMCA):

- ``<mv>-1`` ... ``<mv>-6``: paper E's Table 1 rows
  (:data:`skinny_mj.experiments.paper_e.study.TABLE_1`,
  their overrides in :data:`skinny_mj.experiments.paper_e.study.ROWS`): original method with 1, 5,
  10
  repetitions, new method with β = 0.3, 0.1, 0.05;
- ``<mv>-ridge1``, ``-ridge5``, ``-ridge10``: rows 1–3 (original method, reservoir noise
  0.03) with ``esn.readout=ridge`` and ``method.fit=ridge-select``: each fit's lambda from the
  grid 1e-8 ... 10 (:data:`skinny_mj.controllers.ridge_select.RIDGE_GRID`) that best predicts the
  targets of the cycle before it (:class:`skinny_mj.controllers.ridge_select.RidgeSelector`);
- ``<mv>-ridge-new``: row 5 (new method, β = 0.1) with the same ridge selection.

20 runs per row, tested with the feedback controller off (K = 0) on one repetition:
test position and motor NRMSE, training wall time per run (lockstep batch / R), and the
lambda chosen in the last epoch. Groups: ``ymca``, ``md02``, ``paper`` (rows 1–6 of
both), ``ridge`` (the ridge rows of both). ``--movement`` replaces the YMCA.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from skinny_mj.experiments.claims import claim_lines
from skinny_mj.experiments.paper_e import study as paper_e

from skinny_mj import training
from skinny_mj.engine.results import STANDARD_METRICS, test_figures
from skinny_mj.engine.study import Quick, Row, Study
from skinny_mj.plots import boxplot_png
from skinny_mj.recording import record_test
from skinny_mj.trajectories import sample_clip

NAME = "ridge-vs-new"
#: md_02's excerpt: seconds 3 to 9.26 (313 steps at 50 Hz, as one YMCA).
MD02_EXCERPT = "@start=3,duration=6.26"
TABLE_COLUMNS = {"position_nrmse": "test position NRMSE", "motor_nrmse": "test motor NRMSE",
                 "train_wall_s": "train wall (s)", "log10_lambda": "log10 λ (last epoch)"}
#: Ridge rows: id suffix -> the paper E row whose schedule they take.
RIDGE_ROWS = {"ridge1": "1", "ridge5": "2", "ridge10": "3", "ridge-new": "5"}
RIDGE = {"esn.readout": "ridge", "method.fit": "ridge-select"}


def md02_movement() -> str:
    """The md_02 excerpt as a movement string (the shipped clip's installed path)."""
    return f"{sample_clip('md_02')}{MD02_EXCERPT}"


def _ridge_lambda(result) -> list | None:
    """The ridge λ the readout fit chose, per epoch (None: no ridge selection)."""
    return result.train.extra.get("ridge_lambda")


def _log10_lambda(result) -> float | None:
    lam = _ridge_lambda(result)
    return None if not lam or lam[-1] is None else float(np.log10(lam[-1]))


def _rows() -> tuple[Row, ...]:
    """Per movement paper E's Table rows, then the ridge rows; ``--movement`` replaces the
    YMCA (the md02 rows set their own movement)."""
    out = []
    for mv in ("ymca", "md02"):
        moved = {} if mv == "ymca" else {"movement.trajectory": md02_movement(),
                                         "movement.asf": None}
        for row_id in paper_e.TABLE_1:
            paper = {k: paper_e.STUDY.row(row_id).paper[k]
                     for k in ("position_nrmse", "motor_nrmse")} if mv == "ymca" else {}
            out.append(Row(f"{mv}-{row_id}", {**paper_e.STUDY.row(row_id).overrides, **moved},
                           paper, group=mv))
        for suffix, paper_row in RIDGE_ROWS.items():
            out.append(Row(f"{mv}-{suffix}", {**paper_e.STUDY.row(paper_row).overrides,
                                              **moved, **RIDGE}, group=mv))
    return tuple(out)


ROWS = _rows()


def claims(mv: str) -> list:
    """Ridge vs new, per movement: the mean and the worst run."""
    return [
        (f"{mv}: ridge (original, 1 rep) is on average as good as the new method β = 0.1",
         "mean", f"{mv}-ridge1", "position_nrmse", "<=", "mean", f"{mv}-5"),
        (f"{mv}: the best ridge row (10 reps) is on average as good as the new method",
         "mean", f"{mv}-ridge10", "position_nrmse", "<=", "mean", f"{mv}-5"),
        (f"{mv}: ridge improves the original method (1 rep)",
         "mean", f"{mv}-ridge1", "position_nrmse", "<", "mean", f"{mv}-1"),
        (f"{mv}: ridge adds to the new method",
         "mean", f"{mv}-ridge-new", "position_nrmse", "<", "mean", f"{mv}-5"),
        (f"{mv}: ridge 1 rep trains faster than the new method",
         "mean", f"{mv}-ridge1", "train_wall_s", "<", "mean", f"{mv}-5"),
    ]


def report(results, plan, out_dir: Path) -> str:
    """Box plots of test position NRMSE per movement, claims, one recording per
    movement of the median ridge1 and row-5 runs."""
    lines = []
    for mv in ("ymca", "md02"):
        rows = [r for r in plan.rows if r.group == mv]
        data = {r.id.removeprefix(f"{mv}-"): results.values(r.id, "position_nrmse")
                for r in rows}
        if not any(data.values()):
            continue
        ref = {r.id.removeprefix(f"{mv}-"): r.paper["position_nrmse"] for r in rows
               if r.paper}
        png = boxplot_png(out_dir / f"position_{mv}.png", data, "test position NRMSE",
                          ref or None, title=f"ridge vs new β, {mv} (paper E rows 1–6)")
        lines += [f"figure: {png.name}", claim_lines(out_dir, claims(mv)), ""]
        lines += _recordings(out_dir, results, plan, mv)
    return "\n".join(lines)


def _recordings(out_dir: Path, results, plan, mv: str) -> list[str]:
    """The median run of ``<mv>-ridge1`` and ``<mv>-5`` re-trained and recorded."""
    lines = []
    for row_id in (f"{mv}-ridge1", f"{mv}-5"):
        ok = sorted(results.runs(row_id), key=lambda r: r["metrics"]["position_nrmse"])
        if not ok:
            continue
        run = ok[(len(ok) - 1) // 2]
        path = out_dir / f"{row_id}_median_seed{run['seed']}.rrd"
        if not path.is_file():
            outcome = training.train(plan.config(row_id), int(run["seed"]))
            record_test(path, outcome, f"{NAME} {row_id}, median run", {"row": row_id},
                        figures=test_figures(outcome))
        lines.append(f"recording: {path.name} (test position NRMSE "
                     f"{run['metrics']['position_nrmse']:.4f})")
    return lines


STUDY = Study(
    name=NAME, description=__doc__, rows=ROWS, runs=20,
    groups={"paper": tuple(f"{mv}-{i}" for mv in ("ymca", "md02") for i in paper_e.TABLE_1),
            "ridge": tuple(f"{mv}-{s}" for mv in ("ymca", "md02") for s in RIDGE_ROWS)},
    metrics={**STANDARD_METRICS, "log10_lambda": _log10_lambda,
             "ridge_lambda": _ridge_lambda},
    columns=TABLE_COLUMNS, quick=Quick({"method.epochs": 2}, runs=2), report=report,
)
