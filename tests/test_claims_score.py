"""The claims scored from run files (experiments/claims_score.py, ``skinny claims``): on
synthetic run files written as the engine writes them, each verdict is reached with its
numbers, a missing row, an absent metric, too few runs and a missing sweep are not
testable with that reason, a re-scoring (twice, or read back from the JSON) gives the same
count, and a page's computed section is checked against the run files."""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pytest
from skinny_mj.experiments import claims_page as page
from skinny_mj.experiments import claims_score as cs

from skinny_mj.cli.parser import main
from skinny_mj.engine.stats import to_jsonable
from skinny_mj.errors import SkinnyInputError

N = 20  # paper E's declared run count (claims_rules.RUNS["E"])


def write_runs(folder: Path, study: str, rows: dict[str, dict[str, object]], n: int = N,
               status: dict[str, str] | None = None, quick: bool = False,
               **options: str) -> Path:
    """Run files as the engine writes them: ``runs/<row>-<seed>.json``. ``rows``: row ->
    {metric: mean (noisy, sd 1 % of it) or a list of per-run values}; ``options``: the
    sweep's command-line options in its config.json (movement, protocol)."""
    rng = np.random.default_rng(0)
    (folder / "runs").mkdir(parents=True)
    for i, (row, metrics) in enumerate(rows.items()):
        for k in range(n):
            seed = 1000 * i + k
            values = {m: (v[k] if isinstance(v, list) else v * (1 + 0.01 * rng.standard_normal()))
                      for m, v in metrics.items()}
            st = (status or {}).get(row, "ok")
            rec = {"experiment": study, "row": row, "row_index": i, "run_index": k,
                   "seed": seed, "params": {}, "paper": {}, "status": st,
                   "metrics": values if st == "ok" else {}, "wall_s": 0.1}
            (folder / "runs" / f"{row}-{seed}.json").write_text(json.dumps(to_jsonable(rec)))
    (folder / "config.json").write_text(json.dumps({"experiment": study, "seeding": "row-id",
                                                    "options": {"quick": quick, **options}}))
    return folder


def _paper_e(folder: Path, **kw) -> Path:
    rng = np.random.default_rng(1)
    tiny = list(1.0 + 0.5 * rng.standard_normal(N))  # no real difference from row 2's 1.0
    return write_runs(folder, "paper-e", {
        "1": {"position_nrmse": 0.3, "motor_nrmse": 2.0, "train_wall_s": 1.0},
        "2": {"position_nrmse": 0.1, "motor_nrmse": 0.2, "train_wall_s": 1.0},
        "3": {"position_nrmse": 0.1, "motor_nrmse": 0.2},
        "4": {"position_nrmse": 0.05, "motor_nrmse": 0.1},
        "5": {"position_nrmse": 0.02, "motor_nrmse": 0.07,
              "train_wall_s": [v - 0.05 for v in tiny]},
        "fig3-b0.3": {"position_nrmse": 0.1},  # no convergence curve stored
    }, **kw)


def _column(scored, claim_id: str, column: str = "default") -> dict:
    claim = next(c for c in scored["claims"] if c["id"] == claim_id)
    return next(c for c in claim["columns"] if c["column"] == column)


@pytest.fixture
def scored(tmp_path):
    return cs.score(cs.parse_sources([f"paper-e={_paper_e(tmp_path / 'e')}"]))


def test_every_verdict_is_reached_with_its_numbers(scored):
    e4 = _column(scored, "E4")
    assert e4["outcome"] == "holds" and not e4["weak"]
    (comp,) = e4["comparisons"]
    assert comp["n"] == [N, N] and comp["p"] < 0.05
    assert comp["stat_a"] == pytest.approx(0.05, rel=0.01)
    assert comp["ratio"] == pytest.approx(0.5, rel=0.02)
    (e1,) = _column(scored, "E1")["comparisons"]  # worst run of 5 beats the best of 2
    assert e1["outcome"] == "holds" and e1["statistic"] == "max / min" and e1["p"] is None
    e10 = _column(scored, "E10")  # motor 2.0, not within x1.5 of 0.5
    assert e10["outcome"] == "does not hold" and not e10["weak"]
    assert "outside" in e10["reason"]
    e3 = _column(scored, "E3")  # 5 faster than 2 by 5 % of a 50 % spread: weak
    assert e3["outcome"] == "does not hold" and e3["weak"]
    e11 = _column(scored, "E11")  # negated: exp 3 is NOT better than exp 2
    assert e11["outcome"] == "holds"


def test_not_testable_says_the_measured_reason(tmp_path, scored):
    assert "row fig5a-nu0.03 is not in the sweep" in _column(scored, "E7")["reason"]
    assert "metric cycles_to_converge_tol1 is absent" in _column(scored, "E6")["reason"]
    for name, command in (("recorded", "paper-e --movement ymca-recorded"),
                          ("recorded+fitted-gain-2", "paper-e --protocol thesis")):
        col = _column(scored, "E4", name)
        assert col["outcome"] == "not testable"
        assert f"sweep not run: `skinny experiment {command} --workers 1`" in col["reason"]
    assert _column(scored, "E4", "recorded")["counted"]
    few = write_runs(tmp_path / "few", "paper-e", {"2": {"position_nrmse": 0.1},
                                                   "4": {"position_nrmse": 0.05}}, n=3)
    col = _column(cs.score(cs.parse_sources([f"paper-e={few}"])), "E4")
    assert col["outcome"] == "not testable"
    assert "3 ok runs with position_nrmse (0 failed, 0 errored, of 3) where 20" in col["reason"]


def test_failed_runs_are_counted_apart_and_not_in_the_means(tmp_path):
    folder = write_runs(tmp_path / "f", "paper-e", {"2": {"position_nrmse": 0.1},
                                                    "4": {"position_nrmse": 0.05}},
                        status={"4": "failed"})
    col = _column(cs.score(cs.parse_sources([f"paper-e={folder}"])), "E4")
    assert col["outcome"] == "not testable" and "(20 failed, 0 errored, of 20)" in col["reason"]


BAND = ({"movement": "ymca-recorded", "protocol": "gain-0.5"}, {"movement": "ymca-recorded"},
        {"protocol": "thesis"})


def test_a_band_column_needs_one_sweep_per_point_and_holds_only_at_all(tmp_path):
    one = _paper_e(tmp_path / "g1", **BAND[1])
    scored = cs.score(cs.parse_sources([f"paper-e:recorded+gain-band={one}"]))
    col = _column(scored, "E4", "recorded+gain-band")
    assert col["outcome"] == "not testable"
    assert col["reason"].startswith("1 of the 3 sweeps of its band run: `skinny experiment "
                                    "paper-e --movement ymca-recorded --protocol gain-0.5")
    folders = [_paper_e(tmp_path / "g3", **BAND[2]), one, _paper_e(tmp_path / "g2", **BAND[0])]
    scored = cs.score(cs.parse_sources([f"paper-e:recorded+gain-band={f}" for f in folders]))
    col = _column(scored, "E4", "recorded+gain-band")
    assert col["outcome"] == "holds" and len(col["comparisons"]) == 3
    assert [c["sweep"] for c in col["comparisons"]] == [  # in the band's order
        "skinny experiment paper-e --movement ymca-recorded --protocol gain-0.5",
        "skinny experiment paper-e --movement ymca-recorded",
        "skinny experiment paper-e --protocol thesis"]


def test_a_sweep_made_by_another_command_than_its_reading_is_refused(tmp_path):
    folder = _paper_e(tmp_path / "e")  # the defaults, given as the recorded reading
    with pytest.raises(SkinnyInputError, match=re.escape(
            "its runs were made with the study's defaults, not by the command paper-e under "
            "recorded needs: skinny experiment paper-e --movement ymca-recorded")):
        cs.score(cs.parse_sources([f"paper-e:recorded={folder}"]))
    twice = [f"paper-e:recorded+gain-band={_paper_e(tmp_path / n, **BAND[0])}" for n in "ab"]
    with pytest.raises(SkinnyInputError, match="two sweeps made by the same command"):
        cs.score(cs.parse_sources(twice))

def test_rescoring_twice_or_from_the_json_gives_the_same_count(tmp_path, scored):
    again = cs.score(cs.parse_sources([f"paper-e={tmp_path / 'e'}"]))
    assert cs.counts(again) == cs.counts(scored)
    assert page.markdown(again) == page.markdown(scored)
    back = json.loads(json.dumps(to_jsonable(scored)))
    assert cs.counts(back) == cs.counts(scored)
    counted = cs.counts(scored)["counted"]
    assert counted["holds"] + counted["does not hold"] + counted["not testable"] == 64


def test_the_page_check_compares_a_section_with_the_run_files(tmp_path, scored):
    text = "# Every thesis claim\n\nProse.\n\n" + page.markdown(scored) + "\nMore prose.\n"
    assert page.page_matches(text, scored)
    assert not page.page_matches("# no section\n", scored)
    run = tmp_path / "e" / "runs" / "4-3000.json"  # row 4 (index 3) now worse than row 2
    for path in sorted((tmp_path / "e" / "runs").glob("4-*.json")):
        rec = json.loads(path.read_text())
        rec["metrics"]["position_nrmse"] *= 10
        path.write_text(json.dumps(rec))
    assert run.is_file()
    rescored = cs.score(cs.parse_sources([f"paper-e={tmp_path / 'e'}"]))
    assert not page.page_matches(text, rescored)


@pytest.mark.parametrize("entry, words", [
    ("paper-z=x", "no claim reads study 'paper-z'"),
    ("paper-e", "give STUDY[:READINGS]=FOLDER"),
    ("paper-e:thesis=x", "unknown reading 'thesis'"),
    ("paper-d:recorded=x", "no claim reads paper-d under recorded; its claims read it under "
                           "default, recorded+fitted-gain-2+fitted-tt-noise, recorded+tt-clean,"),
])
def test_bad_sources_are_refused_in_one_line(entry, words):
    with pytest.raises(SkinnyInputError, match=re.escape(words)):
        cs.parse_sources([entry])


def test_a_folder_of_another_study_or_without_runs_is_refused(tmp_path):
    folder = _paper_e(tmp_path / "e")
    with pytest.raises(SkinnyInputError, match="not of 'paper-d'"):
        cs.score(cs.parse_sources([f"paper-d={folder}"]))
    (tmp_path / "empty" / "runs").mkdir(parents=True)
    with pytest.raises(SkinnyInputError, match="no run files"):
        cs.score(cs.parse_sources([f"paper-e={tmp_path / 'empty'}"]))
    with pytest.raises(SkinnyInputError, match="no runs/ folder"):
        cs.score(cs.parse_sources([f"paper-e={tmp_path}"]))


def test_the_command_writes_both_files_prints_the_count_and_refuses_to_overwrite(
        tmp_path, capsys):
    folder = _paper_e(tmp_path / "e", quick=True)
    out = tmp_path / "out"
    assert main(["claims", "--from", f"paper-e={folder}", "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    assert any(line.startswith("counted: ") and "of 64 hold" in line
               for line in printed.splitlines())
    assert "smoke test (--quick)" in printed
    text = (out / "claims.md").read_text()
    data = json.loads((out / "claims.json").read_text())
    assert page.page_matches(text, data) and "Smoke test (--quick)" in text
    assert main(["claims", "--from", f"paper-e={folder}", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "already exists" in err and len(err.strip().splitlines()) == 1
    assert main(["claims", "--from", f"paper-e={folder}", "--out", str(out),
                 "--overwrite"]) == 0
    assert main(["claims", "--from", f"nope={folder}", "--out", str(tmp_path / "o2")]) == 2
    assert "no claim reads study 'nope'" in capsys.readouterr().err
    assert not (tmp_path / "o2").exists()


def test_a_metric_reading_reads_its_metric_from_the_same_runs(tmp_path):
    """Paper A's mean-abs-difference reading: 2 x performance_mae, from the default sweep."""
    folder = write_runs(tmp_path / "a", "paper-a", {
        "inverse-d0": {"performance_nrmse": 0.2, "performance_mae": 0.05},
        "serial-d0": {"performance_nrmse": 0.1, "performance_mae": 0.08}}, n=10)
    scored = cs.score(cs.parse_sources([f"paper-a={folder}"]))
    assert _column(scored, "A10")["outcome"] == "holds"
    col = _column(scored, "A10", "mean-abs-difference")
    assert col["outcome"] == "does not hold" and "wrong direction" in col["reason"]
    assert col["comparisons"][0]["stat_a"] == pytest.approx(0.16, rel=0.01)
    recorded = _column(scored, "A10", "recorded+mean-abs-difference")
    assert ("sweep not run: `skinny experiment paper-a --movement ymca-recorded --workers 1`"
            in recorded["reason"])
