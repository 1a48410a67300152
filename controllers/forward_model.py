"""ESN forward model (paper A): input [s_in(t); command(t)] -> predicted s(t+1).

Modes: "parallel" (trained alongside FEL on every learning cycle), "serial"
(pre-trained on the desired movement with its true commands, then frozen) and
"hybrid" (pre-trained, then trained on like parallel). ``s_in`` is the sensed
signal as the internal models see it, i.e. delayed by ``delay_steps``. ``chained``
(fidelity-a's variant): when there is a delay, the position input is instead the
model's own previous prediction p(t) (it runs ahead of the delayed sensing on its own
predictions), and pre-training fits the one-step map [d(t); c(t)] -> d(t+1).
"""

from __future__ import annotations

import numpy as np
from skinny_mj.controllers.esn import ESN
from skinny_mj.controllers.metrics import nrmse

MODES = ("parallel", "serial", "hybrid")


class ForwardModel:
    """Wraps an :class:`ESN` with n_inputs = n_sig + n_dof and n_outputs = n_sig.

    Parameters
    ----------
    esn : the network (R runs, like the inverse model it serves).
    mode : "parallel", "serial" or "hybrid".
    chained : with a delay, feed the model its own previous prediction, not s_in.
    """

    def __init__(self, esn: ESN, mode: str = "serial", chained: bool = False) -> None:
        if mode not in MODES:
            raise ValueError(f"forward model mode must be one of {MODES}, got {mode!r}")
        self.esn, self.mode, self.chained = esn, mode, bool(chained)

    def begin(self, plant) -> None:
        """Called by the rollout before each cycle with the plant it drives (a model
        that reads a forced arm's command,
        :class:`skinny_mj.controllers.arm_forward.ArmForwardModels`,
        binds it here); this one needs nothing from the plant."""

    def step(self, sensed: np.ndarray, command: np.ndarray, noise: bool = True) -> np.ndarray:
        """Prediction (R, n_sig) of the next position from sensed (R, n_sig) and
        command (R, n_dof)."""
        return self.esn.step(np.concatenate([sensed, command], axis=1), noise=noise)

    def fit_rollout(self, ro, runs: np.ndarray | None = None) -> None:
        """Fit on one FEL cycle: states ``ro.fm_states`` -> next sensed positions."""
        self.esn.fit(ro.fm_states, ro.sensed[:, 1:], runs=runs)

    def sequence_inputs(
        self, positions: np.ndarray, commands: np.ndarray, delay_steps: int = 0
    ) -> np.ndarray:
        """Inputs (T-1, n_sig + n_dof) [p(max(t - delay, 0)); c(t)] for positions
        (T, n_sig) and commands (T-1, n_dof)."""
        idx = np.maximum(np.arange(commands.shape[0]) - delay_steps, 0)
        return np.concatenate([positions[idx], commands], axis=1)

    def pretrain(
        self,
        desired: np.ndarray,
        true_commands: np.ndarray,
        delay_steps: int = 0,
        noise: bool = True,
        sensor_noise: float = 0.0,
    ) -> np.ndarray:
        """Pre-train on the desired movement (paper A §3.4): "the forward model was
        trained to predict the next state in the sequence of desired states given the
        correct motor command and the delayed and noisy sensory signal".

        Inputs [d(t - delay) + e(t); c*(t)], e ~ N(0, sensor_noise²) drawn per run
        from the run's own Generator (``esn.rngs[r]``, before any reservoir noise of
        this pass); reset, one washout pass, one pass whose states are fitted to d(t+1).

        Parameters
        ----------
        desired : (T, n_sig) desired positions, normalized.
        true_commands : (T-1, n_dof) analytic commands in [-1, 1].
        delay_steps : steps by which the sensed input lags.
        noise : reservoir noise on during both passes.
        sensor_noise : std of the Gaussian noise on the sensed input (normalized units).

        Returns
        -------
        (R,) prediction NRMSE of the fitted readout on the fitting pass against d(t+1)
        ("the prediction error in the last run of pre-training").
        """
        desired = np.asarray(desired, float)
        n_runs = self.esn.n_runs
        if sensor_noise > 0:
            noisy = [desired + sensor_noise * g.standard_normal(desired.shape)
                     for g in self.esn.rngs]
            batch = np.stack([self.sequence_inputs(p, true_commands, delay_steps)
                              for p in noisy])
        else:
            inputs = self.sequence_inputs(desired, true_commands, delay_steps)
            batch = np.broadcast_to(inputs, (n_runs, *inputs.shape))
        self.esn.reset()
        self.esn.run(batch, noise=noise)
        _, states = self.esn.run(batch, noise=noise)
        targets = np.broadcast_to(desired[1:], (n_runs, *desired[1:].shape))
        self.esn.fit(states, targets)
        return nrmse(self.esn.readout(states), desired[1:])

    def prediction_error(self, desired: np.ndarray, true_commands: np.ndarray,
                         delay_steps: int = 0) -> np.ndarray:
        """Free prediction NRMSE (R,) on a movement, noise off, after a washout pass."""
        inputs = self.sequence_inputs(desired, true_commands, delay_steps)
        batch = np.broadcast_to(inputs, (self.esn.n_runs, *inputs.shape))
        self.esn.reset()
        self.esn.run(batch, noise=False)
        predicted, _ = self.esn.run(batch, noise=False)
        return nrmse(predicted, desired[1:])


def rollout_prediction_error(ro) -> np.ndarray:
    """Prediction NRMSE (R,) of p(t) against the noise-free positions in a FEL rollout."""
    return nrmse(ro.predictions[:, 1:], ro.true_signals[:, 1:])
