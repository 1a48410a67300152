"""Figure-eight generation with output feedback (Jaeger): does paper E's new β method
beat the ordinary teacher-forced fit, FORCE and reservoirpy?

One ESN (N = 200, spectral radius 0.8, input scaling 0.5 on the bias, output feedback
scaling 1, identity readout, uniform state noise 1e-3, pinv) learns the 1:2 Lissajous
figure eight (period 100 steps, amplitude 0.5,
:func:`skinny_mj.controllers.generation.figure_eight`)
from 12 periods (2 of washout), then runs free for 20 periods. Rows and metrics:
:mod:`skinny_mj.experiments.generation_runs`; FORCE: P_0 = I / 1e-4, no forgetting; reservoirpy:
``ESN(units=200, sr=0.8, input_scaling=0.5, ridge=1e-6, feedback=True)`` with a
constant input 1 (its bias), the same teacher. The hyper-parameters were set on pilot
seeds 1001–1003 (outside the sweep's) so that the ordinary fit and FORCE work at all;
every row uses the same ones. 20 seeds per row.

Rows ``ordinary-short`` and ``new-conv-short`` train on :attr:`Config.short_train_periods`
periods (2 of them washout) instead of 12: the thesis's preliminary finding that the new
method "needs shorter training sequences" (paper E's discussion) compares them.
"""

from __future__ import annotations

import functools
import time
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from skinny_mj.controllers.esn import ESNConfig
from skinny_mj.controllers.generation import figure_eight
from skinny_mj.experiments import generation_runs as common

from skinny_mj.engine.experiment import Experiment, Row

NAME = "figure-eight"
#: Methods also trained on the short sequence.
SHORT_METHODS = ("ordinary", "new-conv")


@dataclass(frozen=True)
class Config:
    period: int = 100
    train_periods: int = 12
    washout_periods: int = 2
    free_periods: int = 20
    short_train_periods: int = 4
    reservoir: int = 200
    noise: float = 1e-3
    force_lambda: float = 1e-4
    rpy_ridge: float = 1e-6
    runs: int = 20

    @property
    def n_fit(self) -> int:
        return self.period * self.train_periods

    @property
    def length(self) -> int:
        return self.period * (self.train_periods + self.free_periods)


def esn_config(cfg: Config) -> ESNConfig:
    return ESNConfig(n_inputs=1, n_outputs=2, n_reservoir=cfg.reservoir, spectral_radius=0.8,
                     input_scaling=0.5, output_feedback=True, feedback_scaling=1.0,
                     readout_activation="identity", noise_level=cfg.noise)


def run_batch(cfg: Config, row: Row, seeds: list[int]) -> list:
    n_fit = cfg.period * row.params.get("train_periods", cfg.train_periods)
    series = figure_eight(n_fit + cfg.period * cfg.free_periods, cfg.period)  # every seed's
    scale = float(series.std())
    washout = cfg.period * cfg.washout_periods
    method = row.params["method"]
    if method == "reservoirpy":
        return [_reservoirpy(cfg, series, washout, scale, s) for s in seeds]
    free, target, wall, passes = common.run_ours(method, esn_config(cfg), seeds,
                                                 lambda _: series, n_fit, washout,
                                                 cfg.force_lambda)
    return [{**m, "fit_wall_s": wall, "passes": int(p)}
            for m, p in zip(common.metrics(free, target, cfg.period, scale), passes,
                            strict=True)]


def _reservoirpy(cfg: Config, series: np.ndarray, washout: int, scale: float,
                 seed: int) -> dict:
    from reservoirpy import ESN

    seed32 = int(np.random.SeedSequence(seed).generate_state(1)[0])
    start = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = ESN(units=cfg.reservoir, sr=0.8, lr=1.0, input_scaling=0.5,
                    ridge=cfg.rpy_ridge, feedback=True, seed=seed32)
        model.fit(np.ones((cfg.n_fit, 1)), series[:cfg.n_fit], warmup=washout)
        wall = time.perf_counter() - start
        free = model.run(np.ones((cfg.length - cfg.n_fit, 1)))
    (m,) = common.metrics(free[None], series[None, cfg.n_fit:], cfg.period, scale)
    return {**m, "fit_wall_s": wall}


def estimate_bytes(cfg: Config, row: Row, runs: int):
    """The memory a batch of ``runs`` seeds of ``row`` needs (the sweep's check)."""
    n_fit = cfg.period * row.params.get("train_periods", cfg.train_periods)
    return common.estimate(row.params["method"], esn_config(cfg), n_fit,
                           cfg.period * cfg.free_periods, runs)


def run_one(cfg: Config, row: Row, seed: int) -> dict:
    return run_batch(cfg, row, [seed])[0]


def build(quick: bool = False, movement: str | None = None, asf: str | None = None,
          dof: int | None = None, signals: str | None = None) -> Experiment:
    """The sweep (no plant: ``movement``, ``asf``, ``dof``, ``signals`` do not apply and
    are ignored); ``quick``: 2 seeds, 4 training periods."""
    cfg = Config(runs=2, train_periods=4, free_periods=4, short_train_periods=3) if quick \
        else Config()
    every = common.rows(common.METHODS, cfg.runs) + tuple(
        Row(f"{m}-short", {"method": m, "train_periods": cfg.short_train_periods},
            runs=cfg.runs) for m in SHORT_METHODS)
    return Experiment(name=NAME, rows=every, run_one=functools.partial(run_one, cfg),
                      config=cfg, runs=cfg.runs, table_columns=common.COLUMNS,
                      run_batch=functools.partial(run_batch, cfg),
                      unavailable=common.unavailable_rows())


def report(results: dict, out_dir: Path) -> str:
    from skinny_mj.experiments.claims import claim_lines

    short = claim_lines(Path(out_dir), [
        ("figure-eight, short training sequence: the new β method run to convergence runs "
         "free longer than the ordinary fit (the thesis: it 'needs shorter training "
         "sequences')", "mean", "new-conv-short", "horizon", ">", "mean", "ordinary-short")])
    return common.report(results, out_dir, NAME, [short])
