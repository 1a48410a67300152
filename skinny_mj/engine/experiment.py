"""The experiment engine shared by every study: a sweep of (row, seed) runs.

A study (:class:`skinny_mj.engine.study.Study`: a base config, rows of overrides) planned
for one sweep is an :class:`Experiment` (:mod:`skinny_mj.engine.plan`); :func:`run_sweep`
runs it in parallel (joblib/loky here, or a Dask cluster), writing one JSON file per
finished run to ``out/runs/<row>-<seed>.json``; :func:`aggregate` rebuilds
``results.json`` from those files only and :func:`markdown_table` sets our numbers beside
the paper's.

The contract
------------
``Study.build(*, quick=False, movement=None, asf=None, body=None, signals=None) ->
Experiment`` takes exactly the options of ``skinny experiment`` (``--quick --movement
--asf --body --signals``), each None meaning the study's default; every one of them that
changes the runs is in ``Experiment.to_dict()`` (``config.json`` records it and
``--resume`` refuses a different one), never in the name: the name is the study's whatever
the movement, so the default output folder stays ``results/<name>/<time>``.

**An Experiment holds ALL its rows** (the study's :class:`~skinny_mj.engine.study.Row`\ s,
``--quick`` applied); ``build`` never filters them. Selection is the engine's:
``run_sweep(..., rows=["5", "fig4"])`` takes row ids and group names
(``Experiment.groups``: group name -> row ids, e.g. ``{"table": ("1", ..., "6")}``).
A run's seed is ``run_seed(base_seed, row_id, run_index)``, ``row_id`` the row's (or its
``Row.seeds_of`` row's) id: a seed depends on what the row is called, never on where it
stands, so rows can be added, reordered and deleted without moving any other row's
numbers, and ``--rows`` reproduces the full sweep's files bit for bit. An unknown entry raises
:class:`SkinnyInputError` naming the known ids and groups.

**A run** is ``Experiment.run_batch(row, seeds) -> list``: the row's seeds in lockstep,
per seed a mapping of metrics (numbers are aggregated; other JSON-able values are kept in
the run file only), a :class:`RunFailed` or another exception instance; the Experiment is
shipped to worker processes with cloudpickle. A seed's outcome is one of:

- its metrics: status ``"ok"``;
- a :class:`RunFailed` (the network diverged): status ``"failed"``. A diverged
  run is data: it counts in ``failed / n`` and is left out of the means;
- anything else (or a value that is not a mapping of JSON-able values) is a bug, not
  data: status ``"error"`` with the full traceback; the sweep finishes the other runs,
  ``--resume`` runs it again, and ``skinny experiment`` exits 1.

If ``run_batch`` itself raises (or returns the wrong number of results), the engine runs
that batch's seeds one by one (``Experiment.run_one``, a batch of one seed) and each of
those records carries ``"fallback": "<ExcType>: <message> (batch of N seeds)"`` and
``"fallback_traceback"``. Batched or not, the run files are the same.

**A run file** ``runs/<row>-<seed>.json`` (:func:`skinny_mj.engine.stats.load_run`
validates it; a damaged file is an error naming it, hidden ``.*.tmp`` leftovers of
atomic writes are ignored)::

    {"experiment", "row", "row_index", "run_index", "seed", "params", "paper",
     "status": "ok" | "failed" | "error",
     "metrics": {...} ({} unless ok), "nonfinite_metrics": [names stored as null] (ok),
     "fail_reason": str | None (failed), "error": "ExcType: message" | None (error),
     "traceback": str (error only), "fallback", "fallback_traceback" (fell back only),
     "wall_s", "finished_at"}

**config.json** records ``experiment``, ``config`` (``Experiment.to_dict()``), every row
(``rows``: row, params (:attr:`Row.settings <skinny_mj.engine.study.Row.settings>`, as in
the run files), paper[, runs, seeds_of]), ``groups``, ``runs``, ``base_seed``,
``selection`` (``{"requested": [entries] | None, "rows": [ids run]}``), ``options`` (the
CLI's quick, movement, asf, body, signals), ``started_at``, versions, and ``resumes`` (one
``{"at", "runs", "selection", "options"}`` per ``--resume``). ``--resume`` needs the same
experiment, config, rows and base_seed; the selection and ``--runs`` may differ. It reruns
errored runs and runs missing ones, never an ok or failed one.

**results.json** (:func:`aggregate`, from the run files on disk only)::

    {"experiment", "n_runs", "n_ok", "n_failed", "n_error",
     "rows": [{"row", "row_index", "params", "paper", "n", "n_ok", "n_failed",
               "n_error", "n_fallback", "failures": [{"seed", "fail_reason"}],
               "errors": [{"seed", "error"}], "seeds",
               "metrics": {name: {mean, variance, sd, median, min, max, n}},
               "wall_s": {"mean", "total"}}]}

with ``n = n_ok + n_failed`` (the runs that are data) and metric statistics over the ok
runs only. ``table.md`` shows ``failed / n`` per row (``1 / 20 (+1 error)``) and says
under the table that the means exclude failed runs.

While a sweep runs, ``out/sweep.lock`` (its pid, host and start time) keeps a second
sweep out of the folder (:mod:`skinny_mj.engine.folder`; a lock whose process died on
this host is taken over, with a warning of the ``skinny_mj`` logger).

Output layout::

    results/<experiment>/<timestamp>/{config.json, runs/*.json, results.json, table.md}
"""

from __future__ import annotations

import functools
import logging
import os
import sys
from collections.abc import Callable, Iterable, Mapping, Sequence
from pathlib import Path
from typing import Any

from skinny_mj.engine.folder import prepare_out_dir, sweep_lock
from skinny_mj.engine.plan import Experiment
from skinny_mj.engine.stats import aggregate, load_run, markdown_table
from skinny_mj.engine.study import Row
from skinny_mj.engine.sweep import (
    RunFailed,
    RunSpec,
    execute_batch,
    execute_run,
    iter_dask,
    iter_joblib,
    run_seed,
)
from skinny_mj.errors import SkinnyInputError
from skinny_mj.io import atomic_write_json, atomic_write_text
from skinny_mj.preflight import new_folder

_log = logging.getLogger(__name__)

__all__ = ["Row", "Experiment", "RunFailed", "RunSpec", "run_seed", "select_rows",
           "run_sweep", "aggregate", "markdown_table", "execute_run", "execute_batch",
           "default_out_dir", "default_workers", "default_batch_size"]

def _entries(rows: Sequence[str] | str) -> list[str]:
    parts = rows.split(",") if isinstance(rows, str) else rows
    return [e.strip() for e in parts if e.strip()]


def select_rows(experiment: Experiment, rows: Sequence[str] | str | None = None
                ) -> tuple[Row, ...]:
    """The rows named by ``rows`` (row ids and group names; a string is split at commas),
    in experiment order; None selects every row."""
    if rows is None:
        return tuple(r for r in experiment.rows if r.id not in experiment.unavailable)
    entries = _entries(rows)
    ids = [r.id for r in experiment.rows]
    unknown = [e for e in entries if e not in ids and e not in experiment.groups]
    if unknown or not entries:
        what = f"no row or group {', '.join(map(repr, unknown))}" if unknown else "no rows"
        raise SkinnyInputError(
            f"experiment {experiment.name!r} has {what}; groups: "
            f"{', '.join(experiment.groups) or '(none)'}; row ids: {', '.join(ids)}")
    chosen = {m for e in entries for m in experiment.groups.get(e, (e,))}
    missing = sorted(chosen & set(experiment.unavailable))
    if missing:
        raise SkinnyInputError(f"experiment {experiment.name!r}: row {missing[0]!r} "
                               f"{experiment.unavailable[missing[0]]}")
    return tuple(r for r in experiment.rows if r.id in chosen)


def default_workers(workers: int | None = None) -> int:
    """``workers``, or by default every core this process may use."""
    if workers is not None:
        return workers
    if hasattr(os, "sched_getaffinity"):
        return len(os.sched_getaffinity(0))
    return os.cpu_count() or 1


def default_batch_size(n_rows: int, runs: int, workers: int) -> int:
    """Seeds per lockstep batch: as many as possible (a step's Python overhead is
    shared by the whole batch: ~55 us + ~5 us per run at N = 200), cutting each row
    into the fewest equal chunks that give every worker the same number of jobs."""
    splits = 1
    while (n_rows * splits) % workers and splits < runs:
        splits += 1
    return max(1, -(-runs // splits))


def _batches(specs: list[RunSpec], size: int) -> list[list[RunSpec]]:
    """Group specs by row, then cut each row's seeds into chunks of at most ``size``."""
    by_row: dict[str, list[RunSpec]] = {}
    for spec in specs:
        by_row.setdefault(spec.row.id, []).append(spec)
    return [group[i:i + size] for group in by_row.values() for i in range(0, len(group), size)]


def default_out_dir(experiment_name: str, root: str | Path = "results") -> Path:
    """A new folder ``results/<experiment>/<UTC timestamp>``, made now: a sweep started
    in the same second gets ``<timestamp>-2`` (:func:`skinny_mj.preflight.new_folder`)."""
    return new_folder(Path(root) / experiment_name)


def _key(job: RunSpec | list[RunSpec]) -> str:
    return job.filename if isinstance(job, RunSpec) else "+".join(s.filename for s in job)


def _run_specs(experiment: Experiment, runs: int, selected: Sequence[Row]) -> list[RunSpec]:
    chosen = {r.id for r in selected}
    return [RunSpec(row, i, k, run_seed(experiment.base_seed, row.seeds_of or row.id, k))
            for k in range(runs) for i, row in enumerate(experiment.rows)
            if row.id in chosen and (row.runs is None or k < row.runs)]


def _report(records: list[dict[str, Any]]) -> None:
    """A warning per batch that fell back, per errored run and per failed run."""
    if records and records[0].get("fallback"):
        _log.warning("row %s: run_batch raised %s; ran its seeds one by one",
                     records[0]["row"], records[0]["fallback"])
    for rec in records:
        name = f"{rec['row']}-{rec['seed']}.json"
        if rec["status"] == "error":
            _log.warning("run %s errored (a bug, not data): %s", name, rec["error"])
        elif rec["status"] == "failed":
            _log.warning("run %s failed (diverged): %s", name, rec["fail_reason"])


def run_sweep(experiment: Experiment, out_dir: str | Path | None = None, *,
              rows: Sequence[str] | str | None = None, runs: int | None = None,
              workers: int | None = None, resume: bool = False, scheduler: str | None = None,
              progress: bool = True, batch_size: int | None = None,
              options: Mapping[str, Any] | None = None) -> dict[str, Any]:
    """Run the (row, seed) runs of ``experiment`` and write its results.

    Parameters
    ----------
    experiment : the sweep (all its rows).
    out_dir : output folder; default a new ``results/<name>/<timestamp>`` (made now,
        never another sweep's).
    rows : row ids and group names to run (default: all); seeds do not depend on it.
    runs : runs per row (default ``experiment.runs``).
    workers : parallel processes (default: all cores); 1 runs in this process.
    resume : skip runs whose ok or failed file is already in ``out_dir/runs``
        (errored runs run again).
    scheduler : None (joblib), ``"local"`` (a Dask LocalCluster on 127.0.0.1) or a
        Dask scheduler address ``tcp://host:port``. Same run files either way.
    progress : tqdm bar over runs (with ETA) on stderr.
    batch_size : the most seeds of one row a worker runs in lockstep; default
        :func:`default_batch_size` (whole rows when the rows share out evenly over the
        workers). 0: every run a job of its own (``Experiment.run_one``).
    options : recorded in ``config.json`` (the CLI's quick, movement, asf, body, signals).

    Returns
    -------
    The results dict also written to ``out_dir/results.json`` (see :func:`aggregate`;
    ``n_error`` counts errored runs on disk); ``table.md`` is written beside it.
    """
    selected = select_rows(experiment, rows)
    if rows is None and experiment.unavailable:
        for row_id, why in experiment.unavailable.items():
            _log.warning("%s: row %s left out: it %s", experiment.name, row_id, why)
    runs = experiment.runs if runs is None else int(runs)
    if runs < 1:
        raise SkinnyInputError(f"runs must be >= 1, got {runs}")
    workers = default_workers(workers)
    if workers < 1:
        raise SkinnyInputError(f"workers must be >= 1, got {workers}")
    if out_dir is None:
        if resume:
            raise SkinnyInputError("--resume needs the --out folder of the sweep to resume")
        out_dir = default_out_dir(experiment.name)
    out_dir = Path(out_dir)
    invocation = {"runs": runs, "options": dict(options or {}), "selection": {
        "requested": None if rows is None else _entries(rows),
        "rows": [r.id for r in selected]}}
    with sweep_lock(out_dir):  # one sweep at a time in a folder
        prepare_out_dir(experiment, out_dir, runs, resume, invocation)
        results = _sweep(experiment, out_dir, selected, runs, workers, resume, scheduler,
                         progress, batch_size)
        atomic_write_text(out_dir / "table.md",  # a --quick sweep's says it is a smoke test
                          markdown_table(results, experiment.table_columns,
                                         smoke=bool((options or {}).get("quick"))) + "\n")
        return results


def _sweep(experiment: Experiment, out_dir: Path, selected: Sequence[Row], runs: int,
           workers: int, resume: bool, scheduler: str | None, progress: bool,
           batch_size: int | None) -> dict[str, Any]:
    from tqdm import tqdm

    runs_dir = out_dir / "runs"
    runs_dir.mkdir(parents=True, exist_ok=True)

    specs = _run_specs(experiment, runs, selected)
    if resume:  # an errored run (a bug) runs again; ok and failed runs are data
        n_all = len(specs)
        specs = [s for s in specs if not (runs_dir / s.filename).is_file()
                 or load_run(runs_dir / s.filename)["status"] == "error"]
        _log.info("%s: %d of %d run(s) already in %s are kept", experiment.name,
                  n_all - len(specs), n_all, runs_dir)
    _log.info("%s: %d run(s) of %d row(s) on %s -> %s", experiment.name, len(specs),
              len(selected), scheduler or f"{workers} worker(s)", out_dir)
    jobs: list = specs
    fn: Callable[[Any], Any] = functools.partial(
        execute_run, experiment.run_one, experiment_name=experiment.name)
    if batch_size != 0 and specs:
        size = batch_size or default_batch_size(len(selected), runs, workers)
        jobs = _batches(specs, size)
        fn = functools.partial(execute_batch, experiment.run_batch, experiment.run_one,
                               experiment_name=experiment.name)
    jobs = sorted(jobs, key=lambda job: -sum(
        experiment.cost(spec.row) for spec in (job if isinstance(job, list) else [job])))
    results_iter: Iterable[Any]
    if not jobs:
        results_iter = ()
    elif scheduler is not None:
        results_iter = iter_dask(fn, jobs, workers, scheduler, [_key(j) for j in jobs])
    elif workers == 1:
        results_iter = (fn(job) for job in jobs)
    else:
        results_iter = iter_joblib(fn, jobs, min(workers, len(jobs)))
    with tqdm(total=len(specs), desc=experiment.name, unit="run", file=sys.stderr,
              disable=not progress, dynamic_ncols=True) as bar:
        for result in results_iter:
            records = result if isinstance(result, list) else [result]
            for record in records:
                # The parent writes every file, so remote Dask workers need no shared disk.
                atomic_write_json(runs_dir / f"{record['row']}-{record['seed']}.json", record)
                bar.update(1)
            _report(records)

    return aggregate(out_dir)
