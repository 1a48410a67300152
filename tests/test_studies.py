"""One contract test over every registered study (as dm_control's ``suite_test``): it
builds, plans its ``--quick`` rows, executes one tiny run and writes its table and report.

Registering is setting ``NAME`` and ``STUDY`` in a module of ``experiments/`` (or an entry
point of another package): every name :func:`skinny_mj.engine.registry.names` lists is covered
here, so a study that fails this cannot be registered. Every study is declared as data (a
:class:`~skinny_mj.engine.study.Study`) and runs its cheapest ``--quick`` row once with its
``tiny`` shrink (one epoch of a small reservoir).
"""

from __future__ import annotations

import json

import pytest

from skinny_mj.engine import registry
from skinny_mj.engine.experiment import run_sweep
from skinny_mj.engine.plan import plan
from skinny_mj.engine.stats import load_runs
from skinny_mj.engine.study import Study
from skinny_mj.errors import SkinnyInputError


def _cheapest(exp):
    """The cheapest row this machine can run (an optional extra's rows left out)."""
    rows = [r for r in exp.rows if r.id not in exp.unavailable]
    if exp.cost is None:
        return rows[0]
    return min(rows, key=exp.cost)


#: Studies whose report fails on a sweep of one row (to fix in the study, then remove here).
REPORT_FAILS_ON_ONE_ROW: dict[str, str] = {}


@pytest.mark.parametrize("name", registry.names())
def test_study_builds_plans_runs_one_tiny_run_and_writes_its_table(name, tmp_path):
    study = registry.get(name)
    assert isinstance(study, Study), f"{name} is not declared as data"
    assert registry.describe(name), f"{name} has no description"
    try:
        full = study.build()
    except SkinnyInputError as err:  # an optional extra it needs is not installed
        pytest.skip(f"{name}: {err}")
    quick = study.build(quick=True)
    assert full.name == quick.name == name
    assert quick.rows and quick.runs <= full.runs  # --quick may run another, smaller grid
    exp = plan(study, quick=True, tiny=True)
    assert [r.id for r in exp.rows] == [r.id for r in quick.rows]  # same seeds
    if "movement" in study.takes:  # it changes the runs, never moves a row (or its seeds);
        moved = study.build(quick=True, movement="ymca@0.5")  # paper C adds one after
        assert [r.id for r in moved.rows][:len(quick.rows)] == \
            [r.id for r in quick.rows]
    row = _cheapest(exp)
    results = run_sweep(exp, tmp_path, rows=[row.id], runs=1, workers=1, progress=False)
    (run,) = load_runs(tmp_path)
    assert run["status"] in ("ok", "failed"), run.get("traceback")  # an error is a bug
    assert results["n_ok"] + results["n_failed"] == 1
    if run["status"] == "ok":
        assert run["metrics"], f"{name}: a run without metrics"
    table = (tmp_path / "table.md").read_text()
    assert f"| {row.id} |" in table
    config = json.loads((tmp_path / "config.json").read_text())
    assert config["experiment"] == name and config["selection"]["rows"] == [row.id]
    if name in REPORT_FAILS_ON_ONE_ROW:
        with pytest.raises(Exception):  # noqa: B017 (when it passes, remove it from the list)
            exp.report(results, tmp_path)
        return
    text = exp.report(results, tmp_path)
    assert isinstance(text, str)


def test_a_study_refuses_an_option_it_does_not_take():
    from skinny_mj.engine.study import Row

    study = Study(name="fixed-body", rows=(Row("a"),), metrics={"x": "wall_s"},
                  takes=("movement",))
    assert study.build(movement="y").config("a").movement.trajectory == "y"
    with pytest.raises(SkinnyInputError, match="takes no --body"):
        study.build(body=8)
