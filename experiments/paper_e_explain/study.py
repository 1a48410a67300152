"""Paper E §5.1 measured: why the new method beats the original (Figs. 7–10).

"We trained the same initial network with the setups in experiments 1 (original, 1 rep.),
2 (original, 5 rep.), and 5 (new, β = 0.1) and studied how the ESN output, the actual
position sequence, the estimated target, and the target used for weight calculation
evolved during the training epochs" (paper E §5.1). The thesis shows one network's
curves by eye; here every seed's are measured, per epoch:

- NRMSE against the true (analytic) commands and roughness (RMS of the second
  difference, :func:`roughness`) of y_est (the FEL target estimate), y_used (the target
  fitted: β y_est + (1 − β) y_ESN; = y_est for the original method) and the ESN output
  (during the learning cycle, reservoir noise on, and after the fit, on the epoch's
  noise-free evaluation cycle);
- the quality of teacher forcing: position NRMSE of the plant's (noise-free) positions
  against the desired ones during the learning cycle (Fig. 10 plots "the position
  sequences in epoch 5"; the positions that are the ESN's "current position" input).

The rows are paper E's exps 1, 2 and 5 (their rows of ``paper_e.ROWS``, 20 runs each;
``--quick``: 2 runs of 2 epochs). **One initial network per seed:** rows ``2`` and ``5``
take row ``1``'s seeds (:attr:`skinny_mj.engine.study.Row.seeds_of`), so the three rows of run k
train from the same seed and share the ESN weights, the initial readout, the
reservoir-noise and the sensor-noise streams (``run_streams(seed)``); exp 1's runs are
paper-e row 1's runs, seed for seed.

A run whose network diverges keeps its diagnostics up to the failing epoch (None after
it): the run file is status ``ok`` with ``diverged`` = 1 and no test NRMSE, because the
training curves are this experiment's data. Figures and the table: ``report``
(:mod:`skinny_mj.experiments.paper_e_explain.report`).
"""

from __future__ import annotations

import numpy as np
from skinny_mj.controllers.metrics import nrmse, position_nrmse
from skinny_mj.controllers.rollout import Rollout
from skinny_mj.experiments.paper_e import study as paper_e

from skinny_mj.engine.experiment import run_seed
from skinny_mj.engine.results import no_failure
from skinny_mj.engine.stats import to_jsonable
from skinny_mj.engine.study import Quick, Row, Study
from skinny_mj.training.result import RunResult

NAME = "paper-e-explain"
EXPS = ("1", "2", "5")  # paper E §5.1: original 1 rep, original 5 reps, new β = 0.1
#: epochs (1-based) whose first-repetition signals the run file keeps for the figures
SERIES_EPOCHS = (1, 5, 10)
SERIES_RUNS = 2  # runs (by run index) whose signals are kept: the figures show index 0
#: learning-cycle series (R, E, C) and evaluation-cycle series (R, E) a run keeps
LEARN_KEYS = ("est_nrmse", "est_rough", "used_nrmse", "used_rough", "esn_learn_nrmse",
              "esn_learn_rough", "tf_position_nrmse", "tf_sensed_nrmse")
EVAL_KEYS = ("esn_nrmse", "esn_rough", "eval_position_nrmse")
BASE_SEED = 0


def roughness(y: np.ndarray) -> np.ndarray:
    """Roughness of signals: per signal the RMS over time of the second difference
    y(t+1) − 2 y(t) + y(t−1), then the mean over signals (NRMSE's convention).

    y : (..., T, n) signals (e.g. commands in [-1, 1]), T >= 3. Returns (...)."""
    y = np.ascontiguousarray(y, float)
    d2 = y[..., 2:, :] - 2.0 * y[..., 1:-1, :] + y[..., :-2, :]
    return np.sqrt(np.mean(d2**2, axis=-2)).mean(axis=-1)


class EpochDiagnostics:
    """The study's observer (:class:`~skinny_mj.training.result.Observer`): per run, epoch
    and learning cycle the NRMSE (vs the true commands) and roughness of y_est, y_used and
    y_ESN, the teacher-forcing position NRMSE, and the first repetition's signals of some
    epochs.

    true_commands : (T-1, n_dof) of the training sequence; desired : (T, n_sig);
    one_rep : steps of one repetition (the series kept); n_runs, epochs, cycles."""

    def __init__(self, true_commands: np.ndarray, desired: np.ndarray, one_rep: int,
                 n_runs: int, epochs: int, cycles: int,
                 series_epochs: tuple[int, ...] = SERIES_EPOCHS) -> None:
        self.true_commands, self.desired, self.one_rep = true_commands, desired, one_rep
        self.learn = {k: np.full((n_runs, epochs, cycles), np.nan) for k in LEARN_KEYS}
        self.eval = {k: np.full((n_runs, epochs), np.nan) for k in EVAL_KEYS}
        self.cycles = cycles
        self.keep = sorted({min(e, epochs) - 1 for e in series_epochs})
        self.series: dict[int, dict[str, np.ndarray]] = {e: {} for e in self.keep}
        self.initial_output: np.ndarray | None = None

    def __call__(self, epoch: int, cycle: int, ro: Rollout, y_used: np.ndarray | None) -> None:
        n = self.one_rep
        if cycle == 0:
            if epoch == 0:  # the initial network's output (W_out = 0: all zero)
                self.initial_output = ro.y_esn[:, : n - 1].copy()
            return
        if y_used is None:  # the evaluation cycle: the ESN output after this epoch's fits
            self.eval["esn_nrmse"][:, epoch] = nrmse(ro.y_esn, self.true_commands)
            self.eval["esn_rough"][:, epoch] = roughness(ro.y_esn)
            self.eval["eval_position_nrmse"][:, epoch] = position_nrmse(ro.true_signals,
                                                                        self.desired)
            if epoch in self.series:
                self.series[epoch]["y_esn"] = ro.y_esn[:, : n - 1].copy()
            return
        c = cycle - 1
        for name, y in (("est", ro.y_est), ("used", y_used), ("esn_learn", ro.y_esn)):
            self.learn[f"{name}_nrmse"][:, epoch, c] = nrmse(y, self.true_commands)
            self.learn[f"{name}_rough"][:, epoch, c] = roughness(y)
        self.learn["tf_position_nrmse"][:, epoch, c] = position_nrmse(ro.true_signals,
                                                                      self.desired)
        self.learn["tf_sensed_nrmse"][:, epoch, c] = position_nrmse(ro.sensed, self.desired)
        if epoch in self.series and c == self.cycles - 1:  # the epoch's last fit
            s = self.series[epoch]
            s["y_est"], s["y_used"] = ro.y_est[:, : n - 1].copy(), y_used[:, : n - 1].copy()
            s["positions"] = ro.true_signals[:, :n].copy()

    def observed(self, r: int) -> dict:
        """Run ``r``'s series (learning cycles (E, C), evaluation cycles (E,)), its kept
        epochs' signals and the true commands' roughness."""
        return {"learn": {k: v[r] for k, v in self.learn.items()},
                "eval": {k: v[r] for k, v in self.eval.items()},
                "keep": self.keep,
                "series": {e: {k: a[r] for k, a in s.items()} for e, s in self.series.items()},
                "initial_output": None if self.initial_output is None
                else self.initial_output[r],
                "true_rough": float(roughness(self.true_commands))}

    def metrics(self, r: int, fail_epoch: int | None, with_series: bool = True) -> dict:
        """Run ``r``'s JSON-ready diagnostics (:func:`diagnostics`)."""
        return diagnostics(self.observed(r), fail_epoch, with_series)


def diagnostics(seen: dict, fail_epoch: int | None, with_series: bool = True) -> dict:
    """One run's JSON-ready diagnostics (``seen``: :meth:`EpochDiagnostics.observed`; None
    from its failing epoch on); with ``with_series`` also the kept epochs' signals (one
    repetition)."""
    def clean(a: np.ndarray) -> list:
        a = np.round(np.array(a, float), 6)
        if fail_epoch is not None:
            a[fail_epoch:] = np.nan
        return to_jsonable(a)  # NaN -> None

    def rounded(a: np.ndarray) -> list:
        return np.round(a, 4).tolist()

    learn, evaluation = seen["learn"], seen["eval"]
    out: dict = {f"{k}_per_cycle": clean(v) for k, v in learn.items()}
    out.update({k: clean(v[:, -1]) for k, v in learn.items()})  # last cycle
    out.update({k: clean(v) for k, v in evaluation.items()})
    for k in (*learn, *evaluation):  # scalar columns for the engine's table
        for e in (1, 5, len(out[k])):
            v = out[k][e - 1] if e <= len(out[k]) else None
            out[f"{k}_e{e}"] = v
    out["true_rough"] = seen["true_rough"]
    if not with_series:
        return out
    alive = [e for e in seen["keep"] if fail_epoch is None or e < fail_epoch]
    series = seen["series"]
    out["series"] = {"epochs": [e + 1 for e in alive],
                     **{k: [rounded(series[e][k]) for e in alive]
                        for k in ("y_est", "y_used", "y_esn", "positions")},
                     "initial_output": rounded(seen["initial_output"])}
    return out


def epoch_diagnostics(run, row: Row) -> EpochDiagnostics:
    """The study's observer of a lockstep training's runs."""
    return EpochDiagnostics(run.true_commands, run.desired, len(run.trajectory),
                            len(run.seeds), run.cfg.method.epochs, run.cfg.learning_cycles)


#: The seeds whose signals the run files keep: row ``1``'s first runs (every row takes them).
KEEP = frozenset(run_seed(BASE_SEED, EXPS[0], k) for k in range(SERIES_RUNS))


def metrics(result: RunResult) -> dict:
    """One run's file: its test, its divergence (data: the run stays ``ok``) and the
    diagnostics of every epoch (row ``1``'s first runs: with their signals)."""
    train, test = result.train, result.test
    failed = bool(train.failed or test.failed)
    return {
        "network_seed": result.seed, "diverged": int(failed),
        "fail_reason": train.fail_reason or (test.fail_reason if failed else None),
        "position_nrmse": None if failed else test.position_nrmse,
        "motor_nrmse": None if failed else test.motor_nrmse,
        **diagnostics(result.observed, train.fail_epoch, with_series=result.seed in KEEP),
    }


STUDY = Study(
    name=NAME, description=__doc__, runs=20, base_seed=BASE_SEED,
    observe=epoch_diagnostics, metrics=metrics, failure=no_failure,
    rows=tuple(Row(e, paper_e.STUDY.row(e).overrides, paper_e.STUDY.row(e).paper,
                   seeds_of=None if e == EXPS[0] else EXPS[0]) for e in EXPS),
    columns=("est_rough_e1", "used_rough_e5", "esn_rough_e5", "tf_position_nrmse_e5",
             "position_nrmse", "motor_nrmse"),
    quick=Quick({"method.epochs": 2}, runs=2),
    report="skinny_mj.experiments.paper_e_explain.report:report",
)
