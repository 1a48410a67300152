"""A :class:`~skinny_mj.engine.study.Study` planned for one sweep: the :class:`Experiment`
that :func:`~skinny_mj.engine.experiment.run_sweep` runs (every kept row with its training
configuration, groups, the lockstep run, one run, cost, table columns, the report).

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
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

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

__all__ = ["Experiment", "Results", "plan", "train_metrics", "read_metric"]


def train_metrics(config: TrainConfig, seeds: list[int], metrics: Metrics) -> list[Any]:
    """The default run of a row on its config alone, the standard test, ``metrics``
    read off each result (:func:`skinny_mj.engine.results.default_run`)."""
    return default_run(config, None, seeds, Shape(metrics))


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


def find_row(rows: Sequence[Row], row_id: str, where: str) -> Row:
    """The row ``row_id`` of ``rows``; a SkinnyInputError saying ``where`` has none, with
    the ids it has."""
    for r in rows:
        if r.id == row_id:
            return r
    raise SkinnyInputError(f"{where} has no row {row_id!r}; rows: "
                           f"{', '.join(r.id for r in rows)}")


@dataclass(frozen=True, eq=False)
class Experiment:
    """A study planned for one sweep, what :func:`~skinny_mj.engine.experiment.run_sweep`
    runs: the base (options applied), the overrides after every row's, every kept row
    (``--quick`` applied, its runs capped at ``--quick``'s) and per row id its training
    configuration (``configs``), the row its run gets (``runs_as``: the row with the
    study's params, or the other study's row of ``Row.of``) and how it runs
    (``runners``: a custom ``run_batch``, or the :class:`Shape` of the default run)."""

    study: Study
    base: TrainConfig
    after: Mapping[str, Any]
    quick: bool
    rows: tuple[Row, ...]
    configs: Mapping[str, TrainConfig]
    runs_as: Mapping[str, Row]
    runners: Mapping[str, RunBatch | Shape]
    _costs: dict[str, float] = field(default_factory=dict, repr=False)

    @property
    def name(self) -> str:
        return self.study.name

    @property
    def runs(self) -> int:
        """Runs per row (a row's own ``runs`` aside)."""
        return self.study.quick.runs if self.quick else self.study.runs

    @property
    def base_seed(self) -> int:
        return self.study.base_seed

    @property
    def params(self) -> Mapping[str, Any]:
        """The study-wide parameters of its custom runs (``--quick``'s applied)."""
        return _study_params(self.study, self.quick)

    @property
    def table_columns(self) -> tuple[str, ...] | Mapping[str, str] | None:
        study, quick = self.study, self.study.quick
        columns = quick.columns if self.quick and quick.columns is not None else \
            study.columns if study.columns is not None else \
            () if callable(study.metrics) else tuple(study.metrics)
        return columns or None

    @functools.cached_property
    def groups(self) -> dict[str, tuple[str, ...]]:
        """The rows' groups, then the study's (whose members may name groups), over the
        kept rows; a group left without rows is dropped."""
        kept = [r.id for r in self.rows]
        out: dict[str, list[str]] = {}
        for r in self.rows:
            if r.group is not None:
                out.setdefault(r.group, []).append(r.id)
        for name, members in self.study.groups.items():
            out[name] = [i for m in members for i in out.get(m, [m]) if i in kept]
        return {g: tuple(m) for g, m in out.items() if m}

    @functools.cached_property
    def unavailable(self) -> dict[str, str]:
        """Kept rows this machine cannot run -> why: left out of a sweep of every row
        (with a line saying so), refused when named in ``--rows``."""
        gone = {} if self.study.unavailable is None else self.study.unavailable()
        return {k: v for k, v in gone.items() if k in self.configs}

    def row(self, row_id: str) -> Row:
        """The kept row ``row_id`` (a SkinnyInputError naming the kept ids if there is none)."""
        return find_row(self.rows, row_id, f"this sweep of study {self.name!r}")

    def config(self, row_id: str) -> TrainConfig:
        """Row ``row_id``'s training configuration."""
        self.row(row_id)  # an unknown row: one line naming the rows
        return self.configs[row_id]

    def run_row(self, row_id: str) -> Row:
        """Row ``row_id`` with its params and the study's (what the study's ``cost`` and
        ``memory`` get; a row's own run gets the same, a row ``of`` another study that
        study's row: :attr:`runs_as`)."""
        r = self.row(row_id)
        return dataclasses.replace(r, params={**self.params, **r.params}, quick={})

    def trainings(self, row_id: str) -> dict[str, TrainConfig]:
        """What one run of the row trains: its shape's ``trainings`` (a custom run: the
        study's) or the row's config."""
        run, config = self.runners[row_id], self.config(row_id)
        trainings = run.trainings if isinstance(run, Shape) else self.study.trainings
        if trainings is None:
            return {"run": config}
        return dict(trainings(config, self.runs_as[row_id]))

    def to_dict(self) -> dict[str, Any]:
        """What ``config.json`` records as ``config`` (``--resume`` needs it the same)."""
        return {"study": self.name, "base": self.base.to_dict(),
                "after_rows": dict(self.after), "params": dict(self.params),
                "quick": self.quick}

    def run_batch(self, row: Row, seeds: list[int]) -> list[Any]:
        """Row ``row``'s seeds run in lockstep: per seed a metrics dict or a RunFailed."""
        run, config, runs_as = self.runners[row.id], self.configs[row.id], self.runs_as[row.id]
        if isinstance(run, Shape):
            return default_run(config, runs_as, list(seeds), run)
        return list(run(config, runs_as, list(seeds)))

    def run_one(self, row: Row, seed: int) -> Mapping[str, Any]:
        """One run of row ``row``: the lockstep run of one seed (its RunFailed raised)."""
        return one_of_batch(self.run_batch, row, seed)

    def cost(self, row: Row) -> float:
        """One run's relative cost, worked out when the schedule first asks (a study's
        own cost may load a movement: a study's ``--help`` plans the sweep but runs none)."""
        if row.id not in self._costs:
            cost, config = self.study.cost, self.configs[row.id]
            self._costs[row.id] = relative_cost(config) if cost is None \
                else cost(config, self.run_row(row.id))
        return self._costs[row.id]

    def report(self, results: Mapping[str, Any], out_dir: str | Path) -> str:
        """The study's report of the sweep's results in ``out_dir`` ("" without one)."""
        report = self.study.report
        if report is None:
            return ""
        if isinstance(report, str):
            module, _, name = report.partition(":")
            report = getattr(importlib.import_module(module), name or "report")
        return report(Results(results, out_dir), self, Path(out_dir))


def _study_params(study: Study, quick: bool) -> dict[str, Any]:
    """The study-wide parameters of its custom runs, ``--quick``'s over the study's."""
    return {**study.params, **(study.quick.params if quick else {})}


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
         signals: str | None = None) -> Experiment:
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
    if bad := [r.id for r in kept if r.seeds_of not in (None, *(k.id for k in kept))]:
        raise SkinnyInputError(f"study {study.name!r}: rows {bad}: seeds_of no row")
    rows, configs, runs_as, runners, others = [], {}, {}, {}, {}
    for r in kept:
        if quick:
            r = r.shrunk()
            r = r if r.runs is None else dataclasses.replace(r, runs=min(r.runs, study.quick.runs))
        rows.append(r)
        config = base.override({**r.overrides, **after})
        if tiny:  # the contract test's shrink: of its keys, those this row's config has
            have = set(overrides.keys(config))
            config = config.override({k: v for k, v in study.tiny.items()
                                      if overrides.canonical(config, k) in have})
        if r.of is not None:  # another study's row: that study's planned row runs
            body = {"body": config.plant.body, "signals": config.plant.signals} \
                if r.of.on_body else {}  # by name: its MJCF (and MuJoCo) stays unread
            key = (id(r.of.study), tuple(body.values()))
            if key not in others:  # its --quick shrink on every row, not only those it keeps
                every = dataclasses.replace(r.of.study, quick=dataclasses.replace(
                    r.of.study.quick, rows=None))
                others[key] = plan(every, quick=quick, tiny=tiny, **body)
            other = others[key]
            configs[r.id], runs_as[r.id] = other.config(r.of.row), other.runs_as[r.of.row]
            runners[r.id] = other.runners[r.of.row]
            continue
        configs[r.id] = config
        runs_as[r.id] = dataclasses.replace(
            r, params={**_study_params(study, quick), **r.params}, quick={})
        runners[r.id] = r.run_batch or study.run_batch or r.shape or study.shape
    return Experiment(study, base, after, quick, tuple(rows), configs, runs_as, runners)
