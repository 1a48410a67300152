"""Helpers of the experiment engine (:mod:`skinny_mj.engine.experiment`, which re-exports the
public names and documents the contract).

Here: how a run is seeded, one (row, run) pair's :class:`RunSpec`, one job's run
records (:func:`execute_run`, :func:`execute_batch`: a run's outcome -> ``"ok"``,
``"failed"`` or ``"error"``), and where the jobs run, joblib/loky on this
machine (:func:`iter_joblib`) or a Dask cluster (:func:`iter_dask`), both yielding job
results as they finish, in any order; :mod:`skinny_mj.engine.stats` turns run files into
results.
"""

from __future__ import annotations

import datetime as _dt
import hashlib
import json
import re
import time
import traceback
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from skinny_mj.engine.stats import to_jsonable
from skinny_mj.errors import SkinnyEnvironmentError, SkinnyInputError
from skinny_mj.threads import single_threaded

__all__ = ["THREAD_ENV", "SEEDING", "SAFE_NAME", "run_seed", "stable_hash", "RunSpec",
           "RunFailed", "one_of_batch", "execute_run", "execute_batch", "iter_joblib",
           "iter_dask"]

#: The BLAS/OpenMP thread variables pinned to 1 in every worker process.
THREAD_ENV = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")


#: How :func:`run_seed` derives seeds; ``config.json`` records it and ``--resume`` refuses
#: a sweep folder seeded another way (before it, seeds came from a row's position).
SEEDING = "row-id"


def stable_hash(text: str) -> int:
    """A 64-bit integer of ``text`` that is the same on every machine, Python and run
    (Python's own ``hash`` of a string is salted per process)."""
    return int.from_bytes(hashlib.sha256(text.encode("utf-8")).digest()[:8], "little")


def run_seed(base_seed: int, row_id: str, run_index: int) -> int:
    """Seed of one run: a 32-bit int drawn from
    ``SeedSequence([base, stable_hash(row_id), run])``."""
    if not isinstance(row_id, str):
        raise TypeError(f"run_seed takes a row id (str), not {type(row_id).__name__}")
    seq = np.random.SeedSequence([int(base_seed), stable_hash(row_id), int(run_index)])
    return int(seq.generate_state(1, dtype=np.uint32)[0])


#: A row's or an experiment's name: a plain file-name word (no "..", no hidden file).
SAFE_NAME = re.compile(r"^[A-Za-z0-9_][A-Za-z0-9_.+=-]*$")


@dataclass(frozen=True)
class RunSpec:
    """One (row, run) pair with its derived seed: ``row`` a
    :class:`~skinny_mj.engine.study.Row`, ``row_index`` its place in the experiment's
    ``rows``."""

    row: Any
    row_index: int
    run_index: int
    seed: int

    @property
    def filename(self) -> str:
        return f"{self.row.id}-{self.seed}.json"


class RunFailed(RuntimeError):
    """Raised by ``run_one`` (or returned by ``run_batch``) for a run whose network
    diverged: the run is recorded as ``"failed"`` with this message as its reason. Any
    other exception is a bug and is recorded as ``"error"``."""


def one_of_batch(run_batch: Callable[[Any, list[int]], list[Any]], row: Any,
                 seed: int) -> Mapping[str, Any]:
    """``run_one`` from a lockstep ``run_batch``: the batch of one seed, its
    :class:`RunFailed` (or any other exception instance) raised."""
    (out,) = run_batch(row, [seed])
    if isinstance(out, BaseException):
        raise out
    return out


def _record(spec: RunSpec, experiment_name: str) -> dict[str, Any]:
    return {
        "experiment": experiment_name, "row": spec.row.id, "row_index": spec.row_index,
        "run_index": spec.run_index, "seed": spec.seed, "params": to_jsonable(spec.row.settings),
        "paper": to_jsonable(spec.row.paper), "status": None, "metrics": {},
        "fail_reason": None, "error": None,
    }


def _error(record: dict[str, Any], exc: BaseException, note: str = "") -> dict[str, Any]:
    if exc.__traceback__ is not None:
        tb = "".join(traceback.format_exception(exc))
    else:
        tb = f"{type(exc).__name__}: {exc}\n(no traceback: {note or 'never raised'})\n"
    record.update(status="error", error=f"{type(exc).__name__}: {exc}", traceback=tb)
    return record


def _finish(record: dict[str, Any], out: Any, where: str) -> dict[str, Any]:
    """Fill a record from a run's outcome: metrics, a RunFailed, or anything else."""
    if isinstance(out, RunFailed):
        record.update(status="failed", fail_reason=str(out) or type(out).__name__)
        return record
    if isinstance(out, BaseException):
        return _error(record, out, f"returned by {where}, not raised")
    if not isinstance(out, Mapping):
        return _error(record, TypeError(f"{where} must give a dict of metrics, got "
                                        f"{type(out).__name__}"))
    metrics = to_jsonable(dict(out))
    try:
        json.dumps(metrics, allow_nan=False)
    except (TypeError, ValueError) as exc:  # caught here, not when the parent writes
        return _error(record, exc)
    bad = sorted(str(k) for k, v in out.items() if isinstance(v, float | np.floating)
                 and not np.isfinite(v))
    record.update(status="ok", metrics=metrics, nonfinite_metrics=bad)
    return record


def _stamp(record: dict[str, Any], wall_s: float) -> dict[str, Any]:
    record["wall_s"] = wall_s
    record["finished_at"] = _dt.datetime.now(_dt.UTC).isoformat(timespec="seconds")
    return record


@single_threaded
def execute_run(run_one: Callable[[Any, int], Mapping[str, Any]], spec: RunSpec,
                experiment_name: str) -> dict[str, Any]:
    """Run one (row, seed) and return its JSON-able record: ``"ok"``, ``"failed"`` (a
    :class:`RunFailed`) or ``"error"`` (any other exception, with its traceback)."""
    start = time.perf_counter()
    record = _record(spec, experiment_name)
    try:
        out: Any = run_one(spec.row, spec.seed)
    except Exception as exc:  # RunFailed is data; anything else is kept as an error
        out = exc
    _finish(record, out, "run_one")
    return _stamp(record, time.perf_counter() - start)


@single_threaded
def execute_batch(run_batch: Callable[[Any, list[int]], list[Any]],
                  run_one: Callable[[Any, int], Mapping[str, Any]], specs: list[RunSpec],
                  experiment_name: str) -> list[dict[str, Any]]:
    """Run several seeds of ONE row in lockstep and return one record per seed.

    ``wall_s`` of each record is the batch's wall time divided by its size. If the
    batch itself raises, its seeds are run one by one with ``run_one`` instead, so a
    single bad seed cannot lose the others, and each record says so in ``fallback``.
    """
    rows = {spec.row.id for spec in specs}
    if len(rows) != 1:
        raise ValueError(f"a batch holds one row, got {sorted(rows)}")
    start = time.perf_counter()
    try:
        outs = list(run_batch(specs[0].row, [spec.seed for spec in specs]))
        if len(outs) != len(specs):
            raise ValueError(f"run_batch returned {len(outs)} results for {len(specs)} seeds")
    except Exception as exc:
        note = f"{type(exc).__name__}: {exc} (batch of {len(specs)} seeds)"
        tb = "".join(traceback.format_exception(exc))
        records = [execute_run(run_one, spec, experiment_name) for spec in specs]
        for record in records:
            record.update(fallback=note, fallback_traceback=tb)
        return records
    share = (time.perf_counter() - start) / len(specs)
    return [_stamp(_finish(_record(spec, experiment_name), out, "run_batch"), share)
            for spec, out in zip(specs, outs, strict=True)]


def iter_joblib(fn: Callable[[Any], Any], jobs: Sequence[Any], workers: int) -> Iterator[Any]:
    """``fn(job)`` for every job in ``workers`` loky processes, yielded as they finish."""
    from concurrent.futures import BrokenExecutor

    from joblib import Parallel, delayed, parallel_config

    # One BLAS/OpenMP thread per worker: with several processes, more threads
    # oversubscribe the cores and slow every step down 5-25x.
    with parallel_config(backend="loky", inner_max_num_threads=1):
        parallel = Parallel(n_jobs=workers, return_as="generator_unordered")
        try:
            yield from parallel(delayed(fn)(job) for job in jobs)
        except BrokenExecutor as exc:  # a worker was killed (OOM killer, kill -9)
            raise SkinnyEnvironmentError(
                f"a worker process died mid-run ({' '.join(str(exc).split()[:14])}...); "
                "every run that finished is saved: continue with --resume") from None


#: Seconds to wait for a remote Dask scheduler before giving up (Dask's default is 30 s).
DASK_CONNECT_TIMEOUT_S = 10


def iter_dask(fn: Callable[[Any], Any], jobs: Sequence[Any], workers: int, scheduler: str,
              keys: Sequence[str]) -> Iterator[Any]:
    """``fn(job)`` on a Dask cluster: ``scheduler`` is ``"local"`` (a LocalCluster of
    ``workers`` processes on 127.0.0.1) or an address ``tcp://host:port``; ``keys`` name
    the tasks (one per job, unique). Connects at once (not at the first result), so an
    unreachable scheduler is an error before the sweep starts."""
    client, cluster = _dask_client(workers, scheduler)
    return _dask_results(client, cluster, fn, jobs, keys)


#: Address schemes of a remote Dask scheduler (``--scheduler tcp://host:8786``).
SCHEDULER_SCHEMES = ("tcp://", "tls://", "ws://", "wss://")


def check_scheduler(scheduler: str) -> str:
    """``scheduler`` if it is ``"local"`` or a Dask address, else a
    :class:`SkinnyInputError` (before the sweep's folder is made)."""
    if scheduler != "local" and not scheduler.startswith(SCHEDULER_SCHEMES):
        raise SkinnyInputError(f"scheduler must be 'local' or an address like "
                               f"tcp://host:8786, got {scheduler!r}")
    return scheduler


def _dask_client(workers: int, scheduler: str) -> tuple[Any, Any]:
    try:
        from dask.distributed import Client, LocalCluster
    except ImportError as exc:
        raise SkinnyInputError(
            "--scheduler needs Dask distributed: pip install 'skinny-mj[dask]'") from exc
    cluster = None
    if scheduler == "local":
        cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                               host="127.0.0.1", dashboard_address=None,
                               env={k: "1" for k in THREAD_ENV})
        client = Client(cluster)
    elif scheduler.startswith(SCHEDULER_SCHEMES):
        try:
            client = Client(scheduler, timeout=DASK_CONNECT_TIMEOUT_S)
        except OSError as exc:  # refused or timed out (TimeoutError is an OSError)
            raise SkinnyEnvironmentError(
                f"cannot reach the Dask scheduler {scheduler} within "
                f"{DASK_CONNECT_TIMEOUT_S} s ({' '.join(str(exc).split())}); is it "
                "running, and is the address right?") from None
    else:
        raise SkinnyInputError(f"scheduler must be 'local' or an address like "
                               f"tcp://host:8786, got {scheduler!r}")
    return client, cluster


def _dask_results(client: Any, cluster: Any, fn: Callable[[Any], Any], jobs: Sequence[Any],
                  keys: Sequence[str]) -> Iterator[Any]:
    from dask.distributed import as_completed

    try:
        futures = [client.submit(fn, job, pure=False, key=f"run-{key}")
                   for job, key in zip(jobs, keys, strict=True)]
        for future in as_completed(futures):
            yield future.result()
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
