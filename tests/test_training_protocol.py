"""Faithful data and protocol: the recorded-like YMCA, explicit desired signals, position
retargeting and the toolbox's protocol options (each default = today's behaviour)."""

import numpy as np
import pytest
from skinny_mj.controllers.esn import ESN, ESNConfig
from skinny_mj.controllers.feedback import FeedbackController
from skinny_mj.controllers.fel import Loop, New, Task, Test, evaluate, train
from skinny_mj.controllers.plant import ToyPlant, toy_movement
from skinny_mj.controllers.true_target import TrueTarget, train_true_target

from skinny_mj.errors import SkinnyInputError
from skinny_mj.plant import body
from skinny_mj.training import protocol
from skinny_mj.training.config import TrainConfig
from skinny_mj.training.imitation import movement_stats
from skinny_mj.trajectories import Trajectory, excerpt, ik, load_movement, sample_clip, ymca
from skinny_mj.trajectories.human import markers, ymca_recorded
from skinny_mj.trajectories.retarget import solve_ik

LIMITS = np.tile([0.0, np.pi], (4, 1))


def _toy(noise=0.2):
    q, speed, commands = toy_movement(60, 4, seed=0)
    plant = ToyPlant(2, q[0], LIMITS, speed, seed=3)
    return plant, plant.signals_of(q), commands, ESNConfig(8, 4, n_reservoir=40, noise_level=noise)


def test_protocol_fields_default_to_todays_behaviour_and_validate():
    cfg = TrainConfig()
    tt = cfg.override({"method": "true-target"})
    assert (cfg.test.noise, cfg.method.u_error_gain, tt.method.input_noise,
            cfg.movement.retarget) == (False, 1.0, 0.0, "angles")
    assert {"test.noise", "method.u_error_gain", "movement.retarget"} <= set(cfg.to_dict())
    assert "method.input_noise" in tt.to_dict()
    for bad in ({"method.u_error_gain": 0.0}, {"method": "true-target", "method.input_noise": -1.0},
                {"movement.retarget": "bones"}, {"test.noise": 1}):
        with pytest.raises(SkinnyInputError):
            cfg.override(bad)


def test_u_error_gain_scales_u_error_and_training_follows():
    plant, desired, commands, cfg = _toy()
    sensed = plant.reset()
    base = FeedbackController().u_error(desired[5], sensed, plant)
    np.testing.assert_array_equal(FeedbackController(gain=1.0).u_error(desired[5], sensed, plant),
                                  base)
    np.testing.assert_allclose(FeedbackController(gain=2.0).u_error(desired[5], sensed, plant),
                               2 * base)
    fcfg = New(epochs=2, cycles=1)
    runs = []
    for fb in (None, FeedbackController(gain=1.0), FeedbackController(gain=0.5)):
        p, d, c, ecfg = _toy()
        runs.append(train(ESN(ecfg, n_runs=2, seed=1), p, Task(d, c), fcfg,
                          Loop() if fb is None else Loop(feedback=fb)))
    np.testing.assert_array_equal(runs[0].position_nrmse, runs[1].position_nrmse)
    assert not np.allclose(runs[0].position_nrmse, runs[2].position_nrmse)


def test_u_error_damping_is_a_method_key_whose_default_keeps_fels_own_controller():
    assert TrainConfig().method.u_error_damping == protocol.DAMPING == FeedbackController.damping
    assert protocol.feedback_of(1.0) is None and protocol.feedback_of(1.0, protocol.DAMPING) is None
    fb = protocol.feedback_of(1.0, 0.3)
    assert (fb.damping, fb.gain) == (0.3, 1.0)
    assert TrainConfig().override({"method.u_error_damping": 0.3}).method.u_error_damping == 0.3
    with pytest.raises(SkinnyInputError):
        TrainConfig().override({"method.u_error_damping": -0.1})
    plant, desired, _, _ = _toy()
    sensed = plant.reset()
    plain = FeedbackController().u_error(desired[5], sensed, plant)
    damped = FeedbackController(damping=0.5).u_error(desired[5], sensed, plant)
    assert np.linalg.norm(damped) < np.linalg.norm(plain)  # lambda shrinks the correction


def test_test_noise_is_a_parameter_off_by_default():
    results = []
    for noise in (None, False, True):
        plant, desired, commands, cfg = _toy()
        esn = ESN(cfg, n_runs=2, seed=1)
        esn.W_out[...] = np.random.default_rng(0).normal(0, 0.1, esn.W_out.shape)  # "trained"
        test = Test() if noise is None else Test(noise=noise)
        results.append(evaluate(esn, plant, Task(desired, commands), test=test).position_nrmse)
    np.testing.assert_array_equal(results[0], results[1])
    assert not np.allclose(results[1], results[2])


def test_teacher_forcing_input_noise_perturbs_inputs_only_and_is_seeded():
    _, desired, commands, cfg = _toy(noise=0.0)

    def fit(sd, seed=0):
        esn = ESN(cfg, n_runs=2, seed=1)
        rngs = [np.random.default_rng(seed + r) for r in range(2)]
        tt = TrueTarget(beta=1.0, input_noise=sd)
        return train_true_target(esn, desired, commands, tt, input_rngs=rngs).motor_nrmse

    clean = fit(0.0)
    esn = ESN(cfg, n_runs=2, seed=1)
    np.testing.assert_array_equal(
        clean, train_true_target(esn, desired, commands, TrueTarget(beta=1.0))
        .motor_nrmse)
    np.testing.assert_array_equal(fit(0.05), fit(0.05))
    assert np.all(fit(0.05) > clean)  # noisy inputs: the fit to clean inputs is worse
    with pytest.raises(ValueError):
        train_true_target(ESN(cfg, n_runs=2, seed=1), desired, commands,
                          TrueTarget(input_noise=0.1))


def test_explicit_desired_signals_travel_with_the_trajectory(tmp_path):
    traj = ymca(4)
    sig = traj.position_signals("cartesian") * 0.9  # not Skinny's kinematics of the angles
    t = Trajectory(traj.angles, traj.dt, "x", {"cartesian": sig})
    np.testing.assert_array_equal(t.position_signals("cartesian"), sig)
    np.testing.assert_array_equal(t.position_signals("joint"), traj.position_signals("joint"))
    np.testing.assert_array_equal(t.repeat(2).position_signals("cartesian"), np.tile(sig, (2, 1)))
    assert t.resample(0.5).position_signals("cartesian").shape == (626, 8)
    np.testing.assert_array_equal(excerpt(t, 1.0, 2.0).position_signals("cartesian"),
                                  sig[50:150])
    loaded = Trajectory.load(t.save(tmp_path / "t.npz"))
    np.testing.assert_array_equal(loaded.position_signals("cartesian"), sig)
    with pytest.raises(SkinnyInputError):
        t.save(tmp_path / "t.csv")
    with pytest.raises(SkinnyInputError):
        Trajectory(traj.angles, traj.dt, "x", {"cartesian": sig[:, :4]})


def test_ik_recovers_skinnys_own_angles():
    for dof in (4, 8):
        q = ymca(dof).angles
        seg = body.body_of(dof).segment_vectors(q)
        unit = seg / np.linalg.norm(seg, axis=-1, keepdims=True)
        angles, target = solve_ik(unit[:, :, 0], unit[:, :, 1], dof)
        np.testing.assert_allclose(target, body.body_of(dof).cartesian_signals(q), atol=1e-12)
        assert ik.residual(angles, target, dof).max() < 1e-6


def test_recorded_ymca_is_seeded_never_still_and_not_always_reachable_in_2d():
    a = ymca_recorded(4, 0)
    assert len(a) == 313 and a.desired is not None
    np.testing.assert_array_equal(markers(0), markers(0))  # the capture, seeded
    assert not np.allclose(markers(0), markers(1))
    s2, s3, smooth = movement_stats(a), movement_stats(ymca_recorded(8)), movement_stats(ymca(4))
    assert s2["still_steps"] == 0 and smooth["still_steps"] > 100
    assert s2["unreachable_fraction"] > 0.1 and s3["unreachable_fraction"] == 0.0
    assert smooth["unreachable_fraction"] == 0.0


def test_build_run_picks_up_explicit_signals():
    from skinny_mj.training.loop import build_run

    run = build_run(TrainConfig().override({"movement.trajectory": "ymca-recorded",
                                            "esn.n_reservoir": 20, "method.epochs": 1}), [0])
    np.testing.assert_array_equal(run.desired, ymca_recorded(4).position_signals("cartesian"))
    assert not np.allclose(run.desired, body.body_of(4).cartesian_signals(run.trajectory.angles))


def test_position_retargeting_of_motion_capture():
    clip = f"{sample_clip('md_02')}@start=3,duration=2"
    by_angles, _ = load_movement(clip, 8)
    by_pos, _ = load_movement(clip, 8, retarget="positions")
    assert by_angles.desired is None and by_pos.desired["cartesian"].shape == (100, 12)
    target = by_pos.desired["cartesian"]
    assert ik.residual(by_pos.angles, target, 8).mean() <= \
        ik.residual(by_angles.angles, target, 8).mean() + 1e-12
    with pytest.raises(SkinnyInputError):
        load_movement(clip, 8, retarget="bones")


def test_trajectory_show_cli(capsys):
    from skinny_mj.cli.parser import main

    assert main(["trajectory", "show", "ymca-smooth"]) == 0
    assert "still_steps                      162" in capsys.readouterr().out
    assert main(["trajectory", "show", "nope"]) == 2
    assert len(capsys.readouterr().err.strip().splitlines()) == 1
