"""Ridge vs new: does a ridge readout (lambda chosen per fit on a validation cycle) with
the original FEL method match paper E's new β method?

Rows, on each of two movements (``ymca-*``: the YMCA of paper E; ``md02-*``: CMU
modern dance md_02, seconds 3 to 9.26, the length of one YMCA):

- ``<mv>-1`` ... ``<mv>-6``: paper E's Table 1 rows (:data:`experiments.paper_e.TABLE_1`,
  built by :func:`experiments.paper_e.train_config`): original method with 1, 5, 10
  repetitions, new method with β = 0.3, 0.1, 0.05;
- ``<mv>-ridge1``, ``-ridge5``, ``-ridge10``: rows 1–3 (original method, reservoir noise
  0.03) with ``esn.readout=ridge`` and ``rule.fit=ridge-select``: each fit's lambda from the
  grid 1e-8 ... 10 (:data:`controllers.ridge_select.RIDGE_GRID`) that best predicts the
  targets of the cycle before it (:class:`controllers.ridge_select.RidgeSelector`);
- ``<mv>-ridge-new``: row 5 (new method, β = 0.1) with the same ridge selection.

20 runs per row, tested with the feedback controller off (K = 0) on one repetition:
test position and motor NRMSE, training wall time per run (lockstep batch / R), and the
lambda chosen in the last epoch. Groups: ``ymca``, ``md02``, ``paper`` (rows 1–6 of
both), ``ridge`` (the ridge rows of both). ``--movement`` replaces the YMCA.
"""

from __future__ import annotations

import functools
import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from experiments import paper_e
from experiments.claims import claim_lines
from skinny_mj.config import TrainConfig, relative_cost
from skinny_mj.experiment import Experiment, Row, RunFailed
from skinny_mj.sweep import one_of_batch

NAME = "ridge-vs-new"
#: md_02's excerpt: seconds 3 to 9.26 (313 steps at 50 Hz, as one YMCA).
MD02_EXCERPT = "@start=3,duration=6.26"
TABLE_COLUMNS = {"position_nrmse": "test position NRMSE", "motor_nrmse": "test motor NRMSE",
                 "train_wall_s": "train wall (s)", "log10_lambda": "log10 λ (last epoch)"}
#: Ridge rows: id suffix -> the paper E row whose schedule they take.
RIDGE_ROWS = {"ridge1": "1", "ridge5": "2", "ridge10": "3", "ridge-new": "5"}


def md02_movement() -> str:
    """The md_02 excerpt as a movement string (the shipped clip's installed path)."""
    from skinny_mj.trajectories import sample_clip

    return f"{sample_clip('md_02')}{MD02_EXCERPT}"


@dataclass(frozen=True)
class Config:
    """Shared settings: paper E's, and the two movements (None: md_02's excerpt)."""

    dof: int = 4
    signals: str = "cartesian"
    ymca: str = "ymca"
    asf: str | None = None
    md02: str | None = None
    epochs: int = 10
    runs: int = 20

    def movement(self, key: str) -> tuple[str, str | None]:
        """(trajectory, asf) of movement ``key`` ("ymca" or "md02")."""
        if key == "ymca":
            return self.ymca, self.asf
        return (self.md02 or md02_movement()), None


def train_config(cfg: Config, row: Row) -> TrainConfig:
    """A row's training: paper E's row on the row's movement, + ridge selection."""
    p = row.params
    trajectory, asf = cfg.movement(p["movement"])
    e_cfg = paper_e.Config(dof=cfg.dof, signals=cfg.signals, trajectory=trajectory, asf=asf,
                           epochs=cfg.epochs)
    method, beta, cycles, reps = paper_e.TABLE_1[p["paper_row"]]
    base = paper_e.train_config(e_cfg, Row(p["paper_row"], {
        "method": method, "beta": beta, "cycles": cycles, "reps": reps}))
    if p["ridge"]:
        base = base.override({"esn.readout": "ridge", "rule.fit": "ridge-select"})
    return base


def all_rows() -> tuple[Row, ...]:
    out = []
    for mv in ("ymca", "md02"):
        for row_id in paper_e.TABLE_1:
            paper = {}
            if mv == "ymca":
                pos, _, mot, _ = paper_e.PAPER_TABLE_2[row_id]
                paper = {"position_nrmse": pos, "motor_nrmse": mot}
            out.append(Row(f"{mv}-{row_id}", {"movement": mv, "paper_row": row_id,
                                              "ridge": False}, paper))
        for suffix, paper_row in RIDGE_ROWS.items():
            out.append(Row(f"{mv}-{suffix}", {"movement": mv, "paper_row": paper_row,
                                              "ridge": True}))
    return tuple(out)


def groups(every: tuple[Row, ...]) -> dict[str, tuple[str, ...]]:
    g: dict[str, tuple[str, ...]] = {}
    for row in every:
        mv = row.params["movement"]
        g[mv] = (*g.get(mv, ()), row.row_id)
        kind = "ridge" if row.params["ridge"] else "paper"
        g[kind] = (*g.get(kind, ()), row.row_id)
    return g


def build(quick: bool = False, movement: str | None = None, asf: str | None = None,
          dof: int | None = None, signals: str | None = None) -> Experiment:
    """The sweep; ``quick``: 2 runs of 2 epochs (a smoke test). ``movement`` (+ ``asf``)
    replaces the YMCA; ``dof`` / ``signals`` change the body for every row."""
    changes: dict = {k: v for k, v in (("dof", dof), ("signals", signals)) if v is not None}
    if movement is not None:
        changes.update(ymca=movement, asf=None if asf is None else str(asf))
    if quick:
        changes.update(epochs=2, runs=2)
    cfg = Config(**changes)
    every = all_rows()
    return Experiment(
        name=NAME, rows=every, groups=groups(every), run_one=functools.partial(run_one, cfg),
        config=cfg, runs=cfg.runs, table_columns=TABLE_COLUMNS,
        run_batch=functools.partial(run_batch, cfg),
        cost=lambda row: relative_cost(train_config(cfg, row)),
    )


def run_batch(cfg: Config, row: Row, seeds: list[int]) -> list:
    """The row's seeds in lockstep (seed by seed what each gets alone)."""
    from skinny_mj.training import train_batch

    out: list = []
    for o in train_batch(train_config(cfg, row), seeds):
        m = o.metrics
        if m["failed"]:
            out.append(RunFailed(m.get("fail_reason") or "diverged"))
            continue
        lam = m["train"].get("ridge_lambda")
        out.append({"position_nrmse": m["test"]["position_nrmse"],
                    "motor_nrmse": m["test"]["motor_nrmse"], "train_wall_s": m["wall_s"],
                    "log10_lambda": None if not lam or lam[-1] is None
                    else float(np.log10(lam[-1])),
                    "ridge_lambda": lam})
    return out


def run_one(cfg: Config, row: Row, seed: int) -> dict:
    return dict(one_of_batch(functools.partial(run_batch, cfg), row, seed))


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


def report(results: dict, out_dir: Path) -> str:
    """Box plots of test position NRMSE per movement, claims, one recording per
    movement of the median ridge1 and row-5 runs."""
    from skinny_mj.plots import boxplot_png
    from skinny_mj.sweep.stats import load_runs

    out_dir = Path(out_dir)
    cfg = Config(**json.loads((out_dir / "config.json").read_text())["config"])
    runs = load_runs(out_dir)
    lines = []
    for mv in ("ymca", "md02"):
        ids = [r.row_id for r in all_rows() if r.params["movement"] == mv]
        data = {i.removeprefix(f"{mv}-"): [r["metrics"]["position_nrmse"] for r in runs
                                           if r["row"] == i and r["status"] == "ok"]
                for i in ids}
        if not any(data.values()):
            continue
        ref = {i.removeprefix(f"{mv}-"): r.paper["position_nrmse"] for r in all_rows()
               for i in [r.row_id] if r.row_id in ids and r.paper}
        png = boxplot_png(out_dir / f"position_{mv}.png", data, "test position NRMSE",
                          ref or None, title=f"ridge vs new β, {mv} (paper E rows 1–6)")
        lines += [f"figure: {png.name}", claim_lines(out_dir, claims(mv)), ""]
        lines += _recordings(out_dir, cfg, runs, mv)
    return "\n".join(lines)


def _recordings(out_dir: Path, cfg: Config, runs: list[dict], mv: str) -> list[str]:
    """The median run of ``<mv>-ridge1`` and ``<mv>-5`` re-trained and recorded."""
    from skinny_mj.recording import record_test
    from skinny_mj.training import train

    lines = []
    rows = {r.row_id: r for r in all_rows()}
    for row_id in (f"{mv}-ridge1", f"{mv}-5"):
        ok = sorted((r for r in runs if r["row"] == row_id and r["status"] == "ok"),
                    key=lambda r: r["metrics"]["position_nrmse"])
        if not ok:
            continue
        run = ok[(len(ok) - 1) // 2]
        path = out_dir / f"{row_id}_median_seed{run['seed']}.rrd"
        if not path.is_file():
            outcome = train(train_config(cfg, rows[row_id]), int(run["seed"]))
            record_test(path, outcome, f"{NAME} {row_id}, median run", {"row": row_id})
        lines.append(f"recording: {path.name} (test position NRMSE "
                     f"{run['metrics']['position_nrmse']:.4f})")
    return lines
