"""``skinny sweep key=a,b key2=c``: an ad-hoc grid over any config key, as a study.

Each ``KEY=V1,V2,...`` names a configuration key and its values (a value holding a
comma is quoted: ``trajectory='md_02.amc@start=3,duration=6.26',ymca``); the rows are the
cartesian product of the keys with more than one value, in the order given, and a key
with one value changes the base of every row. A value is read as the key's field type
(:func:`skinny_mj.training.overrides.parse_value`: ``int``, ``float``, ``bool`` true/false,
none/null where the field allows it, else text); the configuration checks the result.
A row's id is its values, ``esn.spectral_radius=0.5`` (keys joined by ``+``), as a
plain file-name word.

The base is :class:`~skinny_mj.training.config.TrainConfig`'s defaults (paper E exp. 5), a config
file's (``--config FILE``: a run's ``metrics.json`` or a bare config), or a study's row
(``--study NAME --row ID``: its configuration, metrics, columns and run). ``--quick`` makes
it a smoke test: a study's row as that study's ``--quick`` has it (and its runs per row),
else the base with :data:`QUICK`'s keys (those it has) and 2 runs per row; the axes are
applied after, so a swept key keeps its values.
"""

from __future__ import annotations

import csv
import dataclasses
import itertools
import re
from collections.abc import Sequence
from typing import Any

from skinny_mj.engine.plan import plan
from skinny_mj.engine.results import STANDARD_METRICS, Shape
from skinny_mj.engine.study import Row, Study
from skinny_mj.errors import SkinnyInputError
from skinny_mj.training.config import TrainConfig
from skinny_mj.training.overrides import canonical, parse_value
from skinny_mj.training.overrides import keys as config_keys

__all__ = ["NAME", "METRICS", "QUICK", "parse_assignment", "grid_study"]

NAME = "sweep"
#: What a grid reports without a ``--study``: the test of every run, and its wall time.
METRICS = STANDARD_METRICS
#: ``--quick`` without a study: these keys of the base (those it has), 2 runs per row.
QUICK = {"method.epochs": 2}
QUICK_RUNS = 2
_UNSAFE = re.compile(r"[^A-Za-z0-9_.+=-]")


def parse_assignment(item: str, base: Any) -> tuple[str, list[Any], list[str]]:
    """``KEY=V1,V2`` -> (key, typed values, their texts)."""
    key, sep, values = item.partition("=")
    key = key.strip()
    if not sep or not key or not values.strip():
        raise SkinnyInputError(f"a sweep axis is KEY=VALUE[,VALUE...], got {item!r}")
    key = canonical(base, key)  # an old key's current name (its row ids say that one)
    texts = [t.strip() for t in next(csv.reader([values], quotechar="'",
                                                skipinitialspace=True))]
    if any(not t for t in texts):
        raise SkinnyInputError(f"{key}: an empty value in {values!r}; give values as "
                               "V1,V2,... with none empty")
    if len(set(texts)) != len(texts):
        raise SkinnyInputError(f"{key}: values must be given once each, got {values!r}")
    return key, [parse_value(base, key, t) for t in texts], texts


def _row_id(pairs: Sequence[tuple[str, str]]) -> str:
    return "+".join(_UNSAFE.sub("_", f"{k}={t}") for k, t in pairs)


def _study_row(study: Study, row: str, quick: bool) -> tuple[TrainConfig, Any, dict, int]:
    """A study's row as the base: its config, the study planned (the row its run gets and
    how it runs), the study's params (``quick``: as the study's ``--quick`` has them) and
    the runs per row (10, or the study's ``--quick`` runs)."""
    study.row(row)  # an unknown row: one line naming the study's rows
    if quick:  # every row, not only those --quick keeps
        study = dataclasses.replace(study, quick=dataclasses.replace(study.quick, rows=None))
    planned = plan(study, quick=quick)
    if study.unavailable is not None and row in (gone := study.unavailable()):
        raise SkinnyInputError(f"study {study.name!r}: row {row!r} {gone[row]}")
    return (planned.config(row), planned, dict(planned.params),
            study.quick.runs if quick else 10)


def grid_study(items: Sequence[str], *, study: Study | None = None, row: str | None = None,
               runs: int | None = None, quick: bool = False,
               base: TrainConfig | None = None) -> Study:
    """The study of ``skinny sweep ITEMS`` (see the module docstring); ``runs`` None: 10,
    or ``--quick``'s."""
    if (study is None) != (row is None):
        raise SkinnyInputError("--study and --row go together: the study's row is the base")
    if study is not None and base is not None:
        raise SkinnyInputError("--config and --study/--row are two bases: give one")
    if study is not None:
        base, planned, params, default_runs = _study_row(study, row, quick)
    else:
        base = TrainConfig() if base is None else base
        if quick:
            have = set(config_keys(base))
            base = base.override({k: v for k, v in QUICK.items() if k in have})
        default_runs = QUICK_RUNS if quick else 10
    runs = default_runs if runs is None else runs
    if not items:
        raise SkinnyInputError("give at least one KEY=VALUE[,VALUE...] to sweep")
    probe, parsed = base, {}
    for i, item in sorted(enumerate(items), key=lambda p: "," in p[1].partition("=")[2]):
        parsed[i] = parse_assignment(item, probe)  # one-value keys first: a type chosen
        if len(parsed[i][1]) == 1:  # (actuation=torque) makes its settings parseable
            probe = probe.override({parsed[i][0]: parsed[i][1][0]}, check=False)
    axes = [parsed[i] for i in range(len(items))]
    keys = [k for k, _, _ in axes]
    if len(set(keys)) != len(keys):
        twice = next(k for k in keys if keys.count(k) > 1)
        raise SkinnyInputError(f"{twice} is given twice: each key may be swept once (give "
                               f"its values together, {twice}=V1,V2,...)")
    fixed = {k: v[0] for k, v, _ in axes if len(v) == 1}
    swept = [a for a in axes if len(a[1]) > 1] or axes
    if fixed:
        base = base.override(fixed)
    rows = []
    for combo in itertools.product(*[list(zip(v, t, strict=True)) for _, v, t in swept]):
        keys = [k for k, _, _ in swept]
        overrides = {k: value for k, (value, _) in zip(keys, combo, strict=True)}
        rid = _row_id([(k, text) for k, (_, text) in zip(keys, combo, strict=True)])
        rows.append(Row(rid, overrides))
    if len({r.id for r in rows}) != len(rows):
        rows = [Row(f"{i}-{r.id}", r.overrides) for i, r in enumerate(rows)]
    for r in rows:  # every row's configuration is checked now, before any run
        base.override(dict(r.overrides))
    what = " ".join(items) + (f" on {study.name} row {row}" if study is not None else "")
    if study is None:
        return Study(name=NAME, description=f"skinny sweep {what}", base=base, rows=tuple(rows),
                     metrics=METRICS, runs=runs, takes=())
    run = planned.runners[row]
    custom, shape = (None, run) if isinstance(run, Shape) else (run, None)
    return Study(name=NAME, description=f"skinny sweep {what}", base=base,
                 rows=tuple(Row(r.id, r.overrides, params=planned.runs_as[row].params,
                                run_batch=custom, shape=shape) for r in rows),
                 metrics=study.metrics, columns=study.columns, runs=runs, takes=(),
                 params=params, trainings=study.trainings, cost=study.cost,
                 memory=study.memory)
