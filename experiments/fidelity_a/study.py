"""Paper A's fidelity: why does our inverse-only error saturate at 8.5–9 %, not 10–20 %?

Paper A's runs (``skinny_mj.experiments.paper_a.MODEL`` / ``train_config``, imported) measured
three ways at once. K is fixed (0.65) through paper A's training, so nothing in epochs
1..E depends on E: ONE training of E epochs records, at every checkpoint epoch c <= E
(:data:`CHECKPOINTS`), what a c-epoch run would report (``tests/test_fidelity_a.py``
checks that a short run equals a long run's checkpoint, bit for bit):

- ``train_*_e<c>``: the evaluation cycle of epoch c (K = 0.65, reservoir noise off) —
  where paper A measures ("the performance error in the last epoch");
- ``test_*_e<c>``: a closed-loop test of the networks as they are after epoch c (K = 0,
  noise off) on a fresh plant (its sensor noise restarts from the run's plant seed, so
  every checkpoint's test sees the same noise; paper A's ``test_position_nrmse`` runs on
  the training plant, its noise stream continuing). The test resets the reservoir
  states, which the next epoch resets anyway: training goes on unchanged.

Each in two metrics: ``nrmse`` (sqrt(MSE) / 2, per signal, averaged: ours) and ``mad``
= mean |desired − actual| / 2 over steps and signals, the thesis's "mean difference
between the desired state and the actual state" as a fraction of the signal range (its
other reading, a fraction of the half-range 1, is 2 × ``mad``). Also the feedback share
and correction ratio (paper A's "online correction ratio"), and with a forward model its
prediction error p(t) vs the actual x(t) (``pred_nrmse``, ``pred_mad``).

Rows ``<architecture>[-chained]-d<delay>``; ``chained``: the forward model fed its own
previous prediction instead of the delayed sensed position (``forward.input``).
:data:`PLAN` gives each row its epochs (the compute budget: see docs/results/fidelity-a.md).
A row is paper A's run (:data:`skinny_mj.experiments.paper_a.MODEL`) with its delay, forward model,
forward input and epochs as overrides.
"""

from __future__ import annotations

import dataclasses

import numpy as np
from skinny_mj.controllers.fel import run_mean
from skinny_mj.controllers.forward_model import rollout_prediction_error
from skinny_mj.controllers.rollout import Rollout
from skinny_mj.experiments import paper_a

from skinny_mj import training
from skinny_mj.engine.results import no_failure
from skinny_mj.engine.study import Quick, Row, Study
from skinny_mj.training.result import RunResult, feedback_share

NAME = "fidelity-a"
#: Epochs at which a run's metrics are recorded (those <= the row's epochs, and its last).
CHECKPOINTS = (1, 2, 5, 10, 20, 50, 100, 150)
#: The epochs the tables report.
TABLE_EPOCHS = (10, 50, 150)
#: (architecture, forward input, delay, epochs): the sweep, sized for one shared core
#: (docs/results/fidelity-a.md). Inverse only d4 gets the long run (150 epochs: its
#: checkpoints give 10, 50, 150); the rest 10 epochs, paper A's schedule.
PLAN = (
    ("inverse", "sensed", 0, 10), ("inverse", "sensed", 2, 10), ("inverse", "sensed", 4, 150),
    ("inverse", "sensed", 6, 10), ("inverse", "sensed", 10, 10),
    ("serial", "sensed", 0, 10), ("serial", "sensed", 2, 10), ("serial", "sensed", 4, 10),
    ("serial", "sensed", 6, 10), ("serial", "sensed", 10, 10),
    ("parallel", "sensed", 4, 10), ("parallel", "sensed", 10, 10),
    ("hybrid", "sensed", 4, 10), ("hybrid", "sensed", 10, 10),
    ("serial", "chained", 4, 10), ("parallel", "chained", 4, 10), ("hybrid", "chained", 4, 10),
)
#: ``--quick``: these rows of :data:`PLAN`, with these epochs.
QUICK_EPOCHS = {("inverse", "sensed", 0): 3, ("inverse", "sensed", 4): 3,
                ("serial", "sensed", 4): 2, ("parallel", "sensed", 4): 2,
                ("hybrid", "sensed", 4): 2, ("serial", "chained", 4): 2}
#: The thesis's numbers for these quantities (paper A §4.1–4.2 text; its figures give no
#: table), beside ours in the report.
THESIS = paper_a.PAPER_TEXT


def row_id(architecture: str, forward_input: str, delay: int) -> str:
    return f"{architecture}{'-chained' if forward_input == 'chained' else ''}-d{delay}"


def plan_row(arch: str, forward_input: str, delay: int, epochs: int) -> Row:
    """Paper A's row (its delay and forward model), with its epochs and the forward
    model's input; ``--quick``: the forward network halved, a few epochs."""
    forward = {} if arch == "inverse" else {"forward": arch, "forward.input": forward_input}
    quick = QUICK_EPOCHS.get((arch, forward_input, delay))
    return Row(row_id(arch, forward_input, delay),
               {"plant.delay": delay, "forward": "none", **forward, "method.epochs": epochs},
               group="chained" if forward_input == "chained" else arch,
               quick={"method.epochs": quick, **({"forward.reservoir": 50} if forward else {})}
               if quick else {})


def checkpoints_of(checkpoints: tuple[int, ...], epochs: int) -> tuple[int, ...]:
    return tuple(sorted({c for c in checkpoints if c <= epochs} | {epochs}))


def _mad(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Mean |a - b| / 2 per run, (R,), for (R, T, n) and (R or T, ..., n)."""
    return run_mean(np.abs(a - b)) / 2.0


def _cycle_metrics(ro, desired: np.ndarray, prefix: str) -> dict[str, np.ndarray]:
    """Per-run metrics (R,) of one closed-loop cycle ``ro`` (the feedback share and
    correction ratio only with the feedback on: in training)."""
    out = {f"{prefix}_mad": _mad(ro.true_signals, desired)}
    if prefix == "train":
        out.update({"train_share": feedback_share(ro),
                    "train_ratio": np.array(ro.correction_ratio)})
    if ro.predictions is not None:
        out[f"{prefix}_pred_nrmse"] = rollout_prediction_error(ro)
        out[f"{prefix}_pred_mad"] = _mad(ro.predictions[:, 1:], ro.true_signals[:, 1:])
    return out


def _test_metrics(run) -> dict[str, np.ndarray]:
    """The K = 0 test of ``run``'s networks as they are, on a fresh plant, (R,) each."""
    tests = training.evaluate(run)
    ro = _stack_rollouts([t.rollout for t in tests])
    out = _cycle_metrics(ro, run.desired, "test")
    failed = np.array([t.failed for t in tests], float)
    out = {k: np.where(failed > 0, np.nan, v) for k, v in out.items()}
    out["test_nrmse"] = np.array([np.nan if t.failed else t.position_nrmse for t in tests])
    out["test_motor_nrmse"] = np.array([np.nan if t.failed else t.motor_nrmse for t in tests])
    out["test_failed"] = failed
    return out


def _stack_rollouts(ros: list):
    """One R-run Rollout from R one-run selections (the test's per-run views)."""
    return Rollout(**{f.name: None if getattr(ros[0], f.name) is None else
                      np.concatenate([getattr(r, f.name) for r in ros])
                      for f in dataclasses.fields(Rollout)})


class Checkpoints:
    """The study's observer (:class:`~skinny_mj.training.result.Observer`): at every
    checkpoint epoch's evaluation cycle, that cycle's figures and a K = 0 test of the
    networks as they are (see the module docstring). Run r's observation: the checkpoint
    epochs and per checkpoint its figures."""

    def __init__(self, run, checks: tuple[int, ...]) -> None:
        self.run, self.checks = run, checks
        self.last_cycle = run.cfg.learning_cycles + 1
        self.recorded: dict[int, dict[str, np.ndarray]] = {}

    def __call__(self, epoch: int, cycle: int, ro, y_used) -> None:
        if cycle == self.last_cycle and epoch + 1 in self.checks:  # the evaluation cycle
            rec = _cycle_metrics(ro, self.run.desired, "train")
            rec.update(_test_metrics(self.run))
            self.recorded[epoch + 1] = rec

    def observed(self, r: int) -> dict:
        return {"checks": self.checks,
                "at": {c: {k: v[r] for k, v in rec.items()} for c, rec in self.recorded.items()}}


def checkpoints(run, row: Row) -> Checkpoints:
    """A row's observer: the study's checkpoints up to the row's epochs, and its last."""
    return Checkpoints(run, checkpoints_of(row.params["checkpoints"], run.cfg.method.epochs))


def metrics(result: RunResult) -> dict:
    """One run's file: per checkpoint c its figures (NaN once the run had diverged by the
    end of epoch c), the epochs it trained, its training curve."""
    seen, train = result.observed, result.train
    ok_epochs = result.config.method.epochs if not train.failed else int(train.fail_epoch)
    out: dict = {"epochs_ok": float(ok_epochs)}
    for c in seen["checks"]:
        alive = c <= ok_epochs  # the run had not diverged by the end of epoch c
        out[f"train_failed_e{c}"] = 0.0 if alive else 1.0
        nrmse = train.position_nrmse[c - 1]
        out[f"train_nrmse_e{c}"] = float("nan") if not alive or nrmse is None else nrmse
        for name, value in seen["at"][c].items():
            keep = alive or name == "test_failed"
            out[f"{name}_e{c}"] = float(value) if keep else float("nan")
    if result.pretrain_prediction_nrmse is not None:
        out["pretrain_prediction_nrmse"] = result.pretrain_prediction_nrmse
    out["curve_train_nrmse"] = list(train.position_nrmse)
    return out


def _columns(epochs: int) -> tuple[str, ...]:
    return (f"train_nrmse_e{epochs}", f"train_mad_e{epochs}", f"test_nrmse_e{epochs}",
            f"test_mad_e{epochs}", f"train_pred_nrmse_e{epochs}")


STUDY = Study(
    name=NAME, description=__doc__, base=paper_a.MODEL, runs=5,
    # train once, watched at its checkpoints; no test after; a diverged run is data
    observe=checkpoints, metrics=metrics, tests=(), failure=no_failure,
    rows=tuple(plan_row(*p) for p in PLAN), params={"checkpoints": CHECKPOINTS},
    columns=_columns(TABLE_EPOCHS[0]),
    # a smoke test (N = 100 / 50, 2 cycles, 2–3 epochs, 2 runs), not a result
    quick=Quick({"esn.n_reservoir": 100, "method.cycles": 2}, runs=2,
                rows=tuple(row_id(*k) for k in QUICK_EPOCHS),
                params={"checkpoints": (1, 2, 3)}, columns=_columns(2)),
    report="skinny_mj.experiments.fidelity_a.report:report",
)
