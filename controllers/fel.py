"""Feedback-error learning (FEL), original and new (beta) method, vectorized over R runs.

Epoch (SPEC §3/§5, paper E §4.2): reset the ESN state to 0; one washout cycle (no
learning, reservoir noise on, feedback on); ``learning_cycles`` cycles that each refit
the readout; one evaluation cycle (feedback on, no learning, noise off) whose position
NRMSE is the training curve. Every cycle resets the plant to the first pose and runs
the whole desired sequence; the ESN state carries over between the cycles of an epoch.
Testing: reset, one cycle with K = 0, no noise, no learning.

Step t (t = 0 .. T-2): sense s(t); ESN input [d(t+1); s_in(t)] (+ the forward model's
prediction p(t)); u_error(t) from (d(t), s(t)); command = clip(y_ESN + K u_error, -1, 1);
step the plant. After the cycle: y_est(t) = command(t) + u_error(t+1), and the learning
rule (:mod:`skinny_mj.controllers.learning`; default the thesis's fit of each cycle alone) fits the
readout to y_used = beta y_est + (1 - beta) y_ESN (beta = 1: the original method).
``s_in`` is the sensed signal delayed by ``delay_steps`` (paper A); the feedback
controller always sees the undelayed s(t). With ``inputs="sensed"`` (paper B) the
desired position is left out of the ESN's input: [s_in(t)] (+ p(t)).

The parts: the method (:class:`~skinny_mj.controllers.methods.Original` or
:class:`~skinny_mj.controllers.methods.New`: epochs, K per epoch, learning cycles, β), the
:class:`~skinny_mj.controllers.loop.Loop` (inputs, feedback or hook, forward model, delay,
learning rule), the :class:`Task` (desired signals, true commands, scored signals) and the
:class:`Test`.

One health check (:func:`health`) decides for training and testing alike whether a
run diverged; a diverged run is silenced (state and readout zero) and excluded from
every later fit, so it cannot poison its lockstep batch.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np
from skinny_mj.controllers.esn import ESN
from skinny_mj.controllers.learning import Cycle, CycleFit, beta_target
from skinny_mj.controllers.loop import INPUTS, Loop
from skinny_mj.controllers.methods import FELMethod, New, Original
from skinny_mj.controllers.metrics import motor_nrmse, position_nrmse
from skinny_mj.controllers.plant import Plant
from skinny_mj.controllers.rollout import DEFAULT_LOOP, Rollout, rollout, run_mean

__all__ = ["INPUTS", "Loop", "Original", "New", "FELMethod", "Task", "Test", "Rollout",
           "rollout", "run_mean", "health", "train", "TrainResult", "evaluate", "EvalResult",
           "beta_target", "learning_cycle"]

#: FEL's observer: ``observe(epoch, cycle, ro, y_used)`` after every cycle
Observer = Callable[[int, int, Rollout, "np.ndarray | None"], None]


@dataclass(frozen=True)
class Task:
    """The movement to track and how a cycle is scored.

    desired : (T, n_sig) desired signals (repetitions already concatenated).
    true_commands : (T-1, n_dof) analytic commands, for the motor error; None: no motor
        error.
    scored : indices of the signals the position error scores (None: all; paper B
        scores the lagging arm's only).
    """

    desired: np.ndarray
    true_commands: np.ndarray | None = None
    scored: np.ndarray | None = None

    @classmethod
    def of(cls, task: Task | np.ndarray) -> Task:
        """``task`` as a :class:`Task` (an array: the desired signals alone)."""
        return task if isinstance(task, Task) else cls(np.asarray(task, float))


@dataclass(frozen=True)
class Test:
    """A closed-loop test: ``washout_cycles`` unscored cycles (papers B, C: one
    "initialization cycle"), then one scored cycle, no learning, feedback gain ``gain``
    (K = 0: the inverse model alone; > 0: the feedback left on); ``noise``: reservoir
    noise on, as the thesis's toolbox ran its tests."""

    __test__: ClassVar[bool] = False  # not a pytest test class
    gain: float = 0.0
    washout_cycles: int = 0
    noise: bool = False

    def __post_init__(self) -> None:
        if not (isinstance(self.gain, int | float) and math.isfinite(self.gain)
                and self.gain >= 0):
            raise ValueError(f"test gain must be >= 0, got {self.gain}")
        if not (isinstance(self.washout_cycles, int) and self.washout_cycles >= 0):
            raise ValueError(f"test washout cycles must be >= 0, got {self.washout_cycles}")


#: the thesis's test: K = 0, no washout, no reservoir noise
DEFAULT_TEST = Test()


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


def learning_cycle(ro: Rollout, beta: float, runs: np.ndarray, epoch: int = 0,
                   lead: int = 0) -> Cycle:
    """What a learning cycle ``ro`` hands the rule: FEL's target (the error ``lead`` steps
    later, :meth:`Rollout.targets`) blended with the networks' output by ``beta``, for the
    runs ``runs``."""
    y_est = ro.targets(lead)
    return Cycle(ro.states, beta_target(y_est, ro.y_esn, beta), runs, epoch, y_est, ro.y_esn)


def train(
    esn: ESN,
    plant: Plant,
    task: Task | np.ndarray,
    method: FELMethod,
    loop: Loop = DEFAULT_LOOP,
    *,
    observe: Observer | None = None,
) -> TrainResult:
    """Train the inverse model ``esn`` (R runs) by FEL on ``plant``.

    Parameters
    ----------
    task : the :class:`Task` (or its desired signals alone, (T, n_sig)).
    method : :class:`~skinny_mj.controllers.methods.Original` or
        :class:`~skinny_mj.controllers.methods.New`: epochs, gains, learning cycles, β.
    loop : the :class:`~skinny_mj.controllers.loop.Loop`; a forward model in it is trained
        on every learning cycle unless its ``mode`` is "serial". Its ``rule`` is the
        learning rule (:class:`skinny_mj.controllers.learning.LearningRule`; None:
        :class:`~skinny_mj.controllers.learning.CycleFit`, each learning cycle's fit alone by
        ``esn.fit``, the thesis's). The rule gets a
        :class:`~skinny_mj.controllers.learning.Cycle` (states, y_used, y_est, y_ESN, the
        runs alive, the epoch) through ``rule.washout(esn, cycle)`` after each washout
        cycle and ``rule.fit(esn, cycle)`` after each learning cycle; an online rule
        (``rule.online``) is also the learning cycles' per-step ``online`` learner (its
        per-step target is blended with its own beta; the loop's own ``online`` is not
        used). Others: :class:`skinny_mj.controllers.ridge_select.RidgeSelector` (lambda per
        run on a validation cycle), :class:`skinny_mj.controllers.torque_readout.
        ForgettingReadout` and :class:`~skinny_mj.controllers.torque_readout.RLSReadout`
        (fits that remember earlier cycles), :class:`skinny_mj.controllers.online.OnlineRLS`
        (RLS at every step).
    observe : optional callback (progress, diagnostics: paper E §5.1), called after every
        cycle as ``observe(epoch, cycle, ro, y_used)`` (cycle 0 = washout, 1..C learning,
        C+1 evaluation); ``y_used`` (R, T-1, n_dof) is the target the readout was fitted
        to on a learning cycle, None on the washout and evaluation cycles. ``ro``'s arrays
        are reused by the next cycle: copy what you keep. It must not change ``esn`` or
        ``ro``.
    """
    task = Task.of(task)
    desired, forward = task.desired, loop.forward
    gains = method.gains()
    n_runs, n_epochs, n_cycles = esn.n_runs, method.epochs, method.learning_cycles
    result = TrainResult(
        position_nrmse=np.full((n_runs, n_epochs), np.nan),
        motor_nrmse=np.full((n_runs, n_epochs), np.nan),
        gains=gains, failed=np.zeros(n_runs, bool),
        fail_reason=[None] * n_runs, fail_epoch=[None] * n_runs,
    )
    beta, rule = method.beta, CycleFit() if loop.rule is None else loop.rule
    # one set of rollout arrays for the whole training: each rollout is used (fit,
    # metrics) before the next overwrites it, and the last one is the last evaluation
    loop = dataclasses.replace(loop, online=None, buffers={})
    learning = loop.learning(rule if rule.online else None)

    def handed(ro: Rollout, epoch: int) -> Cycle:  # what the cycle hands the rule
        return learning_cycle(ro, beta, ~result.failed, epoch, loop.target_lead)

    for epoch, gain in enumerate(gains):
        esn.reset()
        if forward is not None:
            forward.esn.reset()
        ro = rollout(esn, plant, desired, gain, loop, noise=True)
        _mark_failures(esn, ro, result, epoch)
        rule.washout(esn, handed(ro, epoch))
        if observe is not None:
            observe(epoch, 0, ro, None)
        for cycle in range(1, n_cycles + 1):
            ro = rollout(esn, plant, desired, gain, learning, noise=True)
            _mark_failures(esn, ro, result, epoch)
            learned = handed(ro, epoch)
            rule.fit(esn, learned)
            if forward is not None and forward.mode != "serial":
                forward.fit_rollout(ro, runs=learned.runs)
            if observe is not None:
                observe(epoch, cycle, ro, learned.target)
        ro = rollout(esn, plant, desired, gain, loop, noise=False)
        _mark_failures(esn, ro, result, epoch)
        alive = ~result.failed
        result.position_nrmse[alive, epoch] = _scored_nrmse(ro, task)[alive]
        if task.true_commands is not None:
            result.motor_nrmse[alive, epoch] = motor_nrmse(ro.commands,
                                                           task.true_commands)[alive]
        result.last_rollout = ro
        if observe is not None:
            observe(epoch, n_cycles + 1, ro, None)
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
    task: Task | np.ndarray,
    loop: Loop = DEFAULT_LOOP,
    test: Test = DEFAULT_TEST,
) -> EvalResult:
    """Test: reset, ``test.washout_cycles`` cycles without scoring, then one scored cycle
    of ``loop`` with feedback gain ``test.gain``; no learning (``loop.online`` is not
    used); reservoir noise only with ``test.noise``."""
    task = Task.of(task)
    desired, true_commands = task.desired, task.true_commands
    esn.reset()
    if loop.forward is not None:
        loop.forward.esn.reset()
    loop = loop.learning(None)
    for _ in range(test.washout_cycles):
        rollout(esn, plant, desired, test.gain, loop, noise=test.noise)
    ro = rollout(esn, plant, desired, test.gain, loop, noise=test.noise)
    reasons = health(esn, ro)
    failed = np.array([r is not None for r in reasons])
    pos = np.where(failed, np.nan, _scored_nrmse(ro, task))
    mot = np.full(esn.n_runs, np.nan)
    if true_commands is not None:
        mot = np.where(failed, np.nan, motor_nrmse(ro.commands, true_commands))
    return EvalResult(pos, mot, failed, reasons, ro)


def _scored_nrmse(ro: Rollout, task: Task) -> np.ndarray:
    """Position NRMSE (R,) of the noise-free signals, over the ``scored`` ones (or all)."""
    if task.scored is None:
        return position_nrmse(ro.true_signals, task.desired)
    return position_nrmse(ro.true_signals[:, :, task.scored], task.desired[:, task.scored])
