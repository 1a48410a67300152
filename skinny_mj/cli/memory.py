"""The memory checks the commands make before any work (:func:`skinny_mj.preflight.check`
against the training's and the engine's estimates): ``skinny train``, ``test``, ``track``,
``experiment``, ``trajectory export`` and ``bench``."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from skinny_mj.engine import registry
from skinny_mj.engine.experiment import default_batch_size, default_workers, select_rows
from skinny_mj.engine.memory import sweep_estimate
from skinny_mj.errors import SkinnyInputError
from skinny_mj.preflight import Estimate, check, check_writable_file
from skinny_mj.training.memory import steps_cause, test_estimate, track_estimate, train_estimate
from skinny_mj.training.parts import load_trajectory

_F8 = 8  # bytes per float64


def check_train(cfg: Any, what: str = "the training") -> None:
    """Refuse a training of ``cfg`` the machine cannot hold (loads one repetition of its
    movement to count the steps)."""
    traj, _ = load_trajectory(cfg)
    one, reps = len(traj), cfg.movement.reps
    check(train_estimate(cfg, one * reps, one, 1, steps_cause(traj.name, one, reps)), what)


def check_test(esn_cfg: Any, n_dof: int, n_sig: int) -> Any:
    """``check(steps, cause)`` for ``skinny test`` of a network with ``esn_cfg``."""
    def run(steps: int, cause: str) -> None:
        check(test_estimate(esn_cfg.n_reservoir, esn_cfg.n_inputs, esn_cfg.n_outputs, n_dof,
                            n_sig, steps, cause), "the test",
              hint="use a shorter movement or fewer --reps")
    return run


def check_track(n_dof: int, n_sig: int) -> Any:
    """``check(steps, cause)`` for ``skinny track``."""
    def run(steps: int, cause: str) -> None:
        check(track_estimate(n_dof, n_sig, steps, cause), "tracking",
              hint="use a shorter movement or fewer --reps")
    return run


def check_sweep(module: Any, experiment: Any, rows: Any, runs: int | None,
                workers: int | None, scheduler: str | None) -> None:
    """Refuse a sweep whose largest row, times the workers running at once, does not
    fit; on a remote Dask cluster the memory is the cluster's (no check here)."""
    if scheduler is not None and scheduler != "local":
        return
    selected = select_rows(experiment, rows)
    runs = experiment.runs if runs is None else int(runs)
    workers = default_workers(workers)
    found = sweep_estimate(module, experiment, selected, runs, workers,
                           default_batch_size(len(selected), runs, workers))
    if found is not None:
        est, row = found
        check(est, f"the sweep's largest row, {row},",
              hint="use fewer --workers or --runs, or leave that row out with --rows")


def check_export(n_dof: int, out: Any) -> Any:
    """Check ``skinny trajectory export``'s ``out`` (a writable .npz or .csv), and return
    ``check(steps, cause)`` for its memory: the repeated angles, the resampled and clipped
    copies and the file's text."""
    if Path(out).suffix.lower() not in (".npz", ".csv"):
        raise SkinnyInputError("export writes .npz or .csv", path=out)
    check_writable_file(out)

    def run(steps: int, cause: str) -> None:
        check(Estimate({"movement": steps * n_dof * _F8 * 4 + steps * n_dof * 25},
                       {"movement": cause}), "the export", hint="use fewer --reps")
    return run


def check_bench(workers: int | None, quick: bool) -> None:
    """``skinny bench``: its fixed workloads are small but for the whole paper-E table
    (not with ``--quick``), a sweep on ``workers`` processes: checked as a sweep is."""
    if quick:
        return

    module = registry.get("paper-e")
    rows = list(getattr(module, "TABLE_1", ())) or None
    check_sweep(module, module.build(), rows, None, workers, None)
