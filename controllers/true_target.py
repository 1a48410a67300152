"""True-target architecture (paper D) and the cycles-to-convergence curve (paper E Fig. 3).

Targets are the true commands (from an analytic inverse, computed elsewhere and
passed in as an array). Teacher forcing: the inverse model's "current position"
input is the desired position d(t), so the plant is not needed for training; it is
used only in testing (closed loop, K = 0: :func:`skinny_mj.controllers.fel.evaluate`).
The method is a :class:`~skinny_mj.controllers.methods.TrueTarget`; with β = 1 (the
original method) one fitted cycle, else ``cycles`` cycles, each fitting
y_used = beta y_true + (1 - beta) y_ESN (:func:`skinny_mj.controllers.learning.beta_target`) by a
learning rule (default the pinv or ridge fit of each cycle alone). Every run starts
with a reset and one washout cycle; the state carries over between cycles.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from skinny_mj.controllers.esn import ESN
from skinny_mj.controllers.learning import Cycle, CycleFit, LearningRule, beta_target
from skinny_mj.controllers.methods import TrueTarget
from skinny_mj.controllers.metrics import nrmse

__all__ = ["TrueTarget", "TrueTargetResult", "teacher_forced_inputs", "train_true_target",
           "convergence_curve", "cycles_to_converge"]


@dataclass
class TrueTargetResult:
    """outputs (R, T-1, n_dof): teacher-forced outputs of the trained network
    (noise off); motor_nrmse (R,) against the true commands; position_nrmse (R,)
    when a one-step position map was given, else None."""

    outputs: np.ndarray
    motor_nrmse: np.ndarray
    position_nrmse: np.ndarray | None


def teacher_forced_inputs(desired: np.ndarray) -> np.ndarray:
    """Inputs (T-1, 2 n_sig): [d(t+1); d(t)] for desired signals (T, n_sig)."""
    desired = np.asarray(desired, float)
    return np.concatenate([desired[1:], desired[:-1]], axis=1)


def train_true_target(
    esn: ESN,
    desired: np.ndarray,
    true_commands: np.ndarray,
    method: TrueTarget,
    *,
    noise: bool = True,
    one_step: Callable[[np.ndarray, np.ndarray], np.ndarray] | None = None,
    input_rngs: list[np.random.Generator] | None = None,
    extra_inputs: np.ndarray | None = None,
    rule: LearningRule | None = None,
) -> TrueTargetResult:
    """Fit ``esn`` (R runs) to the true commands with teacher forcing.

    Parameters
    ----------
    desired : (T, n_sig) desired signals.  true_commands : (T-1, n_dof).
    one_step : optional map (positions (T-1, n_sig), commands (R, T-1, n_dof)) ->
        next positions (R, T-1, n_sig), for the teacher-forced position error.
    method : :class:`~skinny_mj.controllers.methods.TrueTarget`: β, cycles, input noise.
    noise : reservoir noise on in the training cycles.
    input_rngs : one Generator per run for ``method.input_noise`` (needed when it is > 0).
    extra_inputs : optional (T-1, n_extra) teacher-forced inputs appended after
        [d(t+1); d(t)], as a rollout hook appends its own (the torque loop's desired
        velocities, :mod:`skinny_mj.controllers.torque_fel`).
    rule : the learning rule (:class:`skinny_mj.controllers.learning.LearningRule`): ``washout``
        after the washout cycle, ``fit`` after each cycle, with the blended true target
        (``y_est`` of its :class:`~skinny_mj.controllers.learning.Cycle`: the true commands).
        Default: :class:`~skinny_mj.controllers.learning.CycleFit` reusing the pinv factorization
        while the teacher-forced states repeat.
    """
    forced = teacher_forced_inputs(desired)
    if extra_inputs is not None:
        forced = np.concatenate([forced, np.asarray(extra_inputs, float)], axis=1)
    inputs = np.broadcast_to(forced, (esn.n_runs, *forced.shape))
    y_true = np.broadcast_to(true_commands, (esn.n_runs, *true_commands.shape))
    beta, cycles, input_noise = method.beta, method.fitted_cycles, method.input_noise
    clean = inputs
    if input_noise > 0 and (input_rngs is None or len(input_rngs) != esn.n_runs):
        raise ValueError("input noise needs one Generator per run (input_rngs)")

    def noisy() -> np.ndarray:  # fresh noise per cycle: the toolbox's noisy teacher forcing
        if input_noise == 0:
            return clean
        return clean + np.stack([g.normal(0.0, input_noise, clean.shape[1:])
                                 for g in input_rngs])

    rule = CycleFit(reuse_factors=True) if rule is None else rule
    runs = np.ones(esn.n_runs, bool)

    def handed(run: tuple[np.ndarray, np.ndarray]) -> Cycle:  # what a cycle hands the rule
        y_esn, states = run
        return Cycle(states, beta_target(y_true, y_esn, beta), runs, 0, y_true, y_esn)

    esn.reset()
    rule.washout(esn, handed(esn.run(noisy(), noise=noise)))
    for _ in range(cycles):
        rule.fit(esn, handed(esn.run(noisy(), noise=noise)))
    esn.reset()
    esn.run(inputs, noise=False)
    outputs, _ = esn.run(inputs, noise=False)
    position = None
    if one_step is not None:
        position = nrmse(one_step(desired[:-1], outputs), desired[1:])
    return TrueTargetResult(outputs, nrmse(outputs, true_commands), position)


def convergence_curve(
    esn: ESN, desired: np.ndarray, true_commands: np.ndarray, beta: float, cycles: int = 400
) -> np.ndarray:
    """NRMSE between y_used^i and y_true for each cycle i (R, cycles), with perfect
    targets and teacher forcing, noise off (paper E Fig. 3)."""
    inputs = np.broadcast_to(teacher_forced_inputs(desired), (esn.n_runs, len(desired) - 1,
                                                               2 * desired.shape[1]))
    y_true = np.broadcast_to(true_commands, (esn.n_runs, *true_commands.shape))
    curve = np.empty((esn.n_runs, cycles))
    esn.reset()
    esn.run(inputs, noise=False)
    fit, runs = CycleFit(reuse_factors=True), np.ones(esn.n_runs, bool)
    for i in range(cycles):
        y_esn, states = esn.run(inputs, noise=False)
        y_used = beta_target(y_true, y_esn, beta)
        curve[:, i] = nrmse(y_used, true_commands)
        fit.fit(esn, Cycle(states, y_used, runs, 0, y_true, y_esn))
    return curve


def cycles_to_converge(curve: np.ndarray, tolerance: float) -> np.ndarray:
    """First cycle index (R,) at which the curve (R, cycles) is below ``tolerance``
    (``cycles`` when it never is)."""
    below = np.asarray(curve) < tolerance
    return np.where(below.any(axis=1), below.argmax(axis=1), curve.shape[1])
