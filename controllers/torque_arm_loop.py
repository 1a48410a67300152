"""The rollout hook of :mod:`skinny_mj.controllers.torque_arm`'s laws (a
:class:`skinny_mj.controllers.torque_fel.TorqueLoop` whose motor error is one of those laws).

For a textbook controller alone (``method="none"``, K = 1) the motor error is the law's
whole torque / limit; for feedback-error learning (law ``"fel"``) it is the
inertia-scaled PD's feedback torque / limit, FEL's error signal. The ESN's inputs are
:class:`TorqueLoop`'s: [d(t+1); s(t)] (desired next and sensed position signals) and
[qd_d(t+1); qd(t)] / v_max (desired next and sensed joint velocities), plus its bias.
The feedback part of every step is kept (``feedback_nm``) for the feedback share
|u_fb| / |u| of a cycle.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from skinny_mj.controllers.torque_arm import ArmGains, ArmState, DesiredMotion, arm_torque
from skinny_mj.controllers.torque_fel import TorqueLoop


@dataclass
class ArmLoop(TorqueLoop):
    """:class:`TorqueLoop` plus a law of :mod:`skinny_mj.controllers.torque_arm`.

    law : one of :data:`skinny_mj.controllers.torque_arm.LAWS`. gains : its pole placement.
    motion : the cycle's :class:`DesiredMotion`. state_of : plant side,
    ``state_of(sensed) -> ArmState`` of the current step (R arms). dt : control step, s.
    """

    law: str = "ct"
    gains: ArmGains = field(default_factory=lambda: ArmGains(10.0))
    motion: DesiredMotion | None = None
    state_of: Callable[[np.ndarray], ArmState] | None = None
    dt: float = 0.02
    #: steps by which the sensed state lags the arm: the law compares it with the desired
    #: motion of step t - lag (0: of step t)
    lag: int = 0
    #: (T, R, n) the feedback torque of each step of the last cycle, N m
    feedback_nm: np.ndarray = field(default=None, repr=False)  # type: ignore[assignment]

    def begin(self, plant, n_steps: int) -> None:
        super().begin(plant, n_steps)
        if self.feedback_nm is None or self.feedback_nm.shape != self.velocity_rad_s.shape:
            self.feedback_nm = np.zeros(self.velocity_rad_s.shape)  # reused, as TorqueLoop's

    def u_error(self, t: int, desired: np.ndarray, sensed: np.ndarray, plant) -> np.ndarray:
        state = self.state_of(sensed)
        step = min(max(t - self.lag, 0), len(self.motion.q_mid) - 1)
        total, fb = arm_torque(self.law, state, self.motion, step, self.dt, self.gains)
        self.feedback_nm[t] = fb
        return total / self._limit

    def feedback_share(self, commands: np.ndarray) -> np.ndarray:
        """(R,) mean |u_fb| / mean |u| over the last cycle, for the commands (R, T-1, n)
        as sent (normalized)."""
        fb = np.abs(np.swapaxes(self.feedback_nm[:-1], 0, 1) / self._limit).mean(axis=(1, 2))
        return fb / np.maximum(np.abs(commands).mean(axis=(1, 2)), 1e-12)
