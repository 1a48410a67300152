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

Rows ``ordinary-short`` and ``new-conv-short`` train on :data:`SHORT_TRAIN_PERIODS`
periods (2 of them washout) instead of 12: the thesis's preliminary finding that the new
method "needs shorter training sequences" (paper E's discussion) compares them. No plant:
the task's settings are the study's parameters (:data:`PARAMS`), ``--quick`` shortens the
sequences.
"""

from __future__ import annotations

import time
import warnings
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
from skinny_mj.controllers.esn import ESNConfig
from skinny_mj.controllers.generation import figure_eight
from skinny_mj.experiments import generation_runs as common
from skinny_mj.experiments.claims import claim_lines

from skinny_mj.engine.study import Quick, Row, Study
from skinny_mj.training.config import TrainConfig

NAME = "figure-eight"
#: Methods also trained on the short sequence.
SHORT_METHODS = ("ordinary", "new-conv")
SHORT_TRAIN_PERIODS = 4
#: The task (steps per period; periods of training, of them washout, free) and the network.
PARAMS = {"period": 100, "train_periods": 12, "washout_periods": 2, "free_periods": 20,
          "reservoir": 200, "noise": 1e-3, "force_lambda": 1e-4, "rpy_ridge": 1e-6}


def esn_config(p: Mapping[str, Any]) -> ESNConfig:
    return ESNConfig(n_inputs=1, n_outputs=2, n_reservoir=p["reservoir"], spectral_radius=0.8,
                     input_scaling=0.5, output_feedback=True, feedback_scaling=1.0,
                     readout_activation="identity", noise_level=p["noise"])


def run_batch(config: TrainConfig, row: Row, seeds: list[int]) -> list:
    """The row's fit of every seed (in lockstep; reservoirpy one by one), then free runs."""
    p = row.params
    n_fit = p["period"] * p["train_periods"]
    series = figure_eight(n_fit + p["period"] * p["free_periods"], p["period"])  # every seed's
    scale = float(series.std())
    washout = p["period"] * p["washout_periods"]
    if p["method"] == "reservoirpy":
        return [_reservoirpy(p, series, n_fit, washout, scale, s) for s in seeds]
    free, target, wall, passes = common.run_ours(p["method"], esn_config(p), seeds,
                                                 lambda _: series, n_fit, washout,
                                                 p["force_lambda"])
    return [{**m, "fit_wall_s": wall, "passes": int(n)}
            for m, n in zip(common.metrics(free, target, p["period"], scale), passes,
                            strict=True)]


def _reservoirpy(p: Mapping[str, Any], series: np.ndarray, n_fit: int, washout: int,
                 scale: float, seed: int) -> dict:
    from reservoirpy import ESN

    seed32 = int(np.random.SeedSequence(seed).generate_state(1)[0])
    start = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = ESN(units=p["reservoir"], sr=0.8, lr=1.0, input_scaling=0.5,
                    ridge=p["rpy_ridge"], feedback=True, seed=seed32)
        model.fit(np.ones((n_fit, 1)), series[:n_fit], warmup=washout)
        wall = time.perf_counter() - start
        free = model.run(np.ones((len(series) - n_fit, 1)))
    (m,) = common.metrics(free[None], series[None, n_fit:], p["period"], scale)
    return {**m, "fit_wall_s": wall}


def estimate_bytes(config: TrainConfig, row: Row, runs: int):
    """The memory a batch of ``runs`` seeds of ``row`` needs (the sweep's check)."""
    p = row.params
    return common.estimate(p["method"], esn_config(p), p["period"] * p["train_periods"],
                           p["period"] * p["free_periods"], runs)


def report(results, plan, out_dir: Path) -> str:
    short = claim_lines(Path(out_dir), [
        ("figure-eight, short training sequence: the new β method run to convergence runs "
         "free longer than the ordinary fit (the thesis: it 'needs shorter training "
         "sequences')", "mean", "new-conv-short", "horizon", ">", "mean", "ordinary-short")])
    return common.report(results, plan, out_dir, NAME, [short])


STUDY = Study(
    name=NAME, description=__doc__, run_batch=run_batch, runs=20, params=PARAMS,
    rows=(*common.rows(common.METHODS),
          *(Row(f"{m}-short", params={"method": m, "train_periods": SHORT_TRAIN_PERIODS},
                quick={"train_periods": 3}) for m in SHORT_METHODS)),
    columns=common.COLUMNS,
    # a smoke test: 2 seeds, 4 training periods (the short rows 3), 4 free
    quick=Quick(runs=2, params={"train_periods": 4, "free_periods": 4}),
    memory=estimate_bytes, unavailable=common.unavailable_rows,
    takes=(), report=report,  # no plant: no movement, body or signals to choose
)
