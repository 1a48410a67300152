"""Adaptive computed torque: computed torque on a model whose parameters are estimated
online by recursive least squares on the torque residual.

The plant side hands a regressor (:class:`skinny_mj.plant.regressor.InertialRegressor`):
``regressor(q, qd, qdd) -> (tau_nom, Y)`` with the model's torque
tau = tau_nom + Y theta, exact in theta (payload, link mass scales, friction). Each step:

1. estimate: from the sensed angles q(t-2k), q(t-k), q(t) (``span`` k steps) the
   central differences at c = t-k, qd_c = (q(t) - q(t-2k)) / 2k dt and qdd_c = (q(t) -
   2 q(t-k) + q(t-2k)) / (k dt)^2 (a triangle-weighted mean of the acceleration over the
   2k steps), against the same triangle's mean of the 2k held torques (weights
   k - |j + 1/2|, j = -k .. k-1); the residual tau - tau_nom(q(c), qd_c, qdd_c) =
   Y theta + noise updates theta (:class:`ParameterRLS`, each run its own). A wide
   span keeps the encoders' noise out of qdd: the noise of a second difference grows as
   1 / (k dt)^2, and noise in the regressor biases least squares;
2. command: computed torque with the estimated model,
   tau = tau_nom(q, qd, a) + Y(q, qd, a) theta, a = qdd_d + omega^2 e + 2 zeta omega e_dot
   at the sensed state (e, e_dot at the middle of the held step, as
   :func:`skinny_mj.controllers.torque_arm.arm_torque`).

``update="desired"`` (the default) adapts instead on the regressor of the desired
motion, Y_d = Y(q_d, qd_d, qdd_d), free of sensor noise (Sadegh and Horowitz's
desired-compensation law, the gradient form of Slotine and Li's): the command is
computed torque on the nominal model plus Y_d theta, and theta follows
d theta / dt = Gamma Y_d^T s with the sliding variable s = e_dot + lambda e
(lambda = omega), Gamma = ``gamma`` diag(prior_sd^2), clipped to the bounds. The
measured form above regresses on sensed accelerations, whose noise also enters the
held torques through the feedback loop: least squares is then biased.

The estimate persists across the cycles a loop runs (it is the controller's memory).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from skinny_mj.controllers.torque_arm import feedback_torque, mid_step_error
from skinny_mj.controllers.torque_arm_loop import ArmLoop


@dataclass
class ParameterRLS:
    """Recursive least squares for R runs' parameters theta (R, p) from vector
    observations residual (R, n) = Y (R, n, p) theta + noise.

    prior_sd : (p,) prior standard deviation of each parameter about ``prior`` (0);
    noise_sd : residual noise, N m; forgetting : old information's weight per update (1:
    none); lo, hi : (p,) bounds the estimate is clipped to (a projection).
    """

    prior_sd: np.ndarray
    noise_sd: float = 1.0
    forgetting: float = 1.0
    lo: np.ndarray | None = None
    hi: np.ndarray | None = None
    theta: np.ndarray = field(default=None, repr=False)  # type: ignore[assignment]
    p_cov: np.ndarray = field(default=None, repr=False)  # type: ignore[assignment]

    def reset(self, n_runs: int) -> None:
        sd = np.asarray(self.prior_sd, float)
        self.theta = np.zeros((n_runs, len(sd)))
        self.p_cov = np.broadcast_to(np.diag(sd ** 2), (n_runs, len(sd), len(sd))).copy()

    def update(self, y: np.ndarray, residual: np.ndarray) -> None:
        """One observation per run: y (R, n, p), residual (R, n)."""
        p_yt = self.p_cov @ np.swapaxes(y, 1, 2)  # (R, p, n)
        s = y @ p_yt + self.forgetting * self.noise_sd ** 2 * np.eye(y.shape[1])
        gain = np.swapaxes(np.linalg.solve(s, np.swapaxes(p_yt, 1, 2)), 1, 2)  # (R, p, n)
        innovation = residual - np.einsum("rnp,rp->rn", y, self.theta)
        self.theta = self.theta + np.einsum("rpn,rn->rp", gain, innovation)
        if self.lo is not None or self.hi is not None:
            self.theta = np.clip(self.theta, self.lo, self.hi)
        self.p_cov = (self.p_cov - gain @ np.swapaxes(p_yt, 1, 2)) / self.forgetting
        self.p_cov = 0.5 * (self.p_cov + np.swapaxes(self.p_cov, 1, 2))


@dataclass
class AdaptiveArmLoop(ArmLoop):
    """:class:`ArmLoop` whose law is computed torque on the estimated model (module
    docstring). regressor : ``(q, qd, qdd) (R, n) -> (tau_nom (R, n), Y (R, n, p))``;
    estimator : its :class:`ParameterRLS`."""

    regressor: Callable | None = None
    estimator: ParameterRLS | None = None
    span: int = 3
    update: str = "desired"
    gamma: float = 0.3

    def begin(self, plant, n_steps: int) -> None:
        super().begin(plant, n_steps)
        if self.estimator.theta is None or len(self.estimator.theta) != plant.n_runs:
            self.estimator.reset(plant.n_runs)
        self._q_hist: list[np.ndarray] = []
        k = self.span
        w = k - np.abs(np.arange(-k, k) + 0.5)
        self._weights = w / w.sum()
        if self.update == "desired" and getattr(self, "_y_d", None) is None:
            m = self.motion
            self._tau_d, self._y_d = self.regressor(m.q_mid, m.qd_mid, m.qdd_step)

    def _estimate(self, t: int, q: np.ndarray) -> None:
        k = self.span
        self._q_hist = [*self._q_hist[-2 * k:], q]
        if len(self._q_hist) < 2 * k + 1:
            return
        q0, q1, q2 = self._q_hist[0], self._q_hist[k], self._q_hist[-1]
        h = k * self.dt
        qd = (q2 - q0) / (2.0 * h)
        qdd = (q2 - 2.0 * q1 + q0) / h ** 2
        tau = np.einsum("j,jrn->rn", self._weights, self.applied_nm[t - 2 * k:t])
        tau_nom, y = self.regressor(q1, qd, qdd)
        self.estimator.update(y, tau - tau_nom)

    def u_error(self, t: int, desired: np.ndarray, sensed: np.ndarray, plant) -> np.ndarray:
        state = self.state_of(sensed)
        step = min(t, len(self.motion.q_mid) - 1)
        e, e_dot = mid_step_error(state, self.motion, step, self.dt)
        acc = self.motion.qdd_step[step] + self.gains.kp * e + self.gains.kd * e_dot
        est = self.estimator
        if self.update == "desired":
            y_d = self._y_d[step]  # (n, p)
            if t < len(self.motion.q_mid):
                s = e_dot + self.gains.omega * e
                gain = self.gamma * np.asarray(est.prior_sd, float) ** 2
                est.theta = np.clip(est.theta + self.dt * gain * (s @ y_d), est.lo, est.hi)
            tau_nom, _ = self.regressor(state.q, state.qd, acc)
            total = tau_nom + est.theta @ y_d.T
        else:
            if t < len(self.motion.q_mid):
                self._estimate(t, state.q)
            tau_nom, y = self.regressor(state.q, state.qd, acc)
            total = tau_nom + np.einsum("rnp,rp->rn", y, est.theta)
        self.feedback_nm[t] = feedback_torque(state, e, e_dot, self.gains)
        return total / self._limit
