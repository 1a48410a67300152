"""Mackey-Glass (τ = 17) 84-step prediction with output feedback: does paper E's new β
method beat the ordinary teacher-forced fit and reservoirpy?

Jaeger & Haas (2004)'s task and network (:func:`skinny_mj.cli.bench_mackey_glass.esn_config`:
leak 0.6, spectral radius 0.95, bias 0.2, feedback scaling 0.56, state noise 1e-8,
pinv), N = 400: teacher-forced through 1000 washout + 2000 training samples of a series
of its own (:func:`skinny_mj.controllers.mackey_glass.mackey_glass`, one per seed), then free for
500 steps. Rows: :mod:`skinny_mj.experiments.generation_runs` (no FORCE row); reservoirpy: its own
way (:func:`skinny_mj.cli.bench_mackey_glass.mackey_glass_reservoirpy`: d(t) -> d(t + 1),
ridge 1e-10, closed loop). Metrics: Jaeger & Haas's NRMSE_84 of each run (|y(84) −
d(84)| / std(d), and log10), the free-run NRMSE over the first 84 steps, the horizon
before the error exceeds 0.1 std, stability, fit wall time. 20 seeds per row.
"""

from __future__ import annotations

import functools
import time
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from skinny_mj.controllers.mackey_glass import mackey_glass
from skinny_mj.experiments import generation_runs as common

from skinny_mj.engine.experiment import Experiment, Row

NAME = "mackey-glass"
HORIZON = 84
METHODS = ("ordinary", "new", "new-blend", "reservoirpy", "new-conv")  # new rows last
COLUMNS = {"log10_nrmse84": "log10 NRMSE_84", **common.COLUMNS}


@dataclass(frozen=True)
class Config:
    reservoir: int = 400
    washout: int = 1000
    train: int = 2000
    free: int = 500
    runs: int = 20

    @property
    def n_fit(self) -> int:
        return self.washout + self.train


def _series(cfg: Config, rng: np.random.Generator) -> np.ndarray:
    return mackey_glass(cfg.n_fit + cfg.free, rng)[:, None]  # (L, 1)


def _with_nrmse84(m: dict, free: np.ndarray, target: np.ndarray, scale: float) -> dict:
    e = abs(float(free[HORIZON - 1, 0] - target[HORIZON - 1, 0])) / scale \
        if np.all(np.isfinite(free)) else None
    return {**m, "nrmse84": e,
            "log10_nrmse84": None if e is None or e <= 0 else float(np.log10(e))}


def run_batch(cfg: Config, row: Row, seeds: list[int]) -> list:
    from skinny_mj.cli.bench_mackey_glass import esn_config

    method = row.params["method"]
    if method == "reservoirpy":
        return [_reservoirpy(cfg, s) for s in seeds]
    free, target, wall, passes = common.run_ours(method, esn_config(cfg.reservoir), seeds,
                                                 lambda rng: _series(cfg, rng), cfg.n_fit,
                                                 cfg.washout)
    out = []
    for r, seed in enumerate(seeds):
        scale = float(_series(cfg, common.streams(seed)[0])[cfg.washout:cfg.n_fit].std())
        (m,) = common.metrics(free[r:r + 1], target[r:r + 1], HORIZON, scale)
        out.append({**_with_nrmse84(m, free[r], target[r], scale), "fit_wall_s": wall,
                    "passes": int(passes[r])})
    return out


def _reservoirpy(cfg: Config, seed: int) -> dict:
    from skinny_mj.cli.bench_mackey_glass import mackey_glass_reservoirpy

    series = _series(cfg, common.streams(seed)[0])
    scale = float(series[cfg.washout:cfg.n_fit].std())
    seed32 = int(np.random.SeedSequence(seed).generate_state(1)[0])
    start = time.perf_counter()
    with warnings.catch_warnings():  # its ridge solve warns on ill-conditioned Grams
        warnings.simplefilter("ignore")
        free = mackey_glass_reservoirpy(series[None, :, 0], cfg.reservoir, cfg.washout,
                                        seed32, horizon=cfg.free)[0][:, None]
    wall = time.perf_counter() - start  # fit + the free run (reservoirpy steps both)
    target = series[cfg.n_fit:]
    (m,) = common.metrics(free[None], target[None], HORIZON, scale)
    return {**_with_nrmse84(m, free, target, scale), "fit_wall_s": wall}


def estimate_bytes(cfg: Config, row: Row, runs: int):
    """The memory a batch of ``runs`` seeds of ``row`` needs (the sweep's check)."""
    from skinny_mj.cli.bench_mackey_glass import esn_config

    return common.estimate(row.params["method"], esn_config(cfg.reservoir), cfg.n_fit,
                           cfg.free, runs)


def run_one(cfg: Config, row: Row, seed: int) -> dict:
    return run_batch(cfg, row, [seed])[0]


def build(quick: bool = False, movement: str | None = None, asf: str | None = None,
          dof: int | None = None, signals: str | None = None) -> Experiment:
    """The sweep (no plant: ``movement``, ``asf``, ``dof``, ``signals`` are ignored);
    ``quick``: 2 seeds, N = 100, 500 training samples."""
    cfg = Config(reservoir=100, washout=200, train=500, free=200, runs=2) if quick \
        else Config()
    every = common.rows(METHODS, cfg.runs)
    return Experiment(name=NAME, rows=every, run_one=functools.partial(run_one, cfg),
                      config=cfg, runs=cfg.runs, table_columns=COLUMNS,
                      run_batch=functools.partial(run_batch, cfg),
                      unavailable=common.unavailable_rows())


def report(results: dict, out_dir: Path) -> str:
    from skinny_mj.engine.stats import load_runs

    lines = []
    for row in METHODS:  # Jaeger & Haas pool the squared errors over trials
        e = [r["metrics"]["nrmse84"] for r in load_runs(Path(out_dir))
             if r["row"] == row and r["status"] == "ok" and r["metrics"].get("nrmse84")]
        if e:
            pooled = float(np.log10(np.sqrt(np.mean(np.square(e)))))
            lines.append(f"- {row}: pooled log10 NRMSE_84 = {pooled:.2f} over {len(e)} runs "
                         "(Jaeger & Haas 2004, N = 1000: about -4.2)")
    return common.report(results, out_dir, NAME, ["", *lines])
