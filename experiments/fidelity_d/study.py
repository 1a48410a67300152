"""Paper D's fidelity: which true-target cell trains in the thesis's range, and tests how?

Paper D's true-target (TT) half (``skinny_mj.experiments.paper_d.STUDY``'s rows and ``trainings``,
imported) × Gaussian input noise on the teacher-forced inputs (``method.input_noise``, SD in
normalized units, its own seed stream) {0, 0.01, 0.03, 0.05} × reservoir size N {100, 200,
400} × movement {recorded-like YMCA (``ymca-recorded``: never still, marker noise),
``ymca-smooth`` (today's ``ymca``)}. Row ids ``<movement>-n<N>-i<noise>-e<exp>``.

- stage 1 (group ``stage1``): exps 1 and 2 (original method; reservoir noise off / 0.2, the
  only thing they differ in) at every cell;
- stage 2 (group ``stage2``): all TT exps 1, 2, 3a, 3b, 4 at the cells of
  :data:`STAGE_2_CELLS`, picked from stage 1 by the training error alone
  (:func:`in_thesis_range`), to check the thesis's test ordering 1 > 2 > 3a ≈ 3b ≈ 4.

A group per cell (``<movement>-n<N>-i<noise>``) runs its five exps. Seeds follow the
engine's ``run_seed`` (row id, run index), so stage 2 reuses stage 1's exp 1, 2 runs
with ``--resume`` into the same folder.

The thesis (paper D Table 1, TT): position train NRMSE 0.0033-0.0092, position test
0.300 (exp 1), 0.186 (2), 0.106 (3a), 0.099 (3b), 0.097 (4).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from skinny_mj.experiments import paper_d

from skinny_mj.engine.study import Quick, Row, Study

NAME = "fidelity-d"
MOVEMENTS = {"recorded": "ymca-recorded", "smooth": "ymca-smooth"}
EXPS = tuple(paper_d.EXPERIMENTS)  # "1", "2", "3a", "3b", "4"
STAGE_1_EXPS = ("1", "2")
#: The thesis's TT position training error range (0.0033 exp 1 ... 0.0092 exp 2), as the
#: issue rounds it: a cell is "in range" when exp 1's AND exp 2's means lie in it.
THESIS_TRAIN_RANGE = (0.003, 0.009)
#: Stage 2's cells: those whose stage-1 exp 1 and exp 2 mean TT position train NRMSE
#: both lie in THESIS_TRAIN_RANGE (measured, docs/results/fidelity.md; the report
#: recomputes the criterion and says if this list disagrees with the run folder).
STAGE_2_CELLS: tuple[str, ...] = (
    "recorded-n100-i0.01", "recorded-n100-i0.03", "recorded-n100-i0.05",
    "recorded-n200-i0.01", "recorded-n200-i0.03", "recorded-n200-i0.05", "recorded-n400-i0.01",
    "smooth-n100-i0.05", "smooth-n200-i0.05", "smooth-n400-i0.05")
#: The four TT columns of paper D Table 1 (our metric names = paper_d's).
COLUMNS = {k: v for k, v in paper_d.COLUMNS.items() if k.startswith("tt_")}


@dataclass(frozen=True)
class Grid:
    """The study's grid: movements (keys of MOVEMENTS), reservoir sizes, input noises."""

    movements: tuple[str, ...] = tuple(MOVEMENTS)
    reservoirs: tuple[int, ...] = (100, 200, 400)
    input_noises: tuple[float, ...] = (0.0, 0.01, 0.03, 0.05)


#: A smoke test, not a study: smooth YMCA (the recorded-like one costs 1 s of IK per
#: batch), N = 20, noise {0, 0.05}, 3 TT rounds; stage 2 = every cell.
QUICK_GRID = Grid(movements=("smooth",), reservoirs=(20,), input_noises=(0.0, 0.05))


def cell_id(movement: str, reservoir: int, input_noise: float) -> str:
    return f"{movement}-n{reservoir}-i{input_noise:g}"


def cells(grid: Grid) -> tuple[str, ...]:
    return tuple(cell_id(m, n, s) for m in grid.movements for n in grid.reservoirs
                 for s in grid.input_noises)


def trainings(config, row: Row) -> dict[str, Any]:
    """Paper D's TT training of the row's exp (``config``: its FEL config on the row's
    movement and N) with the row's input noise."""
    tt = paper_d.trainings(config, row)["tt"]
    return {"tt": tt.override({"method.input_noise": row.params["input_noise"]})}


def metrics(results) -> dict[str, Any]:
    """The TT training's train (teacher forced, noise off) and closed-loop test (K = 0)
    errors, and its test's figures in a roboticist's units; a run whose closed-loop test
    diverged is a failed run."""
    tt = results["tt"]
    return {"tt_position_train": tt.train.position_nrmse,
            "tt_motor_train": tt.train.motor_nrmse,
            "tt_position_test": tt.test.position_nrmse, "tt_motor_test": tt.test.motor_nrmse,
            **tt.robot_figures()}


def _rows(grid: Grid, tt_cycles: int, quick_only: bool = False) -> list[Row]:
    out = []
    for m in grid.movements:
        for n in grid.reservoirs:
            for s in grid.input_noises:
                for e in EXPS:
                    d = paper_d.STUDY.row(e)
                    out.append(Row(
                        f"{cell_id(m, n, s)}-e{e}",
                        {**d.overrides, "movement.trajectory": MOVEMENTS[m],
                         "esn.n_reservoir": n},
                        {k: v for k, v in d.paper.items() if k.removesuffix("_var") in COLUMNS},
                        group=cell_id(m, n, s), quick_only=quick_only,
                        params={"movement": m, "reservoir": n, "input_noise": s, "exp": e,
                                "tt_cycles": tt_cycles}))
    return out


def grid_of(plan) -> Grid:
    """The grid of a planned sweep's rows (in their order)."""
    p = [r.params for r in plan.rows]
    return Grid(*(tuple(dict.fromkeys(x[k] for x in p))
                  for k in ("movement", "reservoir", "input_noise")))


def in_thesis_range(results: dict, cell: str) -> bool:
    """Stage 2's criterion: exp 1's and exp 2's mean TT position train NRMSE at ``cell``
    both in :data:`THESIS_TRAIN_RANGE` (test errors play no part)."""
    lo, hi = THESIS_TRAIN_RANGE
    means = {r["row"]: (r["metrics"].get("tt_position_train") or {}).get("mean")
             for r in results["rows"]}
    vals = [means.get(f"{cell}-e{e}") for e in STAGE_1_EXPS]
    return all(v is not None and lo <= v <= hi for v in vals)


_ROWS = (*_rows(Grid(), paper_d.TT_CYCLES), *_rows(QUICK_GRID, 3, quick_only=True))
STUDY = Study(
    name=NAME, description=__doc__, runs=10, rows=_ROWS,
    base=paper_d.STUDY.base, trainings=trainings, metrics=metrics, columns=COLUMNS,
    # stage 2's cells are groups, not part of config.json's config: picking them after
    # stage 1 keeps --resume into stage 1's folder possible (quick: every cell)
    groups={"stage1": [r.id for r in _ROWS if r.params["exp"] in STAGE_1_EXPS],
            "stage2": [*STAGE_2_CELLS, *cells(QUICK_GRID)]},
    quick=Quick(runs=2, rows=cells(QUICK_GRID)),
    takes=("body", "signals"),  # the movements are the study's
    report="skinny_mj.experiments.fidelity_d.report:report",
)
