"""The measures behind two of paper C's claims (skinny_mj.experiments.claims: error_split,
range_excursion, and the command line that prints them)."""

from __future__ import annotations

import numpy as np
import pytest
from skinny_mj.experiments.claims import error_split, main, range_excursion


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


@pytest.mark.parametrize("args", [[], ["a", "b"], ["c7", "results", "5"], ["c7", "no-such", "4"],
                                  ["claims.md"]])
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
