"""Feedback-error learning (FEL), original and new (beta) method, vectorized over R runs.

Epoch (SPEC §3/§5, paper E §4.2): reset the ESN state to 0; one washout cycle (no
learning, reservoir noise on, feedback on); ``learning_cycles`` cycles that each refit
the readout; one evaluation cycle (feedback on, no learning, noise off) whose position
NRMSE is the training curve. Every cycle resets the plant to the first pose and runs
the whole desired sequence; the ESN state carries over between the cycles of an epoch.
Testing: reset, one cycle with K = 0, no noise, no learning.

Step t (t = 0 .. T-2): sense s(t); ESN input [d(t+1); s_in(t)] (+ the forward model's
prediction p(t)); u_error(t) from (d(t), s(t)); command = clip(y_ESN + K u_error, -1, 1);
step the plant. After the cycle: y_est(t) = command(t) + u_error(t+1), and the readout
is fitted to y_used = beta y_est + (1 - beta) y_ESN (beta = 1: the original method).
``s_in`` is the sensed signal delayed by ``delay_steps`` (paper A); the feedback
controller always sees the undelayed s(t).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from controllers.esn import ESN
from controllers.feedback import (
    FeedbackController,
    fixed_gain,
    linear_gain,
    multiplicative_gain,
)
from controllers.metrics import motor_nrmse, position_nrmse
from controllers.plant import Plant

_METHODS = ("original", "new")
_SCHEDULES = ("linear", "multiplicative", "fixed")


@dataclass(frozen=True)
class FELConfig:
    """Training schedule. Defaults: paper E experiment 5 (new method, beta 0.1, 3 cycles)."""

    method: str = "new"
    beta: float = 0.1
    learning_cycles: int = 3
    epochs: int = 10
    gain_schedule: str = "linear"
    gain_factor: float = 0.9  # multiplicative schedule
    gain_value: float = 0.65  # fixed schedule
    delay_steps: int = 0

    def __post_init__(self) -> None:
        if self.method not in _METHODS:
            raise ValueError(f"method must be one of {_METHODS}, got {self.method!r}")
        if not 0 < self.beta <= 1:
            raise ValueError(f"beta must be in (0, 1], got {self.beta}")
        if self.learning_cycles < 1:
            raise ValueError(f"learning cycles must be >= 1, got {self.learning_cycles}")
        if self.gain_schedule not in _SCHEDULES:
            raise ValueError(f"gain schedule must be one of {_SCHEDULES}, got "
                             f"{self.gain_schedule!r}")
        if self.delay_steps < 0:
            raise ValueError(f"delay must be >= 0 steps, got {self.delay_steps}")
        self.gains()  # validates epochs and the schedule's parameters

    @property
    def effective_beta(self) -> float:
        """beta actually used: 1 for the original method."""
        return 1.0 if self.method == "original" else self.beta

    def gains(self) -> np.ndarray:
        """Feedback gain K per epoch, (epochs,)."""
        if self.gain_schedule == "linear":
            return linear_gain(self.epochs)
        if self.gain_schedule == "multiplicative":
            return multiplicative_gain(self.epochs, self.gain_factor)
        return fixed_gain(self.epochs, self.gain_value)


@dataclass(frozen=True)
class PaperERow:
    """One row of paper E's Table 1 with SPEC §5's defaults."""

    fel: FELConfig
    repetitions: int
    noise_level: float


PAPER_E: dict[int, PaperERow] = {
    1: PaperERow(FELConfig("original", 1.0, 1), 1, 0.03),
    2: PaperERow(FELConfig("original", 1.0, 1), 5, 0.03),
    3: PaperERow(FELConfig("original", 1.0, 1), 10, 0.03),
    4: PaperERow(FELConfig("new", 0.3, 2), 1, 0.2),
    5: PaperERow(FELConfig("new", 0.1, 3), 1, 0.2),
    6: PaperERow(FELConfig("new", 0.05, 6), 1, 0.2),
}


@dataclass
class Rollout:
    """One cycle of R runs. T = len(desired).

    commands (R, T-1, n_dof) as sent; y_esn (R, T-1, n_dof) ESN outputs;
    u_error (R, T, n_dof); sensed, true_signals (R, T, n_sig); angles (R, T, n_dof)
    the plant's joint angles, rad; states (R, T-1, D) the inverse model's extended
    states; fm_states (R, T-1, D_fm) or None;
    predictions (R, T, n_sig) the forward model's p(t) or None.
    """

    commands: np.ndarray
    y_esn: np.ndarray
    u_error: np.ndarray
    sensed: np.ndarray
    true_signals: np.ndarray
    angles: np.ndarray
    states: np.ndarray
    fm_states: np.ndarray | None = None
    predictions: np.ndarray | None = None

    @property
    def y_est(self) -> np.ndarray:
        """Estimated target y_est(t) = command(t) + u_error(t+1), (R, T-1, n_dof)."""
        return self.commands + self.u_error[:, 1:]

    @property
    def correction_ratio(self) -> np.ndarray:
        """Online correction ratio per run (R,): mean |command - y_ESN| / mean |command|."""
        num = np.abs(self.commands - self.y_esn).mean(axis=(1, 2))
        return num / np.maximum(np.abs(self.commands).mean(axis=(1, 2)), 1e-12)


def rollout(
    esn: ESN,
    plant: Plant,
    desired: np.ndarray,
    gain: float | np.ndarray,
    *,
    noise: bool = True,
    feedback: FeedbackController | None = None,
    delay_steps: int = 0,
    forward=None,
    buffers: dict | None = None,
) -> Rollout:
    """Run one cycle: plant reset to the first pose, ESN state carried on.

    Parameters
    ----------
    desired : (T, n_sig) desired position signals, normalized.
    gain : K, scalar or (R,).
    noise : reservoir noise on (washout/learning) or off (evaluation/test).
    forward : optional :class:`controllers.forward_model.ForwardModel`, whose
        prediction p(t) is appended to the inverse model's input.
    buffers : optional dict the rollout keeps its arrays in and reuses on the next call
        with the same dict (fresh pages of a few MB per rollout cost about as much as
        the control step); the returned Rollout's arrays are then views that the next
        such call overwrites. :func:`train` passes one per training.
    """
    feedback = feedback or FeedbackController()

    def array(name: str, shape: tuple[int, ...], dtype=np.float64) -> np.ndarray:
        if buffers is None:
            return np.empty(shape, dtype)
        out = buffers.get(name)
        if out is None or out.shape != shape or out.dtype != dtype:
            out = buffers[name] = np.empty(shape, dtype)
        return out

    desired = np.asarray(desired, float)
    n_steps, n_runs = desired.shape[0], esn.n_runs
    gain = np.broadcast_to(np.asarray(gain, float), (n_runs,))[:, None]
    # Time-major buffers (T, R, ...): each step writes contiguous rows, not R rows a
    # whole movement apart (scattered first touches of fresh pages cost more than the
    # writes). The Rollout holds their (R, T, ...) views.
    n_des, n_sig, n_dof = desired.shape[1], plant.n_signals, plant.n_dof
    sensed = array("sensed", (n_steps, n_runs, n_sig))
    true = array("true", (n_steps, n_runs, n_sig))
    angles = array("angles", (n_steps, n_runs, n_dof))
    u_error = array("u_error", (n_steps, n_runs, n_dof))
    commands = array("commands", (n_steps - 1, n_runs, n_dof))
    y_esn = array("y_esn", (n_steps - 1, n_runs, n_dof))
    states = array("states", (n_steps - 1, n_runs, esn.cfg.n_extended), esn.dtype)
    fm_states = None if forward is None else array(
        "fm_states", (n_steps - 1, n_runs, forward.esn.cfg.n_extended))
    predictions = None if forward is None else array("predictions", (n_steps, n_runs, n_sig))
    sensed[0] = plant.reset()
    true[0] = plant.true_signals()
    angles[0] = plant.joint_angles()
    if forward is not None:
        predictions[0] = sensed[0]
    u_in = np.empty((n_runs, n_des + n_sig * (1 if forward is None else 2)))
    for t in range(n_steps - 1):
        s_in = sensed[max(t - delay_steps, 0)]
        u_in[:, :n_des] = desired[t + 1]  # the ESN's input [d(t+1); s(t); p(t)]
        u_in[:, n_des:n_des + n_sig] = s_in
        if forward is not None:
            u_in[:, n_des + n_sig:] = predictions[t]
        y_esn[t] = esn.step(u_in, noise=noise, out_extended=states[t])
        u_error[t] = feedback.u_error(desired[t], sensed[t], plant)
        command = commands[t]  # clip(y_esn + K u_error), in place
        np.multiply(gain, u_error[t], out=command)
        command += y_esn[t]
        np.maximum(command, -1.0, out=command)  # np.clip, without its Python wrapper
        np.minimum(command, 1.0, out=command)
        if forward is not None:
            predictions[t + 1] = forward.step(s_in, command, noise=noise)
            fm_states[t] = forward.esn.extended
        sensed[t + 1] = plant.step(command)
        true[t + 1] = plant.true_signals()
        angles[t + 1] = plant.joint_angles()
    u_error[-1] = feedback.u_error(desired[-1], sensed[-1], plant)
    return Rollout(*(None if a is None else np.swapaxes(a, 0, 1) for a in (
        commands, y_esn, u_error, sensed, true, angles, states, fm_states, predictions)))


@dataclass
class TrainResult:
    """Per-epoch evaluation curve and per-run failures.

    position_nrmse, motor_nrmse : (R, E), NaN after a run failed (motor: all NaN
    without true commands). gains : (E,). failed : (R,) bool. fail_reason : per run.
    """

    position_nrmse: np.ndarray
    motor_nrmse: np.ndarray
    gains: np.ndarray
    failed: np.ndarray
    fail_reason: list[str | None]
    fail_epoch: list[int | None]
    last_rollout: Rollout | None = field(default=None, repr=False)

    def to_dict(self) -> dict:
        """JSON-ready (failed entries and missing metrics become None, never NaN)."""
        def clean(a: np.ndarray) -> list:
            return [[None if not np.isfinite(v) else float(v) for v in row] for row in a]
        return {
            "gains": [float(k) for k in self.gains],
            "position_nrmse": clean(self.position_nrmse),
            "motor_nrmse": clean(self.motor_nrmse),
            "failed": [bool(f) for f in self.failed],
            "fail_reason": list(self.fail_reason),
            "fail_epoch": list(self.fail_epoch),
        }


def _mark_failures(esn: ESN, ro: Rollout, result: TrainResult, epoch: int) -> None:
    reasons = esn.diverged()
    for r in range(esn.n_runs):
        if result.failed[r]:
            continue
        reason = reasons[r]
        if reason is None and not (np.all(np.isfinite(ro.commands[r]))
                                   and np.all(np.isfinite(ro.y_esn[r]))):
            reason = "non-finite ESN output or command"
        if reason is not None:
            result.failed[r], result.fail_reason[r], result.fail_epoch[r] = True, reason, epoch
    # Silence failed runs so they cannot poison the batch (they stay excluded from fits).
    esn.x[result.failed] = 0.0
    esn.W_out[result.failed] = 0.0


def train(
    esn: ESN,
    plant: Plant,
    desired: np.ndarray,
    cfg: FELConfig,
    true_commands: np.ndarray | None = None,
    progress: Callable[[int, int], None] | None = None,
    feedback: FeedbackController | None = None,
    forward=None,
) -> TrainResult:
    """Train the inverse model ``esn`` (R runs) by FEL on ``plant``.

    Parameters
    ----------
    desired : (T, n_sig) desired signals (repetitions already concatenated).
    true_commands : (T-1, n_dof) analytic commands, for the motor-error curve.
    progress : called as progress(epoch, cycle) after every cycle
        (cycle 0 = washout, 1..C learning, C+1 evaluation).
    forward : optional forward model; trained on every learning cycle unless
        its ``mode`` is "serial".
    """
    gains = cfg.gains()
    n_runs, n_epochs = esn.n_runs, cfg.epochs
    result = TrainResult(
        position_nrmse=np.full((n_runs, n_epochs), np.nan),
        motor_nrmse=np.full((n_runs, n_epochs), np.nan),
        gains=gains, failed=np.zeros(n_runs, bool),
        fail_reason=[None] * n_runs, fail_epoch=[None] * n_runs,
    )
    beta = cfg.effective_beta
    # one set of rollout arrays for the whole training: each rollout is used (fit,
    # metrics) before the next overwrites it, and the last one is the last evaluation
    kw = {"feedback": feedback, "delay_steps": cfg.delay_steps, "forward": forward,
          "buffers": {}}
    for epoch, gain in enumerate(gains):
        esn.reset()
        if forward is not None:
            forward.esn.reset()
        ro = rollout(esn, plant, desired, gain, noise=True, **kw)
        _mark_failures(esn, ro, result, epoch)
        _tick(progress, epoch, 0)
        for cycle in range(1, cfg.learning_cycles + 1):
            ro = rollout(esn, plant, desired, gain, noise=True, **kw)
            _mark_failures(esn, ro, result, epoch)
            alive = ~result.failed
            esn.fit(ro.states, beta * ro.y_est + (1.0 - beta) * ro.y_esn, runs=alive)
            if forward is not None and forward.mode != "serial":
                forward.fit_rollout(ro, runs=alive)
            _tick(progress, epoch, cycle)
        ro = rollout(esn, plant, desired, gain, noise=False, **kw)
        _mark_failures(esn, ro, result, epoch)
        alive = ~result.failed
        result.position_nrmse[alive, epoch] = position_nrmse(ro.true_signals, desired)[alive]
        if true_commands is not None:
            result.motor_nrmse[alive, epoch] = motor_nrmse(ro.commands, true_commands)[alive]
        result.last_rollout = ro
        _tick(progress, epoch, cfg.learning_cycles + 1)
    return result


@dataclass
class EvalResult:
    """Closed-loop test (K = 0): position/motor NRMSE (R,) (NaN where failed)."""

    position_nrmse: np.ndarray
    motor_nrmse: np.ndarray
    failed: np.ndarray
    fail_reason: list[str | None]
    rollout: Rollout = field(repr=False)


def evaluate(
    esn: ESN,
    plant: Plant,
    desired: np.ndarray,
    true_commands: np.ndarray | None = None,
    delay_steps: int = 0,
    forward=None,
) -> EvalResult:
    """Reset, one cycle with K = 0, no noise, no learning."""
    esn.reset()
    if forward is not None:
        forward.esn.reset()
    ro = rollout(esn, plant, desired, 0.0, noise=False, delay_steps=delay_steps, forward=forward)
    reasons = esn.diverged()
    failed = np.array([r is not None for r in reasons])
    pos = np.where(failed, np.nan, position_nrmse(ro.true_signals, desired))
    mot = np.full(esn.n_runs, np.nan)
    if true_commands is not None:
        mot = np.where(failed, np.nan, motor_nrmse(ro.commands, true_commands))
    return EvalResult(pos, mot, failed, reasons, ro)



def _tick(progress: Callable[[int, int], None] | None, epoch: int, cycle: int) -> None:
    if progress is not None:
        progress(epoch, cycle)
