"""Online learning inside the closed loop: an RLS (FORCE-style) readout update per
control step, an online learning rule (:class:`skinny_mj.controllers.learning.LearningRule`) for
a :class:`skinny_mj.controllers.loop.Loop`'s ``rule`` (:func:`skinny_mj.controllers.fel.train`)
or its ``online`` learner.

At step t the rollout knows u_error(t), so FEL's estimated target of the step before,
y_est(t-1) = command(t-1) + u_error(t), is available one step late; :class:`OnlineRLS`
then updates every run's readout with (extended state(t-1), beta y_est(t-1) +
(1 - beta) y_ESN(t-1)), the new method's blend (beta = 1: FEL's plain target), through
atanh for a tanh readout as the batch fit does. The next step's output already uses the
updated readout. R runs update in lockstep (:class:`skinny_mj.controllers.readout.RLS`). In
:func:`skinny_mj.controllers.fel.train` it learns at every step of the learning cycles, the runs
that learn following the training's healthy runs, and fits nothing between cycles.
"""

from __future__ import annotations

import numpy as np
from skinny_mj.controllers.esn import ESN
from skinny_mj.controllers.learning import Cycle, LearningRule, beta_target
from skinny_mj.controllers.methods import check_beta
from skinny_mj.controllers.readout import RLS, linear_targets


class OnlineRLS(LearningRule):
    """Per-step RLS on an ESN's readout (``esn.W_out`` is updated in place).

    Parameters
    ----------
    esn : the ESN whose readout learns (float64).
    forgetting : RLS forgetting factor g in (0, 1]; memory about 1 / (1 - g) steps.
    ridge_lambda : P_0 = I / lambda when ``states`` is None.
    states : optional (R, T, D) extended states of the last batch fit: P_0 = (M^T M +
        lambda I)^-1, so the online updates continue that fit instead of starting from a
        prior that trusts the trained readout as much as lambda says.
    beta : blend of the target with the network's own output (1: y_est alone), the
        per-step target's (:func:`skinny_mj.controllers.learning.beta_target`).
    runs : (R,) bool, the runs that learn (default all; e.g. the healthy ones); in
        :func:`skinny_mj.controllers.fel.train`, each cycle's healthy runs.
    """

    online = True

    def __init__(self, esn: ESN, forgetting: float = 0.999, ridge_lambda: float = 1e-2,
                 states: np.ndarray | None = None, beta: float = 1.0,
                 runs: np.ndarray | None = None):
        if esn.W_out.dtype != np.float64:
            raise ValueError("online RLS needs a float64 ESN")
        check_beta(beta)
        self.esn, self.beta = esn, float(beta)
        self.runs = None if runs is None else np.asarray(runs, bool)
        self.rls = RLS(esn.W_out, ridge_lambda, forgetting) if states is None else \
            RLS.from_states(esn.W_out, states, ridge_lambda, forgetting)
        self.updates = 0

    def washout(self, esn: ESN, cycle: Cycle) -> None:
        """The runs that learn from now on: the cycle's healthy ones."""
        self.runs = np.asarray(cycle.runs, bool)

    def fit(self, esn: ESN, cycle: Cycle) -> None:
        """Nothing to fit after a cycle (it learned at every step); the runs that learn
        from now on: the cycle's healthy ones."""
        self.runs = np.asarray(cycle.runs, bool)

    def update(self, state: np.ndarray, y_esn: np.ndarray, y_est: np.ndarray) -> None:
        """One step: state (R, D), y_esn and y_est (R, n_out) of the step before."""
        target = linear_targets(self.esn.cfg, beta_target(y_est, y_esn, self.beta))
        if self.rls.W is not self.esn.W_out:  # the ESN's readout was replaced (a batch fit)
            self.rls.W = self.esn.W_out
        self.rls.update(state, target, self.runs)
        self.updates += 1
