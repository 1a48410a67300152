"""Torque feedback: PD and computed-torque control in normalized torque units.

A torque command is normalized by each motor's peak torque: u = tau / tau_max, so
u in [-1, 1] is what a torque plant takes (the torque twin's ctrl; its motors' gear is
tau_max). Pure NumPy; the plant side supplies the torque limits, the joint inertias
and, for computed torque, the bias or inverse-dynamics torque as arrays.

PD:               tau = Kp e + Kd e_dot
computed torque:  tau = tau_ff + Kp e + Kd e_dot

with e = q_d - q (rad) and e_dot = qd_d - qd (rad/s); tau_ff (N m) is what the caller
knows of the dynamics: the bias torque ``qfrc_bias`` of the current state (gravity
compensation: PD then only has to accelerate the arm), or the inverse dynamics
``mj_inverse`` of the desired state (q_d, qd_d, qdd_d), the classical computed
torque with the mass matrix folded into the gains.

Gain scaling (:meth:`TorqueGains.from_limits`): Kp_i = fraction x tau_max_i / error_rad,
so an error of ``error_rad`` (0.1 rad) asks for ``fraction`` (50 %) of joint i's limit;
Kd_i = 2 zeta sqrt(Kp_i I_i), critically damped (zeta = 1) about the joint's own
inertia I_i. The loop is sampled: the command is held for a control step dt (20 ms),
and a held PD on an inertia is stable only while omega dt < 1 (omega = sqrt(Kp / I),
zeta = 1; the poles of the held double integrator), so Kp_i is capped at
I_i (omega_dt_max / dt)^2 (omega_dt_max = 0.5 by default: 25 rad/s at 20 ms). Pass the
smallest inertia each joint takes over its range (the worst case for the cap): a
light joint (Skinny's shoulder rotation, ~0.006 kg m^2) is capped far below the
fraction of its limit, a heavy one (shoulder abduction, ~0.2-0.5 kg m^2) is not.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from skinny_mj.controllers.feedback import check_error_mode, jacobian_error


@dataclass(frozen=True)
class TorqueGains:
    """Per-DOF gains and limits, (n_dof,) each.

    kp_nm_rad : proportional gain, N m/rad. kd_nm_s_rad : derivative gain, N m s/rad.
    torque_limit_nm : the peak torque that a normalized command of 1 means, N m.
    """

    kp_nm_rad: tuple[float, ...]
    kd_nm_s_rad: tuple[float, ...]
    torque_limit_nm: tuple[float, ...]

    def __post_init__(self) -> None:
        n = len(self.torque_limit_nm)
        if not (len(self.kp_nm_rad) == len(self.kd_nm_s_rad) == n and n > 0):
            raise ValueError("kp, kd and torque limits need one value per DOF each")
        if min(self.torque_limit_nm) <= 0 or min(self.kp_nm_rad) < 0 or \
                min(self.kd_nm_s_rad) < 0:
            raise ValueError("torque limits must be > 0 and gains >= 0")

    @classmethod
    def from_limits(
        cls,
        torque_limit_nm: np.ndarray,
        inertia_kg_m2: np.ndarray,
        *,
        error_rad: float = 0.1,
        fraction: float = 0.5,
        zeta: float = 1.0,
        dt: float | None = 0.02,
        omega_dt_max: float = 0.5,
    ) -> TorqueGains:
        """Gains scaled to the limits (see the module docstring).

        Parameters
        ----------
        torque_limit_nm : (n_dof,) peak torques, N m.
        inertia_kg_m2 : (n_dof,) each joint's own inertia (the diagonal of M), kg m^2;
            the smallest over the joint's range for a safe cap.
        error_rad, fraction : an error of ``error_rad`` asks for ``fraction`` of the
            limit (before the cap).
        zeta : damping ratio of Kd (1: critical).
        dt : control step the command is held for, s; None = no cap (continuous).
        omega_dt_max : the cap, omega x dt.
        """
        limit = np.asarray(torque_limit_nm, float)
        inertia = np.broadcast_to(np.asarray(inertia_kg_m2, float), limit.shape)
        if error_rad <= 0 or fraction <= 0 or zeta < 0 or np.any(inertia <= 0):
            raise ValueError("need error_rad > 0, fraction > 0, zeta >= 0, inertia > 0")
        kp = fraction * limit / error_rad
        if dt is not None:
            if dt <= 0 or omega_dt_max <= 0:
                raise ValueError("need dt > 0 and omega_dt_max > 0")
            kp = np.minimum(kp, inertia * (omega_dt_max / dt) ** 2)
        kd = 2.0 * zeta * np.sqrt(kp * inertia)
        return cls(tuple(kp.tolist()), tuple(kd.tolist()), tuple(limit.tolist()))

    @property
    def kp(self) -> np.ndarray:
        return np.asarray(self.kp_nm_rad)

    @property
    def kd(self) -> np.ndarray:
        return np.asarray(self.kd_nm_s_rad)

    @property
    def limit(self) -> np.ndarray:
        return np.asarray(self.torque_limit_nm)

    def error_fraction(self, error_rad: float = 0.1) -> np.ndarray:
        """(n_dof,) share of each limit that a position error of ``error_rad`` asks for."""
        return self.kp * error_rad / self.limit


def pd_torque(q_error_rad: np.ndarray, qd_error_rad_s: np.ndarray, gains: TorqueGains,
              clip: bool = True) -> np.ndarray:
    """PD command (..., n_dof), normalized torque in [-1, 1] (``clip=False``: not clipped).

    q_error_rad : (..., n_dof) q_d - q, rad. qd_error_rad_s : (..., n_dof) qd_d - qd, rad/s.
    """
    u = (gains.kp * q_error_rad + gains.kd * qd_error_rad_s) / gains.limit
    return np.clip(u, -1.0, 1.0) if clip else u


def computed_torque(q_error_rad: np.ndarray, qd_error_rad_s: np.ndarray,
                    bias_nm: np.ndarray, gains: TorqueGains, clip: bool = True) -> np.ndarray:
    """Computed-torque command (..., n_dof): (bias + Kp e + Kd e_dot) / limit, clipped to
    [-1, 1]; ``bias_nm`` (..., n_dof) N m from the plant side (``qfrc_bias`` of the
    current state, or ``mj_inverse`` of the desired one)."""
    u = pd_torque(q_error_rad, qd_error_rad_s, gains, clip=False)
    u = u + np.asarray(bias_nm, float) / gains.limit
    return np.clip(u, -1.0, 1.0) if clip else u


@dataclass(frozen=True)
class TorqueFeedbackController:
    """Position errors -> motor errors in normalized torque, for a torque plant.

    The torque counterpart of :class:`skinny_mj.controllers.feedback.FeedbackController`, with the
    same ``u_error(desired, sensed, plant)``, so feedback-error learning can use either.
    The joint-space position error comes from the signals as there: ``mode`` "joint"
    divides by ``signal_per_rad`` (joint-angle signals), "jacobian" solves the plant's
    signal Jacobian (damped least squares), which it gets per radian as
    ``command_jacobian() / (max_speed_rad_s * dt)``. The velocity term needs the plant's
    ``joint_velocities()`` (R, n_dof) rad/s.

    gains : :class:`TorqueGains` (their limits define the normalization).
    damping : lambda of the damped least squares, in signal per radian.
    """

    gains: TorqueGains
    mode: str = "jacobian"
    damping: float = 1e-4
    signal_per_rad: tuple[float, ...] | None = None

    def __post_init__(self) -> None:
        check_error_mode(self.mode, self.signal_per_rad, self.damping)

    def joint_error_rad(self, desired: np.ndarray, sensed: np.ndarray, plant) -> np.ndarray:
        """(R, n_dof) joint-space position error, rad, of desired (n_sig,) or (R, n_sig)
        and sensed (R, n_sig) signals."""
        if self.mode == "joint":
            return (np.asarray(desired) - sensed) / np.asarray(self.signal_per_rad)
        per_command = np.asarray(plant.max_speed_rad_s, float) * plant.dt
        jac_rad = plant.command_jacobian() / per_command
        return jacobian_error(desired, sensed, jac_rad, self.damping)

    def u_error(
        self,
        desired: np.ndarray,
        sensed: np.ndarray,
        plant,
        *,
        desired_velocity_rad_s: np.ndarray | None = None,
        bias_nm: np.ndarray | None = None,
        velocity_rad_s: np.ndarray | None = None,
    ) -> np.ndarray:
        """Motor error (R, n_dof) in normalized torque (torque / limit), not clipped
        (as the velocity controller's; the learner clips the command it sends).

        desired (n_sig,) or (R, n_sig), sensed (R, n_sig): position signals.
        desired_velocity_rad_s : (n_dof,) or (R, n_dof) qd_d; None = 0 (the D term
            then damps the joint velocity).
        bias_nm : (R, n_dof) N m; given, the result is the computed-torque command
            (for running the controller alone); FEL's motor error is the PD part
            (None): the inverse model is to learn the rest.
        velocity_rad_s : (R, n_dof) the sensed joint velocities; None: the plant's
            ``joint_velocities()``.
        """
        q_err = self.joint_error_rad(desired, sensed, plant)
        qd = np.asarray(plant.joint_velocities() if velocity_rad_s is None
                        else velocity_rad_s, float)
        qd_err = -qd if desired_velocity_rad_s is None else desired_velocity_rad_s - qd
        if bias_nm is None:
            return pd_torque(q_err, qd_err, self.gains, clip=False)
        return computed_torque(q_err, qd_err, bias_nm, self.gains, clip=False)

    def command(self, desired, sensed, plant, **kw) -> np.ndarray:
        """:meth:`u_error` clipped to [-1, 1]: the command of the controller alone."""
        return np.clip(self.u_error(desired, sensed, plant, **kw), -1.0, 1.0)
