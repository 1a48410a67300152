"""Textbook torque control of the arm at 50 Hz, in the arm's own (inertia-scaled)
coordinates: computed torque, inverse-dynamics feed-forward + low-gain PD, PD + gravity
compensation, and the same PD as feedback-error learning's teacher.

Every controller here is a law of one shape, fed each control step with arrays from the
plant side (:class:`ArmState`): the mass matrix M(q), the bias torque ``qfrc_bias``
c(q, qd) (gravity, Coriolis, centrifugal), the gravity torque g(q), the joint damping b,
and the sensed joint angles and velocities.

    tau = M(q) (a_ff + omega^2 e + 2 zeta omega e_dot) + tau_ff

- computed torque (``"ct"``):    a_ff = qdd_d,  tau_ff = c(q, qd) + b qd
- ID feed-forward + low-gain PD (``"id-pd"``): a_ff = 0, tau_ff = the inverse dynamics
  of the desired motion over the step (``mj_inverse``; a table computed before the run)
- PD + gravity compensation (``"pd-g"``): a_ff = 0, tau_ff = g(q)
- FEL's teacher (``"fel"``; ``"fel-const"`` the same with one constant M, handed in as
  the state's ``mass``): a_ff = 0, tau_ff = 0: the feedback torque of the
  inertia-scaled PD alone, the inverse-reference-model form of feedback-error learning
  (Gomi & Kawato 1993): it is the torque that would give the joint the error
  dynamics e_dd + 2 zeta omega e_dot + omega^2 e = 0 in the feedback-linearized
  coordinates, which are strictly positive real for any omega > 0, zeta > 0
  (Nakanishi & Schaal 2004: K_D^2 > K_P holds for zeta > 1/2).

Pole placement: in the coordinates where the arm is a unit double integrator
(M(q)^-1 applied), omega (rad/s) and zeta place both poles of every joint's error
dynamics alike; M(q) maps them back to torques. The torque is held over the 20 ms
control step (zero-order hold), so the law aims at the middle of the step: the error is
that between the desired state at t + dt/2 and the sensed state predicted there
(q + qd dt/2), and qdd_d is the desired acceleration averaged over the held step
(qd_d(t+1) - qd_d(t)) / dt. The command is tau / limit, clipped to [-1, 1].

Where the signals come from (the plant side says so too): positions are the joint angles
seen through the position sensors, noise included (a plant with Cartesian sensors maps
its sensor noise to the joints by the damped pseudo-inverse of its signal Jacobian);
velocities are the joints' own velocity sensors (noise-free, as a tachometer).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: The laws (see the module docstring).
LAWS = ("ct", "id-pd", "pd-g", "fel", "fel-const")


@dataclass(frozen=True)
class ArmState:
    """One control step's view of R arms, from the plant side.

    q, qd : (R, n) sensed joint angles (rad, with sensor noise) and velocities (rad/s).
    mass : (R, n, n) M(q), kg m^2. bias : (R, n) c(q, qd), N m. gravity : (R, n) g(q),
    N m, or None when the law does not need it. damping : (n,) joint damping, N m s/rad.
    friction : (n,) Coulomb friction the model knows, N m (None: none); computed torque
    adds friction x sign(qd_d).
    """

    q: np.ndarray
    qd: np.ndarray
    mass: np.ndarray
    bias: np.ndarray
    gravity: np.ndarray | None
    damping: np.ndarray
    friction: np.ndarray | None = None


@dataclass(frozen=True)
class DesiredMotion:
    """The desired motion of a cycle of T states, sampled for a held-torque loop.

    q_mid, qd_mid : (T-1, n) desired angle (rad) and velocity (rad/s) at the middle of
    each step; qdd_step : (T-1, n) the desired acceleration averaged over each step
    (rad/s^2); tau_id : (T-1, n) the inverse dynamics of the desired motion held over
    each step (N m), or None.
    """

    q_mid: np.ndarray
    qd_mid: np.ndarray
    qdd_step: np.ndarray
    tau_id: np.ndarray | None = None

    @classmethod
    def from_samples(cls, q: np.ndarray, qd: np.ndarray, dt: float,
                     q_mid: np.ndarray, qd_mid: np.ndarray,
                     tau_id: np.ndarray | None = None) -> DesiredMotion:
        """From the states (T, n) and mid-step samples (T-1, n) of a smooth motion."""
        qd = np.asarray(qd, float)
        return cls(np.asarray(q_mid, float), np.asarray(qd_mid, float),
                   np.diff(qd, axis=0) / dt, None if tau_id is None else np.asarray(tau_id))


@dataclass(frozen=True)
class ArmGains:
    """Pole placement in the inertia-scaled coordinates: every joint's error poles at
    natural frequency ``omega`` (rad/s) with damping ratio ``zeta``."""

    omega: float
    zeta: float = 1.0

    def __post_init__(self) -> None:
        if not (np.isfinite(self.omega) and self.omega >= 0 and np.isfinite(self.zeta)
                and self.zeta >= 0):
            raise ValueError(f"need omega >= 0 and zeta >= 0, got {self.omega}, {self.zeta}")

    @property
    def kp(self) -> float:
        """omega^2, 1/s^2 (per unit inertia)."""
        return self.omega ** 2

    @property
    def kd(self) -> float:
        """2 zeta omega, 1/s (per unit inertia)."""
        return 2.0 * self.zeta * self.omega


def mid_step_error(state: ArmState, motion: DesiredMotion, t: int,
                   dt: float) -> tuple[np.ndarray, np.ndarray]:
    """(e, e_dot) (R, n): desired minus the sensed state predicted to the step's middle."""
    e = motion.q_mid[t] - (state.q + 0.5 * dt * state.qd)
    return e, motion.qd_mid[t] - state.qd


def mass_times(mass: np.ndarray, acc: np.ndarray) -> np.ndarray:
    """(R, n) M(q) a, N m, for mass (R, n, n) kg m^2 and acc (R, n) or (n,) rad/s^2.

    The products M_ij a_j in a C-contiguous (j, R, i) array, summed over its first axis:
    j = 0 .. n-1 in order, the same bits for every batch size R and memory layout of
    ``mass``. np.matmul hands a stack whose matrices are contiguous to BLAS (a one-run
    batch) and sums any other in its own loop, which rounds otherwise, so a lockstep
    run differed from the same run alone.
    """
    a = np.asarray(acc).T  # (n, R) or (n,)
    a = a[:, :, None] if a.ndim == 2 else a[:, None, None]
    products = np.empty((mass.shape[2], mass.shape[0], mass.shape[1]))
    np.multiply(mass.transpose(2, 0, 1), a, out=products)
    return np.add.reduce(products, axis=0)


def feedback_torque(state: ArmState, e: np.ndarray, e_dot: np.ndarray,
                    gains: ArmGains) -> np.ndarray:
    """(R, n) M(q) (omega^2 e + 2 zeta omega e_dot), N m."""
    return mass_times(state.mass, gains.kp * e + gains.kd * e_dot)


def arm_torque(law: str, state: ArmState, motion: DesiredMotion, t: int, dt: float,
               gains: ArmGains) -> tuple[np.ndarray, np.ndarray]:
    """(total, feedback) torque (R, n) N m of ``law`` at step t (module docstring);
    feedback is the inertia-scaled PD part alone (FEL's error signal)."""
    if law not in LAWS:
        raise ValueError(f"law must be one of {LAWS}, got {law!r}")
    e, e_dot = mid_step_error(state, motion, t, dt)
    fb = feedback_torque(state, e, e_dot, gains)
    if law == "ct":
        ff = mass_times(state.mass, motion.qdd_step[t]) + state.bias \
            + state.damping * state.qd
        if state.friction is not None:
            ff = ff + state.friction * np.sign(motion.qd_mid[t])
    elif law == "id-pd":
        if motion.tau_id is None:
            raise ValueError("the ID feed-forward law needs the motion's tau_id")
        ff = np.broadcast_to(motion.tau_id[t], fb.shape)
    elif law == "pd-g":
        if state.gravity is None:
            raise ValueError("PD + gravity compensation needs the gravity torque")
        ff = state.gravity
    else:
        ff = 0.0
    return fb + ff, fb
