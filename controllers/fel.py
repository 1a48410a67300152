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
controller always sees the undelayed s(t). With ``inputs="sensed"`` (paper B) the
desired position is left out of the ESN's input: [s_in(t)] (+ p(t)).

One health check (:func:`health`) decides for training and testing alike whether a
run diverged; a diverged run is silenced (state and readout zero) and excluded from
every later fit, so it cannot poison its lockstep batch.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field, fields

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
#: What the inverse model sees besides the forward model's prediction: the desired next
#: position and the sensed one (papers A, C, D, E), or the sensed one only (paper B).
INPUTS = ("desired+sensed", "sensed")


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
    inputs: str = "desired+sensed"

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
        if self.inputs not in INPUTS:
            raise ValueError(f"inputs must be one of {INPUTS}, got {self.inputs!r}")
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


def run_mean(a: np.ndarray) -> np.ndarray:
    """Mean over every axis but the first, (R,), summed in the same order for every R.

    A rollout's arrays are (R, T, ...) views of time-major buffers; reducing such a view
    over several axes sums in another order than a single run's contiguous array, so a
    lockstep run would differ from its single run in the last bits. Made contiguous
    first (a no-op when R = 1), each run's sum is the single run's."""
    a = np.ascontiguousarray(a)
    return a.mean(axis=tuple(range(1, a.ndim)))


@dataclass
class Rollout:
    """One cycle of R runs. T = len(desired).

    commands (R, T-1, n_dof) as sent; y_esn (R, T-1, n_dof) ESN outputs;
    u_error (R, T, n_dof); sensed, true_signals (R, T, n_sig); angles (R, T, n_joints)
    the plant's joint angles, rad (n_joints = n_dof unless part of the body is forced,
    as paper B's leading arm); states (R, T-1, D) the inverse model's extended
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

    def select(self, r: int) -> Rollout:
        """Run ``r`` of a lockstep rollout (arrays keep R = 1; views, not copies)."""
        if self.commands.shape[0] == 1:
            return self
        return Rollout(**{f.name: None if getattr(self, f.name) is None
                          else getattr(self, f.name)[r:r + 1] for f in fields(self)})

    @property
    def y_est(self) -> np.ndarray:
        """Estimated target y_est(t) = command(t) + u_error(t+1), (R, T-1, n_dof)."""
        return self.commands + self.u_error[:, 1:]

    @property
    def correction_ratio(self) -> np.ndarray:
        """Online correction ratio per run (R,): mean |command - y_ESN| / mean |command|."""
        num = run_mean(np.abs(self.commands - self.y_esn))
        return num / np.maximum(run_mean(np.abs(self.commands)), 1e-12)


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
    inputs: str = "desired+sensed",
) -> Rollout:
    """Run one cycle: plant reset to the first pose, ESN state carried on.

    Parameters
    ----------
    desired : (T, n_sig) desired position signals, normalized.
    gain : K, scalar or (R,).
    noise : reservoir noise on (washout/learning) or off (evaluation/test).
    forward : optional :class:`controllers.forward_model.ForwardModel`, whose
        prediction p(t) is appended to the inverse model's input.
    inputs : "desired+sensed" (ESN input [d(t+1); s_in(t)]) or "sensed" ([s_in(t)]);
        the forward model's p(t) is appended in both cases.
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
    if inputs not in INPUTS:
        raise ValueError(f"inputs must be one of {INPUTS}, got {inputs!r}")
    if plant.n_runs != n_runs:
        raise ValueError(f"{n_runs} networks for {plant.n_runs} plant runs")
    n_sig, n_dof = plant.n_signals, plant.n_dof
    n_des = desired.shape[1] if inputs == "desired+sensed" else 0
    sensed = array("sensed", (n_steps, n_runs, n_sig))
    true = array("true", (n_steps, n_runs, n_sig))
    first = plant.reset()
    angles0 = plant.joint_angles()  # the whole body's: more than n_dof when part is forced
    angles = array("angles", (n_steps, n_runs, angles0.shape[1]))
    u_error = array("u_error", (n_steps, n_runs, n_dof))
    commands = array("commands", (n_steps - 1, n_runs, n_dof))
    y_esn = array("y_esn", (n_steps - 1, n_runs, n_dof))
    states = array("states", (n_steps - 1, n_runs, esn.cfg.n_extended), esn.dtype)
    fm_states = None if forward is None else array(
        "fm_states", (n_steps - 1, n_runs, forward.esn.cfg.n_extended))
    predictions = None if forward is None else array("predictions", (n_steps, n_runs, n_sig))
    sensed[0] = first
    true[0] = plant.true_signals()
    angles[0] = angles0
    if forward is not None:
        predictions[0] = sensed[0]
    u_in = np.empty((n_runs, n_des + n_sig * (1 if forward is None else 2)))
    for t in range(n_steps - 1):
        s_in = sensed[max(t - delay_steps, 0)]
        if n_des:
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


def health(esn: ESN, ro: Rollout) -> list[str | None]:
    """Per run: None if the run is healthy after the cycle ``ro``, else why it diverged
    (the ESN's own check: non-finite or saturated reservoir or readout; or non-finite
    ESN outputs or commands). The one check every training and test uses."""
    reasons = esn.diverged()
    for r in range(esn.n_runs):
        if reasons[r] is None and not (np.all(np.isfinite(ro.commands[r]))
                                       and np.all(np.isfinite(ro.y_esn[r]))):
            reasons[r] = "non-finite ESN output or command"
    return reasons


def _mark_failures(esn: ESN, ro: Rollout, result: TrainResult, epoch: int) -> None:
    for r, reason in enumerate(health(esn, ro)):
        if reason is not None and not result.failed[r]:
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
    scored: np.ndarray | None = None,
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
    scored : indices of the signals the position curve scores (default all; paper B
        scores the lagging arm's only).
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
          "buffers": {}, "inputs": cfg.inputs}
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
        result.position_nrmse[alive, epoch] = _scored_nrmse(ro, desired, scored)[alive]
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
    *,
    inputs: str = "desired+sensed",
    washout_cycles: int = 0,
    scored: np.ndarray | None = None,
) -> EvalResult:
    """Test: reset, ``washout_cycles`` cycles without scoring (papers B, C: one
    "initialization cycle"), then one scored cycle; K = 0, no noise, no learning."""
    if washout_cycles < 0:
        raise ValueError(f"washout cycles must be >= 0, got {washout_cycles}")
    esn.reset()
    if forward is not None:
        forward.esn.reset()
    kw = {"noise": False, "delay_steps": delay_steps, "forward": forward, "inputs": inputs}
    for _ in range(washout_cycles):
        rollout(esn, plant, desired, 0.0, **kw)
    ro = rollout(esn, plant, desired, 0.0, **kw)
    reasons = health(esn, ro)
    failed = np.array([r is not None for r in reasons])
    pos = np.where(failed, np.nan, _scored_nrmse(ro, desired, scored))
    mot = np.full(esn.n_runs, np.nan)
    if true_commands is not None:
        mot = np.where(failed, np.nan, motor_nrmse(ro.commands, true_commands))
    return EvalResult(pos, mot, failed, reasons, ro)


def _scored_nrmse(ro: Rollout, desired: np.ndarray, scored: np.ndarray | None) -> np.ndarray:
    """Position NRMSE (R,) of the noise-free signals, over the ``scored`` ones (or all)."""
    if scored is None:
        return position_nrmse(ro.true_signals, desired)
    return position_nrmse(ro.true_signals[:, :, scored], desired[:, scored])


def _tick(progress: Callable[[int, int], None] | None, epoch: int, cycle: int) -> None:
    if progress is not None:
        progress(epoch, cycle)
