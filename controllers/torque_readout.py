"""Readout fits that remember earlier cycles: learning rules
(:class:`skinny_mj.controllers.learning.LearningRule`) for
a :class:`skinny_mj.controllers.loop.Loop`'s ``rule`` (:func:`skinny_mj.controllers.fel.train`).

- :class:`ForgettingReadout`: the normal equations accumulated over the learning
  cycles, each cycle's old statistics weighted by a forgetting factor g per cycle,
  A <- g A + M^T M, B <- g B + M^T S, then W^T = (A + lambda I)^-1 B. With g = 0 it is
  the ridge fit of the last cycle alone (what ``esn.fit`` does with a ridge readout).
- :class:`RLSReadout`: recursive least squares through the cycle's samples in time
  order (:class:`skinny_mj.controllers.readout.RLS`), the readout carried on from cycle to cycle,
  with the forgetting per sample that gives the same memory per cycle, g^(1/T).

Targets go through atanh (clipped) for a tanh readout, as every fit of the ESN does.
"""

from __future__ import annotations

import numpy as np
from skinny_mj.controllers.esn import ESN
from skinny_mj.controllers.learning import Cycle, LearningRule
from skinny_mj.controllers.readout import RLS, linear_targets


class ForgettingReadout(LearningRule):
    """Normal equations with forgetting (module docstring). forgetting : g in [0, 1]
    per learning cycle; ridge : lambda > 0 on the accumulated Gram matrix."""

    def __init__(self, esn: ESN, forgetting: float = 0.8, ridge: float = 1e-2):
        if not 0 <= forgetting <= 1 or not ridge > 0:
            raise ValueError(f"need 0 <= forgetting <= 1 and ridge > 0, got {forgetting}, "
                             f"{ridge}")
        d, n_out = esn.cfg.n_extended, esn.cfg.n_outputs
        self.forgetting, self.ridge = float(forgetting), float(ridge)
        self.gram = np.zeros((esn.n_runs, d, d))
        self.cross = np.zeros((esn.n_runs, d, n_out))

    def fit(self, esn: ESN, cycle: Cycle) -> None:
        """Add the cycle to the forgetting statistics and solve (washout cycles add
        nothing: they are not learning cycles)."""
        m, s = np.asarray(cycle.states, np.float64), linear_targets(esn.cfg, cycle.target)
        eye = self.ridge * np.eye(m.shape[-1])
        for r in np.flatnonzero(np.asarray(cycle.runs, bool)):
            self.gram[r] = self.forgetting * self.gram[r] + m[r].T @ m[r]
            self.cross[r] = self.forgetting * self.cross[r] + m[r].T @ s[r]
            w_t = np.linalg.solve(self.gram[r] + eye, self.cross[r])
            esn.W_out[r] = w_t.T.astype(esn.dtype)


class RLSReadout(LearningRule):
    """RLS through each learning cycle's samples (module docstring). forgetting : g per
    cycle of ``steps`` samples; ridge : P_0 = I / ridge."""

    def __init__(self, esn: ESN, steps: int, forgetting: float = 0.8, ridge: float = 1e-2):
        if not 0 < forgetting <= 1 or steps < 1:
            raise ValueError(f"need 0 < forgetting <= 1 and steps >= 1, got {forgetting}, "
                             f"{steps}")
        self.rls = RLS(np.array(esn.W_out, np.float64), ridge, forgetting ** (1.0 / steps))

    def fit(self, esn: ESN, cycle: Cycle) -> None:
        """RLS through the cycle's samples in time order (washout cycles add nothing)."""
        m, s = np.asarray(cycle.states, np.float64), linear_targets(esn.cfg, cycle.target)
        runs = np.asarray(cycle.runs, bool)
        for t in range(m.shape[1]):
            self.rls.update(m[:, t], s[:, t], runs)
        esn.W_out[runs] = self.rls.W[runs].astype(esn.dtype)
