"""``skinny bench``'s torque figure (plumbing only: no timing is asserted)."""

from __future__ import annotations

from skinny_mj.cli import bench


def test_torque_figure_times_the_dynamic_studys_two_rows_and_is_a_goal():
    fig = bench.torque_over_kinematic(1, 1, epochs=1)
    assert (fig["R"], fig["torque_epochs"], fig["kinematic_epochs"]) == (1, 1, 1)
    assert fig["torque_s"] > 0 and fig["kinematic_s"] > 0
    assert fig["ratio"] == fig["torque_s"] / fig["kinematic_s"]
    summary = bench.summary({"torque_over_kinematic": fig})
    assert summary["torque_over_kinematic"]["value"] == fig["ratio"]
    assert summary["torque_over_kinematic"]["goal"] == "<= 2"
    assert bench.RUN_STEPS[-1] == "torque_over_kinematic"
