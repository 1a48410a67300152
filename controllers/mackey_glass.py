"""Mackey-Glass series as in Jaeger & Haas (2004): tau = 17, Euler steps of 1/10,
subsampled to one sample per time unit, then squashed with tanh(y - 1)."""

from __future__ import annotations

import numpy as np


def mackey_glass(
    n_samples: int,
    rng: np.random.Generator,
    tau: float = 17.0,
    step: float = 0.1,
    subsample: int = 10,
    warmup: int = 1000,
    squash: bool = True,
) -> np.ndarray:
    """Mackey-Glass samples (n_samples,), one per time unit.

    dy/dt = 0.2 y(t - tau) / (1 + y(t - tau)^10) - 0.1 y(t), integrated by Euler
    with ``step``, every ``subsample``-th value kept; the history starts at
    1.2 + U[-0.1, 0.1] (so ``rng`` picks one trajectory on the attractor) and the
    first ``warmup`` samples are dropped. With ``squash`` returns tanh(y - 1).
    """
    lag = int(round(tau / step))
    total = (n_samples + warmup) * subsample
    y = np.empty(total + lag)
    y[: lag + 1] = 1.2 + rng.uniform(-0.1, 0.1)
    for n in range(lag, total + lag - 1):
        delayed = y[n - lag]
        y[n + 1] = y[n] + step * (0.2 * delayed / (1.0 + delayed**10) - 0.1 * y[n])
    samples = y[lag::subsample][warmup : warmup + n_samples]
    return np.tanh(samples - 1.0) if squash else samples
