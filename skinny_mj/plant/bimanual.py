"""Paper B's plant: a forced leading arm and an ESN-driven lagging arm.

Paper B §3: "the control system controls only the movement of the lagging arm; the
movement of the leading arm is forced. The input to the system is the current states
(the arms' joint angles), while the output is the motor command to the lagging arm"
(Fig. 2: 4 input nodes, 100 internal nodes, 2 output nodes). Eqs. (1)-(3)::

    v(t+1) = plant(u_inverse(t) + K u_feedback(t), u_leading_arm(t))
    x(t+1) = f(W_in v(t+1) + W x(t))                       (no output feedback)
    u_inverse(t+1) = f_out(W_out [v(t+1); x(t+1)])

so the inverse model sees no desired position ("the desired next state is implicit in
the state of the leading arm": ``TrainConfig(inputs="sensed")``); the lagging arm's
desired trajectory is used only by the feedback controller and, through it, by FEL.
The training itself is the one FEL loop (:func:`skinny_mj.controllers.fel.train`) on this plant;
the movements are :mod:`skinny_mj.trajectories.patterns`.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from skinny_mj.plant.adapters import BatchPlant
from skinny_mj.plant.body import BodyLike, body_of
from skinny_mj.plant.ideal import ideal_command


def arm_dofs(which: BodyLike, side: str) -> np.ndarray:
    """Indices of ``side``'s DOFs in the body's :attr:`~skinny_mj.plant.body.Body.dof_names`
    order."""
    return np.array([i for i, n in enumerate(body_of(which).dof_names)
                     if n.startswith(side + "_")])


def arm_signals(which: BodyLike, signals: str, side: str) -> np.ndarray:
    """Indices of ``side``'s position signals in the body's
    :meth:`~skinny_mj.plant.body.Body.signal_names` order."""
    return np.array([i for i, n in enumerate(body_of(which).signal_names(signals))
                     if n.startswith(side + "_")])


class BimanualPlant:
    """Plant-protocol view of a :class:`BatchPlant` (R runs) whose controlled DOFs are
    the lagging arm's; the leading arm follows its part of the movement exactly (the
    ideal command each step).

    Signals are both arms' (``n_signals`` = the body's), ``n_dof`` = one arm's;
    ``command_jacobian`` (R, n_sig, n_dof) has zero rows for the leading arm's signals,
    so a Jacobian feedback controller corrects the lagging arm's error only.

    Parameters
    ----------
    body, signals : the body and its position signals.
    trajectory : the whole movement (both arms, rad); the leader's part is enforced.
    leading : the forced arm, "right" or "left".
    max_speed_rad_s : (n_dof,) full-scale speeds of the body, rad/s.
    n_runs, seeds, sensor_noise : as :class:`BatchPlant`.
    """

    def __init__(self, body: BodyLike, signals: str, trajectory, leading: str,
                 max_speed_rad_s: np.ndarray, n_runs: int = 1, seeds: Sequence[int] | None = None,
                 sensor_noise: float = 0.01):
        if leading not in ("right", "left"):
            raise ValueError(f"leading arm must be 'right' or 'left', got {leading!r}")
        self.angles = np.asarray(trajectory.angles, float)
        self.lead = arm_dofs(body, leading)
        self.lag = arm_dofs(body, "left" if leading == "right" else "right")
        self.whole = BatchPlant(body, signals, trajectory, n_runs=n_runs, seeds=seeds,
                                sensor_noise=sensor_noise, max_speed_rad_s=max_speed_rad_s)
        self.body = self.whole.body
        self.n_runs, self.n_dof, self.n_signals = n_runs, len(self.lag), self.whole.n_signals
        self.dt = self.whole.dt
        self.full_max_speed_rad_s = np.asarray(self.whole.max_speed_rad_s, float)
        self.max_speed_rad_s = self.full_max_speed_rad_s[self.lag]
        self._t = 0

    def reset(self) -> np.ndarray:
        self._t = 0
        return self.whole.reset()

    def leader_command(self) -> np.ndarray:
        """Ideal command (R, n_arm) that puts the leading arm on its next pose."""
        target = self.angles[min(self._t + 1, len(self.angles) - 1), self.lead]
        q = self.whole.joint_angles()[:, self.lead]
        return ideal_command(target, q, self.full_max_speed_rad_s[self.lead], self.dt)

    def step(self, command: np.ndarray) -> np.ndarray:
        full = np.empty((self.n_runs, len(self.lead) + len(self.lag)))
        full[:, self.lead] = self.leader_command()
        full[:, self.lag] = np.asarray(command, float).reshape(self.n_runs, self.n_dof)
        self._t += 1
        return self.whole.step(full)

    def true_signals(self) -> np.ndarray:
        return self.whole.true_signals()

    def joint_angles(self) -> np.ndarray:
        """The whole body's joint angles (R, dof) rad (recordings show both arms)."""
        return self.whole.joint_angles()

    def command_jacobian(self) -> np.ndarray:
        return self.whole.command_jacobian()[:, :, self.lag]


def phase_lag_deg(actual: np.ndarray, desired: np.ndarray, period_steps: float) -> float:
    """Timing error of a rhythmic signal: the shift (in degrees of its period) that best
    aligns ``actual`` (T,) with ``desired`` (T,); positive = actual lags behind.

    Searched within ± half a period by cross-correlation of the mean-removed signals.
    """
    a, d = actual - actual.mean(), desired - desired.mean()
    half = max(1, int(period_steps // 2))
    shifts = np.arange(-half, half + 1)
    n = len(a)
    scores = [np.dot(a[max(k, 0):n + min(k, 0)], d[max(-k, 0):n - max(k, 0)])
              / max(1, n - abs(k)) for k in shifts]
    return float(360.0 * shifts[int(np.argmax(scores))] / period_steps)
