"""A training's :class:`~skinny_mj.training.result.RunResult` as the engine writes it, and the
engine's default run of a study's row.

:func:`run_metrics` is the one serialization of a result (``skinny train``'s
``metrics.json``; a study's dotted metric paths read it). :func:`default_run` is the run
of a row without a run function of its own, taken as its :class:`Shape` says: train the
row's seeds in lockstep (each of the ``trainings``, if it names several) with its
``observe``-r watching, take its ``tests``, and per seed either a
:class:`~skinny_mj.engine.sweep.RunFailed` (``failure`` of the result says why) or the
``metrics`` of the result.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from skinny_mj import training  # the training loop loads on first use (a study's --help runs none)
from skinny_mj.engine.sweep import RunFailed
from skinny_mj.training.config import TrainConfig
from skinny_mj.training.result import STANDARD, Observer, RunResult, Test, TrainFigures

__all__ = ["Metric", "Metrics", "Shape", "run_metrics", "test_figures", "read_metric",
           "default_failure", "no_failure", "train_failure", "default_run", "test_position_nrmse",
           "test_motor_nrmse", "wall_s", "train_position_nrmse", "STANDARD_METRICS"]

#: A metric: a function of a run's result (a :class:`RunResult`, or a mapping name ->
#: RunResult for a study that trains several configurations per run), or a dotted path
#: into :func:`run_metrics` (``"test.position_nrmse"``).
Metric = str | Callable[[Any], Any]
#: What a study reports: name -> metric (the run file also gets the standard test's
#: figures in a roboticist's units the study does not name), or one function of the
#: result giving every metric of the run file.
Metrics = Mapping[str, Metric] | Callable[[Any], Mapping[str, Any]]
Tests = Sequence[Test] | Callable[[TrainConfig, Any], Sequence[Test]]


@dataclass(frozen=True)
class Shape:
    """How the engine's default run takes a row and reads it.

    ``metrics``: name -> a function of the result (or a dotted path into
    :func:`run_metrics`), or one function of the result giving every metric; ``tests``:
    the tests a run takes after training (or a function ``(config, row)`` giving them);
    ``failure(result) -> str | None``: why a run failed (None: :func:`default_failure`);
    ``trainings(config, row) -> {name: TrainConfig}``: several configurations trained
    from the same seeds (the metrics then read a mapping name -> RunResult); ``observe(run,
    row) -> Observer``: watches the training while it runs (what it saw of a run: its
    result's ``observed``).
    """

    metrics: Metrics
    tests: Tests = STANDARD
    failure: Callable[[Any], str | None] | None = None
    trainings: Callable[[TrainConfig, Any], Mapping[str, TrainConfig]] | None = None
    observe: Callable[[Any, Any], Observer] | None = None


def test_position_nrmse(result: RunResult) -> float | None:
    """The standard test's position NRMSE (None for a failed run)."""
    return None if result.failed else result.test.position_nrmse


def test_motor_nrmse(result: RunResult) -> float | None:
    """The standard test's motor NRMSE (None for a failed run)."""
    return None if result.failed else result.test.motor_nrmse


def wall_s(result: RunResult) -> float:
    """The run's wall time (its lockstep batch's / R), s."""
    return result.wall_s


def train_position_nrmse(result: RunResult) -> Any:
    """The training's position NRMSE: FEL's per-epoch curve, the true-target fit's."""
    return result.train.position_nrmse


#: The standard test, NRMSE of positions and commands, and the wall time.
STANDARD_METRICS: dict[str, Metric] = {"position_nrmse": test_position_nrmse,
                                       "motor_nrmse": test_motor_nrmse,
                                       "train_wall_s": wall_s}


def _train_dict(train: TrainFigures) -> dict[str, Any]:
    if train.kind == "true-target":
        return {"motor_nrmse": train.motor_nrmse, "position_nrmse": train.position_nrmse}
    if train.kind == "none":
        return {}
    return {"gains": train.gains, "position_nrmse": train.position_nrmse,
            "motor_nrmse": train.motor_nrmse, **train.extra}


def run_metrics(result: RunResult) -> dict[str, Any]:
    """``result`` JSON-ready: ``train`` (FEL: gains and per-epoch curves, the actuation's
    and the rule's figures; true target: the fit's NRMSEs), ``failed`` / ``fail_reason``
    (/ ``fail_epoch``), ``test`` (the standard test's NRMSEs and robot figures, its torque
    figures), ``train_warnings``, ``pretrain_prediction_nrmse``, the config, the seed and
    the run's sizes and wall time."""
    metrics: dict[str, Any] = {"train": _train_dict(result.train)}
    stage = result.fail_stage
    if stage == "train":
        metrics.update(failed=True, fail_reason=result.fail_reason,
                       fail_epoch=result.train.fail_epoch)
    elif stage == "test":
        metrics.update(failed=True, fail_reason=result.fail_reason)
    metrics.setdefault("failed", False)
    metrics["test"] = test_figures(result)
    test = result.tests.get("")
    if test is not None and test.torque is not None:
        metrics["train_warnings"] = result.train_warnings
        if stage == "physics":
            metrics.update(failed=True, fail_reason=result.fail_reason)
    if result.pretrain_prediction_nrmse is not None:
        metrics["pretrain_prediction_nrmse"] = result.pretrain_prediction_nrmse
    metrics.update(
        config=result.config.to_dict(), seed=result.seed,
        steps_per_cycle=result.steps_per_cycle,
        max_speed_rad_s=[float(v) for v in result.max_speed_rad_s],
        clipped_samples=result.clipped_samples, wall_s=result.wall_s,
        lockstep_runs=result.lockstep_runs)
    return metrics


def test_figures(result: RunResult) -> dict[str, Any]:
    """The standard test of ``result`` JSON-ready: its NRMSEs and figures in a
    roboticist's units (None and none for a failed run), the torque body's figures."""
    test = result.tests.get("")
    if result.failed or test is None:  # a diverged network: no figures
        out: dict[str, Any] = {"position_nrmse": None, "motor_nrmse": None}
    else:
        out = {"position_nrmse": test.position_nrmse, "motor_nrmse": test.motor_nrmse,
               **test.robot_metrics(result.config.plant.dof)}
    if test is not None and test.torque is not None:
        out["torque"] = test.torque_figures
    return out


def read_metric(result: Any, where: Metric) -> Any:
    """One metric of a run's result: a function of it, or a dotted path into its
    :func:`run_metrics` (``"test.position_nrmse"``; a missing key is None)."""
    if callable(where):
        return where(result)
    value: Any = run_metrics(result)
    for part in where.split("."):
        value = value.get(part) if isinstance(value, Mapping) else None
    return value


def default_failure(result: Any) -> str | None:
    """Why a run failed (its first training that did, for several), None if it did not."""
    results = result.values() if isinstance(result, Mapping) else (result,)
    for r in results:
        if r.failed:
            return r.fail_reason or "diverged"
    return None


def no_failure(result: Any) -> None:
    """A study's ``failure`` when a diverged training is data (its metrics say so)."""
    return None


def train_failure(result: Any) -> str | None:
    """A study's ``failure`` when only a diverged training fails a run (its tests'
    failures are data): ``"epoch E: why"``."""
    if not result.train.failed:
        return None
    return f"epoch {result.train.fail_epoch}: {result.train.fail_reason}"


def _picked(result: Any, metrics: Metrics,
            failure: Callable[[Any], str | None] | None) -> Any:
    why = (failure or default_failure)(result)
    if why is not None:
        return RunFailed(why)
    if callable(metrics):
        return dict(metrics(result))
    picked = {name: read_metric(result, where) for name, where in metrics.items()}
    if not isinstance(result, RunResult):
        return picked
    # every run file's figures in a roboticist's units the study does not name itself
    extra = result.robot_figures()
    return {**picked, **{k: v for k, v in extra.items() if k not in picked}}


def default_run(config: TrainConfig, row: Any, seeds: list[int], shape: Shape) -> list[Any]:
    """The default run of a row taken as ``shape`` says (see the module docstring): per
    seed its metrics dict or a :class:`RunFailed`."""
    tests = shape.tests
    taken = tuple(tests(config, row) if callable(tests) else tests)
    observe = shape.observe
    watch = None if observe is None else lambda run: observe(run, row)
    metrics, failure = shape.metrics, shape.failure
    if shape.trainings is None:
        return [_picked(r, metrics, failure)
                for r in training.train_batch(config, seeds, tests=taken, observe=watch)]
    per = {name: training.train_batch(c, seeds, tests=taken, observe=watch)
           for name, c in shape.trainings(config, row).items()}
    return [_picked({name: runs[k] for name, runs in per.items()}, metrics, failure)
            for k in range(len(seeds))]
