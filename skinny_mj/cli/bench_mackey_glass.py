"""``skinny bench``'s accuracy figure: Mackey-Glass (tau = 17) 84-step free-run
prediction after Jaeger & Haas (2004), ours and reservoirpy 0.4's own way on the same
series. Goal (``skinny_mj.cli.bench.GOALS``): our log10 NRMSE_84 <= -4.5 at N = 1000.
"""

from __future__ import annotations

import time
import warnings
from typing import Any

import numpy as np

from skinny_mj.cli.bench_summary import BENCH_EXTRA
from skinny_mj.controllers.esn import ESN, ESNConfig, run_generators
from skinny_mj.controllers.mackey_glass import mackey_glass as series

MG_HORIZON = 84


def mackey_glass_series(trials: int, length: int, seed: int = 0) -> np.ndarray:
    """(trials, length) squashed Mackey-Glass series, one attractor trajectory each."""
    return np.stack([series(length, g) for g in run_generators(seed, trials)])


def _nrmse84(free: np.ndarray, series: np.ndarray, washout: int, n_fit: int) -> float:
    """Jaeger & Haas's NRMSE_84 over trials: sqrt(mean (y(84) - d(84))^2 / var(d))."""
    variance = series[:, washout:n_fit].var()
    err = free[:, MG_HORIZON - 1] - series[:, n_fit + MG_HORIZON - 1]
    return float(np.sqrt(np.mean(err**2) / variance))


def esn_config(n_reservoir: int):
    """Jaeger & Haas's Mackey-Glass ESN (output feedback, leak 0.6, spectral radius
    0.95, bias 0.2, feedback scaling 0.56, state noise 1e-8, pinv, identity readout)."""
    return ESNConfig(n_inputs=1, n_outputs=1, n_reservoir=n_reservoir, spectral_radius=0.95,
                     bias=0.2, leak_rate=0.6, noise_level=1e-8, output_feedback=True,
                     feedback_scaling=0.56, readout_activation="identity")


def mackey_glass_ours(series: np.ndarray, n_reservoir: int, washout: int = 1000,
                      seed: int = 0) -> np.ndarray:
    """Our ESN (Jaeger & Haas's setup: output feedback, leak 0.6, spectral radius
    0.95, bias 0.2, feedback scaling 0.56, state noise 1e-8, pinv readout), all trials
    in lockstep; teacher-forced through the series minus the horizon, then 84 free
    steps. Returns the free run (trials, 84)."""
    trials, n_fit = series.shape[0], series.shape[1] - MG_HORIZON
    esn = ESN(esn_config(n_reservoir), n_runs=trials, rngs=run_generators(seed + 1, trials))
    teacher = series[:, :n_fit, None]
    zeros = np.zeros((trials, n_fit, 1))
    _, states = esn.run(zeros, noise=True, teacher=teacher, washout=washout)
    esn.fit(states, teacher[:, washout:])
    esn.reset()
    esn.run(zeros, noise=False, teacher=teacher)
    return np.stack([esn.step(np.zeros((trials, 1)), noise=False)[:, 0]
                     for _ in range(MG_HORIZON)], axis=1)


def mackey_glass_reservoirpy(series: np.ndarray, n_reservoir: int, washout: int = 1000,
                             seed: int = 0, horizon: int = MG_HORIZON) -> np.ndarray:
    """reservoirpy 0.4's own way on the same series: a ``Reservoir >> Ridge`` trained to
    map d(t) to d(t + 1) (leak 0.6, spectral radius 0.95, ridge 1e-10), then run in a
    closed loop for ``horizon`` (84) steps from the end of the training data (the last
    ``horizon`` samples are not trained on). Returns (trials, horizon)."""
    from reservoirpy.nodes import Reservoir, Ridge

    n_fit = series.shape[1] - horizon
    free = np.empty((series.shape[0], horizon))
    for r, s in enumerate(series):
        model = Reservoir(n_reservoir, lr=0.6, sr=0.95, input_scaling=1.0,
                          rc_connectivity=min(1.0, 10 / n_reservoir), seed=seed + r) \
            >> Ridge(ridge=1e-10)
        model.fit(s[:n_fit - 1, None], s[1:n_fit, None], warmup=washout)
        y = s[n_fit - 1:n_fit]
        for k in range(horizon):
            y = model.step(y)
            free[r, k] = y[0]
    return free


def mackey_glass(n_reservoir: int, trials: int, washout: int = 1000, train: int = 2000,
                 seed: int = 0) -> dict:
    """log10 NRMSE_84 of ours and of reservoirpy on the same ``trials`` series."""
    series = mackey_glass_series(trials, washout + train + MG_HORIZON, seed)
    n_fit = washout + train
    start = time.perf_counter()
    ours = _nrmse84(mackey_glass_ours(series, n_reservoir, washout, seed), series,
                    washout, n_fit)
    out: dict[str, Any] = {"N": n_reservoir, "trials": trials, "train": train,
                           "ours_log10_nrmse84": float(np.log10(ours)),
                           "ours_s": time.perf_counter() - start}
    try:
        import reservoirpy
    except ImportError:
        out["reservoirpy"] = f"skipped: needs reservoirpy, the bench extra: {BENCH_EXTRA}"
        return out
    start = time.perf_counter()
    with warnings.catch_warnings():  # its ridge solve warns on ill-conditioned Gram matrices
        warnings.simplefilter("ignore")
        free = mackey_glass_reservoirpy(series, n_reservoir, washout, seed)
    theirs = _nrmse84(free, series, washout, n_fit)
    out["reservoirpy_version"] = reservoirpy.__version__
    out.update(reservoirpy_log10_nrmse84=float(np.log10(theirs)),
               reservoirpy_s=time.perf_counter() - start)
    return out
