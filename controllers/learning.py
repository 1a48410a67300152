"""The seam for learning: the β target, what a cycle hands a learning rule, and the rule.

A learning rule changes the readouts W_out (R, n_out, D) of R lockstep networks
(:class:`skinny_mj.controllers.esn.ESN`) from what the closed loop produced. The loop
(:func:`skinny_mj.controllers.fel.train`,
:func:`skinny_mj.controllers.true_target.train_true_target`)
calls it at three points:

- :meth:`LearningRule.washout` after a cycle that learns nothing (each epoch's washout
  cycle), with that cycle's :class:`Cycle`: a rule may keep it, e.g. as validation data;
- :meth:`LearningRule.fit` after each learning cycle, with its :class:`Cycle`: the rule
  refits the readouts of ``cycle.runs`` (the runs still alive; the others must keep
  theirs);
- :meth:`LearningRule.update` at every control step of a learning cycle, for a rule whose
  :attr:`~LearningRule.online` is True (the loop passes it as
  :class:`skinny_mj.controllers.loop.Loop`'s ``online``): the step before's extended state,
  ESN output and FEL target, one step late because u_error(t) completes y_est(t-1).

The target a rule fits is FEL's blend (paper E's new method), :func:`beta_target`:
y_used = β y_est + (1 − β) y_ESN, β = 1 the original method. Implementations:
:class:`CycleFit` (each cycle alone, pinv or ridge: the thesis's),
:class:`skinny_mj.controllers.ridge_select.RidgeSelector`,
:class:`skinny_mj.controllers.torque_readout.ForgettingReadout` and
:class:`~skinny_mj.controllers.torque_readout.RLSReadout`,
:class:`skinny_mj.controllers.online.OnlineRLS`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from skinny_mj.controllers.esn import ESN
from skinny_mj.controllers.readout import PinvFactors

__all__ = ["beta_target", "Cycle", "LearningRule", "CycleFit"]


def beta_target(target: np.ndarray, y_esn: np.ndarray, beta: float) -> np.ndarray:
    """The new method's target y_used = β target + (1 − β) y_ESN (paper E); β = 1
    returns ``target`` itself (the original method: no arithmetic, so no rounding and
    no NaN from a non-finite y_ESN). Arrays of one shape, e.g. (R, T, n_out)."""
    if beta == 1.0:
        return target
    return beta * target + (1.0 - beta) * y_esn


@dataclass(frozen=True)
class Cycle:
    """What one cycle of R lockstep runs hands a learning rule.

    states : (R, T, D) extended states M of the networks (T = the cycle's steps).
    target : (R, T, n_out) what the readout should output, in the output domain
        (FEL: :func:`beta_target` of y_est and y_ESN; true target: of the true commands).
    runs : (R,) bool, the runs that learn (the healthy ones); the others keep W_out.
    epoch : the training epoch (0 outside an epoch schedule).
    y_est, y_esn : (R, T, n_out) the two parts of ``target`` (FEL's estimated command and
        the networks' own output), or None where the loop has no such parts.
    """

    states: np.ndarray
    target: np.ndarray
    runs: np.ndarray
    epoch: int = 0
    y_est: np.ndarray | None = None
    y_esn: np.ndarray | None = None


class LearningRule:
    """A learning rule for the readouts of R lockstep networks (module docstring).

    Subclasses implement :meth:`fit`; :meth:`washout` and :meth:`update` do nothing
    unless overridden. A rule with ``online = True`` also learns inside the loop through
    :meth:`update`. A rule that needs the networks' sizes or the number of epochs takes
    them (or the ESN) in its constructor; one rule object serves one training.
    """

    #: True: the loop calls :meth:`update` at every step of a learning cycle
    online: bool = False

    def washout(self, esn: ESN, cycle: Cycle) -> None:
        """After a cycle that learns nothing (the epoch's washout cycle)."""

    def fit(self, esn: ESN, cycle: Cycle) -> None:
        """After a learning cycle: refit ``esn.W_out`` of ``cycle.runs`` (in place)."""
        raise NotImplementedError

    def update(self, state: np.ndarray, y_esn: np.ndarray, y_est: np.ndarray) -> None:
        """Online, after step t: state (R, D), y_esn and y_est (R, n_out) of step t-1."""

    def metrics(self, run: int) -> dict:
        """What the rule reports about run ``run``'s training (JSON-ready; a training's
        ``metrics.json`` adds it under ``train``): nothing unless overridden."""
        return {}


class CycleFit(LearningRule):
    """FEL's fit (the thesis's): each learning cycle alone, by the ESN's own solver
    (:meth:`skinny_mj.controllers.esn.ESN.fit`: pinv, or ridge with its λ).

    reuse_factors : keep the pinv factorization while the states repeat bit for bit
        (teacher forcing without noise: from the second cycle on, the initial state's
        trace has decayed below rounding) and refactor when they change; a pinv readout
        only (ignored otherwise). Same readouts, a fraction of the cost.
    """

    def __init__(self, reuse_factors: bool = False):
        self.reuse_factors = reuse_factors
        self._states: np.ndarray | None = None
        self._factors: PinvFactors | None = None

    def fit(self, esn: ESN, cycle: Cycle) -> None:
        factors = None
        if self.reuse_factors and esn.cfg.readout == "pinv":
            if self._states is None or not np.array_equal(cycle.states, self._states):
                self._states, self._factors = cycle.states, PinvFactors(cycle.states)
            factors = self._factors
        esn.fit(cycle.states, cycle.target, runs=cycle.runs, factors=factors)
