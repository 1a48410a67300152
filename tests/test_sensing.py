"""Joint sensing: encoders with noise, finite-difference velocities, a delay."""

import numpy as np
import pytest
from skinny_mj.controllers.sensing import JointSensing

from skinny_mj.training import TrainConfig, train
from skinny_mj.training.torque import joint_nrmse


def _sensing(**kw):
    args = dict(encoder_noise_rad=0.0, velocity="finite-difference", velocity_filter_hz=None,
                delay_steps=0, dt=0.02, rngs=[np.random.default_rng(0)])
    return JointSensing(**{**args, **kw})


def test_finite_difference_of_a_ramp_is_its_slope_and_starts_at_rest():
    s = _sensing()
    s.reset(np.zeros((1, 2)), np.zeros((1, 2)))
    assert np.array_equal(s.qd, np.zeros((1, 2)))
    for k in range(1, 4):
        s.update(np.array([[0.1 * k, -0.2 * k]]), np.zeros((1, 2)))
    assert np.allclose(s.qd, [[5.0, -10.0]])
    assert np.allclose(s.q, [[0.3, -0.6]])


def test_a_delay_shows_the_state_one_step_late():
    s = _sensing(delay_steps=1)
    s.reset(np.zeros((1, 1)), np.zeros((1, 1)))
    s.update(np.array([[1.0]]), np.zeros((1, 1)))
    assert s.q[0, 0] == 0.0
    s.update(np.array([[2.0]]), np.zeros((1, 1)))
    assert s.q[0, 0] == 1.0 and s.qd[0, 0] == pytest.approx(50.0)


def test_encoder_noise_has_its_standard_deviation_and_each_run_its_stream():
    rngs = [np.random.default_rng(1), np.random.default_rng(2)]
    s = _sensing(encoder_noise_rad=0.01, rngs=rngs)
    s.reset(np.zeros((2, 3)), np.zeros((2, 3)))
    draws = []
    for _ in range(2000):
        s.update(np.zeros((2, 3)), np.zeros((2, 3)))
        draws.append(s.q.copy())
    draws = np.array(draws)
    assert draws.std() == pytest.approx(0.01, rel=0.05)
    alone = _sensing(encoder_noise_rad=0.01, rngs=[np.random.default_rng(2)])
    alone.reset(np.zeros((1, 3)), np.zeros((1, 3)))
    alone.update(np.zeros((1, 3)), np.zeros((1, 3)))
    assert np.array_equal(alone.q[0], draws[0, 1])


def test_the_filter_smooths_the_velocity_and_oracle_passes_it_through():
    s = _sensing(velocity_filter_hz=2.0)
    s.reset(np.zeros((1, 1)), np.zeros((1, 1)))
    s.update(np.array([[0.02]]), np.zeros((1, 1)))
    assert 0 < s.qd[0, 0] < 1.0
    o = _sensing(velocity="oracle")
    o.reset(np.zeros((1, 1)), np.array([[0.5]]))
    o.update(np.zeros((1, 1)), np.array([[3.0]]))
    assert o.qd[0, 0] == 3.0


def test_oracle_sensing_is_what_the_controllers_saw_before_and_encoders_differ():
    base = TrainConfig().override({"actuation": "torque", "movement.trajectory": "y",
                                   "method": "none", "test.gain": 1.0,
                                   "actuation.feedback": "ct"})
    oracle = train(base.override({"actuation.sensing": "oracle"}), seed=0)
    again = train(base.override({"actuation.sensing": "oracle"}), seed=0)
    enc = train(base, seed=0)
    assert joint_nrmse(oracle) == joint_nrmse(again)
    assert joint_nrmse(enc) != joint_nrmse(oracle)
    assert joint_nrmse(enc) < 0.05  # computed torque still tracks on sensed information


def test_the_second_order_difference_has_no_lag_on_a_parabola():
    s = _sensing(velocity="finite-difference-2")
    s.reset(np.zeros((1, 1)), np.zeros((1, 1)))
    for k in range(1, 5):
        s.update(np.array([[(0.02 * k) ** 2]]), np.zeros((1, 1)))
    assert s.qd[0, 0] == pytest.approx(2 * 0.08)  # d/dt t^2 at t = 0.08 s



def _observed(model_accel: float, gains=(1.0, 1.0), noise=0.0, accel=3.0, steps=50):
    """An observer on an arm accelerating at ``accel`` rad/s^2 from rest, whose model
    predicts ``model_accel``; returns the sensing and the true velocity at the end."""
    s = _sensing(velocity="observer", observer_gains=gains, encoder_noise_rad=noise,
                 rngs=[np.random.default_rng(3)])
    s.reset(np.zeros((1, 1)), np.zeros((1, 1)))
    dt, out = 0.02, []
    for k in range(1, steps + 1):
        q_hat, v_hat = s.estimate
        pred = (q_hat + dt * v_hat + 0.5 * dt * dt * model_accel, v_hat + dt * model_accel)
        s.update(np.array([[0.5 * accel * (dt * k) ** 2]]), np.zeros((1, 1)), pred)
        out.append(s.qd[0, 0])
    return s, accel * dt * steps, np.array(out)


def test_the_observer_with_an_exact_model_reads_the_true_velocity():
    for gains in ((1.0, 1.0), (0.5, 0.2)):
        s, v, _ = _observed(3.0, gains)
        assert s.qd[0, 0] == pytest.approx(v)
        assert s.q[0, 0] == pytest.approx(0.5 * 3.0 * 1.0 ** 2)  # the angles: the encoder's


def test_the_observer_corrects_a_wrong_model_through_the_encoders():
    # the model knows no acceleration: the residual keeps the estimate near the truth
    s, v, _ = _observed(0.0, (1.0, 1.0))
    assert s.qd[0, 0] == pytest.approx(v - 0.5 * 3.0 * 0.02)  # the first-order difference
    s, v, _ = _observed(0.0, (0.75, 0.5))
    assert abs(s.qd[0, 0] - v) < 0.1 * v


def test_lower_observer_gains_pass_less_encoder_noise():
    _, _, fast = _observed(0.0, (1.0, 1.0), noise=1e-3, accel=0.0, steps=2000)
    _, _, slow = _observed(0.0, (0.36, 0.08), noise=1e-3, accel=0.0, steps=2000)
    assert fast.std() == pytest.approx(np.sqrt(2) * 1e-3 / 0.02, rel=0.1)
    assert slow.std() < 0.5 * fast.std()


def test_the_observer_needs_a_prediction_and_takes_no_low_pass():
    s = _sensing(velocity="observer")
    s.reset(np.zeros((1, 1)), np.zeros((1, 1)))
    with pytest.raises(ValueError, match="prediction"):
        s.update(np.zeros((1, 1)), np.zeros((1, 1)))
    with pytest.raises(ValueError, match="low-pass"):
        _sensing(velocity="observer", velocity_filter_hz=5.0)


def test_the_observer_on_the_nominal_arm_reads_what_a_tachometer_reads():
    """Noise-free encoders on the arm the model describes: the model's prediction of
    each step is the plant's own, so the observer's velocity is the true one (what the
    controllers do is the same as with the true velocity)."""
    base = TrainConfig().override({"actuation": "torque", "movement.trajectory": "y",
                                   "method": "none", "test.gain": 1.0,
                                   "actuation.sensing.encoder_noise": 0.0})
    for feedback in ("ct", "computed-torque"):  # an arm law's loop, and the plain one
        cfg = base.override({"actuation.feedback": feedback})
        true = train(cfg.override({"actuation.sensing.velocity": "oracle"}), seed=0)
        observed = train(cfg.override({"actuation.sensing.velocity": "observer"}), seed=0)
        fd = train(cfg.override({"actuation.sensing.velocity": "finite-difference"}), seed=0)
        assert joint_nrmse(observed) == pytest.approx(joint_nrmse(true), rel=1e-6)
        assert joint_nrmse(fd) != pytest.approx(joint_nrmse(true), rel=1e-3)


def test_the_observer_needs_the_lockstep_plant():
    from skinny_mj.errors import SkinnyInputError
    with pytest.raises(SkinnyInputError, match="observer"):
        TrainConfig().override({"actuation": "torque", "plant.backend": "env",
                                "actuation.sensing.velocity": "observer"})


def test_fel_target_with_a_lead_pairs_each_command_with_a_later_error():
    from skinny_mj.controllers.rollout import Rollout

    rng = np.random.default_rng(0)
    commands, u_error = rng.normal(size=(2, 5, 3)), rng.normal(size=(2, 6, 3))
    ro = Rollout(commands, commands, u_error, *(np.zeros((2, 6, 3)),) * 3,
                 np.zeros((2, 5, 4)))
    np.testing.assert_array_equal(ro.targets(0), ro.y_est)
    np.testing.assert_array_equal(ro.targets(0), commands + u_error[:, 1:])
    lead = ro.targets(2)
    np.testing.assert_array_equal(lead[:, :3], commands[:, :3] + u_error[:, 3:])
    np.testing.assert_array_equal(lead[:, 3:], commands[:, 3:] + u_error[:, -1:])


def test_a_target_lead_refuses_a_per_step_learner():
    from skinny_mj.controllers.loop import Loop

    class Online:
        def update(self, state, y_esn, y_est):
            pass

    with pytest.raises(ValueError, match="target lead"):
        Loop(online=Online(), target_lead=1)
    with pytest.raises(ValueError, match="target lead"):
        Loop(target_lead=-1)


def test_the_teacher_lags_by_the_sensing_delay_only_when_fel_learns_from_an_arm_law():
    from skinny_mj.training.torque import teacher_lag

    fel = TrainConfig().override({"actuation": "torque", "actuation.feedback": "inertia-pd",
                                  "actuation.sensing.delay": 2})
    assert teacher_lag(fel) == 2
    assert teacher_lag(fel.override({"actuation.align_delay": False})) == 0
    assert teacher_lag(fel.override({"method": "none", "test.gain": 1.0})) == 0
    assert teacher_lag(fel.override({"actuation.sensing.delay": 0})) == 0
    assert teacher_lag(fel.override({"actuation.feedback": "pd"})) == 0
    assert teacher_lag(TrainConfig()) == 0


def test_under_a_sensing_delay_the_aligned_target_learns_what_the_misaligned_one_cannot():
    """One step of sensing delay on the torque body: FEL whose target pairs command(t)
    with the error of the arm it moved learns YMCA; paired with the error of step t + 1
    (which then describes the arm a step earlier) it does not."""
    cfg = TrainConfig().override({"actuation": "torque", "actuation.feedback": "inertia-pd",
                                  "method.beta": 1.0, "method.cycles": 3, "method.epochs": 8,
                                  "method.fit": "forgetting", "actuation.sensing.delay": 1})
    aligned = train(cfg, seed=0).test.position_nrmse
    misaligned = train(cfg.override({"actuation.align_delay": False}), seed=0).test.position_nrmse
    assert aligned < 0.25 * misaligned
