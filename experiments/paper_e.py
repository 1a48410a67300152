"""Paper E — "a novel training method" (the β-blended target), 2D, Cartesian signals.

Table 2 / Figure 6: experiments 1–6 (original method with 1, 5, 10 repetitions of
YMCA; new method with β = 0.3, 0.1, 0.05 and the learning cycles per epoch the
paper derived from its Figure 3), 20 runs each, tested on one YMCA with the
feedback controller off. Defaults per SPEC §4/§5 (N = 200, spectral radius 0.5,
reservoir noise 0.03 original / 0.2 new, sensor noise 0.01, 10 epochs, K 1 → 0).

The paper's numbers (Table 2) are shown beside ours, labelled; they are never used
in place of ours.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from pathlib import Path

from skinny_mj.experiment import Experiment, Row
from skinny_mj.training import TrainConfig, train

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


@dataclass(frozen=True)
class Config:
    """Shared parameters (paper E §4.1); rows vary method, β, cycles and repetitions."""

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
    runs: int = 20


class RunFailed(RuntimeError):
    """The run's ESN diverged; the engine records it as failed with this reason."""


def train_config(cfg: Config, row: Row) -> TrainConfig:
    p = row.params
    return TrainConfig(
        dof=cfg.dof, signals=cfg.signals, trajectory=cfg.trajectory, asf=cfg.asf,
        reps=p["reps"], method=p["method"], beta=p["beta"], cycles=p["cycles"],
        epochs=cfg.epochs, reservoir=cfg.reservoir, spectral_radius=cfg.spectral_radius,
        noise=cfg.noise_new if p["method"] == "new" else cfg.noise_original,
        sensor_noise=cfg.sensor_noise,
    )


def run_one(cfg: Config, row: Row, seed: int) -> dict:
    """One training + test run of a Table 1 row; returns the test metrics."""
    outcome = train(train_config(cfg, row), seed)
    m = outcome.metrics
    if m["failed"]:
        raise RunFailed(m.get("fail_reason") or "diverged")
    return {
        "position_nrmse": m["test"]["position_nrmse"],
        "motor_nrmse": m["test"]["motor_nrmse"],
        "train_wall_s": m["wall_s"],
        "train_curve_position_nrmse": m["train"]["position_nrmse"],
    }


def rows(only: tuple[str, ...] | None = None) -> tuple[Row, ...]:
    out = []
    for row_id, (method, beta, cycles, reps) in TABLE_1.items():
        if only and row_id not in only:
            continue
        pos, pos_var, mot, mot_var = PAPER_TABLE_2[row_id]
        out.append(Row(
            row_id, {"method": method, "beta": beta, "cycles": cycles, "reps": reps},
            {"position_nrmse": pos, "position_nrmse_var": pos_var,
             "motor_nrmse": mot, "motor_nrmse_var": mot_var},
        ))
    return tuple(out)


def build(quick: bool = False, movement: str | None = None, asf: str | None = None,
          only: tuple[str, ...] | None = None) -> Experiment:
    """The sweep; ``quick`` = 2 runs of 2 epochs (a smoke test, not a reproduction)."""
    cfg = Config(epochs=2, runs=2) if quick else Config()
    if movement is not None:
        cfg = Config(**{**cfg.__dict__, "trajectory": movement, "asf": asf})
    return Experiment(
        name=NAME, rows=rows(only), run_one=functools.partial(run_one, cfg), config=cfg,
        runs=cfg.runs, table_columns=("position_nrmse", "motor_nrmse", "train_wall_s"),
    )


def report(results: dict, out_dir: Path) -> str:
    """Figure 6 (box plots beside the paper's means) and the paper's claims, checked."""
    from experiments.claims import claim_lines, values
    from skinny_mj.plots import boxplot_png

    for metric in ("position_nrmse", "motor_nrmse"):
        groups = {f"exp {r}": values(out_dir, r, metric) for r in TABLE_1}
        ref = {f"exp {r}": PAPER_TABLE_2[r][0 if metric == "position_nrmse" else 2]
               for r in TABLE_1}
        groups = {k: v for k, v in groups.items() if v}
        if groups:
            boxplot_png(out_dir / f"fig6_{metric}.png", groups, f"test {metric}",
                        reference={k: ref[k] for k in groups}, title="Paper E, Figure 6")
    return claim_lines(out_dir, [
        # The paper's claim is read off its Figure 6(b), the motor error.
        ("paper: worst run of exp 5 beats the best run of exp 2 (motor, Fig. 6b)",
         "max", "5", "motor_nrmse", "<", "min", "2"),
        ("extra: worst run of exp 5 beats the best run of exp 2 (position)",
         "max", "5", "position_nrmse", "<", "min", "2"),
        ("median: exp 5 < exp 2 (position)", "median", "5", "position_nrmse", "<", "median", "2"),
        ("median: exp 2 < exp 1 (position)", "median", "2", "position_nrmse", "<", "median", "1"),
        ("median: exp 5 < exp 2 (motor)", "median", "5", "motor_nrmse", "<", "median", "2"),
        ("median: exp 2 < exp 1 (motor)", "median", "2", "motor_nrmse", "<", "median", "1"),
        ("exp 5 trains in less wall time than exp 2 (mean)",
         "mean", "5", "train_wall_s", "<", "mean", "2"),
    ])
