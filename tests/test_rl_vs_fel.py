"""``skinny experiment rl-vs-fel``: every learner is tested alike and the RL env is the
training path's loop (its teacher the config's), the curves are segments of one chain,
the data files and the report are made from run files alone, and without the ``rl``
extra the RL rows are left out (refused by name in one line) while the FEL rows run."""

from __future__ import annotations

import itertools
import json
import sys
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("gymnasium")

from skinny_mj.experiments.rl_vs_fel import data, report, runs, study  # noqa: E402
from skinny_mj.experiments.rl_vs_fel.tracking import (  # noqa: E402
    WORST_REWARD,
    TrackingEnv,
    score,
)

from skinny_mj.engine.experiment import run_sweep  # noqa: E402
from skinny_mj.errors import SkinnyInputError  # noqa: E402
from skinny_mj.io import page_section  # noqa: E402
from skinny_mj.training import loop as training  # noqa: E402
from skinny_mj.training.config import TrainConfig  # noqa: E402

YMCA = TrainConfig().override({**study.REGIMES["ymca"][0], "method.epochs": 1})


def _env(tc: TrainConfig, seed: int, gain: float) -> TrackingEnv:
    run = training.build_run(tc, [seed])
    return TrackingEnv(tc, run.trajectory, run.max_speed_rad_s, run.plant_seeds[0], gain,
                       test=True)


@pytest.mark.parametrize("gain, omega", [(0.0, None), (1.0, None), (1.0, 20.0)])
def test_the_zero_policy_scores_as_the_untrained_esn_with_the_configs_teacher(gain, omega):
    """An untrained ESN commands 0: FEL's test at K = gain and the env's score of the
    zero policy with the teacher's gain are the same numbers, bit for bit, whatever
    teacher the config names (here its poles)."""
    tc = YMCA if omega is None else YMCA.override({"actuation.omega": omega})
    run = training.build_run(tc, [7])
    ours = score(lambda obs: np.zeros(4), _env(tc, 7, gain), tc.test.washout_cycles)
    fel = runs._fel_tests(run, {"ymca": None}, gain)["ymca"]
    assert ours == fel
    untaught = runs._fel_tests(run, {"ymca": None}, 0.0)["ymca"]["position_nrmse"]
    assert 0.1 < untaught < 1.0  # no torque: far from tracking
    if gain == 1:
        assert ours["position_nrmse"] < 0.5 * untaught  # the teacher alone tracks, roughly


def test_the_observation_is_the_esns_input():
    env = _env(YMCA, 3, 0.0)
    obs, _ = env.reset()
    n_sig = env.desired.shape[1]
    assert env.observation_space.shape == (2 * n_sig + 2 * 4,)
    np.testing.assert_array_equal(obs[:n_sig], env.desired[1])
    assert np.all(obs[-4:] == 0)  # at rest
    obs, reward, terminated, truncated, _ = env.step(np.full(4, 0.3))
    assert reward == -np.mean(np.abs(env.desired[1] - env.plant.true_signals()[0]))
    assert not (terminated or truncated) and np.any(obs[-4:] != 0)


def test_a_diverged_simulation_ends_the_episode_with_the_worst_reward(monkeypatch):
    env = _env(YMCA, 0, 1.0)
    env.reset()
    for _ in range(3):
        env.step(np.zeros(4))
    warnings = itertools.count(1)  # a new MuJoCo warning after every step from here on
    monkeypatch.setattr(env.plant, "warning_count", lambda: next(warnings))
    _, reward, terminated, truncated, info = env.step(np.zeros(4))
    assert info == {"diverged": True} and terminated and not truncated
    assert reward == WORST_REWARD * (env.n_steps - 3) and env.diverged == 1
    assert score(lambda obs: np.zeros(4), env) is None


def test_fel_curve_ends_at_the_test_of_train():
    tc = YMCA.override({"method.epochs": 2})
    points, facts = runs.fel_curve(tc, 3, {"ymca": None})
    per_epoch = facts["steps_per_epoch"]
    assert per_epoch == (3 + 2) * 312 and [p["steps"] for p in points] == [0, per_epoch,
                                                                           2 * per_epoch]
    final = training.train(tc, 3)
    assert points[-1]["tests"]["ymca"]["position_nrmse"] == final.test.position_nrmse
    assert points[-1]["tests"]["ymca"]["rms_error_deg"] == final.robot_figures()["rms_error_deg"]
    assert 0 < points[1]["cpu_s"] < points[2]["cpu_s"]
    assert set(points[-1]["tests_k1"]) == {"ymca"}


def test_curves_are_chains_of_segments_tested_on_a_log_grid():
    exp = study.STUDY.build()
    rows = {r.id: r for r in exp.rows}
    chain = [r for r in exp.rows if r.params.get("curve") == "ppo-ymca"]
    spans = [tuple(r.params["span"]) for r in chain]
    assert spans[0][0] == 0 and all(a[1] == b[0] for a, b in zip(spans, spans[1:], strict=False))
    assert spans[-1][1] == study.EXTENDED["ppo"] >= 2 * study.BUDGET["ppo"]
    assert {r.seeds_of for r in chain[1:]} == {chain[0].id}
    costs = [exp.cost(r) for r in chain]
    assert costs == sorted(costs, reverse=True) and len(set(costs)) == len(costs)
    assert max(study.cost(exp.config(r.id), rows[r.id]) for r in exp.rows
               if r.params["learner"] != "fel") < 3600  # every RL run within an hour
    budget = set(exp.groups["budget"])
    assert "ppo-general-1000000" in budget and "sac-ymca-100000" in budget
    assert "ppo-ymca-1250000" in exp.groups["extend"] and not budget & set(
        exp.groups["search"])
    assert exp.config("fel-general").movement.trajectory.startswith("set:babble")
    assert exp.config("ppo-res-ymca-250000").actuation.feedback == "inertia-pd"
    assert runs.test_steps(10_000) == [0, 1000, 1500, 2000, 3000, 5000, 7000, 10_000]


def test_without_the_rl_extra_the_rl_rows_are_refused_in_one_line(monkeypatch, tmp_path):
    monkeypatch.setitem(sys.modules, "stable_baselines3", None)  # import raises ImportError
    exp = study.STUDY.build(quick=True)
    assert sorted(exp.unavailable) == sorted(r.id for r in exp.rows
                                             if not r.id.startswith("fel-"))
    with pytest.raises(SkinnyInputError) as err:
        run_sweep(exp, tmp_path, rows=["ppo-ymca-250000"], workers=1, progress=False)
    assert str(err.value) == ("experiment 'rl-vs-fel': row 'ppo-ymca-250000' needs the rl "
                              "extra: pip install -e '.[rl]'")


def _curve(errors, step=1000, learner_tests="tests"):
    return [runs.point(k * step, (k * 2.0, k * 1.0),
                       {"ymca": None if e is None else {"position_nrmse": e,
                                                        "rms_error_deg": 10 * e}})
            for k, e in enumerate(errors)]


def test_curve_metrics_first_test_at_or_below_each_threshold():
    m = runs.curve_metrics(_curve([0.5, None, 0.04, 0.06, 0.02]), {"ymca": ("ymca",)},
                           (0.05, 0.02, 0.01))
    assert (m["ymca__steps_to_0.05"], m["ymca__cpu_to_0.05"]) == (2000, 2.0)
    assert (m["ymca__steps_to_0.02"], m["ymca__wall_to_0.02"]) == (4000, 8.0)
    assert m["ymca__steps_to_0.01"] is None
    assert (m["ymca__nrmse"], m["ymca__best_nrmse"], m["env_steps"]) == (0.02, 0.02, 4000)
    assert m["ymca__rms_error_deg"] == 0.2


def _run_file(folder, row, seed, learner, points, curve=None):
    rec = {"experiment": "rl-vs-fel", "row": row, "row_index": 0, "run_index": 0,
           "seed": seed, "params": {"learner": learner, "regime": "ymca",
                                    "curve": curve or row, "scores": {"ymca": ["ymca"]}},
           "paper": {}, "status": "ok", "metrics": {"curve": points},
           "nonfinite_metrics": [], "fail_reason": None, "error": None, "wall_s": 1.0,
           "finished_at": "now"}
    (folder / "runs").mkdir(parents=True, exist_ok=True)
    (folder / "runs" / f"{row}-{seed}.json").write_text(json.dumps(rec))


def test_data_files_and_the_report_come_from_run_files_alone(tmp_path):
    sweep = tmp_path / "sweep"
    fel = _curve([0.3, 0.04, 0.015, 0.008], step=1560)
    for p in fel:
        p["tests_k1"] = p["tests"]
    for seed in (1, 2):
        _run_file(sweep, "fel-ymca", seed, "fel", fel)
        _run_file(sweep, "ppo-ymca-2000", seed, "ppo", _curve([0.4, 0.3]), "ppo-ymca")
        _run_file(sweep, "ppo-ymca-4000", seed, "ppo", _curve([0.4, 0.3, 0.1, 0.045, 0.03]),
                  "ppo-ymca")
    paths = data.export([sweep], tmp_path / "data")
    assert sorted(p.name for p in paths) == ["fel-ymca-1.json", "fel-ymca-2.json",
                                             "ppo-ymca-1.json", "ppo-ymca-2.json"]
    rec = json.loads((tmp_path / "data" / "ppo-ymca-1.json").read_text())
    assert rec["rows"] == ["ppo-ymca-4000-1.json"] and rec["points"][-1]["steps"] == 4000
    text = report.write(data.load(tmp_path / "data"), tmp_path / "out")
    assert (tmp_path / "out" / "rl-vs-fel_steps.png").stat().st_size > 0
    assert "| ymca | PPO | 2 | 4,000 |" in text and "not reached by 4,000" in text
    assert "| ymca | 0.05 | 1,560, 1.0 | PPO, 3,000, 3.0 | 1.9, 3.0 |" in text
    assert "| ymca | 0.02 | 3,120, 2.0 | none reached | > 1.3 (no RL by 4,000) |" in text


@pytest.mark.parametrize("learner", ["ppo", "sac"])
def test_an_rl_curve_continues_from_its_checkpoint(learner, tmp_path):
    """The smoke test of the rl extra: a residual learner trains two segments of a few
    hundred env steps; the second continues the first's checkpoint (steps, CPU, curve)."""
    pytest.importorskip("stable_baselines3")
    folder, cols = tmp_path / "ckpt", {"ymca": None}
    a, facts = runs.rl_segment(learner, 1.0, YMCA, 5, cols, (0, 150), folder, quick=True)
    assert [p["steps"] for p in a] == [0, 150] and facts["segment"] == [0, 150]
    assert (folder / "150" / "model.zip").is_file()
    b, _ = runs.rl_segment(learner, 1.0, YMCA, 5, cols, (150, 300), folder, quick=True)
    assert b[:2] == a and [p["steps"] for p in b][-1] >= 300
    assert b[-1]["cpu_s"] > a[-1]["cpu_s"] > 0
    assert all(0 < p["tests"]["ymca"]["position_nrmse"] < 1 for p in b)
    with pytest.raises(SkinnyInputError, match="earlier segment"):
        runs.rl_segment(learner, 1.0, YMCA, 5, cols, (300, 450), tmp_path / "none",
                        quick=True)


def test_the_ratio_table_takes_the_fewest_steps_and_the_least_cpu_and_states_bounds():
    def curve(errors, steps_per, cpu_per):
        return [{"steps": k * steps_per, "cpu_s": k * cpu_per, "nrmse": e, "deg": 10 * e}
                for k, e in enumerate(errors)]

    found = {("fel", "ymca"): [curve([0.3, 0.04, 0.03], 1000, 1.0)] * 2,
             ("sac", "ymca"): [curve([0.3, 0.04, 0.015], 2000, 100.0)] * 2,  # fewer steps
             ("ppo", "ymca"): [curve([0.3, 0.2, 0.04, 0.015], 5000, 1.0),  # less CPU
                               curve([0.3, 0.2, 0.04, 0.009], 5000, 1.0)]}
    text = report.ratio_table(found)
    assert ("| ymca | 0.05 | 1,000, 1.0 | SAC, 2,000, 100.0; least CPU: PPO, 10,000, 2.0 "
            "| 2.0, 2.0 |") in text
    # FEL never reached 0.02 in its 2,000 steps: RL's steps are a bound on the ratio
    assert "| ymca | 0.02 | 0/2 seeds | SAC, 4,000, 200.0; least CPU: PPO, 15,000, 3.0 " \
           "| < 2.00 (no FEL by 2,000) |" in text
    assert "| ymca | 0.01 | 0/2 seeds | not in every seed (PPO 1/2 seeds) | — |" in text


def test_the_results_page_shows_the_tables_of_its_committed_data_files():
    """docs/results/rl-vs-fel.md carries its two tables as the report makes them from the
    data files beside it, so a page edited by hand or left behind new data fails here."""
    root = Path(__file__).resolve().parents[1]
    found = report.series(data.load(root / data.DEFAULT_DATA))
    assert {learner for learner, _ in found} >= {"fel", "ppo", "ppo-res", "sac", "sac-res"}
    page = (root / "docs" / "results" / "rl-vs-fel.md").read_text(encoding="utf-8")
    want = report.page_tables(report.tables(found))
    assert page_section(page, report.BEGIN, report.END) == want, (
        "docs/results/rl-vs-fel.md differs from the tables of docs/results/rl-vs-fel-data: "
        "rerun `python -m skinny_mj.experiments.rl_vs_fel.report --page "
        "docs/results/rl-vs-fel.md`")


def test_the_report_rewrites_only_the_pages_section_and_refuses_a_page_without_one(
        tmp_path):
    """``--page``: the tables replace the section between the markers, the rest of the page
    is kept; a page without the markers is refused before any figure is drawn."""
    records = [{"curve": "ppo-ymca", "learner": "ppo", "regime": "ymca", "seed": 1,
                "scores": {"ymca": ["ymca"]},
                "points": [{"steps": s, "cpu_s": s / 1000, "tests": {"ymca": {
                    "position_nrmse": e, "rms_error_deg": 100 * e}}}
                    for s, e in ((0, 0.3), (1000, 0.04), (2000, 0.015))]}]
    page = tmp_path / "page.md"
    page.write_text(f"# title\n\ntext\n\n{report.BEGIN}\nstale table\n{report.END}\n\nafter\n")
    report.write(records, tmp_path / "figs", page=page)
    text = page.read_text()
    assert text.startswith("# title\n\ntext\n\n") and text.endswith("\n\nafter\n")
    assert "stale table" not in text and "| ymca | PPO | 1 | 2,000 |" in text
    assert not (tmp_path / "figs" / "rl-vs-fel_tables.md").exists()
    bare = tmp_path / "bare.md"
    bare.write_text("# no section\n")
    with pytest.raises(SkinnyInputError, match="no computed section"):
        report.write(records, tmp_path / "none", page=bare)
    assert bare.read_text() == "# no section\n" and not (tmp_path / "none").exists()
