"""The per-joint diagnosis of paper C in 3D (experiments/paper_c/why_3d.py)."""

from __future__ import annotations

import numpy as np
import pytest
from skinny_mj.experiments import paper_c_3d
from skinny_mj.experiments.paper_c import elbows, why_3d
from skinny_mj.experiments.paper_c import study as paper_c

from skinny_mj.training.loop import build_run


def test_per_joint_errors_average_to_the_position_nrmse():
    out = why_3d.analyse("y", {"esn.n_reservoir": 20}, [0, 1], epochs=2)
    assert out["overrides"] == {"esn.n_reservoir": 20} and len(out["runs"]) == 2
    for run in out["runs"]:
        assert len(run["test_per_joint"]) == 8
        # the printed per-joint terms are rounded to 3 decimals
        assert np.mean(run["test_per_joint"]) == pytest.approx(run["test_position_nrmse"],
                                                               abs=1e-3)
        assert set(run["next_cycle_error"]) == {"0-10"}
        assert all(g > 0 for g in run["noise_command_rms"])
        assert run["max_loop_eig"] >= 0
    assert out["runs"][0]["test_per_joint"] != out["runs"][1]["test_per_joint"]


def test_signal_per_command_is_the_inverse_dead_beat_gain():
    run = build_run(paper_c_3d.STUDY.config("y").override({"esn.n_reservoir": 20}), [0])
    c = why_3d.signal_per_command(run)
    for joint in range(8):
        assert c[joint] == pytest.approx(1.0 / elbows.dead_beat_gain(run, joint, 8, 0.02))
    assert c[1] > c[0]  # shoulder flexion's range is the narrowest, the shared scale the same


def test_bad_override_ends_with_one_line(capsys):
    with pytest.raises(SystemExit) as exc:
        why_3d.main(["--set", "esn.n_reservoir=many"])
    assert exc.value.code == 2
    assert "esn.n_reservoir" in capsys.readouterr().err


def test_the_3d_plant_is_a_pose_free_integrator_at_ys_poses():
    out = why_3d.plant_response("y", every=40)
    assert len(out["response_min"]) == 8
    np.testing.assert_allclose(out["response_min"], 1.0, atol=0.01)
    np.testing.assert_allclose(out["response_max"], 1.0, atol=0.01)
    assert max(out["zero_command_drift_deg"]) < 1e-3


def test_the_2d_contrast_measures_paper_cs_own_network():
    out = why_3d.analyse("y", {"esn.n_reservoir": 20}, [0], epochs=1, study=paper_c.STUDY)
    assert len(out["joints"]) == 4 and len(out["runs"][0]["sensed_gain"]) == 4
