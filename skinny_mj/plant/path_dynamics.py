"""The torque twin's dynamics along a geometric path: what re-timing a movement needs.

A movement q(t) re-timed along its own path is q(s(t)), with s the clip's own time
(s = t plays it as shipped). Its joint velocities are q' ṡ and accelerations
q' s̈ + q'' ṡ², so its inverse dynamics (``mj_inverse``, as
:meth:`skinny_mj.plant.dynamics.Dynamics.inverse_dynamics_nm`: M qdd + c(q, qd) + b qd,
joint limits off) split into

    tau(s, ṡ, s̈) = a(s) s̈ + b(s) ṡ² + c(s) + d(s) ṡ

with a = M q', b = M q'' + C(q, q') q' (the velocity-product part of ``qfrc_bias``),
c = g(q) (gravity: the bias at rest) and d = beta q' (the joints' viscous damping beta,
:data:`skinny_mj.plant.model.TORQUE_JOINT_DAMPING`: linear in ṡ, the one term that
is not of the form time-optimal path parameterization expects; :func:`path_torque_terms`
keeps it apart). :func:`path_torque_terms` returns the four, exactly (a test compares
their sum with ``mj_inverse``).

Also here: the joints' speed limit (:func:`velocity_limits_rad_s`), the held step
torques' ratio to the limits of a sampled movement (:func:`step_torque_ratio`, the
measure of :meth:`Dynamics.feasibility`) and the share of them that is gravity
(:func:`gravity_share`).
"""

from __future__ import annotations

import functools

import numpy as np

from skinny_mj.plant.body import Body, BodyLike, body_of
from skinny_mj.plant.dynamics import Dynamics
from skinny_mj.plant.model import load_model
from skinny_mj.plant.physics import Layout


def torque_dynamics(which: BodyLike) -> Dynamics:
    """The :class:`Dynamics` of the body's torque twin (itself, if it is a torque body;
    cached: one per body)."""
    return _dynamics(body_of(which).twin("torque"))


@functools.lru_cache(maxsize=4)
def _dynamics(torque: Body) -> Dynamics:
    return Dynamics(load_model(torque), torque)


def joint_damping(dyn: Dynamics) -> np.ndarray:
    """(n_dof,) the joints' viscous damping beta, N m s/rad (passive torque -beta qd)."""
    return dyn.model.dof_damping[dyn.layout.dof_adr].copy()


@functools.lru_cache(maxsize=4)
def _servo_ctrlrange(velocity: Body) -> tuple[float, ...]:
    model = load_model(velocity)
    ids = Layout(model, velocity).actuator_ids
    return tuple(np.abs(model.actuator_ctrlrange[ids]).min(axis=1).tolist())


def velocity_limits_rad_s(which: BodyLike) -> np.ndarray:
    """(n_dof,) the joints' speed limit, rad/s: the velocity servo's command range as the
    MJCF declares it (``skinny_defaults.xml``, 30 rad/s; the servo widens it at run time
    to 1.5x a movement's full scale, the torque twin has no speed limit of its own): the
    one joint-speed figure in the body's description; a torque body's are its velocity
    twin's)."""
    return np.array(_servo_ctrlrange(body_of(which).twin("velocity")))


def path_torque_terms(dyn: Dynamics, q: np.ndarray, qs: np.ndarray, qss: np.ndarray
                      ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``(a, b, c, d)``, each (..., n_dof) N m, of the path q(s) at points with angles q,
    path derivatives qs = q'(s) and qss = q''(s) (rad, rad per unit s, per unit s²):
    tau = a s̈ + b ṡ² + c + d ṡ (see the module docstring), from three ``mj_inverse``
    calls per point."""
    q, qs, qss = np.broadcast_arrays(*(np.asarray(x, float) for x in (q, qs, qss)))
    zero = np.zeros_like(q)
    c = dyn.inverse_dynamics_nm(q, zero, zero)
    a = dyn.inverse_dynamics_nm(q, zero, qs) - c
    d = joint_damping(dyn) * qs
    b = dyn.inverse_dynamics_nm(q, qs, qss) - c - d
    return a, b, c, d


def step_torque_ratio(dyn: Dynamics, angles: np.ndarray, dt: float) -> np.ndarray:
    """(T-1, n_dof) |held step torque| / limit of the movement ``angles`` (T, n_dof)
    sampled every ``dt`` s: :meth:`Dynamics.trajectory_torques_nm` (the clamped cubic
    spline's inverse dynamics averaged over each step), the measure of
    :meth:`Dynamics.feasibility` (a movement is feasible when no entry exceeds 1)."""
    return np.abs(dyn.trajectory_torques_nm(angles, dt)) / dyn.torque_limits_nm()


def gravity_share(dyn: Dynamics, angles: np.ndarray, dt: float) -> float:
    """The share of the torque a movement needs that is gravity: sum over steps and DOFs
    of |g(q)| at each step's start pose over the sum of |held step torque| (the
    movement's :meth:`Dynamics.trajectory_torques_nm`), both in N m."""
    angles = np.asarray(angles, float)
    tau = dyn.trajectory_torques_nm(angles, dt)
    grav = dyn.gravity_torque_nm(angles[:-1])
    return float(np.abs(grav).sum() / np.abs(tau).sum())
