"""Toy sweeps for the engine's tests: a study whose rows run ``run_one(row, seed)`` seed
by seed (``row.params``: the row's params, with the study's)."""

from __future__ import annotations

import functools
import sys
from collections.abc import Callable, Iterable
from typing import Any

import cloudpickle

from skinny_mj.engine.plan import Experiment
from skinny_mj.engine.study import Row, Study

# Loky workers unpickle these by value: they need not import the tests.
cloudpickle.register_pickle_by_value(sys.modules[__name__])


def _each_seed(run_one: Callable[[Row, int], Any], config: Any, row: Row,
               seeds: list[int]) -> list[Any]:
    out: list[Any] = []
    for seed in seeds:
        try:
            out.append(run_one(row, seed))
        except Exception as exc:  # that seed's outcome: a RunFailed is data, others errors
            out.append(exc)
    return out


def toy(name: str, rows: Iterable[Row], run_one: Callable[[Row, int], Any],
        **study: Any) -> Experiment:
    """The sweep of study ``name`` (``study``: its other fields) whose rows run
    ``run_one``, or ``run_batch(config, row, seeds)`` when given."""
    if study.get("run_batch") is None:
        study["run_batch"] = functools.partial(_each_seed, run_one)
    return Study(name, tuple(rows), **study).build()
