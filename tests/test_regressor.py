"""The inertial regressor and adaptive computed torque."""

import copy

import mujoco
import numpy as np
import pytest
from skinny_mj.controllers.adaptive_ct import ParameterRLS

from skinny_mj.plant import body
from skinny_mj.plant.dynamics import Dynamics
from skinny_mj.plant.model import load_model
from skinny_mj.plant.perturb import perturb
from skinny_mj.plant.regressor import InertialRegressor
from skinny_mj.training import TrainConfig, train
from skinny_mj.training.torque import joint_nrmse


@pytest.mark.parametrize("dof", [4, 8])
def test_regressor_times_theta_is_mj_inverse_of_the_changed_twin(dof):
    reg = InertialRegressor(dof)
    changed = copy.copy(load_model(body.body_of(dof).twin("torque")))
    perturb(type("P", (), {"model": changed, "data": mujoco.MjData(changed)})(),
            payload_kg=0.7, mass_scale=1.2, damping_nm_s_rad=0.3)
    rng = np.random.default_rng(0)
    q, qd, qdd = (rng.uniform(0.2, 1.0, (3, dof)) * s for s in (1, 2, 10))
    tau_nom, y = reg(q, qd, qdd)
    theta = np.zeros(reg.n_params)
    theta[:6] = 0.2
    theta[6] = 0.7
    theta[7:7 + dof] = 0.3
    want = Dynamics(changed, body.body_of(dof).twin("torque")).inverse_dynamics_nm(q, qd, qdd)
    assert np.allclose(tau_nom + y @ theta, want, atol=1e-9)


def test_parameter_rls_finds_the_parameters_of_noise_free_observations():
    rng = np.random.default_rng(1)
    theta = np.array([[0.5, -1.0, 2.0]])
    est = ParameterRLS(np.ones(3), noise_sd=0.01)
    est.reset(1)
    for _ in range(50):
        y = rng.standard_normal((1, 2, 3))
        est.update(y, np.einsum("rnp,rp->rn", y, theta))
    assert np.allclose(est.theta, theta, atol=1e-3)


def test_adaptive_ct_beats_nominal_ct_on_a_payload_it_was_not_told_of():
    base = TrainConfig().override({"actuation": "torque", "movement.trajectory": "y",
                                   "method": "none", "test.gain": 1.0,
                                   "actuation.payload_kg": 1.0})
    nominal = joint_nrmse(train(base.override({"actuation.feedback": "ct"}), seed=0))
    adaptive = joint_nrmse(train(base.override({"actuation.feedback": "adaptive-ct",
                                                "test.washout_cycles": 1}), seed=0))
    assert adaptive < nominal
