"""The arm's own dynamics: the textbook laws of ``skinny_mj.controllers.torque_arm``, the readout
fits that remember (``skinny_mj.controllers.torque_readout``) and their settings."""

from __future__ import annotations

import numpy as np
import pytest
from skinny_mj.controllers.esn import ESN
from skinny_mj.controllers.learning import Cycle
from skinny_mj.controllers.readout import ridge_solve
from skinny_mj.controllers.reservoir import ESNConfig
from skinny_mj.controllers.torque_arm import (
    ArmGains,
    ArmState,
    DesiredMotion,
    arm_torque,
    mass_times,
)
from skinny_mj.controllers.torque_readout import ForgettingReadout, RLSReadout

from skinny_mj.errors import SkinnyInputError
from skinny_mj.plant.path_dynamics import torque_dynamics
from skinny_mj.training.loop import TrainConfig


def _esn(n_runs=2) -> ESN:
    cfg = ESNConfig(n_inputs=3, n_outputs=2, n_reservoir=20, readout_activation="identity")
    return ESN(cfg, n_runs=n_runs, rngs=[np.random.default_rng(s) for s in range(n_runs)])


def _cycles(esn: ESN, n: int = 3, steps: int = 40):
    rng = np.random.default_rng(7)
    d = esn.cfg.n_extended
    return [(rng.standard_normal((esn.n_runs, steps, d)),
             rng.standard_normal((esn.n_runs, steps, 2))) for _ in range(n)]


def test_forgetting_readout_spans_one_cycle_to_all_cycles():
    for g in (0.0, 1.0):
        esn = _esn()
        fit = ForgettingReadout(esn, forgetting=g, ridge=0.1)
        cycles = _cycles(esn)
        for m, s in cycles:
            fit.fit(esn, Cycle(m, s, np.ones(2, bool)))
        used = cycles[-1:] if g == 0 else cycles
        for r in range(2):
            m = np.concatenate([c[0][r] for c in used])
            s = np.concatenate([c[1][r] for c in used])
            np.testing.assert_allclose(esn.W_out[r], ridge_solve(m, s, 0.1).T, atol=1e-10)


def test_rls_readout_without_forgetting_is_ridge_on_every_sample():
    esn = _esn()
    fit = RLSReadout(esn, steps=40, forgetting=1.0, ridge=0.1)
    cycles = _cycles(esn)
    for m, s in cycles:
        fit.fit(esn, Cycle(m, s, np.ones(2, bool)))
    m = np.concatenate([c[0][1] for c in cycles])
    s = np.concatenate([c[1][1] for c in cycles])
    np.testing.assert_allclose(esn.W_out[1], ridge_solve(m, s, 0.1).T, atol=1e-8)


def test_a_readout_fit_leaves_runs_that_do_not_learn():
    esn = _esn()
    before = esn.W_out[1].copy()
    m, s = _cycles(esn, 1)[0]
    ForgettingReadout(esn).fit(esn, Cycle(m, s, np.array([True, False])))
    np.testing.assert_array_equal(esn.W_out[1], before)
    assert np.any(esn.W_out[0] != 0)


def test_computed_torque_on_the_desired_state_is_the_inverse_dynamics():
    # e = 0 at the middle of the step: the law's torque is M qdd + c + b qd, which is
    # mj_inverse at that state (joint damping included), and its feedback part is 0
    dyn = torque_dynamics(8)
    rng = np.random.default_rng(3)
    q, qd, qdd = rng.uniform(-0.5, 0.5, 8), rng.normal(0, 1, 8), rng.normal(0, 5, 8)
    dt = 0.02
    state = ArmState(q=q[None], qd=qd[None], mass=dyn.mass_matrix(q)[None],
                     bias=dyn.bias_torque_nm(q, qd)[None], gravity=None,
                     damping=dyn.model.dof_damping[dyn.layout.dof_adr])
    motion = DesiredMotion(q_mid=(q + 0.5 * dt * qd)[None], qd_mid=qd[None],
                           qdd_step=qdd[None])
    total, fb = arm_torque("ct", state, motion, 0, dt, ArmGains(15.0))
    np.testing.assert_allclose(total[0], dyn.inverse_dynamics_nm(q, qd, qdd), atol=1e-9)
    np.testing.assert_allclose(fb, 0.0, atol=1e-12)
    # an error: the feedback is M(q) (omega^2 e + 2 zeta omega e_dot), in the arm's own
    # coordinates
    e = np.full(8, 0.01)
    shifted = DesiredMotion(q_mid=motion.q_mid + e, qd_mid=motion.qd_mid, qdd_step=qdd[None])
    _, fb = arm_torque("fel", state, shifted, 0, dt, ArmGains(5.0, 0.7))
    np.testing.assert_allclose(fb[0], state.mass[0] @ (25.0 * e), atol=1e-12)


@pytest.mark.parametrize("n", [4, 8])
def test_mass_times_is_each_runs_own_sum_whatever_the_batch(n):
    """M(q) a summed over j in order from zero, for each run alone: the same bits in a
    stack of 1 or 5, C or Fortran ordered (np.matmul's differ by the stack's layout)."""
    rng = np.random.default_rng(1)
    mass, acc = rng.standard_normal((5, n, n)), rng.standard_normal((5, n))
    want = np.zeros((5, n))
    for j in range(n):
        want += mass[:, :, j] * acc[:, None, j]
    for m in (mass, np.asfortranarray(mass), np.ascontiguousarray(mass.transpose(0, 2, 1))
              .transpose(0, 2, 1)):
        np.testing.assert_array_equal(mass_times(m, acc), want)
        for r in range(5):
            np.testing.assert_array_equal(mass_times(m[r:r + 1], acc[r:r + 1])[0], want[r])
    np.testing.assert_array_equal(mass_times(mass, acc[0]), mass_times(mass, np.tile(acc[0],
                                                                                  (5, 1))))
    np.testing.assert_allclose(want, np.einsum("rij,rj->ri", mass, acc), rtol=1e-12)


@pytest.mark.parametrize("changes", [
    {"actuation": "torque", "actuation.feedback": "ct"},  # a controller alone: method=none
    {"actuation": "torque", "actuation.feedback": "inertia-pd", "method": "true-target"},
    {"method.fit": "forgetting"},  # remembering fits are for FEL on the torque body
    {"actuation": "torque", "method.fit": "sometimes"},
    {"actuation": "torque", "method.forgetting": 1.5},
    {"actuation": "torque", "actuation.feedback": "inertia-pd", "actuation.omega": -1.0},
    {"actuation.omega": 5.0},  # a torque setting
])
def test_arm_settings_are_validated(changes):
    with pytest.raises(SkinnyInputError):
        TrainConfig().override(changes)


def test_feedback_share_is_the_gain_times_the_error_signal():
    cfg = TrainConfig().override({
        "actuation": "torque", "movement.trajectory": "y", "method": "new", "method.beta": 1.0,
        "method.cycles": 1, "method.epochs": 2, "actuation.feedback": "inertia-pd",
        "method.fit": "forgetting"})
    from skinny_mj.training.loop import train

    t = train(cfg, 0).train
    np.testing.assert_allclose(t.extra["feedback_share"],
                               np.asarray(t.gains) * t.extra["error_signal_share"])
    assert t.extra["error_signal_share"][0] > 0 and t.extra["feedback_share"][-1] == 0.0


@pytest.mark.parametrize("dof", [4, 8])
def test_the_batch_arm_state_mass_matrix_is_each_robots_block_of_mj_fullm(dof):
    """BatchArmState gathers each robot's M(q) from the batch's sparse M: the same bits as
    mj_fullM's dense matrix cut into the robots' diagonal blocks (zeros off the tree)."""
    import mujoco

    from skinny_mj.plant.adapters import BatchPlant
    from skinny_mj.plant.body import by_dof
    from skinny_mj.plant.dynamics import BatchArmState
    from skinny_mj.trajectories import get

    plant = BatchPlant(by_dof(dof, "torque"), "cartesian", get("ymca", dof), n_runs=3)
    state = BatchArmState(plant)
    m, d, n1 = plant.model, plant.data, plant.model.nv // 3
    rng = np.random.default_rng(0)
    for _ in range(3):
        d.qpos[:] = rng.uniform(-1.0, 1.0, m.nq)
        d.qvel[:] = rng.standard_normal(m.nv)
        mujoco.mj_forward(m, d)
        full = np.zeros((m.nv, m.nv))
        mujoco.mj_fullM(m, d, full)
        runs, adr = np.arange(3), state.adr
        dense = full.reshape(3, n1, 3, n1)[runs, :, runs, :][:, adr][:, :, adr]
        mass = state.mass()
        assert np.array_equal(mass, dense)
        assert not np.array_equal(dense[0], np.diag(np.diag(dense[0])))  # coupled joints
