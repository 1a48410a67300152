"""Torques of the torque twin: gravity and bias forces of a pose, inverse dynamics of a
joint trajectory, and the torques that replay a movement step by step.

The plant side of torque control (the controllers in ``controllers/torque_feedback.py``
are pure NumPy and take these as arrays). Every function works on one robot's compiled
model (:func:`skinny_mj.plant.model.load_model` of a torque body) and returns per-DOF
arrays in :attr:`skinny_mj.plant.body.Body.dof_names` order, in N m, or normalized by the motors'
peak torques (:func:`torque_limits_nm`; normalized torque = ctrl).

Conventions (MuJoCo's): ``M(q) qdd + c(q, qd) = tau + tau_passive``, with
``c = qfrc_bias`` (gravity, Coriolis and centrifugal forces) and the joints' viscous
damping ``tau_passive = -b qd``. The inverse dynamics are continuous-time (the twin
integrates with RK4, which has no discrete inverse); joint limits are left out of them
(an arm pressing on a limit is not a torque the motors must make).
"""

from __future__ import annotations

import mujoco
import numpy as np

from skinny_mj.controllers.feedback import jacobian_error
from skinny_mj.controllers.torque_arm import ArmState
from skinny_mj.plant.body import Body
from skinny_mj.plant.model import load_batch_model
from skinny_mj.plant.physics import Layout


class Dynamics:
    """Rigid-body queries on one robot model, with a scratch ``MjData`` of their own
    (the caller's simulation state is never touched).

    Parameters
    ----------
    model : a compiled one-robot model of ``skinny``, usually a torque body's.
    skinny : the :class:`~skinny_mj.plant.body.Body` it is.
    """

    def __init__(self, model: mujoco.MjModel, skinny: Body):
        self.model = model
        self.layout = Layout(model, skinny)
        self.data = mujoco.MjData(model)
        self.n_dof = self.layout.dof

    # -- limits -------------------------------------------------------------------------
    def torque_limits_nm(self) -> np.ndarray:
        """(n_dof,) peak torque of each DOF's motor, N m (its gear; ctrl is in [-1, 1])."""
        return self.model.actuator_gear[self.layout.actuator_ids, 0].copy()

    def normalize(self, torque_nm: np.ndarray) -> np.ndarray:
        """Torques (..., n_dof) N m -> normalized torque commands (torque / limit)."""
        return np.asarray(torque_nm, float) / self.torque_limits_nm()

    # -- forward quantities of a state ------------------------------------------------
    def _set(self, q, qd=None) -> None:
        d = self.data
        d.qpos[self.layout.qpos_adr] = q
        d.qvel[self.layout.dof_adr] = 0.0 if qd is None else qd

    def bias_torque_nm(self, q: np.ndarray, qd: np.ndarray | None = None) -> np.ndarray:
        """Torques (..., n_dof) N m that cancel gravity and the velocity-product forces at
        state (q, qd) (``qfrc_bias``): holding the arm still at q (qd = None) takes
        exactly this; q, qd: (..., n_dof) rad, rad/s."""
        q = np.asarray(q, float)
        qd = None if qd is None else np.broadcast_to(np.asarray(qd, float), q.shape)
        out = np.empty(q.shape)
        for idx in np.ndindex(q.shape[:-1]):
            self._set(q[idx], None if qd is None else qd[idx])
            mujoco.mj_forward(self.model, self.data)
            out[idx] = self.data.qfrc_bias[self.layout.dof_adr]
        return out

    def gravity_torque_nm(self, q: np.ndarray) -> np.ndarray:
        """Torques (..., n_dof) N m that hold the arms still against gravity at q (rad)."""
        return self.bias_torque_nm(q)

    def mass_matrix(self, q: np.ndarray) -> np.ndarray:
        """Joint-space inertia M(q) (n_dof, n_dof), kg m^2, at one pose q (n_dof,) rad."""
        self._set(np.asarray(q, float))
        mujoco.mj_forward(self.model, self.data)
        full = np.zeros((self.model.nv, self.model.nv))
        mujoco.mj_fullM(self.model, self.data, full)
        adr = self.layout.dof_adr
        return full[np.ix_(adr, adr)]

    def inertia_range(self, n_poses: int = 200, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
        """Smallest and largest diagonal of M (each (n_dof,), kg m^2) over ``n_poses``
        random poses inside the joint ranges: what a joint's own inertia can be."""
        rng = np.random.default_rng(seed)
        lo, hi = self.layout.body.joint_ranges().T
        diag = np.array([np.diag(self.mass_matrix(rng.uniform(lo, hi)))
                         for _ in range(n_poses)])
        return diag.min(axis=0), diag.max(axis=0)

    # -- inverse dynamics ---------------------------------------------------------------
    def inverse_dynamics_nm(self, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray) -> np.ndarray:
        """Joint torques (..., n_dof) N m that give accelerations qdd at state (q, qd)
        (``mj_inverse``: M qdd + c - tau_passive; joint limits off); all (..., n_dof) in
        rad, rad/s, rad/s^2."""
        q, qd, qdd = np.broadcast_arrays(*(np.asarray(a, float) for a in (q, qd, qdd)))
        out = np.empty(q.shape)
        m, d = self.model, self.data
        flags = m.opt.disableflags
        m.opt.disableflags = flags | int(mujoco.mjtDisableBit.mjDSBL_CONSTRAINT)
        try:
            for idx in np.ndindex(q.shape[:-1]):
                self._set(q[idx], qd[idx])
                d.qacc[:] = 0.0
                d.qacc[self.layout.dof_adr] = qdd[idx]
                mujoco.mj_inverse(m, d)
                out[idx] = d.qfrc_inverse[self.layout.dof_adr]
        finally:
            m.opt.disableflags = flags
        return out

    def trajectory_torques_nm(self, angles: np.ndarray, dt: float = 0.02,
                              points: int = 4) -> np.ndarray:
        """The torque to hold during each step of a movement, (T-1, n_dof) N m.

        The angles (T, n_dof) rad, sampled every ``dt`` s, are interpolated by a cubic
        spline that starts and ends at rest (as the plant starts after a reset); step
        k's torque is the mean of the inverse dynamics over the step, at ``points``
        Gauss-Legendre nodes: the zero-order-hold torque that gives the step the
        spline's change of momentum to within O(dt^2). Held open loop through
        ``mj_step``, they reproduce the movement closely for a short horizon
        (``tests/test_dynamics.py`` states how closely); the true target of a torque
        inverse model.
        """
        from scipy.interpolate import CubicSpline  # here: scipy.interpolate takes ~0.25 s

        angles = np.asarray(angles, float)
        t = dt * np.arange(len(angles))
        spline = CubicSpline(t, angles, axis=0, bc_type="clamped")
        nodes, weights = np.polynomial.legendre.leggauss(points)
        ts = t[:-1, None] + 0.5 * dt * (1.0 + nodes)  # (T-1, points)
        tau = self.inverse_dynamics_nm(spline(ts), spline(ts, 1), spline(ts, 2))
        return np.einsum("kpn,p->kn", tau, 0.5 * weights)

    # -- feasibility ------------------------------------------------------------------
    def feasibility(self, angles: np.ndarray, dt: float = 0.02) -> dict[str, np.ndarray]:
        """What a movement asks of the motors: per DOF, each (n_dof,).

        From the held step torques of :meth:`trajectory_torques_nm` (the inverse dynamics
        of the movement's clamped cubic spline): ``peak_ratio``, ``p99_ratio`` and
        ``mean_ratio`` of |tau| / limit, ``mean_abs_nm`` (N m), ``over_limit_share``
        (share of steps whose torque exceeds the limit); the spline's
        ``peak_speed_rad_s`` and ``peak_accel_rad_s2`` (at the steps' Gauss nodes);
        ``work_j``: the motor's positive work, sum over steps of max(tau_k (q_k+1 - q_k),
        0), J (exact for a torque held over the step). ``feasible`` (a 0-d bool array):
        no step of any DOF over its limit.
        """
        from scipy.interpolate import CubicSpline  # here: scipy.interpolate takes ~0.25 s

        angles = np.asarray(angles, float)
        tau = self.trajectory_torques_nm(angles, dt)
        ratio = np.abs(tau) / self.torque_limits_nm()
        t = dt * np.arange(len(angles))
        spline = CubicSpline(t, angles, axis=0, bc_type="clamped")
        nodes, _ = np.polynomial.legendre.leggauss(4)
        ts = (t[:-1, None] + 0.5 * dt * (1.0 + nodes)).ravel()
        return {
            "peak_ratio": ratio.max(axis=0), "p99_ratio": np.percentile(ratio, 99, axis=0),
            "mean_ratio": ratio.mean(axis=0), "mean_abs_nm": np.abs(tau).mean(axis=0),
            "over_limit_share": (ratio > 1.0).mean(axis=0),
            "peak_speed_rad_s": np.abs(spline(ts, 1)).max(axis=0),
            "peak_accel_rad_s2": np.abs(spline(ts, 2)).max(axis=0),
            "work_j": np.maximum(tau * np.diff(angles, axis=0), 0.0).sum(axis=0),
            "feasible": np.asarray(bool((ratio <= 1.0).all())),
        }


class BatchArmState:
    """The plant side of :mod:`skinny_mj.controllers.torque_arm` for a lockstep
    :class:`skinny_mj.plant.adapters.BatchPlant` of the torque twin: each call returns the
    :class:`skinny_mj.controllers.torque_arm.ArmState` of the current step.

    M(q) is each robot's diagonal block of the batch's own ``M`` (gathered: the numbers
    ``mj_fullM`` gives);
    the bias ``qfrc_bias``; the gravity torque (``gravity=True`` only) from a scratch
    ``MjData`` at the same poses with zero velocity.

    Without ``sensing`` (the oracle's information): sensed angles are the true angles plus
    the position sensors' noise seen in joint space (joint signals: exactly the noise
    over the signals' scale; Cartesian signals: the damped pseudo-inverse of the signal
    Jacobian applied to the noise); velocities the plant's noise-free joint velocities;
    the model's quantities at the true state. With ``sensing`` (a
    :class:`skinny_mj.controllers.sensing.JointSensing` the loop keeps up to date): angles
    and velocities are its sensed ones, and M(q), the bias and the gravity are evaluated
    at that sensed state (a controller knows no other).

    ``nominal=True``: M(q), the bias, the gravity and the joint damping come from the
    nominal twin (a batch model of its own) instead of the plant's model: what a
    controller knows of a plant whose masses or joints were changed behind its back (a
    payload, link masses x 1.2, friction); on an unchanged plant the two are the same
    numbers. ``constant_mass`` (n, n) kg m^2: M is this one matrix at every state (a
    teacher scaled by one constant inertia).
    """

    def __init__(self, plant, gravity: bool = False, nominal: bool = False, sensing=None,
                 constant_mass: np.ndarray | None = None):
        self.plant, self.n_runs, self.sensing = plant, plant.n_runs, sensing
        self.model = load_batch_model(plant.body, plant.n_runs) if nominal \
            else plant.model
        m = self.model
        self._own = mujoco.MjData(m) if nominal or sensing is not None else None
        self.nv1 = m.nv // plant.n_runs
        self.nq1 = m.nq // plant.n_runs
        self.adr = np.asarray(plant.layout.dof_adr)
        self.qadr = np.asarray(plant.layout.qpos_adr)
        self.damping = m.dof_damping[self.adr].copy()
        friction = m.dof_frictionloss[self.adr].copy()
        self.friction = friction if np.any(friction > 0) else None
        self._mass_at, self._qm = _mass_index(m, plant.n_runs, self.adr)
        self._scratch = mujoco.MjData(m) if gravity else None
        self._constant = None if constant_mass is None else np.broadcast_to(
            np.asarray(constant_mass, float), (plant.n_runs, len(self.adr), len(self.adr)))
        lo, hi = plant.body.joint_ranges().T
        self._per_rad = 2.0 / (hi - lo)
        self._predictor = None  # MjData of predict()

    def sensed_angles(self, sensed: np.ndarray) -> np.ndarray:
        """(R, n) joint angles as the position sensors see them, rad."""
        plant = self.plant
        noise = np.asarray(sensed, float) - plant.true_signals()
        if plant.signals == "joint":
            noise_rad = noise / self._per_rad
        else:
            jac = plant.command_jacobian() / (np.asarray(plant.max_speed_rad_s) * plant.dt)
            noise_rad = jacobian_error(noise, np.zeros_like(noise), jac)
        return plant.joint_angles() + noise_rad

    def _state_into(self, d, zero_velocity: bool = False) -> None:
        """The plant's state into ``d``, its arms' angles and velocities the sensed ones."""
        d.qpos[:] = self.plant.data.qpos
        d.qvel[:] = 0.0 if zero_velocity else self.plant.data.qvel
        if self.sensing is not None:
            d.qpos.reshape(self.n_runs, self.nq1)[:, self.qadr] = self.sensing.q
            if not zero_velocity:
                d.qvel.reshape(self.n_runs, self.nv1)[:, self.adr] = self.sensing.qd

    def _data(self):
        """The plant's MjData, or the chosen model's own at the (sensed) state."""
        if self._own is None:
            return self.plant.data
        d = self._own
        self._state_into(d)
        mujoco.mj_fwdPosition(self.model, d)
        mujoco.mj_fwdVelocity(self.model, d)
        return d

    def mass(self, d=None) -> np.ndarray:
        """(R, n, n) each robot's M(q) of the current state, kg m^2."""
        if self._constant is not None:
            return self._constant
        d = self._data() if d is None else d
        self._qm[:-1] = d.M  # the last entry stays 0: the structural zeros
        return self._qm[self._mass_at]

    def gravity(self) -> np.ndarray:
        """(R, n) g(q) of the current (sensed) poses, N m."""
        m, sd = self.model, self._scratch
        self._state_into(sd, zero_velocity=True)
        mujoco.mj_fwdPosition(m, sd)
        mujoco.mj_fwdVelocity(m, sd)
        return sd.qfrc_bias.reshape(self.n_runs, -1)[:, self.adr].copy()

    def predict(self, q: np.ndarray, qd: np.ndarray, tau_nm: np.ndarray
                ) -> tuple[np.ndarray, np.ndarray]:
        """The model's prediction of one control step: from the arms at (R, n) angles
        ``q`` (rad) and velocities ``qd`` (rad/s), under the torque ``tau_nm`` (R, n) N m
        held over the step, the angles and velocities (R, n) at its end (the model
        stepped as the plant steps, its joint limits included)."""
        m, plant = self.model, self.plant
        d = self._predictor
        if d is None:
            d = self._predictor = mujoco.MjData(m)
            self._substeps = int(round(plant.dt / m.opt.timestep))
        d.qpos[:] = plant.data.qpos
        d.qvel[:] = plant.data.qvel
        d.qpos.reshape(self.n_runs, self.nq1)[:, self.qadr] = q
        d.qvel.reshape(self.n_runs, self.nv1)[:, self.adr] = qd
        d.ctrl[:] = 0.0
        d.qfrc_applied[:] = 0.0
        d.qfrc_applied.reshape(self.n_runs, self.nv1)[:, self.adr] = tau_nm
        mujoco.mj_step(m, d, self._substeps)
        return (d.qpos.reshape(self.n_runs, self.nq1)[:, self.qadr].copy(),
                d.qvel.reshape(self.n_runs, self.nv1)[:, self.adr].copy())

    def __call__(self, sensed: np.ndarray):
        plant, d = self.plant, self._data()
        bias = plant.bias_torque_nm() if d is plant.data else \
            d.qfrc_bias.reshape(self.n_runs, -1)[:, self.adr].copy()
        if self.sensing is None:
            q, qd = self.sensed_angles(sensed), plant.joint_velocities()
        else:
            q, qd = self.sensing.q, self.sensing.qd
        return ArmState(q=q, qd=qd, mass=self.mass(d), bias=bias,
                        gravity=None if self._scratch is None else self.gravity(),
                        damping=self.damping, friction=self.friction)


def _mass_index(model, n_runs: int, adr: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Where each robot's M(q) entries sit in ``MjData.M`` (its size for a structural
    zero), as (R, n, n), and a buffer of that size + 1 zeros: M(q) is then one gather,
    the same numbers as ``mj_fullM`` (which copies ``M`` into the dense matrix) without
    the dense (R n)^2 matrix of the whole batch."""
    d = mujoco.MjData(model)
    d.M[:] = np.arange(1, d.M.size + 1)
    full = np.zeros((model.nv, model.nv))
    mujoco.mj_fullM(model, d, full)
    n1 = model.nv // n_runs
    at = np.stack([full[np.ix_(r * n1 + adr, r * n1 + adr)] for r in range(n_runs)])
    at = np.where(at > 0, at - 1, d.M.size).astype(np.intp)
    return at, np.zeros(d.M.size + 1)


def feasibility_lines(figures: dict[str, np.ndarray], names: list[str]) -> list[str]:
    """:meth:`Dynamics.feasibility` as text: one line per DOF, then the totals."""
    lines = [f"  {'DOF':24} {'peak':>6} {'p99':>6} {'mean':>6} {'>limit':>7} "
             f"{'mean|τ|':>8} {'speed':>7} {'accel':>8} {'work':>7}",
             f"  {'':24} {'|τ|/limit':>20} {'steps':>7} {'N m':>8} {'rad/s':>7} "
             f"{'rad/s²':>8} {'J':>7}"]
    for i, name in enumerate(names):
        f = {k: v[i] for k, v in figures.items() if k != "feasible"}
        lines.append(f"  {name:24} {f['peak_ratio']:6.2f} {f['p99_ratio']:6.2f} "
                     f"{f['mean_ratio']:6.2f} {100 * f['over_limit_share']:6.1f}% "
                     f"{f['mean_abs_nm']:8.2f} {f['peak_speed_rad_s']:7.2f} "
                     f"{f['peak_accel_rad_s2']:8.1f} {f['work_j']:7.1f}")
    verdict = "feasible" if bool(figures["feasible"]) else \
        "NOT feasible: some steps need more torque than the motors have"
    lines.append(f"  all DOFs: mean |τ| {figures['mean_abs_nm'].mean():.2f} N m, "
                 f"peak |τ|/limit {figures['peak_ratio'].max():.2f}, "
                 f"motor work {figures['work_j'].sum():.1f} J -> {verdict}")
    return lines
