"""The torque twin's dynamics: gravity and bias torques equal the two-link arm's closed
forms from the mass table, inverse dynamics inverts forward dynamics, and the true
torques of a movement replay it open loop (tolerances measured and stated)."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from skinny_mj.plant import body
from skinny_mj.plant.adapters import BatchPlant
from skinny_mj.plant.dynamics import Dynamics
from skinny_mj.plant.model import (
    TORQUE_ARMATURE_3D_SHOULDER,
    TORQUE_GEAR_NM,
    forearm_hand_inertia,
    load_model,
    segment_inertias,
)

G = 9.81
L_UPPER = body.body_of("2d").lengths_m()[0]


@pytest.fixture(scope="module", params=[4, 8])
def dyn(request):
    torque = body.body_of(request.param).twin("torque")
    return Dynamics(load_model(torque), torque)


def _two_link():
    """Upper arm (m1, r1, I1 about its CoM, the abduction axis) and forearm+hand as one
    body (m2, r2 from the elbow, I2), from the tables (parallel-axis combined)."""
    upper, fore = segment_inertias()["upper_arm"], forearm_hand_inertia()
    return upper.mass_kg, upper.com_m, upper.inertia_kg_m2[1], fore.mass_kg, fore.com_m, \
        fore.inertia_kg_m2[1]


def _pose(dof, abduction, elbow):
    """Both arms at the same abduction and elbow angles (rad), other DOFs 0."""
    q = np.zeros(dof)
    names = body.body_of(dof).dof_names
    for side in body.SIDES:
        q[names.index(f"{side}_shoulder_abduction")] = abduction
        q[names.index(f"{side}_elbow_flexion")] = elbow
    return q


def _abd_elbow(dof):
    names = body.body_of(dof).dof_names
    return [names.index(f"{s}_{j}") for s in body.SIDES
            for j in ("shoulder_abduction", "elbow_flexion")]


def test_gravity_torque_of_the_arm_held_horizontal_is_m_g_r(dyn):
    m1, r1, _, m2, r2, _ = _two_link()
    cols = _abd_elbow(dyn.n_dof)
    # straight arm horizontal: shoulder carries both segments, elbow the forearm+hand
    tau = dyn.gravity_torque_nm(_pose(dyn.n_dof, np.pi / 2, 0.0))
    want = [G * (m1 * r1 + m2 * (L_UPPER + r2)), G * m2 * r2] * 2
    np.testing.assert_allclose(tau[cols], want, rtol=1e-12)
    assert abs(want[0] - 10.6) < 0.1  # 10.6 N m: 21 % of the 50 N m abduction limit
    # upper arm down, forearm horizontal: both joints carry the forearm+hand alone
    tau = dyn.gravity_torque_nm(_pose(dyn.n_dof, 0.0, np.pi / 2))
    np.testing.assert_allclose(tau[cols], [G * m2 * r2] * 4, rtol=1e-12)
    np.testing.assert_allclose(dyn.gravity_torque_nm(np.zeros(dyn.n_dof)), 0.0, atol=1e-12)
    # and in normalized torque
    np.testing.assert_allclose(dyn.normalize(tau)[cols[:2]],
                               [G * m2 * r2 / TORQUE_GEAR_NM["shoulder_abduction"],
                                G * m2 * r2 / TORQUE_GEAR_NM["elbow_flexion"]], rtol=1e-12)


def test_mass_matrix_and_velocity_forces_are_the_two_link_arm(dyn):
    """MuJoCo combines the forearm and hand bodies as the parallel-axis table does, and
    qfrc_bias holds the planar two-link arm's Coriolis and centrifugal torques."""
    m1, r1, i1, m2, r2, i2 = _two_link()
    rng = np.random.default_rng(0)
    cols = _abd_elbow(dyn.n_dof)
    i1 += TORQUE_ARMATURE_3D_SHOULDER if dyn.n_dof == 8 else 0.0  # the abduction's rotor
    for _ in range(5):
        th, ph = rng.uniform(0.2, 2.9, 2)
        q = _pose(dyn.n_dof, th, ph)
        mass = dyn.mass_matrix(q)[np.ix_(cols[:2], cols[:2])]
        c = np.cos(ph)
        want = [[i1 + m1 * r1**2 + i2 + m2 * (L_UPPER**2 + r2**2 + 2 * L_UPPER * r2 * c),
                 i2 + m2 * (r2**2 + L_UPPER * r2 * c)],
                [i2 + m2 * (r2**2 + L_UPPER * r2 * c), i2 + m2 * r2**2]]
        np.testing.assert_allclose(mass, want, rtol=1e-12)
        qd = np.zeros(dyn.n_dof)
        qd[cols] = rng.uniform(-3, 3, 4)
        vel = dyn.bias_torque_nm(q, qd) - dyn.gravity_torque_nm(q)
        h = m2 * L_UPPER * r2 * np.sin(ph)
        for arm in range(2):
            d1, d2 = qd[cols[2 * arm]], qd[cols[2 * arm + 1]]
            np.testing.assert_allclose(vel[cols[2 * arm:2 * arm + 2]],
                                       [-h * (2 * d1 * d2 + d2**2), h * d1**2],
                                       rtol=1e-10, atol=1e-12)


def test_inverse_dynamics_inverts_the_forward_dynamics(dyn):
    model = dyn.model
    data = mujoco.MjData(model)
    lay, rng = dyn.layout, np.random.default_rng(1)
    lo, hi = body.body_of(dyn.n_dof).joint_ranges().T
    for _ in range(10):
        q, qd = rng.uniform(lo + 0.1, hi - 0.1), rng.uniform(-2, 2, dyn.n_dof)
        qdd = rng.uniform(-5, 5, dyn.n_dof)
        tau = dyn.inverse_dynamics_nm(q, qd, qdd)
        u = dyn.normalize(tau)
        assert np.all(np.abs(u) < 1)
        data.qpos[lay.qpos_adr], data.qvel[lay.dof_adr] = q, qd
        data.ctrl[lay.actuator_ids] = u
        mujoco.mj_forward(model, data)
        np.testing.assert_allclose(data.qacc[lay.dof_adr], qdd, rtol=0, atol=1e-9)
    np.testing.assert_allclose(dyn.torque_limits_nm(),
                               [TORQUE_GEAR_NM[n.split("_", 1)[1]]
                                for n in body.body_of(dyn.n_dof).dof_names])


def _minimum_jerk(dof, seconds, dt, seed):
    """A movement from rest to rest between two random poses inside the ranges."""
    rng = np.random.default_rng(seed)
    lo, hi = body.body_of(dof).joint_ranges().T
    q0, q1 = rng.uniform(lo + 0.3, hi - 0.3), rng.uniform(lo + 0.3, hi - 0.3)
    s = np.linspace(0.0, 1.0, int(round(seconds / dt)) + 1)[:, None]
    return q0 + (q1 - q0) * (10 * s**3 - 15 * s**4 + 6 * s**5)


class _Movement:
    def __init__(self, angles, dof):
        self.angles, self.dof, self.dt = angles, dof, 0.02


# Measured over 0.5 s movements (seeds 0-2) between random poses, up to 55 % of a limit:
# worst error 2.5e-3 rad (2D) and 1.2e-2 rad (3D) with one torque per 20 ms control
# step, 1.6e-4 / 7.3e-4 rad with one per 5 ms physics step: the zero-order hold's
# O(dt^2), growing open loop. The bounds are about 1.5x that.
CONTROL_STEP_TOL = {4: 4e-3, 8: 2e-2}
PHYSICS_STEP_TOL = {4: 3e-4, 8: 1.2e-3}


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_true_torques_replay_the_movement_open_loop(dyn, seed):
    dof = dyn.n_dof
    model = dyn.model
    # one torque per 20 ms control step, through the plant (RK4 substeps)
    angles = _minimum_jerk(dof, 0.5, 0.02, seed)
    u = dyn.normalize(dyn.trajectory_torques_nm(angles, 0.02))
    assert np.all(np.abs(u) < 1.0)
    plant = BatchPlant(body.body_of(dof).twin("torque"), "joint", _Movement(angles, dof),
                       n_runs=1, sensor_noise=0.0)
    plant.set_joint_angles(angles[:1])
    worst = 0.0
    for k, command in enumerate(u):
        plant.step(command[None])
        worst = max(worst, np.abs(plant.joint_angles()[0] - angles[k + 1]).max())
        tau = plant.data.qfrc_actuator[plant.layout.dof_adr]
        assert np.all(np.abs(tau) <= dyn.torque_limits_nm())
    assert all(w.number == 0 for w in plant.data.warning)
    assert worst < CONTROL_STEP_TOL[dof], worst
    # one torque per 5 ms physics step, straight through mj_step
    h = model.opt.timestep
    fine = _minimum_jerk(dof, 0.5, h, seed)
    u = dyn.normalize(dyn.trajectory_torques_nm(fine, h))
    data = mujoco.MjData(model)
    lay = dyn.layout
    data.qpos[lay.qpos_adr] = fine[0]
    mujoco.mj_forward(model, data)
    worst = 0.0
    for k, command in enumerate(u):
        data.ctrl[lay.actuator_ids] = command
        mujoco.mj_step(model, data)
        worst = max(worst, np.abs(data.qpos[lay.qpos_adr] - fine[k + 1]).max())
    assert all(w.number == 0 for w in data.warning)
    assert worst < PHYSICS_STEP_TOL[dof], worst


def test_ymca_is_within_the_torque_limits(dyn):
    """The task's movement at 1x needs at most ~45 % of any limit (shoulder abduction),
    and stays feasible at 1.5x (~86 %)."""
    from skinny_mj.trajectories import get

    for name, bound in (("ymca", 0.5), ("ymca@1.5", 0.9)):
        u = dyn.normalize(dyn.trajectory_torques_nm(get(name, dyn.n_dof).angles))
        assert np.abs(u).max() < bound
