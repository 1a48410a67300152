"""Paper D's fidelity: which true-target cell trains in the thesis's range, and tests how?

Paper D's true-target (TT) half (``experiments.paper_d.EXPERIMENTS`` / ``train_configs``,
imported) × Gaussian input noise on the teacher-forced inputs (``rule.input_noise``, SD in
normalized units, its own seed stream) {0, 0.01, 0.03, 0.05} × reservoir size N {100, 200,
400} × movement {recorded-like YMCA (``ymca-recorded``: never still, marker noise),
``ymca-smooth`` (today's ``ymca``)}. Row ids ``<movement>-n<N>-i<noise>-e<exp>``.

- stage 1 (group ``stage1``): exps 1 and 2 (original method; reservoir noise off / 0.2, the
  only thing they differ in) at every cell;
- stage 2 (group ``stage2``): all TT exps 1, 2, 3a, 3b, 4 at the cells of
  :data:`STAGE_2_CELLS`, picked from stage 1 by the training error alone
  (:func:`in_thesis_range`), to check the thesis's test ordering 1 > 2 > 3a ≈ 3b ≈ 4.

A group per cell (``<movement>-n<N>-i<noise>``) runs its five exps. Seeds follow the
engine's ``run_seed`` (row index, run index), so stage 2 reuses stage 1's exp 1, 2 runs
with ``--resume`` into the same folder.

The thesis (paper D Table 1, TT): position train NRMSE 0.0033-0.0092, position test
0.300 (exp 1), 0.186 (2), 0.106 (3a), 0.099 (3b), 0.097 (4).
"""

from __future__ import annotations

import functools
import json
from dataclasses import dataclass, replace
from pathlib import Path

from experiments import paper_d
from skinny_mj.config import relative_cost
from skinny_mj.experiment import Experiment, Row, RunFailed
from skinny_mj.sweep import one_of_batch
from skinny_mj.sweep.options import config_from_dict

NAME = "fidelity-d"
MOVEMENTS = {"recorded": "ymca-recorded", "smooth": "ymca-smooth"}
EXPS = tuple(paper_d.EXPERIMENTS)  # "1", "2", "3a", "3b", "4"
STAGE_1_EXPS = ("1", "2")
#: The thesis's TT position training error range (0.0033 exp 1 ... 0.0092 exp 2), as the
#: issue rounds it: a cell is "in range" when exp 1's AND exp 2's means lie in it.
THESIS_TRAIN_RANGE = (0.003, 0.009)
#: Stage 2's cells: those whose stage-1 exp 1 and exp 2 mean TT position train NRMSE
#: both lie in THESIS_TRAIN_RANGE (measured, docs/results/fidelity-d.md; the report
#: recomputes the criterion and says if this list disagrees with the run folder).
STAGE_2_CELLS: tuple[str, ...] = (
    "recorded-n100-i0.01", "recorded-n100-i0.03", "recorded-n100-i0.05",
    "recorded-n200-i0.01", "recorded-n200-i0.03", "recorded-n200-i0.05", "recorded-n400-i0.01",
    "smooth-n100-i0.05", "smooth-n200-i0.05", "smooth-n400-i0.05")
#: The four TT columns of paper D Table 1 (our metric names = paper_d's).
COLUMNS = {k: v for k, v in paper_d.COLUMNS.items() if k.startswith("tt_")}


@dataclass(frozen=True)
class Config:
    """The study's grid; everything else is paper D's :class:`paper_d.Config`."""

    movements: tuple[str, ...] = tuple(MOVEMENTS)
    reservoirs: tuple[int, ...] = (100, 200, 400)
    input_noises: tuple[float, ...] = (0.0, 0.01, 0.03, 0.05)
    runs: int = 10
    tt_cycles: int = 50  # exp 4's rounds (paper D)
    dof: int = 8
    signals: str = "cartesian"

    @classmethod
    def from_dict(cls, d: dict) -> Config:
        return config_from_dict(cls, d)


def cell_id(movement: str, reservoir: int, input_noise: float) -> str:
    return f"{movement}-n{reservoir}-i{input_noise:g}"


def cells(cfg: Config) -> tuple[str, ...]:
    return tuple(cell_id(m, n, s) for m in cfg.movements for n in cfg.reservoirs
                 for s in cfg.input_noises)


def train_config(cfg: Config, row: Row):
    """Paper D's TT config of ``row``'s exp, on its movement, N and input noise."""
    p = row.params
    method, noise, reps = paper_d.EXPERIMENTS[p["exp"]]
    base = paper_d.Config(dof=cfg.dof, signals=cfg.signals, trajectory=MOVEMENTS[p["movement"]],
                          reservoir=p["reservoir"], tt_cycles=cfg.tt_cycles)
    tt = paper_d.train_configs(base, Row(p["exp"], {"method": method, "noise": noise,
                                                    "reps": reps}))["tt"]
    return tt.override({"rule.input_noise": p["input_noise"]})


def all_rows(cfg: Config) -> tuple[Row, ...]:
    out = []
    for m in cfg.movements:
        for n in cfg.reservoirs:
            for s in cfg.input_noises:
                for e in EXPS:
                    paper = {}
                    for metric, (mean, var) in zip(paper_d.COLUMNS, paper_d.PAPER_TABLE_1[e],
                                                   strict=True):
                        if metric in COLUMNS:
                            paper[metric], paper[f"{metric}_var"] = mean, var
                    out.append(Row(f"{cell_id(m, n, s)}-e{e}", {
                        "movement": m, "reservoir": n, "input_noise": s, "exp": e}, paper))
    return tuple(out)


def groups(cfg: Config, every: tuple[Row, ...],
           stage_2_cells: tuple[str, ...] = STAGE_2_CELLS) -> dict[str, tuple[str, ...]]:
    """``stage1``, ``stage2`` (when it has cells) and one group per cell. (Stage 2's
    cells are not part of ``config.json``'s config, so picking them after stage 1 keeps
    ``--resume`` into stage 1's folder possible.)"""
    by_cell = {c: tuple(f"{c}-e{e}" for e in EXPS) for c in cells(cfg)}
    out = {"stage1": tuple(r.row_id for r in every if r.params["exp"] in STAGE_1_EXPS)}
    stage_2 = tuple(r for c in stage_2_cells if c in by_cell for r in by_cell[c])
    if stage_2:
        out["stage2"] = stage_2
    return {**out, **by_cell}


def run_batch(cfg: Config, row: Row, seeds: list[int]) -> list:
    """TT train (teacher forced, noise off) and closed-loop test (K = 0) errors per seed;
    a run whose closed-loop test diverged is a :class:`RunFailed`."""
    from skinny_mj.training import train_batch

    out: list = []
    for o in train_batch(train_config(cfg, row), seeds):
        if o.failed:
            out.append(RunFailed(o.metrics.get("fail_reason") or "failed"))
            continue
        out.append({"tt_position_train": o.metrics["train"]["position_nrmse"],
                    "tt_motor_train": o.metrics["train"]["motor_nrmse"],
                    "tt_position_test": o.metrics["test"]["position_nrmse"],
                    "tt_motor_test": o.metrics["test"]["motor_nrmse"]})
    return out


def run_one(cfg: Config, row: Row, seed: int) -> dict:
    return dict(one_of_batch(functools.partial(run_batch, cfg), row, seed))


def quick_config() -> Config:
    """A smoke test, not a study: smooth YMCA (the recorded-like one costs 1 s of IK per
    batch), N = 20, noise {0, 0.05}, 2 runs, 3 TT rounds; stage 2 = every cell."""
    return Config(movements=("smooth",), reservoirs=(20,), input_noises=(0.0, 0.05), runs=2,
                  tt_cycles=3)


def build(quick: bool = False, movement: str | None = None, asf: str | None = None,
          dof: int | None = None, signals: str | None = None) -> Experiment:
    """The grid (``movement``/``asf`` are not used: the movements are the study's)."""
    changes = {k: v for k, v in (("dof", dof), ("signals", signals)) if v is not None}
    cfg = replace(quick_config() if quick else Config(), **changes)
    every = all_rows(cfg)
    stage_2 = cells(cfg) if quick else STAGE_2_CELLS
    return Experiment(name=NAME, rows=every, groups=groups(cfg, every, stage_2),
                      run_one=functools.partial(run_one, cfg), config=cfg, runs=cfg.runs,
                      table_columns=COLUMNS, run_batch=functools.partial(run_batch, cfg),
                      cost=lambda row: relative_cost(train_config(cfg, row)))


def in_thesis_range(results: dict, cell: str) -> bool:
    """Stage 2's criterion: exp 1's and exp 2's mean TT position train NRMSE at ``cell``
    both in :data:`THESIS_TRAIN_RANGE` (test errors play no part)."""
    lo, hi = THESIS_TRAIN_RANGE
    means = {r["row"]: (r["metrics"].get("tt_position_train") or {}).get("mean")
             for r in results["rows"]}
    vals = [means.get(f"{cell}-e{e}") for e in STAGE_1_EXPS]
    return all(v is not None and lo <= v <= hi for v in vals)


def report(results: dict, out_dir: Path) -> str:
    """stage1.md / stage2.md tables and fig_train_error.png / fig_test_error.png."""
    from experiments.fidelity_d_report import write_report

    out_dir = Path(out_dir)
    cfg = Config.from_dict(json.loads((out_dir / "config.json").read_text())["config"])
    return write_report(results, out_dir, cfg)
