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

__all__ = ["Row", "Experiment", "RunSpec", "run_seed", "run_sweep", "aggregate",
           "markdown_table", "execute_run", "default_out_dir"]

_SAFE_NAME = re.compile(r"^[A-Za-z0-9_.][A-Za-z0-9_.+=-]*$")
_THREAD_ENV = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")


@dataclass(frozen=True)
class Row:
    """One row of a paper's table: its id, the parameters that differ, the paper's values."""

    row_id: str
    params: Mapping[str, Any] = field(default_factory=dict)
    paper: Mapping[str, float] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if not _SAFE_NAME.match(self.row_id):
            raise SkinnyInputError(f"row id {self.row_id!r} must be a plain file-name word")


@dataclass(frozen=True)
class Experiment:
    """A sweep description.

    ``run_one(row, seed) -> dict`` returns a run's metrics (numbers; other JSON-able
    values are kept in the run file but not aggregated). It is shipped to worker
    processes with cloudpickle, so bind the config with ``functools.partial``.
    ``config`` is a frozen dataclass (or a mapping) recorded in ``config.json``.
    """

    name: str
    rows: tuple[Row, ...]
    run_one: Callable[[Row, int], Mapping[str, Any]]
    config: Any = None
    runs: int = 10
    base_seed: int = 0
    table_columns: tuple[str, ...] | None = None

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
        "rows": [{"row": r.row_id, "params": dict(r.params), "paper": dict(r.paper)}
                 for r in experiment.rows],
        "runs": runs,
        "base_seed": experiment.base_seed,
    })


def execute_run(run_one: Callable[[Row, int], Mapping[str, Any]], spec: RunSpec,
                experiment_name: str) -> dict[str, Any]:
    """Run one (row, seed) and return its JSON-able record; an exception becomes a
    ``"failed"`` record with the error, never a lost run."""
    start = time.perf_counter()
    record: dict[str, Any] = {
        "experiment": experiment_name, "row": spec.row.row_id, "row_index": spec.row_index,
        "run_index": spec.run_index, "seed": spec.seed, "params": dict(spec.row.params),
        "paper": dict(spec.row.paper),
    }
    try:
        out = run_one(spec.row, spec.seed)
        if not isinstance(out, Mapping):
            raise TypeError(f"run_one must return a dict, got {type(out).__name__}")
        metrics = to_jsonable(dict(out))
        bad = sorted(k for k, v in out.items() if isinstance(v, float | np.floating)
                     and not np.isfinite(v))
        record.update(status="ok", error=None, metrics=metrics, nonfinite_metrics=bad)
    except Exception as exc:  # a run's failure is data, not a crash
        tb = traceback.format_exception(exc)
        record.update(status="failed", error=f"{type(exc).__name__}: {exc}",
                      traceback="".join(tb[-6:]), metrics={})
    record["wall_s"] = time.perf_counter() - start
    record["finished_at"] = _dt.datetime.now(_dt.UTC).isoformat(timespec="seconds")
    return record


def default_out_dir(experiment_name: str, root: str | Path = "results") -> Path:
    """``results/<experiment>/<UTC timestamp>``."""
    stamp = _dt.datetime.now(_dt.UTC).strftime("%Y%m%d-%H%M%S")
    return Path(root) / experiment_name / stamp


def _iter_joblib(fn, specs: list[RunSpec], workers: int) -> Iterator[dict[str, Any]]:
    from joblib import Parallel, delayed, parallel_config

    # One BLAS/OpenMP thread per worker: with several processes, more threads
    # oversubscribe the cores and slow every step down 5-25x.
    with parallel_config(backend="loky", inner_max_num_threads=1):
        parallel = Parallel(n_jobs=workers, return_as="generator_unordered")
        yield from parallel(delayed(fn)(spec) for spec in specs)


def _iter_dask(fn, specs: list[RunSpec], workers: int, scheduler: str
               ) -> Iterator[dict[str, Any]]:
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
        futures = [client.submit(fn, spec, pure=False, key=f"run-{spec.filename}")
                   for spec in specs]
        for future in as_completed(futures):
            yield future.result()
    finally:
        client.close()
        if cluster is not None:
            cluster.close()


def _run_specs(experiment: Experiment, runs: int) -> list[RunSpec]:
    return [RunSpec(row, i, k, run_seed(experiment.base_seed, i, k))
            for k in range(runs) for i, row in enumerate(experiment.rows)]


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
              scheduler: str | None = None, progress: bool = True) -> dict[str, Any]:
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
    fn = functools.partial(execute_run, experiment.run_one, experiment_name=experiment.name)
    results_iter: Iterable[dict[str, Any]]
    if not specs:
        results_iter = ()
    elif scheduler is not None:
        results_iter = _iter_dask(fn, specs, workers, scheduler)
    elif workers == 1:
        results_iter = (fn(spec) for spec in specs)
    else:
        results_iter = _iter_joblib(fn, specs, min(workers, len(specs)))
    with tqdm(total=len(specs), desc=experiment.name, unit="run", file=sys.stderr,
              disable=not progress, dynamic_ncols=True) as bar:
        for record in results_iter:
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
