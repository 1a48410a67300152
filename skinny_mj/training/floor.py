"""The torque-limited floor: the least joint-tracking error a controller of the torque body
can reach on a movement, found by iterative LQR on MuJoCo's own derivatives.

A movement that asks more torque than the motors have (the shipped CMU clips at full
speed, :func:`skinny_mj.training.torque.feasibility`) cannot be tracked exactly by any
controller; computed torque with its commands clipped at the limits is one answer, not the
best one. The floor here is the answer of an optimal controller that knows everything a
controller could: the true model (the torque twin itself), the whole movement in advance
and the exact state. It minimises

    J(u) = sum_t  |n(q_t) - n(q*_t)|^2 / n_dof  +  w_v |qd_t - qd*_t|^2 / n_dof  +  r |u_t|^2

over the held, normalised torque commands u_t in [-1, 1] (one per 20 ms control step, as
every controller of the body sends them), n the joint-angle normalisation of the NRMSE
(each range to [-1, 1]). The solver is iLQR with box-constrained controls (Tassa, Mansard
and Todorov 2014, "Control-limited differential dynamic programming"): the control step's
linearisation is central finite differences of MuJoCo stepping the twin through the
control step's physics substeps (RK4, which ``mujoco.mjd_transitionFD`` does not take);
each backward step solves its
box QP by projected Newton (:func:`box_qp`).

The floor is a bound, labelled "oracle" wherever it is shown: no controller of the
project has this information, so a learned or textbook controller is measured by how far
it stays above it. Its tracking error is that of the optimised commands played open loop
on the same deterministic plant (the rollout the optimiser scored).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import mujoco
import numpy as np

from skinny_mj.controllers.metrics import position_nrmse
from skinny_mj.plant import body
from skinny_mj.plant.path_dynamics import torque_dynamics
from skinny_mj.training.imitation import robot_metrics

_log = logging.getLogger(__name__)

__all__ = ["Floor", "box_qp", "torque_floor"]

#: The cost's weights: joint velocity error (per unit normalised angle per s) and command.
VELOCITY_WEIGHT = 1e-4
COMMAND_WEIGHT = 1e-6
#: The poles (rad/s) of the computed-torque rollout the optimisation starts from.
CT_OMEGA = 15.0
#: The finite-difference step of the linearisation (state units: rad, rad/s; command).
FD_EPS = 1e-6


@dataclass(frozen=True)
class Floor:
    """One movement's floor: the optimised commands and what they do.

    commands : (T-1, n_dof) normalised torque commands in [-1, 1]; angles : (T, n_dof)
    joint angles they produce, rad; joint_nrmse : their joint-angle NRMSE against the
    movement; cost : J at the optimum; iterations : iLQR iterations run;
    start_joint_nrmse : the optimiser's start's: computed torque on the exact state with
    its commands clipped at the limits (:func:`_computed_torque`).
    """

    commands: np.ndarray
    angles: np.ndarray
    joint_nrmse: float
    cost: float
    iterations: int
    start_joint_nrmse: float

    def metrics(self, wanted: np.ndarray, dof: int, dt: float) -> dict[str, float]:
        """The floor's figures, named as in the run files (:func:`robot_metrics`)."""
        return {"joint_nrmse": self.joint_nrmse, "start_joint_nrmse": self.start_joint_nrmse,
                "max_command": float(np.abs(self.commands).max()),
                "iterations": float(self.iterations),
                **robot_metrics(self.angles, wanted, dof, dt)}


def box_qp(h: np.ndarray, g: np.ndarray, lower: np.ndarray, upper: np.ndarray,
           x0: np.ndarray, iterations: int = 50) -> tuple[np.ndarray, np.ndarray]:
    """Minimise ``x' h x / 2 + g' x`` over ``lower <= x <= upper`` by projected Newton.

    Returns ``(x, free)``: the minimiser and the mask of its components not held at a
    bound (the ones the feedback gain acts on). ``h`` must be positive definite.
    """
    x = np.clip(x0, lower, upper)
    free = np.ones(len(x), bool)
    for _ in range(iterations):
        grad = g + h @ x
        held = ((x <= lower) & (grad > 0)) | ((x >= upper) & (grad < 0))
        free = ~held
        if not free.any():
            break
        step = np.zeros_like(x)
        step[free] = -np.linalg.solve(h[np.ix_(free, free)], grad[free])
        value = 0.5 * x @ h @ x + g @ x
        alpha, moved = 1.0, False
        while alpha > 1e-8:
            cand = np.clip(x + alpha * step, lower, upper)
            if 0.5 * cand @ h @ cand + g @ cand < value - 1e-12 * abs(value):
                moved = True
                break
            alpha *= 0.5
        if not moved:
            break
        done = np.abs(cand - x).max() < 1e-10
        x = cand
        if done:
            break
    return x, free


class _Plant:
    """The torque twin stepped one control step at a time from a full state."""

    def __init__(self, dof: int, substeps: int):
        self.dynamics = torque_dynamics(dof)
        self.model, self.layout = self.dynamics.model, self.dynamics.layout
        self.substeps = substeps
        self.data = mujoco.MjData(self.model)
        self.nv = self.model.nv
        self.act = self.layout.actuator_ids

    def _set(self, x: np.ndarray, u: np.ndarray) -> None:
        d = self.data
        d.qpos[:], d.qvel[:] = x[:self.nv], x[self.nv:]
        d.ctrl[:] = 0.0
        d.ctrl[self.act] = u
        d.time = 0.0

    def step(self, x: np.ndarray, u: np.ndarray) -> np.ndarray:
        self._set(x, u)
        mujoco.mj_step(self.model, self.data, self.substeps)
        return np.concatenate([self.data.qpos, self.data.qvel])

    def linearize(self, x: np.ndarray, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(A, B) of one control step at (x, u), by central finite differences of
        :meth:`step` (MuJoCo's ``mjd_transitionFD`` does not take the RK4 integrator the
        torque twin steps with, and a control step is several physics steps)."""
        n, nu = len(x), len(u)
        a, b = np.empty((n, n)), np.empty((n, nu))
        for i in range(n):
            e = np.zeros(n)
            e[i] = FD_EPS
            a[:, i] = (self.step(x + e, u) - self.step(x - e, u)) / (2 * FD_EPS)
        for i in range(nu):
            e = np.zeros(nu)
            e[i] = FD_EPS
            b[:, i] = (self.step(x, u + e) - self.step(x, u - e)) / (2 * FD_EPS)
        return a, b


def _computed_torque(plant: _Plant, x0: np.ndarray, target: np.ndarray, dt: float,
                     omega: float = CT_OMEGA) -> tuple[np.ndarray, np.ndarray]:
    """The start of the optimisation: computed torque (poles at ``omega``, critically
    damped) on the exact state, its commands clipped at the limits: states (T, n) and
    commands (T-1, nu)."""
    nv, model, data = plant.nv, plant.model, plant.data
    limit = plant.dynamics.torque_limits_nm()
    steps = len(target) - 1
    xs, us = np.empty((steps + 1, len(x0))), np.empty((steps, len(plant.act)))
    xs[0] = x0
    mass = np.empty((nv, nv))
    for t in range(steps):
        plant._set(xs[t], np.zeros(len(plant.act)))
        mujoco.mj_forward(model, data)
        mujoco.mj_fullM(model, data, mass)
        q, qd = xs[t, :nv], xs[t, nv:]
        want_q, want_v = target[t + 1, :nv], target[t + 1, nv:]
        acc = (want_v - target[t, nv:]) / dt + omega ** 2 * (want_q - q - qd * dt) \
            + 2 * omega * (want_v - qd)
        tau = mass @ acc + data.qfrc_bias + model.dof_damping * qd
        us[t] = np.clip(tau[plant.layout.dof_adr] / limit, -1.0, 1.0)
        xs[t + 1] = plant.step(xs[t], us[t])
    return xs, us


def torque_floor(trajectory, dof: int, *, substeps: int | None = None,
                 iterations: int = 100, tolerance: float = 1e-6) -> Floor:
    """The floor (module docstring) of ``trajectory`` (its ``angles`` (T, n_dof) rad,
    ``dt`` the control step) on body ``dof``'s torque twin, starting at rest in its first
    pose as every test of the body does. ``iterations`` bounds the iLQR iterations; it
    stops earlier when an iteration lowers the cost by less than ``tolerance`` (relative).
    """
    wanted = np.asarray(trajectory.angles, float)
    dt = float(trajectory.dt)
    probe = torque_dynamics(dof).model
    if substeps is None:
        substeps = int(round(dt / probe.opt.timestep))
    if substeps < 1 or abs(substeps * probe.opt.timestep - dt) > 1e-9:
        raise ValueError(f"the control step {dt} s is not a whole number of the torque "
                         f"body's {probe.opt.timestep} s physics steps")
    plant = _Plant(dof, substeps)
    nv, n = plant.nv, 2 * plant.nv
    qa = plant.layout.qpos_adr
    va = plant.layout.dof_adr
    scale = 2.0 / np.ptp(plant.layout.range_rad, axis=1)  # the NRMSE's normalisation
    steps = len(wanted) - 1
    wanted_v = np.gradient(wanted, dt, axis=0)
    # quadratic cost in the state: l_t(x) = (x - x*_t)' Q (x - x*_t)
    q_diag = np.zeros(n)
    q_diag[qa] = scale ** 2 / dof
    q_diag[nv + va] = VELOCITY_WEIGHT * scale ** 2 / dof
    target = np.zeros((steps + 1, n))
    target[:, qa], target[:, nv + va] = wanted, wanted_v
    r = COMMAND_WEIGHT
    nu = len(plant.act)
    lower, upper = -np.ones(nu), np.ones(nu)

    def cost(xs, us):
        dx = xs[1:] - target[1:]
        return float(np.sum(dx * dx * q_diag) + r * np.sum(us * us))

    x0 = np.zeros(n)
    x0[qa] = wanted[0]
    xs, us = _computed_torque(plant, x0, target, dt)
    start_angles = xs[:, qa]
    j = cost(xs, us)
    mu, it = 1e-6, 0
    for it in range(1, iterations + 1):
        lin = [plant.linearize(xs[t], us[t]) for t in range(steps)]
        k_ff = np.zeros((steps, nu))
        k_fb = np.zeros((steps, nu, n))
        v_x = 2 * q_diag * (xs[-1] - target[-1])
        v_xx = np.diag(2 * q_diag)
        expected = 0.0
        ok = True
        for t in range(steps - 1, -1, -1):
            a, b = lin[t]
            q_x = a.T @ v_x
            q_u = b.T @ v_x + 2 * r * us[t]
            q_xx = a.T @ v_xx @ a
            q_uu = b.T @ v_xx @ b + 2 * r * np.eye(nu)
            q_ux = b.T @ v_xx @ a
            reg = q_uu + mu * np.eye(nu)
            if np.linalg.eigvalsh(0.5 * (reg + reg.T)).min() <= 0:
                ok = False
                break
            k, free = box_qp(reg, q_u, lower - us[t], upper - us[t], k_ff[min(t + 1, steps - 1)])
            gain = np.zeros((nu, n))
            if free.any():
                gain[free] = -np.linalg.solve(reg[np.ix_(free, free)], q_ux[free])
            k_ff[t], k_fb[t] = k, gain
            expected += k @ q_u
            v_x = (q_x + gain.T @ q_uu @ k + gain.T @ q_u + q_ux.T @ k)
            v_xx = q_xx + gain.T @ q_uu @ gain + gain.T @ q_ux + q_ux.T @ gain
            v_xx = 0.5 * (v_xx + v_xx.T)
            # the stage cost of x_t (x_0 is fixed: its term does not matter)
            if t > 0:
                v_x = v_x + 2 * q_diag * (xs[t] - target[t])
                v_xx = v_xx + np.diag(2 * q_diag)
        if not ok:
            mu *= 10
            continue
        improved = False
        for alpha in (1.0, 0.5, 0.25, 0.1, 0.03, 0.01):
            new_us = np.empty_like(us)
            new_xs = np.empty_like(xs)
            new_xs[0] = x0
            for t in range(steps):
                u = us[t] + alpha * k_ff[t] + k_fb[t] @ (new_xs[t] - xs[t])
                new_us[t] = np.clip(u, -1.0, 1.0)
                new_xs[t + 1] = plant.step(new_xs[t], new_us[t])
            new_j = cost(new_xs, new_us)
            if np.isfinite(new_j) and new_j < j:
                improved = True
                break
        if not improved:
            mu *= 10
            if mu > 1e6:
                break
            continue
        gain_rel = (j - new_j) / max(j, 1e-300)
        xs, us, j = new_xs, new_us, new_j
        mu = max(mu / 10, 1e-9)
        _log.info("floor iteration %d: cost %.6g (alpha %.3g)", it, j, alpha)
        if gain_rel < tolerance:
            break
    angles = xs[:, qa]

    def nrmse(produced):
        return float(position_nrmse(body.body_of(dof).normalize_angles(produced[None]),
                                    body.body_of(dof).normalize_angles(wanted))[0])

    return Floor(us, angles, nrmse(angles), j, it, nrmse(start_angles))
