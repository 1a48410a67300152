"""The torque twin's inverse dynamics as a linear function of what a payload, link masses
and joint friction change: the regressor of adaptive computed torque.

Inverse dynamics are linear in each body's inertial parameters (its mass m, first moment
m c and inertia I). Scaling body i's three together by (1 + s_i) adds s_i times that
body's own share of the torque, and a point mass p at the right hand's centre of mass adds
p times the torque of 1 kg there; the joints' unmodelled viscous damping v_j and Coulomb
friction f_j add v_j qd_j and f_j sign(qd_j). So, exactly,

    tau(q, qd, qdd) = tau_nom(q, qd, qdd) + Y(q, qd, qdd) theta,
    theta = [s_1 .. s_B, p, v_1 .. v_n, f_1 .. f_n]

with ``tau_nom`` the nominal twin's ``mj_inverse`` (M qdd + c + b qd, joint limits off)
and Y's columns the differences ``mj_inverse`` gives on the nominal twin with body i's
mass and inertia doubled (B = the six arm links of :data:`skinny_mj.plant.perturb.ARM_BODIES`),
with 1 kg at the hand, then diag(qd) and diag(sign qd). :class:`InertialRegressor`
evaluates both for R arms; a test checks Y theta against ``mj_inverse`` on a changed twin.
"""

from __future__ import annotations

import copy

import mujoco
import numpy as np

from skinny_mj.plant.body import BodyLike, body_of
from skinny_mj.plant.dynamics import Dynamics
from skinny_mj.plant.model import load_model
from skinny_mj.plant.perturb import ARM_BODIES, PAYLOAD_BODY


def _variant(nominal: mujoco.MjModel, scale_body: str | None = None,
             payload_kg: float = 0.0) -> mujoco.MjModel:
    model = copy.copy(nominal)  # a deep copy
    for i in range(model.nbody):
        name = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, i) or ""
        if name == scale_body:
            model.body_mass[i] *= 2.0
            model.body_inertia[i] *= 2.0
        if name == PAYLOAD_BODY:
            model.body_mass[i] += payload_kg
    mujoco.mj_setConst(model, mujoco.MjData(model))
    return model


class InertialRegressor:
    """``tau_nom`` and Y of the module docstring for the body ``which``'s torque twin.

    ``names`` : (p,) each parameter's name; ``n_params`` = len(names).
    """

    def __init__(self, which: BodyLike):
        torque = body_of(which).twin("torque")
        nominal = load_model(torque)
        self.nominal = Dynamics(nominal, torque)
        self.n_dof = torque.dof
        self.variants = [Dynamics(_variant(nominal, scale_body=b), torque) for b in ARM_BODIES]
        self.variants.append(Dynamics(_variant(nominal, payload_kg=1.0), torque))
        joints = [f"j{j}" for j in range(self.n_dof)]
        self.names = (*(f"mass_scale_{b}" for b in ARM_BODIES), "payload_kg",
                      *(f"viscous_{j}" for j in joints), *(f"coulomb_{j}" for j in joints))
        self.n_params = len(self.names)

    def __call__(self, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray
                 ) -> tuple[np.ndarray, np.ndarray]:
        """``(tau_nom (R, n), Y (R, n, p))`` in N m (and N m per unit parameter) at the
        states q, qd, qdd (R, n) rad, rad/s, rad/s^2."""
        q, qd, qdd = (np.atleast_2d(np.asarray(a, float)) for a in (q, qd, qdd))
        tau = self.nominal.inverse_dynamics_nm(q, qd, qdd)
        cols = [v.inverse_dynamics_nm(q, qd, qdd) - tau for v in self.variants]
        eye = np.eye(self.n_dof)
        y = np.concatenate([np.stack(cols, axis=2), qd[:, :, None] * eye,
                            np.sign(qd)[:, :, None] * eye], axis=2)
        return tau, y
