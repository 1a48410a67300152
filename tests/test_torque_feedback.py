"""Torque feedback (PD, computed torque) on pure-NumPy pendulums: gains scale to the
limits, PD converges, the exact bias makes computed torque track, outputs clip."""

from __future__ import annotations

import numpy as np
import pytest
from skinny_mj.controllers.torque_feedback import (
    TorqueFeedbackController,
    TorqueGains,
    computed_torque,
    pd_torque,
)

DT = 0.02
G = 9.81


class Pendulums:
    """R runs of n independent torque-driven pendulums: I qdd = tau_max u - mgr sin q -
    b qd, the normalized command u held for each 20 ms step (RK4 at 1 ms). With
    mgr = 0 and b = 0 each joint is a double integrator. Signals are normalized angles
    over [0, pi] (joint signals), as Skinny's."""

    def __init__(self, q0, inertia, limit, mgr=0.0, b=0.0, n_runs=1):
        self.q0 = np.atleast_1d(np.asarray(q0, float))
        self.n_runs, self.n_dof, self.dt = n_runs, self.q0.size, DT
        self.inertia, self.limit = np.asarray(inertia, float), np.asarray(limit, float)
        self.mgr, self.b = np.asarray(mgr, float), np.asarray(b, float)
        self.max_speed_rad_s = np.full(self.n_dof, 3.0)
        self.reset()

    def reset(self):
        self.q = np.tile(self.q0, (self.n_runs, 1))
        self.qd = np.zeros_like(self.q)
        return self.signals()

    def acc(self, q, qd, u):
        return (self.limit * u - self.mgr * np.sin(q) - self.b * qd) / self.inertia

    def inverse_dynamics(self, q, qd, qdd):
        return self.inertia * qdd + self.mgr * np.sin(q) + self.b * qd

    def step(self, u):
        u = np.clip(np.asarray(u, float).reshape(self.n_runs, self.n_dof), -1.0, 1.0)
        h = self.dt / 20
        for _ in range(20):
            q, v = self.q, self.qd
            k1 = v, self.acc(q, v, u)
            k2 = v + h / 2 * k1[1], self.acc(q + h / 2 * k1[0], v + h / 2 * k1[1], u)
            k3 = v + h / 2 * k2[1], self.acc(q + h / 2 * k2[0], v + h / 2 * k2[1], u)
            k4 = v + h * k3[1], self.acc(q + h * k3[0], v + h * k3[1], u)
            self.q = q + h / 6 * (k1[0] + 2 * k2[0] + 2 * k3[0] + k4[0])
            self.qd = v + h / 6 * (k1[1] + 2 * k2[1] + 2 * k3[1] + k4[1])
        return self.signals()

    def signals(self):
        return 2.0 * self.q / np.pi - 1.0

    def joint_angles(self):
        return self.q.copy()

    def joint_velocities(self):
        return self.qd.copy()

    def command_jacobian(self):
        jac = np.diag(2.0 / np.pi * self.max_speed_rad_s * self.dt)
        return np.broadcast_to(jac, (self.n_runs, self.n_dof, self.n_dof)).copy()


PER_RAD = (2.0 / np.pi,)


def _run_pd(plant, gains, target_rad, steps):
    err = []
    for _ in range(steps):
        u = pd_torque(target_rad - plant.q, -plant.qd, gains)
        plant.step(u)
        err.append(target_rad - plant.q)
    return np.array(err)[:, 0]  # (steps, n_dof)


def test_gains_scale_to_the_limits_and_are_critically_damped():
    limits, inertia = np.array([50.0, 30.0]), np.array([0.5, 0.006])
    free = TorqueGains.from_limits(limits, inertia, dt=None)
    np.testing.assert_allclose(free.error_fraction(0.1), [0.5, 0.5])
    np.testing.assert_allclose(free.kp, [250.0, 150.0])
    np.testing.assert_allclose(free.kd, 2.0 * np.sqrt(free.kp * inertia))
    held = TorqueGains.from_limits(limits, inertia, dt=DT)  # cap omega dt <= 0.5
    assert held.kp[0] == free.kp[0]  # the heavy joint: omega dt = 0.45, not capped
    np.testing.assert_allclose(np.sqrt(held.kp[1] / inertia[1]) * DT, 0.5)
    # the light joint: Kp = I (0.5 / dt)^2 = 3.75 N m/rad, 1.25 % of its limit at 0.1 rad
    np.testing.assert_allclose(held.error_fraction(0.1)[1], 0.0125)
    with pytest.raises(ValueError):
        TorqueGains.from_limits(limits, [0.5, 0.0])
    with pytest.raises(ValueError):
        TorqueGains((1.0,), (1.0, 2.0), (3.0,))


def test_pd_converges_on_a_double_integrator_without_overshoot():
    plant = Pendulums(q0=[1.0, 1.0], inertia=[0.5, 0.006], limit=[50.0, 30.0])
    gains = TorqueGains.from_limits(plant.limit, plant.inertia, dt=DT)
    err = _run_pd(plant, gains, np.array([1.3, 0.8]), steps=100)  # 2 s
    assert np.all(np.abs(err[-1]) < 1e-4) and np.all(np.abs(plant.qd) < 1e-3)
    # critically damped, held for 20 ms: the error never changes sign by more than 2 %
    assert np.all(err * np.sign(err[0]) > -0.02 * np.abs(err[0]))


def test_the_sampling_cap_is_what_keeps_a_light_joint_stable():
    uncapped = TorqueGains.from_limits([30.0], [0.006], dt=None)  # omega dt = 3.2
    capped = TorqueGains.from_limits([30.0], [0.006], dt=DT)
    results = {}
    for name, gains in (("uncapped", uncapped), ("capped", capped)):
        plant = Pendulums(q0=[1.0], inertia=[0.006], limit=[30.0])
        results[name] = np.abs(_run_pd(plant, gains, np.array([1.05]), steps=100))
    assert results["capped"][-1, 0] < 1e-4
    assert results["uncapped"][-25:, 0].max() > 0.01  # a limit cycle, never settles


def test_gravity_leaves_pd_a_steady_error_that_the_bias_removes():
    mgr, target = 10.6, 1.2  # Skinny's arm held out: ~10.6 N m at horizontal
    gains = TorqueGains.from_limits([50.0], [0.45], dt=DT)
    plant = Pendulums(q0=[1.0], inertia=[0.45], limit=[50.0], mgr=mgr, b=0.5)
    err = _run_pd(plant, gains, np.array([target]), steps=150)
    # steady state: Kp e = mgr sin(q)
    np.testing.assert_allclose(err[-1, 0], mgr * np.sin(target - err[-1, 0]) / gains.kp[0],
                               rtol=1e-3)
    assert err[-1, 0] > 0.03
    plant.reset()
    for _ in range(150):
        bias = mgr * np.sin(plant.q)  # qfrc_bias of the current state
        plant.step(computed_torque(target - plant.q, -plant.qd, bias, gains))
    assert abs(target - plant.q[0, 0]) < 1e-6


def test_computed_torque_with_the_exact_bias_tracks_much_better_than_pd():
    plant = Pendulums(q0=[1.2], inertia=[0.45], limit=[50.0], mgr=10.6, b=0.5)
    gains = TorqueGains.from_limits(plant.limit, plant.inertia, dt=DT)
    w = 2 * np.pi * 0.7

    def desired(t):
        return 1.2 + 0.5 * np.sin(w * t), 0.5 * w * np.cos(w * t), -0.5 * w**2 * np.sin(w * t)

    rms = {}
    for name in ("pd", "computed"):
        plant.reset()
        errs = []
        for k in range(200):  # 4 s
            q_d, qd_d, _ = desired(k * DT)
            e, ed = q_d - plant.q, qd_d - plant.qd
            if name == "pd":
                u = pd_torque(e, ed, gains)
            else:  # inverse dynamics of the desired motion over the held step (midpoint)
                tau_ff = plant.inverse_dynamics(*desired((k + 0.5) * DT))
                u = computed_torque(e, ed, tau_ff, gains)
            assert np.all(np.abs(u) <= 1.0)
            plant.step(u)
            errs.append(desired((k + 1) * DT)[0] - plant.q[0, 0])
        rms[name] = np.sqrt(np.mean(np.square(errs[50:])))
    assert rms["computed"] < 0.05 * rms["pd"], rms
    assert rms["computed"] < 1e-3


def test_outputs_are_normalized_torque_clipped_to_one():
    gains = TorqueGains.from_limits([50.0, 60.0, 30.0, 45.0], [0.3, 0.3, 0.006, 0.07])
    rng = np.random.default_rng(0)
    e, ed, bias = rng.normal(0, 1, (3, 64, 4)) * np.array([1.0, 10.0, 40.0])[:, None, None]
    for u, raw in ((pd_torque(e, ed, gains), pd_torque(e, ed, gains, clip=False)),
                   (computed_torque(e, ed, bias, gains),
                    computed_torque(e, ed, bias, gains, clip=False))):
        assert np.all(np.abs(u) <= 1.0) and np.any(np.abs(u) == 1.0)
        inside = np.abs(raw) < 1.0
        np.testing.assert_array_equal(u[inside], raw[inside])
        np.testing.assert_array_equal(u[~inside], np.sign(raw[~inside]))
    np.testing.assert_allclose(pd_torque(e, ed, gains, clip=False),
                               (gains.kp * e + gains.kd * ed) / gains.limit)


def test_u_error_joint_and_jacobian_modes_agree_and_are_the_pd_motor_error():
    plant = Pendulums(q0=[0.4, 1.0, 2.0], inertia=[0.3, 0.006, 0.07], limit=[50, 30, 45],
                      n_runs=2)
    plant.step(np.array([[0.3, -0.2, 0.1], [0.1, 0.2, -0.3]]))  # moving
    gains = TorqueGains.from_limits(plant.limit, plant.inertia)
    sensed = plant.signals()
    desired = sensed + np.random.default_rng(1).normal(0, 0.02, sensed.shape)
    joint = TorqueFeedbackController(gains, "joint", signal_per_rad=PER_RAD * 3)
    jac = TorqueFeedbackController(gains, "jacobian", damping=0.0)
    u_joint = joint.u_error(desired, sensed, plant)
    np.testing.assert_allclose(jac.u_error(desired, sensed, plant), u_joint, rtol=1e-10)
    e = (desired - sensed) / (2.0 / np.pi)
    np.testing.assert_allclose(u_joint, pd_torque(e, -plant.qd, gains, clip=False))
    qd_d = np.full(3, 0.5)
    bias = np.array([[1.0, 2.0, 3.0]])
    np.testing.assert_allclose(
        joint.u_error(desired, sensed, plant, desired_velocity_rad_s=qd_d, bias_nm=bias),
        computed_torque(e, qd_d - plant.qd, bias, gains, clip=False))
    big = joint.command(desired + 1.0, sensed, plant)
    assert np.all(np.abs(big) <= 1.0)
    with pytest.raises(ValueError):
        TorqueFeedbackController(gains, "joint")


def test_the_controller_alone_holds_a_pendulum_against_gravity():
    """The FEL interface used as a controller (K = 1, no learner): with the plant's
    bias torque it settles on the target; the PD motor error alone sags."""
    plant = Pendulums(q0=[0.5], inertia=[0.45], limit=[50.0], mgr=10.6, b=0.5)
    gains = TorqueGains.from_limits(plant.limit, plant.inertia, dt=DT)
    ctrl = TorqueFeedbackController(gains, "joint", signal_per_rad=PER_RAD)
    desired = np.array([2.0 * 1.5 / np.pi - 1.0])  # 1.5 rad
    for bias in (False, True):
        plant.reset()
        for _ in range(150):
            kw = {"bias_nm": plant.mgr * np.sin(plant.q)} if bias else {}
            plant.step(ctrl.command(desired, plant.signals(), plant, **kw))
        error = 1.5 - plant.q[0, 0]
        assert (abs(error) < 1e-6) if bias else (error > 0.03)
