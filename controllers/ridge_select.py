"""Ridge readout with lambda chosen per run and per fit on a validation cycle.

A learning rule (:class:`skinny_mj.controllers.learning.LearningRule`) for FEL
(a :class:`skinny_mj.controllers.loop.Loop`'s ``rule``): every learning cycle's fit
takes, per run, the lambda of a log grid whose readout, fitted on this cycle's
(states, targets), best predicts the targets of the cycle before it (the epoch's
washout cycle, or the previous learning cycle): the same controller, another draw of
reservoir and sensor noise. The validation error is the squared error in the
readout's linear domain (targets through atanh for a tanh readout), what the ridge fit
itself minimises. One eigendecomposition of the fit cycle's Gram matrix serves the
whole grid, and the validation cycle is kept as its sufficient statistics (M^T M,
M^T S, S^T S), so neither cycle's states need to outlive the rollout buffers.
"""

from __future__ import annotations

import numpy as np
from skinny_mj.controllers.esn import ESN
from skinny_mj.controllers.learning import Cycle, LearningRule
from skinny_mj.controllers.readout import linear_targets

#: The default grid: 10^-8 ... 10^1 (10 values; the thesis's pinv is lambda -> 0).
RIDGE_GRID: tuple[float, ...] = tuple(float(10.0 ** k) for k in range(-8, 2))


def ridge_path(m: np.ndarray, s: np.ndarray, lambdas: np.ndarray) -> np.ndarray:
    """Ridge solutions W (L, D, n) of M (T, D), S (T, n) for every lambda (L,)."""
    evals, vecs = np.linalg.eigh(m.T @ m)
    proj = vecs.T @ (m.T @ s)  # (D, n)
    evals = np.maximum(evals, 0.0)  # rounding can make tiny eigenvalues negative
    return np.stack([vecs @ (proj / (evals + lam)[:, None]) for lam in lambdas])


def validation_errors(w: np.ndarray, gram: np.ndarray, cross: np.ndarray,
                      energy: float) -> np.ndarray:
    """Sum of squared errors ||M_v W - S_v||^2 (L,) from the validation cycle's
    statistics: gram = M_v^T M_v (D, D), cross = M_v^T S_v (D, n), energy = ||S_v||^2."""
    quad = np.einsum("ldn,de,len->l", w, gram, w)
    return quad - 2.0 * np.einsum("ldn,dn->l", w, cross) + energy


class RidgeSelector(LearningRule):
    """Per run and fit: the grid's lambda with the least validation error.

    Parameters
    ----------
    esn : the R networks whose readouts are fitted.
    n_epochs : E (for :attr:`chosen`).
    grid : the lambdas, > 0.

    Attributes
    ----------
    chosen : (R, E) the lambda of each epoch's last fit (NaN where not fitted).
    """

    def __init__(self, esn: ESN, n_epochs: int, grid: tuple[float, ...] = RIDGE_GRID):
        self.grid = np.asarray(grid, float)
        if self.grid.size == 0 or np.any(~(self.grid > 0)):
            raise ValueError(f"the ridge grid needs lambdas > 0, got {grid}")
        self.esn = esn
        self.chosen = np.full((esn.n_runs, n_epochs), np.nan)
        self._val: list[tuple[np.ndarray, np.ndarray, float] | None] = [None] * esn.n_runs

    def metrics(self, run: int) -> dict:
        """``ridge_lambda``: run ``run``'s lambda per epoch (None where not fitted)."""
        return {"ridge_lambda": [None if not np.isfinite(v) else float(v)
                                 for v in self.chosen[run]]}

    def washout(self, esn: ESN, cycle: Cycle) -> None:
        """Keep the cycle as the next validation cycle of its runs."""
        self._keep(cycle)

    def fit(self, esn: ESN, cycle: Cycle) -> None:
        """Fit the readout of the ``cycle.runs`` on this cycle, lambda chosen on the
        last kept cycle (the grid's middle if none was), then keep this cycle as the
        next validation cycle."""
        s = linear_targets(esn.cfg, cycle.target)
        for r in np.flatnonzero(cycle.runs):
            m = np.asarray(cycle.states[r], np.float64)
            w = ridge_path(m, s[r], self.grid)
            val = self._val[r]
            best = len(self.grid) // 2 if val is None else int(np.argmin(
                validation_errors(w, *val)))
            esn.W_out[r] = w[best].T.astype(esn.dtype)
            self.chosen[r, cycle.epoch] = self.grid[best]
        self._keep(cycle)

    def _keep(self, cycle: Cycle) -> None:
        """The cycle's statistics as the next validation cycle of its runs."""
        s = linear_targets(self.esn.cfg, cycle.target)
        for r in np.flatnonzero(cycle.runs):
            m = np.asarray(cycle.states[r], np.float64)
            self._val[r] = (m.T @ m, m.T @ s[r], float(np.sum(s[r] ** 2)))
