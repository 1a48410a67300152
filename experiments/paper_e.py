"""Paper E — "a novel training method" (the β-blended target), 2D, Cartesian signals.

Rows of one sweep, grouped by id (``--rows table,fig3,fig4,fig5``; or single ids):

- ``table`` (ids ``1``–``6``): Table 1/2 and Figure 6, experiments 1–6 (original
  method with 1, 5, 10 repetitions of YMCA; new method with β = 0.3, 0.1, 0.05 and
  the learning cycles per epoch the paper derived from its Figure 3), 20 runs each,
  tested on one repetition with the feedback controller off.
- ``fig3`` (``fig3-b0.3`` ...): cycles to convergence of y_used toward the true target
  for β = 0.3, 0.1, 0.05, 1 with perfect targets and teacher forcing, 400 cycles.
- ``fig4`` (``fig4-n200`` ...): reservoir size sweep, original method, 5 repetitions,
  reservoir noise 0.02, 10 runs per size.
- ``fig5`` (``fig5a-nu0.03``, ``fig5b-nu0.2`` ...): reservoir noise sweep, (a) original
  method with 5 repetitions, (b) new method β = 0.1 with 1 repetition, N = 200,
  10 runs per level.

The thesis's defaults (N = 200, spectral radius 0.5, reservoir noise 0.03 original /
0.2 new, sensor noise 0.01, 10 epochs, K 1 → 0). ``--movement`` trains and tests every
row on another movement, e.g. an excerpt of motion capture:
``--movement md_02.amc@start=3,duration=6.26`` (recorded in
config.json and the table heading); ``--dof 8`` runs it on the 3D body.

The paper's numbers are shown beside ours, labelled; never in place of ours.
"""

from __future__ import annotations

import functools
import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from skinny_mj.config import TrainConfig, relative_cost
from skinny_mj.experiment import Experiment, Row, RunFailed
from skinny_mj.sweep import one_of_batch
from skinny_mj.sweep.options import config_from_dict, movement_changes

NAME = "paper-e"

#: Paper E, Table 2: mean and variance of test position / motor NRMSE, 20 runs each.
PAPER_TABLE_2 = {
    "1": (0.4000, 0.0024, 0.4737, 1.4e-4),
    "2": (0.1088, 0.0125, 0.2435, 0.0071),
    "3": (0.1193, 0.0081, 0.2500, 0.0066),
    "4": (0.0494, 0.0018, 0.1100, 6.9e-4),
    "5": (0.0245, 7.0e-5, 0.0717, 1.4e-4),
    "6": (0.0385, 0.0020, 0.0669, 9.2e-4),
}
#: Paper E, Table 1: method, β, learning cycles per epoch, repetitions.
TABLE_1 = {
    "1": ("original", 1.0, 1, 1),
    "2": ("original", 1.0, 1, 5),
    "3": ("original", 1.0, 1, 10),
    "4": ("new", 0.3, 2, 1),
    "5": ("new", 0.1, 3, 1),
    "6": ("new", 0.05, 6, 1),
}
#: Cycles the paper read off its Figure 3 for each β: Table 1's cycles/epoch x 10 epochs
#: (β = 1: "only one cycle of training is needed", Fig. 3 caption).
PAPER_FIG3_CYCLES = {0.3: 20, 0.1: 30, 0.05: 60, 1.0: 1}
#: Columns of table.md: metric -> header.
TABLE_COLUMNS = {"position_nrmse": "test position NRMSE", "motor_nrmse": "test motor NRMSE",
                 "train_wall_s": "train wall (s)", "cycles_to_converge": "Fig. 3 cycles"}


@dataclass(frozen=True)
class Config:
    """Shared parameters (paper E §4.1, Figs. 3–5); rows vary the rest."""

    dof: int = 4
    signals: str = "cartesian"
    trajectory: str = "ymca"
    asf: str | None = None
    reservoir: int = 200
    spectral_radius: float = 0.5
    noise_original: float = 0.03
    noise_new: float = 0.2
    sensor_noise: float = 0.01
    epochs: int = 10
    runs: int = 20  # Table 2 / Fig. 6
    figure_runs: int = 10  # Figs. 4, 5 ("10 repetitions of each experiment"); Fig. 3 too
    fig3_betas: tuple[float, ...] = (0.3, 0.1, 0.05, 1.0)
    fig3_cycles: int = 400
    #: Fig. 3 "converged": the excess over the final value is below this share of the
    #: initial excess (so the count does not depend on the ESN's fit floor).
    fig3_tolerance: float = 0.05
    fig4_sizes: tuple[int, ...] = (50, 100, 200, 400, 600, 800, 1000)
    fig4_noise: float = 0.02
    fig4_reps: int = 5
    fig5_noise: tuple[float, ...] = (0.0, 0.01, 0.02, 0.03, 0.05, 0.1, 0.2, 0.3, 0.5)
    fig5a_reps: int = 5
    fig5b_beta: float = 0.1

    @classmethod
    def quick(cls, **changes) -> Config:
        """2 runs of 2 epochs, tiny sweeps (1 repetition in Figs. 4/5a): a smoke test,
        not a reproduction."""
        return cls(**{"epochs": 2, "runs": 2, "figure_runs": 2, "fig3_cycles": 20,
                      "fig4_sizes": (50, 100), "fig4_reps": 1, "fig5_noise": (0.03, 0.2),
                      "fig5a_reps": 1, **changes})

    @classmethod
    def from_dict(cls, d: dict) -> Config:
        """From ``config.json`` (lists back to tuples)."""
        return config_from_dict(cls, d)


def train_config(cfg: Config, row: Row) -> TrainConfig:
    """The training of a FEL row (Table rows, Figs. 4 and 5); a Fig. 3 row: its network
    (:func:`convergence_config`)."""
    p = row.params
    if p.get("kind") == "convergence":
        return convergence_config(cfg, row)
    default_noise = cfg.noise_new if p["method"] == "new" else cfg.noise_original
    rule = {"rule": p["method"], "rule.cycles": p["cycles"], "rule.epochs": cfg.epochs}
    if p["method"] == "new":
        rule["rule.beta"] = p["beta"]
    return TrainConfig().override({
        "plant.dof": cfg.dof, "plant.signals": cfg.signals,
        "plant.sensor_noise": cfg.sensor_noise, "movement.trajectory": cfg.trajectory,
        "movement.asf": cfg.asf, "movement.reps": p["reps"], **rule,
        "esn.n_reservoir": p.get("reservoir", cfg.reservoir),
        "esn.spectral_radius": cfg.spectral_radius,
        "esn.noise_level": p.get("noise", default_noise),
    })


def convergence_config(cfg: Config, row: Row) -> TrainConfig:
    """Fig. 3's network: the Table's, without reservoir noise."""
    return TrainConfig().override({
        "plant.dof": cfg.dof, "plant.signals": cfg.signals,
        "movement.trajectory": cfg.trajectory, "movement.asf": cfg.asf,
        "rule": "new", "rule.beta": float(row.params["beta"]),
        "esn.n_reservoir": cfg.reservoir, "esn.spectral_radius": cfg.spectral_radius,
        "esn.noise_level": 0.0})


def run_convergence(cfg: Config, row: Row, seeds: list[int]) -> list[dict]:
    """Fig. 3: NRMSE(y_used^i, y_true) over ``fig3_cycles`` cycles with perfect targets
    and teacher forcing (true commands at full scale 2 x the fastest speed), for
    several seeds in lockstep."""
    from controllers.true_target import convergence_curve
    from skinny_mj.training import build_run

    run = build_run(convergence_config(cfg, row), seeds)
    curves = convergence_curve(run.esn, run.desired, run.true_commands,
                               float(row.params["beta"]), int(row.params["cycles"]))
    return [{"cycles_to_converge": cycles_to_converge(curve, cfg.fig3_tolerance),
             "initial_nrmse": float(curve[0]), "final_nrmse": float(curve[-1]),
             "convergence_curve": curve} for curve in curves]


def cycles_to_converge(curve: np.ndarray, tolerance: float) -> int:
    """Training cycles needed: 1 + the first cycle i whose target y_used^i is within
    ``tolerance`` x (initial − final) of the final value (β = 1: 1 cycle)."""
    curve = np.asarray(curve, dtype=float)
    excess = curve - curve[-1]
    return int(np.argmax(excess <= tolerance * max(excess[0], 0.0))) + 1


def run_one(cfg: Config, row: Row, seed: int) -> dict:
    """One run of any row: :func:`run_batch` of one seed."""
    return dict(one_of_batch(functools.partial(run_batch, cfg), row, seed))


def group_of(row_id: str) -> str:
    """``table`` for Table rows, else the id's prefix (``fig3``, ``fig4``, ``fig5a`` ...)."""
    return "table" if row_id in TABLE_1 else row_id.split("-")[0]


def all_rows(cfg: Config) -> tuple[Row, ...]:
    out = []
    for row_id, (method, beta, cycles, reps) in TABLE_1.items():
        pos, pos_var, mot, mot_var = PAPER_TABLE_2[row_id]
        out.append(Row(
            row_id, {"method": method, "beta": beta, "cycles": cycles, "reps": reps},
            {"position_nrmse": pos, "position_nrmse_var": pos_var,
             "motor_nrmse": mot, "motor_nrmse_var": mot_var},
        ))
    for beta in cfg.fig3_betas:
        paper = {"cycles_to_converge": PAPER_FIG3_CYCLES[beta]} \
            if beta in PAPER_FIG3_CYCLES else {}
        out.append(Row(f"fig3-b{beta:g}", {"kind": "convergence", "beta": beta,
                                           "cycles": cfg.fig3_cycles}, paper,
                       runs=cfg.figure_runs))
    for n in cfg.fig4_sizes:
        out.append(Row(f"fig4-n{n}", {"method": "original", "beta": 1.0, "cycles": 1,
                                      "reps": cfg.fig4_reps, "reservoir": n,
                                      "noise": cfg.fig4_noise}, runs=cfg.figure_runs))
    for nu in cfg.fig5_noise:
        out.append(Row(f"fig5a-nu{nu:g}", {"method": "original", "beta": 1.0, "cycles": 1,
                                           "reps": cfg.fig5a_reps, "noise": nu},
                       runs=cfg.figure_runs))
    for nu in cfg.fig5_noise:
        out.append(Row(f"fig5b-nu{nu:g}", {"method": "new", "beta": cfg.fig5b_beta,
                                           "cycles": None, "reps": 1, "noise": nu},
                       runs=cfg.figure_runs))
    return tuple(out)


def rows(cfg: Config | None = None) -> tuple[Row, ...]:
    """Every row of the sweep (the engine selects with ``--rows``, see :func:`groups`)."""
    return all_rows(Config() if cfg is None else cfg)


def groups(every: tuple[Row, ...]) -> dict[str, tuple[str, ...]]:
    """Row groups for ``--rows``: ``table``, ``fig3``, ``fig4``, ``fig5a``, ``fig5b`` and
    ``fig5`` (= fig5a + fig5b)."""
    out: dict[str, tuple[str, ...]] = {}
    for row in every:
        out[group_of(row.row_id)] = (*out.get(group_of(row.row_id), ()), row.row_id)
    out["fig5"] = out.get("fig5a", ()) + out.get("fig5b", ())
    return out


def build(quick: bool = False, movement: str | None = None, asf: str | None = None,
          dof: int | None = None, signals: str | None = None) -> Experiment:
    """The sweep; ``quick``: see :meth:`Config.quick`. ``movement`` (+ ``asf``), ``dof``,
    ``signals``: train and test every row on another movement or body (None: the
    paper's)."""
    changes = movement_changes(movement, asf, dof, signals)
    cfg = Config.quick(**changes) if quick else Config(**changes)
    every = rows(cfg)
    return Experiment(
        name=NAME, rows=every, groups=groups(every), run_one=functools.partial(run_one, cfg),
        config=cfg, runs=cfg.runs, table_columns=tuple(TABLE_COLUMNS),
        run_batch=functools.partial(run_batch, cfg), cost=functools.partial(cost, cfg),
    )


def cost(cfg: Config, row: Row) -> float:
    """One run's relative cost (the engine starts the costliest batches first): Fig. 3's
    teacher-forced cycles run the ESN alone, about a third of a closed-loop cycle."""
    if row.params.get("kind") == "convergence":
        return float(row.params["cycles"]) / 3
    return relative_cost(train_config(cfg, row))


def report(results: dict, out_dir: Path) -> str:
    """Figures 3–6, one ``.rrd`` of the median run per Table row, the movement line in
    table.md, the Fig. 3 cycle counts and the paper's claims, checked."""
    from experiments import paper_e_figures as figs

    out_dir = Path(out_dir)
    cfg = Config.from_dict(json.loads((out_dir / "config.json").read_text())["config"])
    figs.write_table(results, out_dir, cfg)
    figs.fig3(out_dir, cfg)
    figs.fig4(out_dir, cfg)
    figs.fig5(out_dir, cfg)
    figs.fig6(out_dir)
    rrd_lines = figs.median_recordings(out_dir, cfg, [r for r in rows(cfg) if r.row_id in
                                                      TABLE_1])
    return "\n".join([figs.claims(out_dir), "", figs.fig3_summary(out_dir, cfg),
                      "", *rrd_lines])


def run_batch(cfg: Config, row: Row, seeds: list[int]) -> list:
    """Several seeds of one row in lockstep (the engine's fast path): seed by seed the
    numbers each gets alone, or the :class:`RunFailed` of a diverged run."""
    from skinny_mj.training import train_batch

    if row.params.get("kind") == "convergence":
        return run_convergence(cfg, row, seeds)
    return [RunFailed(m.get("fail_reason") or "diverged") if m["failed"] else {
        "position_nrmse": m["test"]["position_nrmse"],
        "motor_nrmse": m["test"]["motor_nrmse"],
        "train_wall_s": m["wall_s"],
        "train_curve_position_nrmse": m["train"]["position_nrmse"],
    } for m in (o.metrics for o in train_batch(train_config(cfg, row), seeds))]
