"""A study is data: a base training configuration, rows of overrides, the paper's numbers.

A study module under ``experiments/`` (or any package, see :mod:`skinny_mj.engine.registry`)
declares one :class:`Study`::

    STUDY = Study(
        name="sr-sweep", description="Spectral radius 0.5 vs 0.9 on paper E exp. 5.",
        rows=(Row("sr0.5", {"esn.spectral_radius": 0.5}),
              Row("sr0.9", {"esn.spectral_radius": 0.9})),
        metrics={"position_nrmse": lambda r: r.test.position_nrmse}, runs=20)

and the engine (:mod:`skinny_mj.engine.plan`) derives the rest: the sweep of (row, seed)
runs, each run's training configuration (``base``, then ``--movement/--body/--signals``,
then the row's overrides, then ``--quick``'s), the lockstep run, its cost, its groups
and its table.

The lockstep run (:func:`skinny_mj.engine.results.default_run`) trains the row's seeds
with :func:`skinny_mj.training.loop.train_batch` and reads ``metrics`` off each
:class:`~skinny_mj.training.result.RunResult`; a diverged run is a failed run. A study
shapes it as data: ``tests`` (train once, then test on each movement or plant variant:
:class:`~skinny_mj.training.result.Test`), ``trainings`` (several configurations trained
from the same seeds, the metrics then read a mapping name -> RunResult), ``observe``
(an :class:`~skinny_mj.training.result.Observer` watching the training while it runs:
what it saw lands in the result's ``observed``), ``failure`` (a function of the result:
why the run failed, None if it did not) and ``metrics`` (name -> function of the result,
or one function giving every metric). A row taken another way has its own
:class:`Shape` (:attr:`Row.shape`); a row that is another study's row, run as that study
runs it, says so (:attr:`Row.of`, an :class:`Of`).

A row's run that is none of these supplies ``run_batch(config, row, seeds) -> list``
(per seed a metrics dict, or a :class:`~skinny_mj.engine.experiment.RunFailed`), for the
whole study or for one row (:attr:`Row.run_batch`); ``config`` is the row's training
configuration and ``row.params`` its study-specific parameters.

An option of ``skinny experiment`` is a change of config keys (``--body 3d`` sets
``plant.body`` on the base). A study that takes one its own way instead, as a change of its
rows or params, names a function in ``own_options``: ``fn(study, **values) -> Study``, the
study that option makes. Paper C's ``--movement X.amc --asf Y.asf`` adds a training row
``real`` and makes ``X.amc`` its test column ``real``::

    def with_movement(study, movement, asf):
        real = Row("real", {"movement.trajectory": movement, "movement.asf": asf})
        return dataclasses.replace(study, rows=(*study.rows, real),
                                   params={**study.params, "real": movement, "asf": asf})

    STUDY = Study(..., own_options={"movement": with_movement})

The engine plans the study the function returns (its rows, seeds, params, ``--quick``)
and sets none of that option's config keys.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from skinny_mj.engine.options import OPTION_KEYS
from skinny_mj.engine.plan import Experiment, Results, find_row, plan
from skinny_mj.engine.results import Metrics, Shape, Tests, default_run
from skinny_mj.engine.sweep import SAFE_NAME
from skinny_mj.errors import SkinnyInputError
from skinny_mj.training.config import TrainConfig
from skinny_mj.training.result import STANDARD, Observer, Test

if TYPE_CHECKING:
    from pathlib import Path

__all__ = ["Study", "Row", "Of", "Shape", "Quick", "Test", "OPTIONS", "TINY"]

#: ``skinny experiment``'s options a study may take (the config keys each sets:
#: :data:`skinny_mj.engine.options.OPTION_KEYS`).
OPTIONS = tuple(OPTION_KEYS)
#: The contract test's shrink (after ``--quick``'s): one epoch of a small reservoir (each
#: row takes the keys its config has: a true-target row has no epochs).
TINY = {"method.epochs": 1, "esn.n_reservoir": 20}

RunBatch = Callable[[TrainConfig, "Row", list[int]], list[Any]]


def _frozen(mapping: Mapping[str, Any] | None) -> dict[str, Any]:
    return dict(mapping or {})


@dataclass(frozen=True)
class Of:
    """Another study's row, run as that study runs it (its configuration, shape and
    parameters, ``--quick``'s when this sweep is quick): row ``row`` of ``study``, on
    that study's own body, or (``on_body``) on the body of this row's configuration (its
    ``plant.body`` and ``plant.signals``, as ``--body --signals`` would give them)."""

    study: Study
    row: str
    on_body: bool = False


@dataclass(frozen=True)
class Row:
    """One row: its id (a plain file-name word), the config keys it changes, the paper's
    numbers (``<metric>`` and ``<metric>_var``), optionally its own run count
    (``runs``), the row whose seeds it takes (``seeds_of``, a paired comparison), its
    group (``--rows GROUP``), study-specific ``params`` (read by a custom run), what
    ``--quick`` changes of this row (``quick``: overrides or params keys), its own
    ``run_batch``, its own ``shape`` (None: the study's) or the other study's row it runs
    (``of``); ``quick_only``: a row only ``--quick`` sweeps have (a smoke test's smaller
    grid)."""

    id: str
    overrides: Mapping[str, Any] = field(default_factory=dict)
    paper: Mapping[str, float] = field(default_factory=dict)
    runs: int | None = None
    seeds_of: str | None = None
    group: str | None = None
    params: Mapping[str, Any] = field(default_factory=dict)
    quick: Mapping[str, Any] = field(default_factory=dict)
    run_batch: RunBatch | None = None
    quick_only: bool = False
    shape: Shape | None = None
    of: Of | None = None

    def __post_init__(self) -> None:
        if not SAFE_NAME.match(self.id):
            raise SkinnyInputError(f"row id {self.id!r} must be a plain file-name word")
        if self.runs is not None and self.runs < 1:
            raise SkinnyInputError(f"row {self.id!r}: runs must be >= 1, got {self.runs}")
        for name in ("overrides", "paper", "params", "quick"):
            object.__setattr__(self, name, _frozen(getattr(self, name)))
        if both := sorted(set(self.overrides) & set(self.params)):
            raise SkinnyInputError(f"row {self.id!r}: {both} both a config override and a "
                                   "study parameter")

    @property
    def settings(self) -> dict[str, Any]:
        """What sets this row apart, as its run files and ``config.json`` record it (their
        ``params``): its overrides and its own params."""
        return {**self.overrides, **self.params}

    def shrunk(self) -> Row:
        """This row under ``--quick``: its ``quick`` keys replace params or overrides."""
        params = {**self.params, **{k: v for k, v in self.quick.items() if k in self.params}}
        over = {**self.overrides, **{k: v for k, v in self.quick.items()
                                     if k not in self.params}}
        return dataclasses.replace(self, overrides=over, params=params, quick={})


@dataclass(frozen=True)
class Quick:
    """What ``--quick`` (a smoke test, not a reproduction) shrinks: ``overrides`` applied
    after every row's, the runs per row, the rows kept (ids or groups; None: all), the
    study-wide ``params`` it replaces and the table's ``columns`` (None: the study's)."""

    overrides: Mapping[str, Any] = field(default_factory=dict)
    runs: int = 2
    rows: tuple[str, ...] | None = None
    params: Mapping[str, Any] = field(default_factory=dict)
    columns: Sequence[str] | Mapping[str, str] | None = None


@dataclass(frozen=True)
class Study:
    """A sweep as data (see the module docstring).

    ``metrics``: name -> a function of a run's result (or a dotted path into its
    :func:`~skinny_mj.engine.results.run_metrics`), or one function of the result giving
    the run file's every metric; ``tests``: the tests a run takes (or a function
    ``(config, row)`` giving them; default the standard test); ``failure(result) -> str |
    None``: why a run failed (default: its training's or its standard test's divergence);
    ``observe(run, row) -> Observer``: watches each training while it runs (what it saw
    of a run: the result's ``observed``); these five are the study's :attr:`shape`;
    ``columns``: the table's metric columns (names, or name -> header; default every
    metric); ``groups``: extra groups (name -> row ids or groups) beside the rows' own;
    ``params``: study-wide parameters of a custom run (a row's ``params`` add to them);
    ``trainings(config, row) -> {name: TrainConfig}``: what one run trains, where that is
    not the row's config alone (the default run trains each; the memory check);
    ``takes``: the options of ``OPTIONS`` it accepts (any other is refused in one line);
    ``report(results, plan, out_dir) -> str``: figures and claims after the sweep, or the
    ``"module:function"`` that has it (a study kept in one folder with its report names
    its report so: the report imports the study, never the other way round);
    ``tiny``: the contract test's shrink (default :data:`TINY`); ``cost(config, row) ->
    float``: one run's relative cost, for the schedule (default: the training's
    :func:`~skinny_mj.training.config.relative_cost`); ``memory(config, row, runs)``: the
    bytes a lockstep batch of a custom run needs (a :class:`skinny_mj.preflight.Estimate`;
    None: its ``trainings``' estimate); ``unavailable() -> {row id: why}``: rows this
    machine cannot run (an optional package missing).
    """

    name: str
    rows: tuple[Row, ...]
    description: str = ""
    base: TrainConfig = field(default_factory=TrainConfig)
    metrics: Metrics = field(default_factory=dict)
    tests: Tests = STANDARD
    failure: Callable[[Any], str | None] | None = None
    observe: Callable[[Any, Row], Observer] | None = None
    columns: Sequence[str] | Mapping[str, str] | None = None
    runs: int = 10
    quick: Quick = field(default_factory=Quick)
    groups: Mapping[str, Sequence[str]] = field(default_factory=dict)
    params: Mapping[str, Any] = field(default_factory=dict)
    run_batch: RunBatch | None = None
    trainings: Callable[[TrainConfig, Row], Mapping[str, TrainConfig]] | None = None
    report: Callable[[Results, Experiment, Path], str] | str | None = None
    takes: tuple[str, ...] = OPTIONS
    tiny: Mapping[str, Any] = field(default_factory=lambda: dict(TINY))
    base_seed: int = 0
    cost: Callable[[TrainConfig, Row], float] | None = None
    memory: Callable[[TrainConfig, Row, int], Any] | None = None
    unavailable: Callable[[], Mapping[str, str]] | None = None
    own_options: Mapping[str, Callable[..., Study]] = field(default_factory=dict)

    def __post_init__(self) -> None:
        object.__setattr__(self, "rows", tuple(self.rows))
        ids = [r.id for r in self.rows]
        if not SAFE_NAME.match(self.name):
            raise SkinnyInputError(f"study name {self.name!r} must be a plain file-name word")
        if not ids or len(set(ids)) != len(ids):
            raise SkinnyInputError(f"study {self.name!r} needs unique row ids, got {ids}")
        groups = {*(r.group for r in self.rows if r.group), *self.groups}
        if bad := sorted(groups & set(ids)):
            raise SkinnyInputError(f"study {self.name!r}: groups {bad} are row ids too")
        if bad := sorted({m for ms in self.groups.values() for m in ms} - groups - set(ids)):
            raise SkinnyInputError(f"study {self.name!r}: groups name no row or group {bad}")
        if bad := sorted(set(self.takes) - set(OPTIONS)):
            raise SkinnyInputError(f"study {self.name!r}: takes {bad}; options are "
                                   f"{', '.join(OPTIONS)}")
        if bad := sorted(set(self.own_options) - set(self.takes)):
            raise SkinnyInputError(f"study {self.name!r}: own_options {bad} it does not take")
        if not self.metrics and self.run_batch is None and any(
                r.run_batch is None and r.shape is None and r.of is None for r in self.rows):
            raise SkinnyInputError(f"study {self.name!r} declares no metrics and no run_batch")

    @property
    def shape(self) -> Shape:
        """How the engine's default run takes a row without a shape of its own."""
        return Shape(self.metrics if callable(self.metrics) else dict(self.metrics),
                     self.tests, self.failure, self.trainings, self.observe)

    def row(self, row_id: str) -> Row:
        """The row ``row_id`` (a SkinnyInputError naming the ids if there is none)."""
        return find_row(self.rows, row_id, f"study {self.name!r}")

    def config(self, row_id: str, **options: Any) -> TrainConfig:
        """The training configuration of row ``row_id`` (full, not quick), with the
        options of ``skinny experiment`` (``movement``, ``asf``, ``body``, ``signals``)."""
        return plan(self, **options).config(row_id)

    def run(self, config: TrainConfig, row: Row, seeds: list[int]) -> list[Any]:
        """Row ``row``'s lockstep run of ``seeds`` on ``config``: its own ``run_batch``, or
        the engine's default run of its shape (its own, else the study's); per seed a
        metrics dict or a ``RunFailed``."""
        custom = row.run_batch or self.run_batch
        if custom is not None:
            return list(custom(config, row, list(seeds)))
        return default_run(config, row, list(seeds), row.shape or self.shape)

    # -- what `skinny experiment`, the memory check and the study help call --
    def build(self, quick: bool = False, movement: str | None = None, asf: Any = None,
              body: str | int | None = None, signals: str | None = None) -> Experiment:
        """The :class:`~skinny_mj.engine.plan.Experiment` of ``skinny experiment NAME``."""
        return plan(self, quick=quick, movement=movement, asf=asf, body=body,
                    signals=signals)

    def train_configs(self, experiment: Experiment, row: Row) -> dict[str, TrainConfig]:
        """The training configurations one run of ``row`` of the built ``experiment``
        trains (for the memory check)."""
        return experiment.trainings(row.id)

    def estimate_bytes(self, experiment: Experiment, row: Row, runs: int) -> Any:
        """The memory check's estimate of ``runs`` lockstep runs of ``row`` of the built
        ``experiment``: the study's ``memory``, None without one."""
        if self.memory is None:
            return None
        return self.memory(experiment.config(row.id), experiment.run_row(row.id), runs)
