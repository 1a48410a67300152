"""The one training path: build a run's parts from a :class:`TrainConfig`, train, test.

Every experiment and command goes through these functions:

- :func:`build_run` (``cfg``, R seeds) -> :class:`Run`: the movement, the full-scale
  speeds, the seed streams, the ESN inverse model (R networks in lockstep), the
  optional forward model, the desired signals and true commands, and the plant
  (built when first used: one :class:`skinny_mj.plant.adapters.BatchPlant` for all R runs,
  paper B's :class:`skinny_mj.plant.bimanual.BimanualPlant`, or the dm_control env);
- :func:`train_run`: forward-model pre-training (:meth:`ForwardModel.pretrain`), then
  feedback-error learning (:func:`skinny_mj.controllers.fel.train`, original or β) or the
  true-target architecture (:func:`skinny_mj.controllers.true_target.train_true_target`);
- :func:`evaluate`: the test (:func:`skinny_mj.controllers.fel.evaluate`, K = 0) on any movement;
- :func:`train_batch` / :func:`train`: the three together, one
  :class:`~skinny_mj.training.result.RunResult` per seed (papers D, E and the ``skinny
  train`` command).

Seeds: a run's seed s spawns three streams, ``SeedSequence(s).spawn(3)``: the inverse
ESN's Generator (weights, then reservoir noise), the plant's sensor-noise seed, and the
forward ESN's Generator (weights, pre-training sensor noise, reservoir noise). So a
run is reproduced from (config, seed) alone, whichever plant path and batch runs it.
"""

from __future__ import annotations

import dataclasses
import functools
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from skinny_mj.controllers import fel
from skinny_mj.controllers.esn import ESN
from skinny_mj.controllers.feedback import FeedbackController
from skinny_mj.controllers.forward_model import ForwardModel, rollout_prediction_error
from skinny_mj.controllers.loop import Loop
from skinny_mj.controllers.true_target import train_true_target
from skinny_mj.plant.bimanual import arm_signals
from skinny_mj.threads import single_threaded
from skinny_mj.training import protocol
from skinny_mj.training.actuation import Actuation, actuation_of
from skinny_mj.training.config import (  # noqa: F401  (re-exported: the training API in one place)
    DEFAULT_NOISE,
    METHODS,
    PAPER_CYCLES_FOR_BETA,
    Forward,
    NoLearning,
    Torque,
    TrainConfig,
    TrueTarget,
    relative_cost,
)
from skinny_mj.training.fits import make_rule
from skinny_mj.training.parts import (  # noqa: F401  (re-exported)
    RunStreams,
    arm_forward_models,
    controlled_dofs,
    full_scale_speeds,
    lagging_arm,
    load_trajectory,
    make_plant,
    network_sizes,
    run_streams,
    true_commands_of,
)
from skinny_mj.training.perform import perform
from skinny_mj.training.result import (  # noqa: F401  (re-exported)
    STANDARD,
    Observer,
    Perform,
    RolloutFigures,
    RunResult,
    Test,
    TestOutcome,
    TrainFigures,
    feedback_share,
    mean_abs_error,
)
from skinny_mj.training.torque import teacher_lag


@dataclass
class Run:
    """The parts of R runs of one config, built by :func:`build_run`.

    trajectory : one repetition (the test movement by default); training : the
    repeated movement the training cycles run; desired (T, n_sig) / true_commands
    (T-1, n_out) of ``training``; max_speed_rad_s (n_dof,) full scale; esn : R
    inverse networks; forward : R forward networks or None; plant_seeds : (R,).
    """

    cfg: TrainConfig
    seeds: list[int]
    trajectory: Any
    training: Any
    report: Any
    max_speed_rad_s: np.ndarray
    esn: ESN
    forward: ForwardModel | None
    plant_seeds: list[int]
    desired: np.ndarray
    true_commands: np.ndarray

    @functools.cached_property
    def plant(self):
        """The training plant (built on first use: Fig. 3-style runs never need it)."""
        plant = make_plant(self.cfg, self.training, self.plant_seeds, self.max_speed_rad_s)
        self.actuation.training_plant(plant)
        return plant

    @property
    def scored(self) -> np.ndarray | None:
        """Signals the position metrics score: all (None), or paper B's lagging arm's."""
        plant = self.cfg.plant
        if plant.leading_arm is None:
            return None

        return arm_signals(plant.body, plant.signals, lagging_arm(self.cfg))

    @functools.cached_property
    def actuation(self) -> Actuation:
        """How the body is driven (:mod:`skinny_mj.training.actuation`)."""
        return actuation_of(self.cfg)

    def loop(self, hook=None, feedback: FeedbackController | None = None, rule=None) -> Loop:
        """The closed loop of the inverse model: ``cfg.inputs``, ``feedback`` (default the
        plain controller), the actuation's ``hook``, the forward model, the delay, and the
        learning rule FEL refits the readout with (None: each cycle alone)."""
        return Loop(self.cfg.inputs, feedback or FeedbackController(), hook, self.forward,
                    delay_steps=self.cfg.plant.delay + self.actuation.sensing_delay,
                    target_lead=teacher_lag(self.cfg), rule=rule)


@single_threaded
def build_run(cfg: TrainConfig, seeds: Sequence[int]) -> Run:
    """The parts of ``len(seeds)`` runs of ``cfg`` in lockstep (see :class:`Run`)."""
    seeds = [int(s) for s in seeds]
    if not seeds:
        raise ValueError("build_run needs at least one seed")
    trajectory, report = load_trajectory(cfg)
    reps, fwd = cfg.movement.reps, cfg.forward
    training = trajectory.repeat(reps) if reps > 1 else trajectory
    max_speed = full_scale_speeds(cfg, trajectory)
    streams = [run_streams(s) for s in seeds]
    n_sig, n_out, n_in = network_sizes(cfg)
    esn = ESN(cfg.esn_config(n_in, n_out), n_runs=len(seeds), rngs=[s.esn for s in streams])
    forward = None
    if isinstance(fwd, Forward) and fwd.sharing is not None:  # one per arm (paper B)
        forward = arm_forward_models(cfg, [s.forward for s in streams])
    elif isinstance(fwd, Forward):
        fm_cfg = cfg.esn_config(n_sig + n_out, n_sig, fwd.reservoir)
        forward = ForwardModel(ESN(fm_cfg, n_runs=len(seeds), rngs=[s.forward for s in streams]),
                               fwd.kind, chained=fwd.input == "chained")
    return Run(cfg=cfg, seeds=seeds, trajectory=trajectory, training=training, report=report,
               max_speed_rad_s=max_speed, esn=esn, forward=forward,
               plant_seeds=[s.plant_seed for s in streams],
               desired=training.position_signals(cfg.plant.signals),
               true_commands=true_commands_of(cfg, training, max_speed))


def run_of(cfg: TrainConfig, esn: ESN, max_speed_rad_s: np.ndarray, trajectory,
           plant_seeds: Sequence[int]) -> Run:
    """A :class:`Run` around networks trained elsewhere (e.g. a saved ``model.npz``),
    to :func:`evaluate` them on ``trajectory`` with the full scale they were trained with."""
    max_speed = np.asarray(max_speed_rad_s, float)
    return Run(cfg=cfg, seeds=[0] * esn.n_runs, trajectory=trajectory, training=trajectory,
               report=None, max_speed_rad_s=max_speed, esn=esn, forward=None,
               plant_seeds=[int(s) for s in plant_seeds],
               desired=trajectory.position_signals(cfg.plant.signals),
               true_commands=true_commands_of(cfg, trajectory, max_speed))


@dataclass
class Training:
    """What :func:`train_run` measured. fel : the FEL curve and failures (None for the
    true-target architecture); true_target : the TT fit's errors (None for FEL);
    pretrain_prediction_nrmse : (R,) the forward model's pre-training error or None."""

    fel: fel.TrainResult | None = None
    true_target: Any = None
    pretrain_prediction_nrmse: np.ndarray | None = None
    #: the FEL readout fit's rule (method.fit; None: each cycle alone): its ``metrics(r)``,
    #: if it has them, join run r's train metrics
    rule: Any = None
    feedback_share: Any = None  # the actuation's recorder (torque: torque.ShareRecorder)


@single_threaded
def train_run(run: Run, progress: Callable[[int, int], None] | None = None,
              observe: Callable[..., None] | None = None) -> Training:
    """Train ``run``'s networks in place. ``progress(done, total)`` after every cycle;
    ``observe``: FEL's optional per-cycle diagnostics callback
    (:func:`skinny_mj.controllers.fel.train`,
    e.g. paper E §5.1's y_est / y_used per epoch; ignored by the true-target architecture)."""
    cfg, method, out = run.cfg, run.cfg.method, Training()
    fwd, body, act = cfg.forward, cfg.plant, run.actuation
    if run.forward is not None and fwd.kind in ("serial", "hybrid"):
        out.pretrain_prediction_nrmse = run.forward.pretrain(
            run.trajectory.position_signals(body.signals),
            true_commands_of(cfg, run.trajectory, run.max_speed_rad_s),  # chained: one step
            0 if fwd.input == "chained" else body.delay, sensor_noise=body.sensor_noise)
    if isinstance(method, NoLearning):  # the feedback controller alone: nothing to learn
        return out
    if isinstance(method, TrueTarget):
        out.true_target = train_true_target(
            run.esn, run.desired, run.true_commands, method, noise=cfg.noise_level > 0,
            one_step=act.one_step(run.training, run.max_speed_rad_s),
            extra_inputs=act.teacher_inputs(run.training, run.max_speed_rad_s),
            input_rngs=[protocol.tt_input_rng(s) for s in run.seeds])
        _report(progress, 1, 1)
        return out
    # FEL: Original or New, the controllers' method types with their fit
    per_epoch = method.learning_cycles + 2
    total = method.epochs * per_epoch

    def tick(epoch: int, cycle: int, ro, y_used) -> None:
        _report(progress, epoch * per_epoch + cycle + 1, total)

    out.rule = make_rule(cfg, run.esn, len(run.desired) - 1)  # method.fit (training.fits)
    out.feedback_share = act.recorder(method, run.esn.n_runs)  # the actuation's, if any
    loop = run.loop(act.hook(run.training, run.max_speed_rad_s, run.plant),
                    protocol.feedback_of(method.u_error_gain, method.u_error_damping), out.rule)
    out.fel = fel.train(run.esn, run.plant, fel.Task(run.desired, run.true_commands, run.scored),
                        method, loop, observe=_all(observe, out.feedback_share, tick))
    return out


@single_threaded
def evaluate(run: Run, trajectory=None, *, plant_seeds: Sequence[int] | None = None,
             plant=None) -> list[TestOutcome]:
    """Test the R trained networks of ``run`` (K = ``test.gain``, no learning, reservoir
    noise only with ``test.noise``) on ``trajectory`` (default: one repetition of the
    training movement), after ``test.washout_cycles`` unscored cycles, with ``run``'s
    full-scale speeds.

    The plant is a fresh one whose sensor noise restarts from ``plant_seeds``
    (default: the runs' own plant seeds), or ``plant`` as given (e.g. ``run.plant``,
    whose noise stream then continues from training)."""
    cfg, test = run.cfg, run.cfg.test
    trajectory = run.trajectory if trajectory is None else trajectory
    if plant is None:
        seeds = run.plant_seeds if plant_seeds is None else plant_seeds
        plant = make_plant(cfg, trajectory, seeds, run.max_speed_rad_s)
        run.actuation.test_plant(plant)  # e.g. the torque body's robustness test
    desired = trajectory.position_signals(cfg.plant.signals)
    hook = run.actuation.hook(trajectory, run.max_speed_rad_s, plant)
    commands = true_commands_of(cfg, trajectory, run.max_speed_rad_s)
    ev = fel.evaluate(run.esn, plant, fel.Task(desired, commands, run.scored), run.loop(hook),
                      test)
    return [TestOutcome(
        position_nrmse=None if ev.failed[r] else float(ev.position_nrmse[r]),
        motor_nrmse=None if ev.failed[r] else float(ev.motor_nrmse[r]),
        failed=bool(ev.failed[r]), fail_reason=ev.fail_reason[r],
        rollout=ev.rollout.select(r), trajectory=trajectory, desired=desired,
        true_commands=commands,
        torque=run.actuation.test_figures(hook, ev.rollout, plant, r),
    ) for r in range(run.esn.n_runs)]


def train(cfg: TrainConfig, seed: int = 0,
          progress: Callable[[int, int], None] | None = None) -> RunResult:
    """Train one ESN inverse model with ``cfg`` and test it on one repetition.

    ``progress(done, total)`` is called after every cycle (for a progress bar).
    """
    return train_batch(cfg, [seed], progress)[0]


@single_threaded
def train_batch(cfg: TrainConfig, seeds: Sequence[int],
                progress: Callable[[int, int], None] | None = None,
                tests: Sequence[Test | Perform] = STANDARD,
                observe: Callable[[Run], Observer] | None = None) -> list[RunResult]:
    """Train R = len(seeds) runs of ``cfg`` in lockstep, then take ``tests`` in order
    (default: the standard test, one repetition of the training movement; a
    :class:`~skinny_mj.training.result.Perform`: a performance with the plant changed
    mid-run, its outcome a :class:`~skinny_mj.training.result.Performance`); run r equals
    ``train_batch(cfg, [seeds[r]], tests=tests)``. ``observe(run)``: an
    :class:`~skinny_mj.training.result.Observer` that watches the training (what it saw of
    run r: that result's ``observed``).

    A result's ``wall_s`` is the batch's wall time divided by R (``lockstep_runs`` = R).
    With ``plant.backend == "env"`` (dm_control, one run per environment) the runs are
    trained one after another.
    """
    seeds = [int(s) for s in seeds]
    if cfg.plant.backend == "env" and len(seeds) > 1:
        return [o for s in seeds for o in train_batch(cfg, [s], progress, tests, observe)]
    if not seeds:
        return []
    start = time.perf_counter()
    run = build_run(cfg, seeds)
    observer = None if observe is None else observe(run)
    trained = train_run(run, progress, observe=observer)
    train_wall = (time.perf_counter() - start) / len(seeds)
    taken = {t.name: perform(run, t, trained) if isinstance(t, Perform) else take_test(run, t)
             for t in tests}
    standard = taken.get("")
    if len(seeds) > 1 and standard is not None and physics_warnings(run, standard[0]):
        # the lockstep runs share one MjData, which MuJoCo resets whole when one run
        # diverges: the batch no longer equals its runs alone, so run them alone
        raise PhysicsBatchError(f"MuJoCo warnings in a lockstep batch of {len(seeds)} runs")
    wall = (time.perf_counter() - start) / len(seeds)
    figures = _rollout_figures(run, trained)
    return [_result(run, trained, r, {name: t[r] for name, t in taken.items()},
                    None if figures is None else figures[r], wall, train_wall,
                    None if observer is None else observer.observed(r))
            for r in range(len(seeds))]


def take_test(run: Run, test: Test) -> list[TestOutcome]:
    """The R trained networks of ``run`` take ``test`` (:class:`Test`)."""
    cfg = run.cfg.override(dict(test.overrides)) if test.overrides else run.cfg
    taker = run if cfg is run.cfg else dataclasses.replace(run, cfg=cfg)
    trajectory = None if test.movement is None else test.movement(run.cfg)
    if test.plant == "training":
        return evaluate(taker, trajectory, plant=run.plant)
    seeds = None if not test.plant_seed_offset else \
        [s + test.plant_seed_offset for s in run.plant_seeds]
    return evaluate(taker, trajectory, plant_seeds=seeds)


def _rollout_figures(run: Run, trained: Training) -> list[RolloutFigures] | None:
    """Per run the figures of FEL's last training rollout (None: no FEL training)."""
    ro = None if trained.fel is None else trained.fel.last_rollout
    if ro is None:
        return None
    mae, share = mean_abs_error(ro.true_signals, run.desired), feedback_share(ro)
    ratio = ro.correction_ratio
    prediction = None if run.forward is None else rollout_prediction_error(ro)
    return [RolloutFigures(float(mae[r]), float(ratio[r]), float(share[r]),
                           None if prediction is None else float(prediction[r]),
                           ro.select(r)) for r in range(run.esn.n_runs)]


def _train_figures(run: Run, trained: Training, r: int) -> TrainFigures:
    """Run r's :class:`TrainFigures`."""
    if trained.true_target is not None:
        tt = trained.true_target
        return TrainFigures("true-target", None if tt.position_nrmse is None
                            else float(tt.position_nrmse[r]), float(tt.motor_nrmse[r]))
    if trained.fel is None:  # method=none: nothing was trained
        return TrainFigures("none")
    result = trained.fel
    curve = result.to_dict()
    extra = dict(run.actuation.recorded(trained.feedback_share, r))
    reported = getattr(trained.rule, "metrics", None)  # the rule's own, if any
    if reported is not None:
        extra.update(reported(r))
    return TrainFigures("fel", curve["position_nrmse"][r], curve["motor_nrmse"][r],
                        curve["gains"], extra, bool(result.failed[r]), result.fail_reason[r],
                        result.fail_epoch[r])


def _result(run: Run, trained: Training, r: int, tests: dict[str, TestOutcome],
            figures: RolloutFigures | None, wall_share: float,
            train_wall_share: float, observed: Any = None) -> RunResult:
    """Run r's :class:`RunResult`: fails with its training, then its standard test, then
    (torque body) MuJoCo's warnings."""
    train = _train_figures(run, trained, r)
    standard = tests.get("")
    stage, reason = None, None
    if train.failed:
        stage, reason = "train", train.fail_reason
    elif standard is not None and standard.failed:
        stage, reason = "test", f"test: {standard.fail_reason}"
    warnings = None
    if standard is not None and standard.torque is not None:
        warnings = run.actuation.train_warnings(run)
        n_warnings = physics_warnings(run, standard)
        if n_warnings and stage is None:  # MuJoCo reset a diverged simulation
            stage, reason = "physics", (f"physics diverged: {n_warnings} MuJoCo warning(s) "
                                        "in training or test")
    pretrain = trained.pretrain_prediction_nrmse
    return RunResult(
        config=run.cfg, seed=run.seeds[r], train=train, tests=tests,
        failed=stage is not None, fail_reason=reason, fail_stage=stage,
        last_rollout=figures,
        pretrain_prediction_nrmse=None if pretrain is None else float(pretrain[r]),
        train_warnings=warnings, steps_per_cycle=len(run.desired),
        max_speed_rad_s=run.max_speed_rad_s, clipped_samples=int(run.report.clipped_samples),
        wall_s=wall_share, train_wall_s=train_wall_share, lockstep_runs=len(run.seeds),
        trajectory=run.trajectory, esn=esn_run(run.esn, r), observed=observed)


def test_robot_metrics(run: Run, test: TestOutcome) -> dict[str, float]:
    """A test's :func:`skinny_mj.training.imitation.robot_metrics` (joint error in degrees,
    hand error in cm, lag in s) of its produced joint angles against its movement's."""
    return test.robot_metrics(run.cfg.plant.body)


def physics_warnings(run: Run, test: TestOutcome) -> int:
    """MuJoCo warnings of the torque body's training and test plants (0 for the velocity
    servo); counted over a lockstep batch's shared simulation."""
    if test.torque is None:
        return 0
    return (run.actuation.train_warnings(run) or 0) + int(test.torque["metrics"]["warnings"])


class PhysicsBatchError(RuntimeError):
    """A lockstep batch whose shared simulation diverged (the engine then runs its seeds
    one at a time, each failing or not on its own)."""


def esn_run(esn: ESN, r: int) -> ESN:
    """Run ``r`` of a lockstep ESN as a one-run ESN (weights, state, noise stream)."""
    return esn if esn.n_runs == 1 else esn.select([r])


def _all(*observers: Callable[..., None] | None) -> Callable[..., None]:
    """One FEL observer calling ``observers`` (those not None) in order."""
    chosen = [o for o in observers if o is not None]

    def every(*args) -> None:
        for o in chosen:
            o(*args)
    return every


def _report(progress: Callable[[int, int], None] | None, done: int, total: int) -> None:
    if progress is not None:
        progress(done, total)
