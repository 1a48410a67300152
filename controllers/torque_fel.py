"""The torque loop: what :func:`skinny_mj.controllers.fel.rollout` adds on a torque plant.

A :class:`skinny_mj.controllers.loop.Loop` takes an optional ``hook``
(:class:`~skinny_mj.controllers.loop.Hook`): the
smallest set of calls that turns the velocity-servo loop into a torque loop without a
second training loop. Per step t it asks the hook for

- extra ESN inputs, appended after [d(t+1); s(t)] (here the desired next joint
  velocity and the sensed one, each divided by the full-scale speed:
  [qd_d(t+1) / v_max; qd(t) / v_max], so the inverse model sees the state it must
  accelerate, not the positions only);
- the motor error u_error(t) (here :class:`TorqueFeedbackController`'s PD torque on the
  position and velocity errors, normalized by the torque limits; for the controller
  alone in computed-torque form, plus the inverse-dynamics torque of the desired motion);
- a feed-forward command added to y_ESN + K u_error before the clip (here the bias
  torque ``qfrc_bias`` of the current state / limit: gravity compensation), which the
  rollout stores so that FEL's target leaves it out (the ESN learns the rest);
- ``after_step``: a look at the plant after each step (here the applied actuator torque
  and the joint velocities are recorded for the torque metrics and recordings).

Pure NumPy: the plant supplies ``joint_velocities()`` (R, n_dof) rad/s,
``bias_torque_nm()`` (R, n_dof) N m and ``actuator_force_nm()`` (R, n_dof) N m.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from skinny_mj.controllers.loop import Hook
from skinny_mj.controllers.metrics import torque_use
from skinny_mj.controllers.sensing import JointSensing
from skinny_mj.controllers.torque_feedback import TorqueFeedbackController

#: the rollout hook's protocol, :class:`skinny_mj.controllers.loop.Hook`
RolloutHook = Hook


@dataclass
class TorqueLoop:
    """The :class:`~skinny_mj.controllers.loop.Hook` of a torque plant (see the module docstring).

    Parameters
    ----------
    controller : the PD teacher in normalized torque.
    desired_velocity_rad_s : (T, n_dof) qd_d of the cycle's movement, rad/s.
    velocity_scale_rad_s : (n_dof,) full-scale speed that normalizes velocity inputs.
    velocity_inputs : append [qd_d(t+1); qd(t)] / v_max to the ESN input.
    gravity_feedforward : add bias torque / limit to the command.
    inverse_dynamics : (T-1, n_dof) normalized torques of the desired motion; given,
        u_error is the computed-torque command (PD + these), for the controller alone.
    sensing : the joints' sensing (:class:`skinny_mj.controllers.sensing.JointSensing`),
        kept up to date each step; given, the ESN's velocity inputs and the teacher's
        velocity are its sensed velocities (None: the plant's true ones).
    predict : plant side, ``predict(q, qd, tau_nm) -> (q, qd)``: the controllers' model
        of the arm stepped one control step (each (R, n_dof), rad, rad/s, N m); the
        sensing's observer velocity needs it (None: no model).
    """

    controller: TorqueFeedbackController
    desired_velocity_rad_s: np.ndarray
    velocity_scale_rad_s: np.ndarray
    velocity_inputs: bool = True
    gravity_feedforward: bool = False
    inverse_dynamics: np.ndarray | None = None
    sensing: JointSensing | None = None
    predict: Callable | None = None
    #: (T-1, R, n_dof) applied torque (N m) and (T, R, n_dof) joint velocity (rad/s) and
    #: bias torque (N m) of the last cycle, time-major
    applied_nm: np.ndarray = field(default=None, repr=False)  # type: ignore[assignment]
    velocity_rad_s: np.ndarray = field(default=None, repr=False)  # type: ignore[assignment]
    bias_nm: np.ndarray = field(default=None, repr=False)  # type: ignore[assignment]

    def __post_init__(self) -> None:
        self.desired_velocity_rad_s = np.asarray(self.desired_velocity_rad_s, float)
        self.velocity_scale_rad_s = np.asarray(self.velocity_scale_rad_s, float)
        self._limit = self.controller.gains.limit
        # qd_d(t+1) / v_max of every step, once (each row as the step would divide it)
        self._desired_in = self.desired_velocity_rad_s[1:] / self.velocity_scale_rad_s

    @property
    def n_inputs(self) -> int:
        return 2 * self.desired_velocity_rad_s.shape[1] if self.velocity_inputs else 0

    def begin(self, plant, n_steps: int) -> None:
        if n_steps != len(self.desired_velocity_rad_s):
            raise ValueError(f"torque loop built for {len(self.desired_velocity_rad_s)} "
                             f"states, rollout has {n_steps}")
        shape = (n_steps, plant.n_runs, plant.n_dof)
        if self.velocity_rad_s is None or self.velocity_rad_s.shape != shape:
            # the arrays of the last cycle, reused by the next one (every entry is written)
            self.applied_nm = np.zeros((n_steps - 1, *shape[1:]))
            self.velocity_rad_s = np.zeros(shape)
            self.bias_nm = np.zeros(shape)
            self._inputs = np.zeros((plant.n_runs, 2 * plant.n_dof))
            self._no_feedforward = np.zeros(shape[1:])
        self._record(0, plant)
        if self.sensing is not None:
            self.sensing.reset(plant.joint_angles(), self.velocity_rad_s[0])

    def _record(self, t: int, plant) -> None:
        self.velocity_rad_s[t] = plant.joint_velocities()
        self.bias_nm[t] = plant.bias_torque_nm()

    def inputs(self, t: int, plant) -> np.ndarray:
        """(R, 2 n_dof) [qd_d(t+1); qd(t)] / v_max, in a buffer the next call overwrites."""
        out, n = self._inputs, self._desired_in.shape[1]
        out[:, :n] = self._desired_in[t]
        qd = self.velocity_rad_s[t] if self.sensing is None else self.sensing.qd
        np.divide(qd, self.velocity_scale_rad_s, out=out[:, n:])
        return out

    def u_error(self, t: int, desired: np.ndarray, sensed: np.ndarray, plant) -> np.ndarray:
        bias = None
        if self.inverse_dynamics is not None:
            ff = self.inverse_dynamics[min(t, len(self.inverse_dynamics) - 1)]
            bias = np.broadcast_to(ff * self._limit, (plant.n_runs, len(ff)))
        return self.controller.u_error(desired, sensed, plant,
                                       desired_velocity_rad_s=self.desired_velocity_rad_s[t],
                                       bias_nm=bias, velocity_rad_s=None if self.sensing
                                       is None else self.sensing.qd)

    def feedforward(self, t: int, plant) -> np.ndarray:
        if not self.gravity_feedforward:
            return self._no_feedforward
        return self.bias_nm[t] / self._limit

    def after_step(self, t: int, plant) -> None:
        self.applied_nm[t] = plant.actuator_force_nm()
        self._record(t + 1, plant)
        if self.sensing is not None:
            pred = self.model_prediction(t) if self.sensing.needs_prediction else None
            self.sensing.update(plant.joint_angles(), self.velocity_rad_s[t + 1], pred)

    def model_prediction(self, t: int) -> tuple[np.ndarray, np.ndarray]:
        """``predict(q^, v^, tau)``: the model's step from the sensing's estimate under the
        torque applied in step t (the command, clipped to the limits), ((R, n_dof) rad,
        (R, n_dof) rad/s): the observer velocity's input."""
        if self.predict is None:
            raise ValueError("the observer velocity needs a model of the arm (predict)")
        return self.predict(*self.sensing.estimate, self.applied_nm[t])

    def metrics(self, commands: np.ndarray, dt: float) -> dict[str, np.ndarray]:
        """Per-run torque figures (each (R,)) of the last cycle, for commands (R, T-1, n_dof)
        as sent (normalized torque).

        mean_abs_torque_nm : mean |applied torque| over steps and DOFs, N m;
        max_commanded_ratio / max_applied_ratio : max |torque| / limit (<= 1 within the
        limits); energy_j : positive mechanical work of the motors, sum max(tau qd, 0) dt, J;
        torque_rms_nm : RMS applied torque over steps and DOFs, N m; abs_work_j : mechanical
        work magnitude of the motors, sum |tau qd| dt over DOFs and steps, J
        (:func:`skinny_mj.controllers.metrics.torque_use`).
        """
        # contiguous (R, T-1, n_dof): each run's sums in the order it has alone (lockstep)
        applied = np.ascontiguousarray(np.swapaxes(self.applied_nm, 0, 1))
        qd = np.ascontiguousarray(np.swapaxes(self.velocity_rad_s, 0, 1)[:, 1:])
        commands = np.ascontiguousarray(commands)
        power = np.maximum(applied * qd, 0.0).sum(axis=2)
        return {
            "mean_abs_torque_nm": np.abs(applied).mean(axis=(1, 2)),
            "max_commanded_ratio": np.abs(commands).max(axis=(1, 2)),
            "max_applied_ratio": (np.abs(applied) / self._limit).max(axis=(1, 2)),
            "energy_j": power.sum(axis=1) * dt,
            **torque_use(applied, qd, dt),
        }
