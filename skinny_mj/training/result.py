"""What one run produced, as types: :class:`RunResult` (the training's figures, the last
training rollout's figures, a test per movement, the torque figures, the failure, what an
observer saw), the tests a run is asked to take (:class:`Test`; :class:`Perform`, a
performance with the plant changed mid-run) and the :class:`Observer` that watches a
training while it runs.

:func:`skinny_mj.training.loop.train_batch` returns one :class:`RunResult` per seed; the
engine (:mod:`skinny_mj.engine.results`) writes it into a run file, and a study reads its
metrics off it as functions of the result (``lambda r: r.test.position_nrmse``).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any, Protocol

import numpy as np

from skinny_mj.controllers.esn import ESN
from skinny_mj.controllers.rollout import Rollout, run_mean
from skinny_mj.training.config import TrainConfig
from skinny_mj.training.imitation import ROBOT_METRICS, TORQUE_METRICS, robot_metrics

__all__ = ["Test", "STANDARD", "Perform", "Performance", "Observer", "TestOutcome",
           "TrainFigures", "RolloutFigures", "RunResult", "mean_abs_error", "feedback_share"]


@dataclass(frozen=True)
class Test:
    """A closed-loop test (K = ``test.gain``, no learning) the trained networks take.

    ``name``: the test's key in :attr:`RunResult.tests` (``""``: the standard test, one
    repetition of the training movement, whose failure fails the run); ``movement``: a
    function of the run's config giving the movement to test on (None: the training
    movement); ``overrides``: config keys changed for this test only (``{"test.noise":
    True}``); ``plant``: ``"fresh"`` (a new plant whose sensor noise restarts from the
    runs' plant seeds + ``plant_seed_offset``) or ``"training"`` (the training plant, its
    noise stream continuing).
    """

    name: str = ""
    movement: Callable[[TrainConfig], Any] | None = None
    overrides: Mapping[str, Any] = field(default_factory=dict)
    plant: str = "fresh"
    plant_seed_offset: int = 0

    def __post_init__(self) -> None:
        if self.plant not in ("fresh", "training"):
            raise ValueError(f"test {self.name!r}: plant must be 'fresh' or 'training', "
                             f"got {self.plant!r}")


#: The standard test alone: one repetition of the training movement on a fresh plant.
STANDARD = (Test(),)


@dataclass(frozen=True)
class Perform:
    """A test: after training, a performance with the plant changed mid-run
    (:mod:`skinny_mj.training.perform`); ``name``: its key in the run's tests (never
    ``""``, the standard test's)."""

    name: str
    cycles: int
    gain: float
    switch_cycle: int
    payload_kg: float = 0.0
    mass_scale: float = 1.0
    rls_forgetting: float | None = None
    rls_lambda: float = 1.0
    #: after every cycle, refit the readout on it by the training's own rule (method.fit,
    #: its statistics carried on from training), FEL's target at ``gain``; with
    #: ``refit_forgetting``, the forgetting rule's factor per cycle from then on
    refit: bool = False
    refit_forgetting: float | None = None

    def __post_init__(self) -> None:
        if not self.name or not 0 <= self.switch_cycle < self.cycles:
            raise ValueError(f"perform {self.name!r}: needs a name and a switch cycle in "
                             f"0..{self.cycles - 1}, got {self.switch_cycle}")
        if self.refit and self.rls_forgetting is not None:
            raise ValueError(f"perform {self.name!r}: learns by RLS or by refitting each "
                             "cycle, not both")


@dataclass
class Performance:
    """One run's performance: per cycle the position NRMSE and the joint-angle NRMSE
    (normalized angles; NaN from the cycle the run diverged in, or all of them when its
    training had), and whether it diverged while performing (or in training)."""

    position_nrmse: np.ndarray = field(repr=False)
    angle_nrmse: np.ndarray = field(repr=False)
    failed: bool


class Observer(Protocol):
    """Watches R lockstep runs train: FEL calls it after every cycle (cycle 0 the washout,
    1..C the learning cycles with ``y_used`` the fitted target, C + 1 the epoch's
    evaluation cycle with ``y_used`` None); ``observed(r)`` is what it saw of run r, kept
    in :attr:`RunResult.observed`. A study declares how to make one from the run's parts
    (``observe(run, row) -> Observer``); the true-target fit calls no observer."""

    def __call__(self, epoch: int, cycle: int, ro: Rollout, y_used: np.ndarray | None
                 ) -> None: ...

    def observed(self, r: int) -> Any: ...


@dataclass
class TestOutcome:
    """A closed-loop test (K = 0) of a trained network on one movement."""

    position_nrmse: float | None
    motor_nrmse: float | None
    failed: bool
    fail_reason: str | None
    rollout: Rollout = field(repr=False)
    trajectory: Any = field(repr=False)
    desired: np.ndarray = field(repr=False)
    true_commands: np.ndarray = field(repr=False)
    #: torque body: per-run torque figures and series (:func:`torque_training.test_torques`)
    torque: dict | None = field(default=None, repr=False)

    def robot_metrics(self, which: Any) -> dict[str, float]:
        """:func:`skinny_mj.training.imitation.robot_metrics` (joint error in degrees, hand
        error in cm, lag in s) of the produced joint angles of the body ``which`` against
        the movement's."""
        return robot_metrics(self.rollout.angles[0], self.trajectory.angles, which,
                             self.trajectory.dt)

    @property
    def torque_figures(self) -> dict | None:
        """The torque body's figures of this test (limits, |torque|, work, MuJoCo
        warnings), None on the velocity servo."""
        return None if self.torque is None else self.torque["metrics"]


@dataclass
class TrainFigures:
    """The training's figures of one run.

    ``kind``: ``"fel"`` (feedback-error learning: ``gains`` and the per-epoch evaluation
    curves ``position_nrmse`` / ``motor_nrmse``, None where the run had failed),
    ``"true-target"`` (the fit's ``motor_nrmse`` and ``position_nrmse``, floats) or
    ``"none"`` (nothing learned); ``extra``: the actuation's recorders and the readout
    rule's own figures (JSON-ready); ``failed`` / ``fail_reason`` / ``fail_epoch``: the
    training's divergence.
    """

    kind: str
    position_nrmse: Any = None
    motor_nrmse: Any = None
    gains: list[float] | None = None
    extra: dict[str, Any] = field(default_factory=dict)
    failed: bool = False
    fail_reason: str | None = None
    fail_epoch: int | None = None

    @property
    def last_position_nrmse(self) -> float | None:
        """The last epoch's evaluation position NRMSE (FEL), the fit's (true target)."""
        v = self.position_nrmse
        return v[-1] if isinstance(v, list) else v

    @property
    def last_motor_nrmse(self) -> float | None:
        v = self.motor_nrmse
        return v[-1] if isinstance(v, list) else v


def mean_abs_error(true_signals: np.ndarray, desired: np.ndarray) -> np.ndarray:
    """Mean |desired - actual| as a fraction of the signal range 2, (R,) for (R, T, n)."""
    return run_mean(np.abs(true_signals - desired)) / 2.0


def feedback_share(ro: Rollout) -> np.ndarray:
    """The feedback controller's share of the command, in [0, 1], (R,):
    mean |u_feedback| / (mean |u_feedback| + mean |y_ESN|), with u_feedback = command -
    y_ESN (the clipped K u_error). Unlike ``Rollout.correction_ratio`` (|u_feedback| /
    |u|, which exceeds 1 when the inverse model and the feedback controller push against
    each other) it reads directly as "the feedback controller's contribution in percent"."""
    fb, ff = run_mean(np.abs(ro.commands - ro.y_esn)), run_mean(np.abs(ro.y_esn))
    return fb / np.maximum(fb + ff, 1e-12)


@dataclass
class RolloutFigures:
    """The figures of FEL's last training rollout (the last epoch's evaluation cycle, the
    feedback controller on): ``mean_abs_error`` mean |desired − actual| / 2 (a fraction of
    the signal range); ``correction_ratio`` mean |u_fb| / mean |u|; ``feedback_share``
    |u_fb| / (|u_fb| + |y_ESN|) in [0, 1]; ``prediction_nrmse`` the forward model's
    prediction error (None without one)."""

    mean_abs_error: float
    correction_ratio: float
    feedback_share: float
    prediction_nrmse: float | None
    rollout: Rollout = field(repr=False)


@dataclass
class RunResult:
    """Everything one run of :func:`~skinny_mj.training.loop.train_batch` produced.

    ``tests``: the tests it took, by name (``""``: the standard test; a
    :class:`Perform`'s outcome: a :class:`Performance`); ``failed`` /
    ``fail_reason`` / ``fail_epoch``: the run's failure (the training's, then the standard
    test's, then the torque body's MuJoCo warnings: ``fail_stage`` says which);
    ``trajectory``: one repetition of the training movement; ``esn``: the trained network
    (one run); ``wall_s``: the lockstep batch's wall time / R, ``train_wall_s`` its
    training's share; ``observed``: what the study's :class:`Observer` saw of this run
    (None without one).
    """

    config: TrainConfig
    seed: int
    train: TrainFigures
    tests: dict[str, TestOutcome]
    failed: bool
    fail_reason: str | None
    fail_stage: str | None
    last_rollout: RolloutFigures | None
    pretrain_prediction_nrmse: float | None
    train_warnings: int | None
    steps_per_cycle: int
    max_speed_rad_s: np.ndarray = field(repr=False)
    clipped_samples: int = 0
    wall_s: float = 0.0
    train_wall_s: float = 0.0
    lockstep_runs: int = 1
    trajectory: Any = field(default=None, repr=False)
    esn: ESN | None = field(default=None, repr=False)
    observed: Any = field(default=None, repr=False)

    @property
    def test(self) -> TestOutcome:
        """The standard test (one repetition of the training movement)."""
        return self.tests[""]

    @property
    def fail_epoch(self) -> int | None:
        return self.train.fail_epoch if self.fail_stage == "train" else None

    def robot_figures(self) -> dict[str, Any]:
        """The standard test's figures in a roboticist's units, flat: the
        :data:`~skinny_mj.training.imitation.ROBOT_METRICS` and (torque body) the
        :data:`~skinny_mj.training.imitation.TORQUE_METRICS`; None where a figure is
        missing (a failed run)."""
        test = self.tests.get("")
        robot = {} if test is None or self.failed else \
            test.robot_metrics(self.config.plant.dof)
        out: dict[str, Any] = {k: robot.get(k) for k in ROBOT_METRICS}
        torque = None if test is None else test.torque_figures
        if torque is not None:
            out.update({k: torque.get(k) for k in TORQUE_METRICS})
        return out
