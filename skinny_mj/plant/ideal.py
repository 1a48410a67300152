"""The analytic ideal controller and the movement's speed scale. Pure NumPy.

The plant moves a joint by ``command * max_speed_rad_s * dt`` per control step, so
the exact inverse is ``command = (q_desired(t+1) - q(t)) / (max_speed_rad_s * dt)``.
Applied to the desired angles themselves it gives the "true" motor commands the
motor NRMSE is measured against.
"""

from __future__ import annotations

import numpy as np

from skinny_mj.plant.body import BodyLike, body_of

# Full scale of a DOF that (almost) does not move in the movement, rad/s: keeps a
# still joint controllable (0.5 rad/s = 0.01 rad per 20 ms step at command 1).
MIN_MAX_SPEED_RAD_S = 0.5


def max_speeds(
    angles: np.ndarray,
    dt: float,
    speed_factor: float = 2.0,
    floor_rad_s: float = MIN_MAX_SPEED_RAD_S,
) -> np.ndarray:
    """Full-scale speed per DOF: ``speed_factor`` x the fastest |dq/dt| in the movement.

    Parameters
    ----------
    angles : (T, n_dof) joint angles, rad, T >= 2.
    dt : sample interval, s.
    speed_factor : multiple of the fastest speed (the thesis uses 1.5-2; papers D/E: 2).
    floor_rad_s : lower bound for DOFs that barely move.

    Returns
    -------
    (n_dof,) max speed, rad/s.
    """
    angles = np.asarray(angles, dtype=float)
    fastest = np.abs(np.diff(angles, axis=0)).max(axis=0) / dt
    return np.maximum(speed_factor * fastest, floor_rad_s)


def ideal_command(
    q_next_desired: np.ndarray, q: np.ndarray, max_speed_rad_s: np.ndarray, dt: float
) -> np.ndarray:
    """Command (..., n_dof) in [-1, 1] that moves q (..., n_dof) rad to the desired next
    angles (..., n_dof) rad in one control step of ``dt`` s."""
    return np.clip((q_next_desired - q) / (np.asarray(max_speed_rad_s) * dt), -1.0, 1.0)


def true_commands(angles: np.ndarray, max_speed_rad_s: np.ndarray, dt: float) -> np.ndarray:
    """The "true" motor commands of a movement: (T-1, n_dof) in [-1, 1] for angles
    (T, n_dof) rad; step t carries the arm from angles[t] to angles[t+1]."""
    angles = np.asarray(angles, dtype=float)
    return ideal_command(angles[1:], angles[:-1], max_speed_rad_s, dt)


class IdealController:
    """Closed-loop exact inverse: reads the true joint angles, commands the next pose.

    Parameters
    ----------
    angles : (T, n_dof) desired joint angles, rad.
    max_speed_rad_s : (n_dof,) the plant's full-scale speed, rad/s.
    dt : control step, s.
    """

    def __init__(self, angles: np.ndarray, max_speed_rad_s: np.ndarray, dt: float):
        self.angles = np.asarray(angles, dtype=float)
        self.max_speed_rad_s = np.asarray(max_speed_rad_s, dtype=float)
        self.dt = float(dt)

    def command(self, step: int, q: np.ndarray) -> np.ndarray:
        """Command (..., n_dof) at control step ``step`` from the current angles q, rad."""
        target = self.angles[min(step + 1, len(self.angles) - 1)]
        return ideal_command(target, q, self.max_speed_rad_s, self.dt)


def one_step_positions(trajectory, which: BodyLike, signals: str,
                       max_speed_rad_s: np.ndarray):
    """The true-target architecture's training position error: each teacher-forced
    command applied for one step from the desired pose q_d(t), through the body's
    kinematics (the servo follows a command to < 1 %; joints clip at their ranges)."""
    skinny, dt = body_of(which), trajectory.dt
    lo, hi = skinny.joint_ranges().T
    q_from = trajectory.angles[:-1]

    def one_step(_positions: np.ndarray, commands: np.ndarray) -> np.ndarray:
        q_next = np.clip(q_from + np.clip(commands, -1, 1) * max_speed_rad_s * dt, lo, hi)
        return skinny.position_signals(q_next, signals)

    return one_step
