"""The figures a roboticist reads beside the NRMSEs: joint error in degrees, hand error in
cm, lag, torque use (:func:`skinny_mj.training.imitation.robot_metrics`,
:func:`skinny_mj.controllers.metrics.torque_use`), and that run files carry them."""

from __future__ import annotations

import math

import numpy as np
import pytest
from skinny_mj.controllers.metrics import torque_use

from skinny_mj.plant import body
from skinny_mj.training.imitation import ROBOT_METRICS, TORQUE_METRICS, robot_metrics


def _still(dof: int, steps: int = 40) -> np.ndarray:
    """A pose inside every joint range, held for ``steps`` steps."""
    lo, hi = body.body_of(dof).joint_ranges().T
    return np.broadcast_to(0.5 * (lo + hi), (steps, dof)).copy()


@pytest.mark.parametrize("dof", [4, 8])
def test_a_constant_one_degree_offset(dof):
    wanted = _still(dof)
    produced = wanted + np.radians(1.0)
    produced[0] = wanted[0]  # step 0 is not scored, whatever it holds
    m = robot_metrics(produced, wanted, dof, 0.02)
    assert m["rms_error_deg"] == pytest.approx(1.0, abs=1e-12)
    assert m["peak_error_deg"] == pytest.approx(1.0, abs=1e-12)
    assert set(m) == set(ROBOT_METRICS)


def test_the_peak_is_the_largest_error_and_step_0_is_not_scored():
    wanted = _still(4)
    produced = wanted.copy()
    produced[0] += 1.0  # unscored
    produced[10, 2] += np.radians(3.0)
    m = robot_metrics(produced, wanted, 4, 0.02)
    assert m["peak_error_deg"] == pytest.approx(3.0)
    assert m["rms_error_deg"] == pytest.approx(math.sqrt(9.0 / (39 * 4)))


def test_hand_error_in_cm():
    # 2D: shoulder and elbow of each arm; the elbow turned by a small angle moves the
    # wrist by the forearm's chord 2 L sin(a / 2)
    wanted = _still(4)
    produced = wanted.copy()
    a = np.radians(2.0)
    elbows = body.body_of(4).elbow_dofs()
    produced[1:, elbows[0]] += a  # one arm only
    m = robot_metrics(produced, wanted, 4, 0.02)
    chord_cm = 100 * 2 * body.body_of("2d").lengths_m()[1] * math.sin(a / 2)
    assert m["peak_hand_error_cm"] == pytest.approx(chord_cm, rel=1e-9)
    assert m["hand_error_cm"] == pytest.approx(chord_cm / math.sqrt(2), rel=1e-9)  # 2 arms
    # the same from the body's forward kinematics, by hand
    skinny = body.body_of(4)
    wrist = skinny.arm_points(produced[5])[:, 2] - skinny.arm_points(wanted[5])[:, 2]
    assert 100 * np.linalg.norm(wrist, axis=-1).max() == pytest.approx(chord_cm)


def test_a_late_movement_has_a_positive_lag():
    dof, dt, steps = 4, 0.02, 90
    t = np.arange(steps + 3) * dt
    lo, hi = body.body_of(dof).joint_ranges().T
    wave = 0.5 * (lo + hi) + 0.2 * (hi - lo) * np.sin(2 * np.pi * t)[:, None]
    m = robot_metrics(wave[:steps], wave[3:], dof, dt)
    assert m["lag_s"] == pytest.approx(3 * dt)


def test_torque_use_of_a_known_torque_and_velocity():
    dt = 0.01
    tau = np.zeros((1, 100, 2))
    qd = np.zeros((1, 100, 2))
    tau[0, :, 0], qd[0, :, 0] = 2.0, 0.5  # 1 W for 1 s
    tau[0, :, 1], qd[0, :, 1] = -2.0, 1.5  # braking: 3 W of |power| for 1 s
    u = torque_use(tau, qd, dt)
    assert u["abs_work_j"][0] == pytest.approx(4.0)
    assert u["torque_rms_nm"][0] == pytest.approx(2.0)
    assert set(u) == set(TORQUE_METRICS)


def test_a_quick_dynamic_row_carries_the_figures(tmp_path):
    from skinny_mj.experiments.dynamic import study as dynamic

    from skinny_mj.engine.plan import plan

    p = plan(dynamic.STUDY, quick=True)
    cfg = p.config("2d-ymca-arm-ct")  # computed torque alone: no training, quick
    (m,) = dynamic.STUDY.run(cfg, p.row("2d-ymca-arm-ct"), [0])
    for key in (*ROBOT_METRICS, *TORQUE_METRICS):
        assert isinstance(m[key], float) and math.isfinite(m[key]), key
    assert m["rms_error_deg"] <= m["peak_error_deg"]
    assert m["hand_error_cm"] <= m["peak_hand_error_cm"]
    # the tables show them beside the NRMSE
    assert {"rms_error_deg", "peak_error_deg", "hand_error_cm"} <= set(dynamic.TABLE_COLUMNS)
