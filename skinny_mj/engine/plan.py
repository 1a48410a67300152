"""What the engine derives from a :class:`~skinny_mj.engine.study.Study`: a :class:`Plan` (every
kept row with its training configuration) and from it the engine's
:class:`~skinny_mj.engine.experiment.Experiment` (rows, groups, the lockstep run, one run,
cost, table columns, the report).

A row's configuration is ``study.base`` with, in order, the options of ``skinny
experiment`` (``--movement`` -> trajectory + asf, ``--body``, ``--signals``: those the
study ``takes``, any other refused in one line), the row's overrides (and, under
``--quick``, the row's ``quick`` ones), then the overrides after every row's
(``Quick.overrides``; the contract test's ``tiny``). An option the study takes its own way
(``Study.own_options``) sets no config key: the study its function returns is planned. A
quick sweep keeps ``Quick.rows`` (default: every row) in the study's order, a full sweep
every row but the ``quick_only`` ones, and a run's seed is
``run_seed(base_seed, row_id, run_index)``: the row's id, not its place, fixes its seeds.
A row that is another study's row (``Row.of``) runs that study's planned row (its
configuration, shape, parameters, ``--quick``'s and ``tiny``'s with this sweep's) under
its own id and seeds.
"""

from __future__ import annotations

import dataclasses
import functools
import importlib
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from skinny_mj.engine.experiment import Experiment
from skinny_mj.engine.experiment import Row as EngineRow
from skinny_mj.engine.options import movement_changes
from skinny_mj.engine.results import Metrics, Shape, default_run, read_metric
from skinny_mj.engine.stats import load_runs
from skinny_mj.engine.sweep import one_of_batch
from skinny_mj.errors import SkinnyInputError
from skinny_mj.training import overrides
from skinny_mj.training.config import TrainConfig, relative_cost

# The study's types (skinny_mj.engine.study's Study, Row, RunBatch), named for the
# reader only: the study module imports this one to build its sweep, not the other way round.
Study = Row = RunBatch = Any

__all__ = ["Plan", "Results", "plan", "train_metrics", "read_metric"]


def train_metrics(config: TrainConfig, seeds: list[int], metrics: Metrics) -> list[Any]:
    """The default run of a row on its config alone, the standard test, ``metrics``
    read off each result (:func:`skinny_mj.engine.results.default_run`)."""
    return default_run(config, None, seeds, Shape(metrics))


@dataclass(frozen=True)
class _Runner:
    """The Experiment's ``run_batch`` (shipped to worker processes): per row id its
    config, the row its run gets (params with the study's) and its custom run or its
    shape."""

    rows: Mapping[str, tuple[TrainConfig, Row, RunBatch | None, Shape | None]]

    def __call__(self, row: EngineRow, seeds: list[int]) -> list[Any]:
        config, study_row, custom, shape = self.rows[row.id]
        if custom is not None:
            return list(custom(config, study_row, list(seeds)))
        return default_run(config, study_row, list(seeds), shape)


def _cost(plan: Plan, costs: dict[str, float], row: EngineRow) -> float:
    """Row ``row``'s relative cost, worked out when the schedule first asks (a study's
    own cost may load a movement: a study's ``--help`` builds the sweep but runs none)."""
    if row.id not in costs:
        p, cost = plan.row(row.id), plan.study.cost
        costs[row.id] = relative_cost(p.config) if cost is None \
            else cost(p.config, plan.run_row(row.id))
    return costs[row.id]


class Results(dict):
    """The sweep's results (the dict :func:`skinny_mj.engine.stats.aggregate` wrote), with
    the run files at hand: :meth:`runs` and :meth:`values`."""

    def __init__(self, summary: Mapping[str, Any], out_dir: str | Path) -> None:
        super().__init__(summary)
        self.out_dir = Path(out_dir)

    def runs(self, row_id: str | None = None, status: str | None = "ok") -> list[dict]:
        """The run records of ``row_id`` (None: every row) with ``status`` (None: any)."""
        return [r for r in load_runs(self.out_dir) if row_id in (None, r["row"])
                and status in (None, r["status"])]

    def values(self, row_id: str, metric: str) -> list[float]:
        """``metric`` of every ok run of ``row_id`` that has a number for it."""
        return [r["metrics"][metric] for r in self.runs(row_id)
                if isinstance(r["metrics"].get(metric), int | float)]


@dataclass(frozen=True)
class PlannedRow:
    """A kept row (``--quick`` applied), its params (with the study's), the config its
    runs train, the row its run gets (itself with its params, or the other study's row
    of ``Row.of``) and how it runs: a custom ``run_batch`` or the default run's ``shape``."""

    row: Row
    params: Mapping[str, Any]
    config: TrainConfig
    runs_as: Row
    custom: RunBatch | None
    shape: Shape | None


@dataclass(frozen=True, eq=False)
class Plan:
    """A study planned for one sweep: the base (options applied), the overrides after
    every row's, and every kept row with its configuration."""

    study: Study
    base: TrainConfig
    after: Mapping[str, Any]
    quick: bool
    rows: tuple[PlannedRow, ...]

    def row(self, row_id: str) -> PlannedRow:
        for p in self.rows:
            if p.row.id == row_id:
                return p
        raise SkinnyInputError(f"study {self.study.name!r}: no row {row_id!r} in this "
                               f"sweep; rows: {', '.join(p.row.id for p in self.rows)}")

    def config(self, row_id: str) -> TrainConfig:
        """Row ``row_id``'s training configuration."""
        return self.row(row_id).config

    @property
    def params(self) -> Mapping[str, Any]:
        """The study-wide parameters of its custom runs (``--quick``'s applied)."""
        return _study_params(self.study, self.quick)

    def trainings(self, row_id: str) -> dict[str, TrainConfig]:
        """What one run of the row trains: its shape's ``trainings`` (a custom run: the
        study's) or the row's config."""
        p = self.row(row_id)
        trainings = self.study.trainings if p.shape is None else p.shape.trainings
        if trainings is None:
            return {"run": p.config}
        return dict(trainings(p.config, p.runs_as))

    def to_dict(self) -> dict[str, Any]:
        """What ``config.json`` records as ``config`` (``--resume`` needs it the same)."""
        return {"study": self.study.name, "base": self.base.to_dict(),
                "after_rows": dict(self.after), "params": dict(self.params),
                "quick": self.quick}

    def groups(self) -> dict[str, tuple[str, ...]]:
        """The rows' groups, then the study's (whose members may name groups), over the
        kept rows; a group left without rows is dropped."""
        kept = [p.row.id for p in self.rows]
        out: dict[str, list[str]] = {}
        for p in self.rows:
            if p.row.group is not None:
                out.setdefault(p.row.group, []).append(p.row.id)
        for name, members in self.study.groups.items():
            out[name] = [i for m in members for i in out.get(m, [m]) if i in kept]
        return {g: tuple(m) for g, m in out.items() if m}

    def run_row(self, row_id: str) -> Row:
        """Row ``row_id`` with its params and the study's (what the study's ``cost`` and
        ``memory`` get; a row's own run gets the same, a row ``of`` another study that
        study's row: :attr:`PlannedRow.runs_as`)."""
        p = self.row(row_id)
        return dataclasses.replace(p.row, params=p.params, quick={})

    def experiment(self) -> Experiment:
        """The engine's Experiment of this plan."""
        study = self.study
        quick = study.quick
        runs = quick.runs if self.quick else study.runs

        def row_runs(r: Row) -> int | None:
            return r.runs if r.runs is None or not self.quick else min(r.runs, quick.runs)

        engine_rows = tuple(
            EngineRow(p.row.id, {**p.row.overrides, **p.row.params}, p.row.paper,
                      row_runs(p.row), p.row.seeds_of) for p in self.rows)
        runner = _Runner({p.row.id: (p.config, p.runs_as, p.custom, p.shape)
                          for p in self.rows})
        columns = quick.columns if self.quick and quick.columns is not None else \
            study.columns if study.columns is not None else \
            () if callable(study.metrics) else tuple(study.metrics)
        kept = {p.row.id for p in self.rows}
        unavailable = {} if study.unavailable is None else {
            k: v for k, v in study.unavailable().items() if k in kept}
        return Experiment(
            name=study.name, rows=engine_rows, run_one=functools.partial(one_of_batch, runner),
            config=self, runs=runs, base_seed=study.base_seed, table_columns=columns or None,
            run_batch=runner, cost=functools.partial(_cost, self, {}), groups=self.groups(),
            unavailable=unavailable, report=functools.partial(_report, self))


def _study_params(study: Study, quick: bool) -> dict[str, Any]:
    """The study-wide parameters of its custom runs, ``--quick``'s over the study's."""
    return {**study.params, **(study.quick.params if quick else {})}


def _report(plan: Plan, results: Mapping[str, Any], out_dir: str | Path) -> str:
    report = plan.study.report
    if report is None:
        return ""
    if isinstance(report, str):
        module, _, name = report.partition(":")
        report = getattr(importlib.import_module(module), name or "report")
    return report(Results(results, out_dir), plan, Path(out_dir))


def _expand(study: Study, entries: Iterable[str]) -> set[str]:
    """Row ids named by ``entries`` (ids, the rows' groups, the study's groups)."""
    by_group: dict[str, list[str]] = {}
    for r in study.rows:
        if r.group is not None:
            by_group.setdefault(r.group, []).append(r.id)
    ids = {r.id for r in study.rows}
    out: set[str] = set()
    for e in entries:
        members = study.groups.get(e, by_group.get(e, [e]))
        for m in members:
            out |= set(by_group.get(m, [m]))
    if unknown := sorted(out - ids):
        raise SkinnyInputError(f"study {study.name!r}: quick rows {unknown} name no row")
    return out


def plan(study: Study, *, quick: bool = False, tiny: bool = False,
         movement: str | None = None, asf: Any = None, body: str | int | None = None,
         signals: str | None = None) -> Plan:
    """Plan ``study`` for one sweep (see the module docstring); ``tiny``: also apply the
    study's ``tiny`` shrink (the contract test's)."""
    given = {"movement": movement, "body": body, "signals": signals}
    if refused := [k for k, v in given.items() if v is not None and k not in study.takes]:
        takes = ", ".join(f"--{k}" for k in study.takes) or "none of them"
        raise SkinnyInputError(f"study {study.name!r} takes no --{refused[0]} (it takes "
                               f"{takes})")
    values = {"movement": {"movement": movement, "asf": asf}, "body": {"body": body},
              "signals": {"signals": signals}}
    for option, derive in study.own_options.items():  # a change of rows or params
        if given[option] is not None:
            study, given[option] = derive(study, **values[option]), None
    changes = movement_changes(given["movement"], asf, given["body"], given["signals"])
    base = study.base.override(changes) if changes else study.base
    after = dict(study.quick.overrides if quick else {})
    kept: Sequence[Row] = [r for r in study.rows if quick or not r.quick_only]
    if quick and study.quick.rows is not None:
        chosen = _expand(study, study.quick.rows)
        kept = [r for r in study.rows if r.id in chosen]
    planned, others = [], {}
    for r in kept:
        r = r.shrunk() if quick else r
        config = base.override({**r.overrides, **after})
        if tiny:  # the contract test's shrink: of its keys, those this row's config has
            have = set(overrides.keys(config))
            config = config.override({k: v for k, v in study.tiny.items()
                                      if overrides.canonical(config, k) in have})
        params = {**_study_params(study, quick), **r.params}
        if r.of is not None:  # another study's row: that study's planned row runs
            body = {"body": config.plant.body, "signals": config.plant.signals} \
                if r.of.on_body else {}  # by name: its MJCF (and MuJoCo) stays unread
            key = (id(r.of.study), tuple(body.values()))
            if key not in others:  # its --quick shrink on every row, not only those it keeps
                every = dataclasses.replace(r.of.study, quick=dataclasses.replace(
                    r.of.study.quick, rows=None))
                others[key] = plan(every, quick=quick, tiny=tiny, **body)
            other = others[key].row(r.of.row)
            planned.append(PlannedRow(r, params, other.config, other.runs_as, other.custom,
                                      other.shape))
            continue
        custom = r.run_batch or study.run_batch
        run_row = dataclasses.replace(r, params=params, quick={})
        planned.append(PlannedRow(r, params, config, run_row, custom,
                                  None if custom is not None else r.shape or study.shape))
    return Plan(study, base, after, quick, tuple(planned))
