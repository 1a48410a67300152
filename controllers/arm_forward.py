"""One forward model per arm for paper B's bimanual plant, with what the arms share.

The thesis's future work (§4.3): "add delays in the sensory-motor loop during the
bimanual experiments ... each arm could have both an inverse model and a forward model
as in the delay experiments. Instead of, or in addition to, having access to the sensed
state of the other arm, the control system of one arm could have access to the
prediction made by the other arm's forward model"; and (§4.1) "we would consider
sharing motor commands instead of position".

:class:`ArmForwardModels` speaks :class:`skinny_mj.controllers.forward_model.ForwardModel`'s verbs
(``begin``, ``step``, ``fit_rollout``, ``esn.reset``), so the one rollout
(:func:`skinny_mj.controllers.rollout.rollout`) drives it unchanged. Its step returns a vector
laid out like the body's signals (R, n_sig), which the rollout appends to the lagging
arm's inverse-model input as it appends paper A's prediction p(t):

- at the lagging arm's signals: the lagging arm's forward model's prediction of its next
  position, from its delayed sensed position and its own command;
- at the leading arm's signals, by ``sharing``: ``"none"`` zeros (nothing shared);
  ``"predictions"`` the leading arm's forward model's prediction of its next position,
  from its delayed sensed position and its (forced) command; ``"commands"`` the leading
  arm's last motor command (an efference copy: not delayed), in command units [-1, 1].

The leading arm is forced (paper B): its command is the plant's
(``plant.leader_command()``, read at :meth:`ArmForwardModels.begin`'s plant before
each step). As every rollout, p(0) = s(0) in every slot. Both forward models are
trained "parallel" (paper A: refitted on every learning cycle) to the arm's next
sensed position.
"""

from __future__ import annotations

import numpy as np
from skinny_mj.controllers.esn import ESN
from skinny_mj.controllers.metrics import nrmse

SHARING = ("none", "predictions", "commands")


class _Networks:
    """The arms' forward networks seen as one (what the rollout resets and records):
    ``extended`` (R, D_lag + D_lead) is the lagging network's extended state then the
    leading one's (none in modes that do not use it)."""

    def __init__(self, lag: ESN, lead: ESN | None) -> None:
        self.lag, self.lead = lag, lead
        self.n_runs = lag.n_runs
        self.cfg = _Shape(lag.cfg.n_extended + (0 if lead is None else lead.cfg.n_extended))

    def reset(self) -> None:
        self.lag.reset()
        if self.lead is not None:
            self.lead.reset()

    @property
    def extended(self) -> np.ndarray:
        if self.lead is None:
            return self.lag.extended
        return np.concatenate([self.lag.extended, self.lead.extended], axis=1)


class _Shape:
    def __init__(self, n_extended: int) -> None:
        self.n_extended = n_extended


class ArmForwardModels:
    """The lagging arm's forward model (and the leading arm's, when its predictions
    are shared) over a body whose signals split into the two arms'.

    Parameters
    ----------
    lag : R networks, inputs [s_lag (n_lag_sig); u_lag (n_lag_dof)], outputs n_lag_sig.
    lead : R networks, inputs [s_lead; u_lead], outputs n_lead_sig; needed (and used)
        only with ``sharing="predictions"``.
    lag_signals, lead_signals : indices of each arm's signals in the body's signals.
    sharing : "none", "predictions" or "commands" (see the module docstring).
    """

    chained = False  # always fed the (delayed) sensed positions (ForwardModel's option)
    mode = "parallel"

    def __init__(self, lag: ESN, lead: ESN | None, lag_signals: np.ndarray,
                 lead_signals: np.ndarray, sharing: str) -> None:
        if sharing not in SHARING:
            raise ValueError(f"sharing must be one of {SHARING}, got {sharing!r}")
        if (lead is not None) != (sharing == "predictions"):
            raise ValueError("the leading arm's forward model goes with sharing='predictions'")
        self.sharing = sharing
        self.lag_signals = np.asarray(lag_signals, int)
        self.lead_signals = np.asarray(lead_signals, int)
        self.n_signals = len(self.lag_signals) + len(self.lead_signals)
        self.esn = _Networks(lag, lead)
        self._plant = None

    def begin(self, plant) -> None:
        """Bind the plant of the cycle about to run (its forced arm's commands)."""
        if not hasattr(plant, "leader_command"):
            raise TypeError("ArmForwardModels needs a plant with a forced leading arm "
                            "(skinny_mj.plant.bimanual.BimanualPlant)")
        self._plant = plant

    def step(self, sensed: np.ndarray, command: np.ndarray, noise: bool = True) -> np.ndarray:
        """(R, n_sig) what the lagging arm's inverse model gets next, from the delayed
        sensed signals (R, n_sig) and the lagging arm's command (R, n_lag_dof)."""
        nets = self.esn
        out = np.zeros((nets.n_runs, self.n_signals))
        out[:, self.lag_signals] = nets.lag.step(
            np.concatenate([sensed[:, self.lag_signals], command], axis=1), noise=noise)
        if self.sharing == "none":
            return out
        u_lead = self._plant.leader_command()
        if self.sharing == "commands":
            out[:, self.lead_signals] = u_lead
        else:
            out[:, self.lead_signals] = nets.lead.step(
                np.concatenate([sensed[:, self.lead_signals], u_lead], axis=1), noise=noise)
        return out

    def fit_rollout(self, ro, runs: np.ndarray | None = None) -> None:
        """Fit each arm's network on one FEL cycle to that arm's next sensed positions."""
        d_lag = self.esn.lag.cfg.n_extended
        self.esn.lag.fit(ro.fm_states[..., :d_lag], ro.sensed[:, 1:, self.lag_signals],
                         runs=runs)
        if self.esn.lead is not None:
            self.esn.lead.fit(ro.fm_states[..., d_lag:], ro.sensed[:, 1:, self.lead_signals],
                              runs=runs)

    def prediction_nrmse(self, ro) -> np.ndarray:
        """(R,) the lagging arm's prediction NRMSE against its noise-free positions."""
        return nrmse(ro.predictions[:, 1:, self.lag_signals],
                     ro.true_signals[:, 1:, self.lag_signals])
