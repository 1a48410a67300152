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
before the error exceeds 0.1 std, stability, fit wall time. 20 seeds per row. No plant:
the series' lengths and the reservoir size are the study's parameters (:data:`PARAMS`),
``--quick`` shrinks them.
"""

from __future__ import annotations

import time
import warnings
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
from skinny_mj.controllers.mackey_glass import mackey_glass
from skinny_mj.experiments import generation_runs as common

from skinny_mj.cli.bench_mackey_glass import esn_config, mackey_glass_reservoirpy
from skinny_mj.engine.study import Quick, Row, Study
from skinny_mj.training.config import TrainConfig

NAME = "mackey-glass"
HORIZON = 84
METHODS = ("ordinary", "new", "new-blend", "reservoirpy", "new-conv")  # new rows last
COLUMNS = {"log10_nrmse84": "log10 NRMSE_84", **common.COLUMNS}
#: Reservoir size; samples of washout, training (teacher-forced), free run.
PARAMS = {"reservoir": 400, "washout": 1000, "train": 2000, "free": 500}


def _series(p: Mapping[str, Any], rng: np.random.Generator) -> np.ndarray:
    return mackey_glass(p["washout"] + p["train"] + p["free"], rng)[:, None]  # (L, 1)


def _with_nrmse84(m: dict, free: np.ndarray, target: np.ndarray, scale: float) -> dict:
    e = abs(float(free[HORIZON - 1, 0] - target[HORIZON - 1, 0])) / scale \
        if np.all(np.isfinite(free)) else None
    return {**m, "nrmse84": e,
            "log10_nrmse84": None if e is None or e <= 0 else float(np.log10(e))}


def run_batch(config: TrainConfig, row: Row, seeds: list[int]) -> list:
    """The row's fit of every seed's series (in lockstep; reservoirpy one by one), then
    free runs."""
    p = row.params
    if p["method"] == "reservoirpy":
        return [_reservoirpy(p, s) for s in seeds]
    n_fit = p["washout"] + p["train"]
    free, target, wall, passes = common.run_ours(p["method"], esn_config(p["reservoir"]),
                                                 seeds, lambda rng: _series(p, rng), n_fit,
                                                 p["washout"])
    out = []
    for r, seed in enumerate(seeds):
        scale = float(_series(p, common.streams(seed)[0])[p["washout"]:n_fit].std())
        (m,) = common.metrics(free[r:r + 1], target[r:r + 1], HORIZON, scale)
        out.append({**_with_nrmse84(m, free[r], target[r], scale), "fit_wall_s": wall,
                    "passes": int(passes[r])})
    return out


def _reservoirpy(p: Mapping[str, Any], seed: int) -> dict:
    series = _series(p, common.streams(seed)[0])
    n_fit = p["washout"] + p["train"]
    scale = float(series[p["washout"]:n_fit].std())
    seed32 = int(np.random.SeedSequence(seed).generate_state(1)[0])
    start = time.perf_counter()
    with warnings.catch_warnings():  # its ridge solve warns on ill-conditioned Grams
        warnings.simplefilter("ignore")
        free = mackey_glass_reservoirpy(series[None, :, 0], p["reservoir"], p["washout"],
                                        seed32, horizon=p["free"])[0][:, None]
    wall = time.perf_counter() - start  # fit + the free run (reservoirpy steps both)
    target = series[n_fit:]
    (m,) = common.metrics(free[None], target[None], HORIZON, scale)
    return {**_with_nrmse84(m, free, target, scale), "fit_wall_s": wall}


def estimate_bytes(config: TrainConfig, row: Row, runs: int):
    """The memory a batch of ``runs`` seeds of ``row`` needs (the sweep's check)."""
    p = row.params
    return common.estimate(p["method"], esn_config(p["reservoir"]), p["washout"] + p["train"],
                           p["free"], runs)


def report(results, plan, out_dir: Path) -> str:
    lines = []
    for row in METHODS:  # Jaeger & Haas pool the squared errors over trials
        e = [v for v in results.values(row, "nrmse84") if v]
        if e:
            pooled = float(np.log10(np.sqrt(np.mean(np.square(e)))))
            lines.append(f"- {row}: pooled log10 NRMSE_84 = {pooled:.2f} over {len(e)} runs "
                         "(Jaeger & Haas 2004, N = 1000: about -4.2)")
    return common.report(results, plan, out_dir, NAME, ["", *lines])


STUDY = Study(
    name=NAME, description=__doc__, rows=common.rows(METHODS), run_batch=run_batch,
    runs=20, params=PARAMS, columns=COLUMNS,
    # a smoke test: 2 seeds, N = 100, 500 training samples
    quick=Quick(runs=2, params={"reservoir": 100, "washout": 200, "train": 500, "free": 200}),
    memory=estimate_bytes, unavailable=common.unavailable_rows,
    takes=(), report=report,  # no plant: no movement, body or signals to choose
)
