"""Paper E: the whole quick sweep end to end (Table rows + Figs. 3–6, recordings,
resume), row groups, the Fig. 3 cycle count, the movement-excerpt syntax."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from skinny_mj.experiments.paper_e import study as paper_e
from toy import toy

from skinny_mj.engine.experiment import Row, aggregate, run_sweep, select_rows
from skinny_mj.engine.stats import load_runs
from skinny_mj.errors import SkinnyInputError
from skinny_mj.trajectories import load_movement, sample_clip, ymca
from skinny_mj.trajectories.library import split_excerpt

MD02 = sample_clip("md_02")  # shipped with the package


@pytest.fixture(scope="module")
def quick_sweep(tmp_path_factory):
    """``skinny experiment paper-e --quick --workers 1``, through the Python API."""
    out = tmp_path_factory.mktemp("paper_e_quick")
    exp = paper_e.STUDY.build(quick=True)
    results = run_sweep(exp, out, workers=1, progress=False)
    text = exp.report(results, out)
    return exp, out, results, text


def test_quick_sweep_is_complete(quick_sweep):
    exp, out, results, _ = quick_sweep
    ids = [r.id for r in exp.rows]
    assert [r["row"] for r in results["rows"]] == ids  # Table rows first, then the figures
    assert ids[:6] == ["1", "2", "3", "4", "5", "6"]
    assert set(exp.groups) == {"table", "fig3", "fig4", "fig5a", "fig5b", "fig5"}
    for row in results["rows"]:
        assert row["n_ok"] + row["n_failed"] == 2, row["row"]
    assert len(list((out / "runs").glob("*.json"))) == 2 * len(ids)
    by_id = {r["row"]: r for r in results["rows"]}
    assert by_id["5"]["metrics"]["position_nrmse"]["n"] == by_id["5"]["n_ok"]
    assert by_id["fig3-b0.1"]["paper"] == {"cycles_to_converge": 30}
    assert by_id["fig3-b1"]["metrics"]["cycles_to_converge"]["mean"] == 1


def test_rows_5_reproduces_row_5_of_the_full_quick_sweep(quick_sweep, tmp_path):
    """``skinny experiment paper-e --quick --rows 5``: the same seeds and, bit for bit,
    the same run files as row 5 of the whole sweep (timing fields aside)."""
    exp, out, _, _ = quick_sweep
    run_sweep(exp, tmp_path, rows=["5"], workers=1, progress=False)
    timing = ("wall_s", "finished_at")

    def strip(path):
        record = json.loads(path.read_text())
        record["metrics"].pop("train_wall_s", None)
        return {k: v for k, v in record.items() if k not in timing}

    alone = sorted((tmp_path / "runs").glob("*.json"))
    assert [p.name for p in alone] == sorted(p.name for p in (out / "runs").glob("5-*.json"))
    for path in alone:
        assert strip(path) == strip(out / "runs" / path.name)


def test_results_equal_the_aggregate_of_the_run_files(quick_sweep):
    _, out, results, _ = quick_sweep
    assert json.loads((out / "results.json").read_text()) == results
    assert aggregate(out, write=False) == results
    runs = [r for r in load_runs(out) if r["row"] == "fig4-n50" and r["status"] == "ok"]
    row = next(r for r in results["rows"] if r["row"] == "fig4-n50")
    values = [r["metrics"]["position_nrmse"] for r in runs]
    assert row["metrics"]["position_nrmse"]["mean"] == pytest.approx(np.mean(values))
    assert row["params"]["esn.n_reservoir"] == 50 and row["params"]["esn.noise_level"] == 0.02
    assert row["params"]["movement.reps"] == 1  # quick; the paper: 5


def test_report_writes_figures_table_recordings_and_claims(quick_sweep):
    _, out, _, text = quick_sweep
    for name in ("fig3.png", "fig4.png", "fig5.png", "fig6_position_nrmse.png",
                 "fig6_motor_nrmse.png"):
        assert (out / name).stat().st_size > 1000, name
    rrds = sorted(p.name for p in out.glob("exp*_median_seed*.rrd"))
    assert [n.split("_")[0] for n in rrds] == [f"exp{i}" for i in range(1, 7)]
    assert "re-run DIFFERS" not in text and text.count("re-run identical") == 6
    table = (out / "table.md").read_text()
    assert table.startswith("Movement: `ymca`")
    assert table.index("| 1 |") < table.index("| fig3-b0.3 |") < table.index("| fig5b-nu0.2 |")
    assert "worst run of exp 5 beats the best run of exp 2" in text
    assert "- β = 0.1:" in text and "paper: 30" in text


def test_resume_does_no_new_runs(quick_sweep):
    exp, out, results, _ = quick_sweep
    before = {p.name: (p.stat().st_mtime_ns, json.loads(p.read_text())["finished_at"])
              for p in (out / "runs").glob("*.json")}
    again = run_sweep(exp, out, workers=1, resume=True, progress=False)
    after = {p.name: (p.stat().st_mtime_ns, json.loads(p.read_text())["finished_at"])
             for p in (out / "runs").glob("*.json")}
    assert after == before
    assert again == results


def test_row_groups_and_run_counts():
    exp = paper_e.STUDY.build()
    every, groups = exp.rows, exp.groups
    assert len(every) == 6 + 4 + 7 + 9 + 9
    assert groups["table"] == ("1", "2", "3", "4", "5", "6")
    fig5 = groups["fig5"]
    assert fig5[0] == "fig5a-nu0" and fig5[-1] == "fig5b-nu0.5" and len(fig5) == 18
    chosen = select_rows(exp, ["5", "fig4-n200"])
    assert [r.id for r in chosen] == ["5", "fig4-n200"]
    assert {r.runs for r in every if r.id in paper_e.TABLE_1} == {None}  # 20 (Config.runs)
    assert {r.runs for r in every if r.id not in paper_e.TABLE_1} == {10}
    with pytest.raises(SkinnyInputError, match="fig9"):
        select_rows(exp, ["fig9"])


def test_row_runs_cap_the_sweep(tmp_path):
    """Engine: a row's own run count (Figs. 4/5: 10 beside the Table's 20)."""
    exp = toy("rowruns", (Row("a"), Row("b", runs=1)), lambda row, seed: {"x": 1.0},
                     runs=3)
    results = run_sweep(exp, tmp_path, workers=1, progress=False)
    assert [r["n_ok"] for r in results["rows"]] == [3, 1]
    with pytest.raises(SkinnyInputError):
        Row("c", runs=0)


def test_cycles_to_converge_counts_training_cycles():
    i = np.arange(400)
    for beta in (0.3, 0.1, 0.05):
        curve = 0.4 * (1 - beta) ** i + 1e-3  # a perfect fit: geometric toward a floor
        expected = next(k for k in i if (1 - beta) ** k <= 0.05) + 1
        assert paper_e.cycles_to_converge(curve, 0.05) == expected
    assert paper_e.cycles_to_converge(0.4 * 0.9 ** i, 0.05) == math.ceil(
        math.log(0.05) / math.log(0.9)) + 1
    assert paper_e.cycles_to_converge(np.zeros(400), 0.05) == 1  # β = 1


def test_split_excerpt_syntax():
    assert split_excerpt("a/b.amc@start=3,duration=6.26") == ("a/b.amc", (3.0, 6.26))
    assert split_excerpt("b.npz@duration=2") == ("b.npz", (0.0, 2.0))
    assert split_excerpt("b.bvh@start=1") == ("b.bvh", (1.0, None))
    assert split_excerpt("ymca@1.5") == ("ymca@1.5", None)
    assert split_excerpt("clip.amc") == ("clip.amc", None)
    for bad in ("b.amc@start=x", "b.amc@begin=1", "b.amc@start=1,start=2",
                "b.amc@duration=0", "b.amc@start=-1"):
        with pytest.raises(SkinnyInputError):
            split_excerpt(bad)


def test_excerpt_of_a_trajectory_file(tmp_path):
    path = ymca(4).save(tmp_path / "y.npz")
    traj, report = load_movement(f"{path}@start=1,duration=2", 4)
    np.testing.assert_array_equal(traj.angles, ymca(4).angles[50:150])
    assert report.steps == 100 and "1s+2s" in traj.name
    with pytest.raises(SkinnyInputError):
        load_movement(f"{path}@start=5,duration=2", 4)


def test_mocap_excerpt_reports_its_own_clipping():
    full, full_report = load_movement(MD02, 4)
    part, report = load_movement(f"{MD02}@start=3,duration=6.26", 4)
    assert len(part) == 313 and report.steps == 313
    assert 0 < report.clipped_samples < full_report.clipped_samples
    inside = np.isclose(part.angles, full.angles[150:463]).mean()
    assert inside > 0.8  # same retarget; only clip ramps at the excerpt's edges differ


def test_sweep_on_a_movement_excerpt(tmp_path):
    movement = f"{MD02}@start=3,duration=6.26"
    exp = paper_e.STUDY.build(quick=True, movement=movement)
    assert exp.name == "paper-e"  # the movement is recorded in config.json
    assert exp.base.movement.trajectory == movement
    assert {exp.config(r.id).movement.trajectory for r in exp.rows} == {movement}
    results = run_sweep(exp, tmp_path, rows=["5", "fig3-b0.3"], runs=1, workers=1,
                        progress=False)
    text = exp.report(results, tmp_path)
    table = (tmp_path / "table.md").read_text()
    assert "md_02" in table.splitlines()[0] and "313 steps" in table
    assert (tmp_path / "fig3.png").is_file()
    assert "exp 5:" in text or next(r for r in results["rows"] if r["row"] == "5")["n_failed"]
