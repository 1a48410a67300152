"""The claims table's count (skinny_mj.experiments.claims.tally), the page that states it,
and the measures behind two of its reasons (error_split, range_excursion)."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest
from skinny_mj.experiments.claims import error_split, main, range_excursion, tally, tally_lines

PAGE = Path(__file__).resolve().parents[1] / "docs" / "results" / "claims.md"

TWO = """| # | claim | ours | verdict (default; thesis reading) |
|---|---|---|---|
| E1 | a \\| b | 1 | holds; holds |
| E2 | c | 2 | does not hold; weak |
| E3 | d | 3 | weak; not run |

Extensions (not a claim row):

| # | claim | verdict |
|---|---|---|
| A1 | e | does not hold |
| x | not a claim id | holds |
"""


def test_tally_counts_each_reading_and_a_single_verdict_under_both():
    counts = tally(TWO)
    assert dict(counts["default"]) == {"holds": 1, "does not hold": 2, "weak": 1}
    assert dict(counts["thesis reading"]) == {"holds": 1, "weak": 1, "not run": 1,
                                              "does not hold": 1}
    assert tally_lines(counts)[1] == ("thesis reading: 2 of 4 hold (1 of them weak), 1 do not "
                                      "hold, 1 not run")


@pytest.mark.parametrize("row, message", [("| E1 | a | 1 | holds; maybe |", "unknown verdict"),
                                          ("| E1 | a | 1 | holds |", "1 verdicts for 2")])
def test_tally_refuses_a_verdict_it_cannot_count(row, message):
    table = TWO.splitlines()[:2] + [row]
    with pytest.raises(ValueError, match=message):
        tally("\n".join(table))


def test_the_page_states_the_tables_own_count():
    text = PAGE.read_text(encoding="utf-8")
    stated = dict(re.findall(r"^- \*\*([a-z ]+)\*\*: (.+)$", text, flags=re.M))
    counted = dict(line.split(": ", 1) for line in tally_lines(tally(text)))
    assert stated == counted


def test_error_split_shares_the_squared_error_and_splits_the_steps():
    desired = np.zeros((4, 2))
    produced = np.array([[0.0, 0.2], [0.0, 0.2], [0.4, 0.0], [0.4, 0.0]])
    split = error_split(produced, desired, np.array([False, False, True, True]))
    np.testing.assert_allclose(split["share"], [0.8, 0.2])
    assert split["nrmse_selected"] == pytest.approx(np.sqrt(0.08) / 2)  # mean over both signals
    assert split["nrmse_other"] == pytest.approx(np.sqrt(0.02) / 2)


def test_range_excursion_measures_only_what_leaves_the_reference_range():
    reference = np.array([[0.0, -1.0], [1.0, 1.0]])
    angles = np.array([[0.5, 0.0], [1.5, 0.0], [-0.2, 0.0], [1.0, 1.0]])
    most, frac = range_excursion(angles, reference, tol=0.3)
    np.testing.assert_allclose(most, [0.5, 0.0])
    np.testing.assert_allclose(frac, [0.25, 0.0])


@pytest.mark.parametrize("args", [[], ["a", "b"], ["c7", "results", "5"], ["no-such.md"]])
def test_the_command_line_refuses_bad_input_in_one_line(args):
    with pytest.raises(SystemExit) as e:
        main(args)
    assert "\n" not in str(e.value)


def test_the_mirrors_measure_runs_on_both_bodies():
    lines = main(["mirrors"]).splitlines()
    assert [line.split(",")[0] for line in lines] == [
        "4 DOF", "4 DOF", "8 DOF", "8 DOF"]
    assert all("beyond YMCA's range:" in line for line in lines)


def test_the_c7_measure_reads_a_sweeps_y_runs(tmp_path):
    """A Y-trained run whose produced YM angles miss YM in the elbows alone: all of its
    error is the elbows'."""
    import json

    from skinny_mj.experiments.paper_c import study as paper_c

    ym = paper_c.load(paper_c.MOVEMENTS["ym"], 4).angles
    produced = ym.copy()
    produced[:, paper_c.elbow_dofs(4)] += 0.1
    (tmp_path / "runs").mkdir()
    run = {"experiment": "paper-c", "row": "y", "row_index": 1, "run_index": 0, "seed": 7,
           "status": "ok", "metrics": {"angles__ym": produced.tolist()}}
    (tmp_path / "runs" / "y-7.json").write_text(json.dumps(run))
    (line,) = main(["c7", str(tmp_path), "4"]).splitlines()
    assert line.startswith("seed 7:") and "elbows' share of the YM error 1.000" in line
