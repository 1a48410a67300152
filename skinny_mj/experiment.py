"""The experiment engine shared by every paper: a sweep of (row, seed) runs.

A paper module describes an :class:`Experiment` (its rows with the paper's values and a
``run_one(row, seed) -> dict`` of metrics); :func:`run_sweep` runs it in parallel
(joblib/loky on this machine, or a Dask cluster), writing one JSON file per finished run
to ``out/runs/<row>-<seed>.json``. :func:`aggregate` rebuilds ``results.json`` from those
files only, and :func:`markdown_table` sets our numbers beside the paper's.

Output layout::

    results/<experiment>/<timestamp>/{config.json, runs/*.json, results.json, table.md}
"""

from __future__ import annotations

import dataclasses
import datetime as _dt
import os
import re
import sys
import time
import traceback
from collections.abc import Callable, Iterable, Iterator, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from skinny_mj.errors import SkinnyInputError
from skinny_mj.io import atomic_write_json, atomic_write_text
from skinny_mj.sweep.stats import aggregate, markdown_table, to_jsonable

__all__ = ["Row", "Experiment", "RunFailed", "RunSpec", "run_seed", "run_sweep", "aggregate",
           "markdown_table", "execute_run", "execute_batch", "default_out_dir"]

_SAFE_NAME = re.compile(r"^[A-Za-z0-9_.][A-Za-z0-9_.+=-]*$")
_THREAD_ENV = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")


class RunFailed(RuntimeError):
    """Raised (or returned by ``run_batch``) for a run whose network diverged: the engine
    records the run as failed with this reason instead of its metrics."""


@dataclass(frozen=True)
class Row:
    """One row of a paper's table: its id, the parameters that differ, the paper's values.

    ``runs``: this row's run count when it differs from the experiment's (e.g. a figure
    the paper ran 10 times beside a table of 20); ``--runs N`` caps it at N.
    """

    row_id: str
    params: Mapping[str, Any] = field(default_factory=dict)
    paper: Mapping[str, float] = field(default_factory=dict)
    runs: int | None = None

    def __post_init__(self) -> None:
        if not _SAFE_NAME.match(self.row_id):
            raise SkinnyInputError(f"row id {self.row_id!r} must be a plain file-name word")
        if self.runs is not None and self.runs < 1:
            raise SkinnyInputError(f"row {self.row_id!r}: runs must be >= 1, got {self.runs}")


@dataclass(frozen=True)
class Experiment:
    """A sweep description.

    ``run_one(row, seed) -> dict`` returns a run's metrics (numbers; other JSON-able
    values are kept in the run file but not aggregated). It is shipped to worker
    processes with cloudpickle, so bind the config with ``functools.partial``.
    ``config`` is a frozen dataclass (or a mapping) recorded in ``config.json``.
    With ``run_batch``, the engine hands each worker a chunk of one row's seeds to run
    in lockstep; the run files are the same as with ``run_one``.
    """

    name: str
    rows: tuple[Row, ...]
    run_one: Callable[[Row, int], Mapping[str, Any]]
    config: Any = None
    runs: int = 10
    base_seed: int = 0
    table_columns: tuple[str, ...] | None = None
    #: optional ``run_batch(row, seeds) -> list`` running one row's seeds in lockstep
    #: (the fast path); element k is seed k's metrics dict, or an Exception for a run
    #: that failed. Must give the same metrics as ``run_one`` seed by seed.
    run_batch: Callable[[Row, list[int]], list[Any]] | None = None
    #: optional ``cost(row) -> float``: one run's relative cost (e.g. its control steps).
    #: Only the schedule uses it: the costliest jobs start first (longest processing
    #: time first), so a long row does not start last and keep the other workers idle.
    cost: Callable[[Row], float] | None = None

    def __post_init__(self) -> None:
        if not _SAFE_NAME.match(self.name):
            raise SkinnyInputError(f"experiment name {self.name!r} must be a plain word")
        ids = [r.row_id for r in self.rows]
        if not ids or len(set(ids)) != len(ids):
            raise SkinnyInputError(f"experiment {self.name!r} needs unique row ids, got {ids}")


@dataclass(frozen=True)
class RunSpec:
    """One (row, run) pair with its derived seed."""

    row: Row
    row_index: int
    run_index: int
    seed: int

    @property
    def filename(self) -> str:
        return f"{self.row.row_id}-{self.seed}.json"


def run_seed(base_seed: int, row_index: int, run_index: int) -> int:
    """Seed of one run: a 32-bit int drawn from ``SeedSequence([base, row, run])``."""
    seq = np.random.SeedSequence([int(base_seed), int(row_index), int(run_index)])
    return int(seq.generate_state(1, dtype=np.uint32)[0])


def _config_dict(experiment: Experiment, runs: int) -> dict[str, Any]:
    cfg = experiment.config
    if dataclasses.is_dataclass(cfg) and not isinstance(cfg, type):
        cfg = dataclasses.asdict(cfg)
    return to_jsonable({
        "experiment": experiment.name,
        "config": cfg,
        "rows": [{"row": r.row_id, "params": dict(r.params), "paper": dict(r.paper),
                  **({} if r.runs is None else {"runs": r.runs})} for r in experiment.rows],
        "runs": runs,
        "base_seed": experiment.base_seed,
    })


def _record(spec: RunSpec, experiment_name: str) -> dict[str, Any]:
    return {
        "experiment": experiment_name, "row": spec.row.row_id, "row_index": spec.row_index,
        "run_index": spec.run_index, "seed": spec.seed, "params": dict(spec.row.params),
        "paper": dict(spec.row.paper),
    }


def _finish(record: dict[str, Any], out: Any, tb: str | None = None) -> dict[str, Any]:
    """Fill a record from a run's output: a metrics mapping, or an exception."""
    if not isinstance(out, Mapping | BaseException):
        out = TypeError(f"run_one must return a dict, got {type(out).__name__}")
    if isinstance(out, BaseException):
        tb = tb or "".join(traceback.format_exception(out)[-6:])
        record.update(status="failed", error=f"{type(out).__name__}: {out}",
                      traceback=tb, metrics={})
    else:
        metrics = to_jsonable(dict(out))
        bad = sorted(k for k, v in out.items() if isinstance(v, float | np.floating)
                     and not np.isfinite(v))
        record.update(status="ok", error=None, metrics=metrics, nonfinite_metrics=bad)
    return record


def _stamp(record: dict[str, Any], wall_s: float) -> dict[str, Any]:
    record["wall_s"] = wall_s
    record["finished_at"] = _dt.datetime.now(_dt.UTC).isoformat(timespec="seconds")
    return record


def execute_run(run_one: Callable[[Row, int], Mapping[str, Any]], spec: RunSpec,
                experiment_name: str) -> dict[str, Any]:
    """Run one (row, seed) and return its JSON-able record; an exception becomes a
    ``"failed"`` record with the error, never a lost run."""
    start = time.perf_counter()
    record = _record(spec, experiment_name)
    try:
        out: Any = run_one(spec.row, spec.seed)
    except Exception as exc:  # a run's failure is data, not a crash
        out = exc
    _finish(record, out)
    return _stamp(record, time.perf_counter() - start)


def execute_batch(run_batch: Callable[[Row, list[int]], list[Any]],
                  run_one: Callable[[Row, int], Mapping[str, Any]], specs: list[RunSpec],
                  experiment_name: str) -> list[dict[str, Any]]:
    """Run several seeds of ONE row in lockstep and return one record per seed.

    ``wall_s`` of each record is the batch's wall time divided by its size. If the
    batch itself raises, its seeds are run one by one with ``run_one`` instead, so a
    single bad seed cannot lose the others.
    """
    rows = {spec.row.row_id for spec in specs}
    if len(rows) != 1:
        raise ValueError(f"a batch holds one row, got {sorted(rows)}")
    start = time.perf_counter()
    try:
        outs = list(run_batch(specs[0].row, [spec.seed for spec in specs]))
        if len(outs) != len(specs):
            raise ValueError(f"run_batch returned {len(outs)} results for {len(specs)} seeds")
    except Exception:
        return [execute_run(run_one, spec, experiment_name) for spec in specs]
    share = (time.perf_counter() - start) / len(specs)
    return [_stamp(_finish(_record(spec, experiment_name), out), share)
            for spec, out in zip(specs, outs, strict=True)]


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
        by_row.setdefault(spec.row.row_id, []).append(spec)
    return [group[i:i + size] for group in by_row.values()
            for i in range(0, len(group), size)]


def default_out_dir(experiment_name: str, root: str | Path = "results") -> Path:
    """``results/<experiment>/<UTC timestamp>``."""
    stamp = _dt.datetime.now(_dt.UTC).strftime("%Y%m%d-%H%M%S")
    return Path(root) / experiment_name / stamp


def _iter_joblib(fn, specs: list, workers: int) -> Iterator[Any]:
    from joblib import Parallel, delayed, parallel_config

    # One BLAS/OpenMP thread per worker: with several processes, more threads
    # oversubscribe the cores and slow every step down 5-25x.
    with parallel_config(backend="loky", inner_max_num_threads=1):
        parallel = Parallel(n_jobs=workers, return_as="generator_unordered")
        yield from parallel(delayed(fn)(spec) for spec in specs)


def _iter_dask(fn, specs: list, workers: int, scheduler: str) -> Iterator[Any]:
    try:
        from dask.distributed import Client, LocalCluster, as_completed
    except ImportError as exc:
        raise SkinnyInputError(
            "--scheduler needs Dask distributed: pip install 'skinny-mj[dask]'") from exc
    cluster = None
    if scheduler == "local":
        cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                               host="127.0.0.1", dashboard_address=None,
                               env={k: "1" for k in _THREAD_ENV})
        client = Client(cluster)
    elif scheduler.startswith(("tcp://", "tls://", "ws://", "wss://")):
        client = Client(scheduler)
    else:
        raise SkinnyInputError(f"scheduler must be 'local' or an address like "
                               f"tcp://host:8786, got {scheduler!r}")
    try:
        futures = [client.submit(fn, spec, pure=False, key=f"run-{_key(spec)}")
                   for spec in specs]
        for future in as_completed(futures):
            yield future.result()
    finally:
        client.close()
        if cluster is not None:
            cluster.close()


def _key(spec: RunSpec | list[RunSpec]) -> str:
    return spec.filename if isinstance(spec, RunSpec) else "+".join(s.filename for s in spec)


def _run_specs(experiment: Experiment, runs: int) -> list[RunSpec]:
    return [RunSpec(row, i, k, run_seed(experiment.base_seed, i, k))
            for k in range(runs) for i, row in enumerate(experiment.rows)
            if row.runs is None or k < row.runs]


def _prepare_out_dir(experiment: Experiment, out_dir: Path, runs: int, resume: bool) -> None:
    config = _config_dict(experiment, runs)
    config_path = out_dir / "config.json"
    if resume and config_path.is_file():
        import json

        old = json.loads(config_path.read_text())
        same = {k: old.get(k) for k in ("experiment", "config", "rows", "base_seed")}
        if same != {k: config[k] for k in same}:
            raise SkinnyInputError("holds a different sweep (experiment, config, rows or "
                                   "seed differ); use a new --out", path=config_path)
        return
    config["started_at"] = _dt.datetime.now(_dt.UTC).isoformat(timespec="seconds")
    config["python"] = sys.version.split()[0]
    config["numpy"] = np.__version__
    atomic_write_json(config_path, config)


def run_sweep(experiment: Experiment, out_dir: str | Path | None = None, *,
              runs: int | None = None, workers: int | None = None, resume: bool = False,
              scheduler: str | None = None, progress: bool = True,
              batch_size: int | None = None) -> dict[str, Any]:
    """Run every (row, seed) of ``experiment`` and write its results.

    Parameters
    ----------
    experiment : the sweep.
    out_dir : output folder; default ``results/<name>/<timestamp>``.
    runs : runs per row (default ``experiment.runs``).
    workers : parallel processes (default: all cores); 1 runs in this process.
    resume : skip runs whose file already exists in ``out_dir/runs``.
    scheduler : None (joblib), ``"local"`` (a Dask LocalCluster on 127.0.0.1) or a
        Dask scheduler address ``tcp://host:port``. Same run files either way.
    progress : tqdm bar over runs (with ETA) on stderr.
    batch_size : with ``experiment.run_batch``, the most seeds of one row a worker runs
        in lockstep; default :func:`default_batch_size` (whole rows when the rows
        share out evenly over the workers). 0 disables the fast path (every run
        through ``run_one``).

    Returns
    -------
    The results dict also written to ``out_dir/results.json`` (see :func:`aggregate`);
    ``table.md`` is written beside it.
    """
    import functools

    from tqdm import tqdm

    runs = experiment.runs if runs is None else int(runs)
    if runs < 1:
        raise SkinnyInputError(f"runs must be >= 1, got {runs}")
    if workers is None:
        workers = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") \
            else (os.cpu_count() or 1)
    if workers < 1:
        raise SkinnyInputError(f"workers must be >= 1, got {workers}")
    if out_dir is None:
        if resume:
            raise SkinnyInputError("--resume needs the --out folder of the sweep to resume")
        out_dir = default_out_dir(experiment.name)
    out_dir = Path(out_dir)
    runs_dir = out_dir / "runs"
    runs_dir.mkdir(parents=True, exist_ok=True)
    _prepare_out_dir(experiment, out_dir, runs, resume)

    specs = _run_specs(experiment, runs)
    if resume:
        specs = [s for s in specs if not (runs_dir / s.filename).is_file()]
    jobs: list = specs
    fn: Callable[[Any], Any] = functools.partial(
        execute_run, experiment.run_one, experiment_name=experiment.name)
    if experiment.run_batch is not None and batch_size != 0 and specs:
        size = batch_size or default_batch_size(len(experiment.rows), runs, workers)
        jobs = _batches(specs, size)
        fn = functools.partial(execute_batch, experiment.run_batch, experiment.run_one,
                               experiment_name=experiment.name)
    if experiment.cost is not None:
        cost = experiment.cost
        jobs = sorted(jobs, key=lambda job: -sum(
            cost(spec.row) for spec in (job if isinstance(job, list) else [job])))
    results_iter: Iterable[Any]
    if not jobs:
        results_iter = ()
    elif scheduler is not None:
        results_iter = _iter_dask(fn, jobs, workers, scheduler)
    elif workers == 1:
        results_iter = (fn(job) for job in jobs)
    else:
        results_iter = _iter_joblib(fn, jobs, min(workers, len(jobs)))
    with tqdm(total=len(specs), desc=experiment.name, unit="run", file=sys.stderr,
              disable=not progress, dynamic_ncols=True) as bar:
        for result in results_iter:
            for record in result if isinstance(result, list) else [result]:
                # The parent writes every file, so remote Dask workers need no shared disk.
                name = f"{record['row']}-{record['seed']}.json"
                atomic_write_json(runs_dir / name, record)
                bar.update(1)
                if record["status"] != "ok":
                    bar.write(f"run {name} failed: {record['error']}", file=sys.stderr)

    results = aggregate(out_dir)
    atomic_write_text(out_dir / "table.md",
                      markdown_table(results, experiment.table_columns) + "\n")
    return results
