"""One cycle of R runs in lockstep: the closed loop of ESN, feedback controller and plant.

Step t (t = 0 .. T-2): sense s(t); ESN input [d(t+1); s_in(t)] (+ the forward model's
prediction p(t), + a hook's extra inputs); u_error(t) from (d(t), s(t)); command =
clip(y_ESN + K u_error, -1, 1); step the plant. ``s_in`` is the sensed signal delayed by
``delay_steps`` (paper A); the feedback controller always sees the undelayed s(t). With
``inputs="sensed"`` (paper B) the desired position is left out of the ESN's input. The
loop's parts are a :class:`~skinny_mj.controllers.loop.Loop`.
:mod:`skinny_mj.controllers.fel` builds the training and the test from these cycles.
"""

from __future__ import annotations

from dataclasses import dataclass, fields

import numpy as np
from skinny_mj.controllers.esn import ESN
from skinny_mj.controllers.loop import INPUTS, Loop
from skinny_mj.controllers.plant import Plant

__all__ = ["INPUTS", "Loop", "Rollout", "rollout", "run_mean"]

#: the plain loop: desired + sensed inputs, the default feedback controller, nothing else
DEFAULT_LOOP = Loop()


def run_mean(a: np.ndarray) -> np.ndarray:
    """Mean over every axis but the first, (R,), summed in the same order for every R.

    A rollout's arrays are (R, T, ...) views of time-major buffers; reducing such a view
    over several axes sums in another order than a single run's contiguous array, so a
    lockstep run would differ from its single run in the last bits. Made contiguous
    first (a no-op when R = 1), each run's sum is the single run's."""
    a = np.ascontiguousarray(a)
    return a.mean(axis=tuple(range(1, a.ndim)))


@dataclass
class Rollout:
    """One cycle of R runs. T = len(desired).

    commands (R, T-1, n_dof) as sent; y_esn (R, T-1, n_dof) ESN outputs;
    u_error (R, T, n_dof); sensed, true_signals (R, T, n_sig); angles (R, T, n_joints)
    the plant's joint angles, rad (n_joints = n_dof unless part of the body is forced,
    as paper B's leading arm); states (R, T-1, D) the inverse model's extended
    states; fm_states (R, T-1, D_fm) or None;
    predictions (R, T, n_sig) the forward model's p(t) or None;
    feedforward (R, T-1, n_dof) a hook's feed-forward part of the commands or None.
    """

    commands: np.ndarray
    y_esn: np.ndarray
    u_error: np.ndarray
    sensed: np.ndarray
    true_signals: np.ndarray
    angles: np.ndarray
    states: np.ndarray
    fm_states: np.ndarray | None = None
    predictions: np.ndarray | None = None
    feedforward: np.ndarray | None = None  # (R, T-1, n_dof) a hook's unlearned command

    def select(self, r: int) -> Rollout:
        """Run ``r`` of a lockstep rollout (arrays keep R = 1; views, not copies)."""
        if self.commands.shape[0] == 1:
            return self
        return Rollout(**{f.name: None if getattr(self, f.name) is None
                          else getattr(self, f.name)[r:r + 1] for f in fields(self)})

    @property
    def y_est(self) -> np.ndarray:
        """Estimated target y_est(t) = command(t) + u_error(t+1), (R, T-1, n_dof), less
        a hook's feed-forward (which the ESN does not make)."""
        y = self.commands + self.u_error[:, 1:]
        return y if self.feedforward is None else y - self.feedforward

    @property
    def correction_ratio(self) -> np.ndarray:
        """Online correction ratio per run (R,): mean |command - y_ESN| / mean |command|."""
        num = run_mean(np.abs(self.commands - self.y_esn))
        return num / np.maximum(run_mean(np.abs(self.commands)), 1e-12)


def rollout(
    esn: ESN,
    plant: Plant,
    desired: np.ndarray,
    gain: float | np.ndarray,
    loop: Loop = DEFAULT_LOOP,
    *,
    noise: bool = True,
) -> Rollout:
    """Run one cycle of ``loop``: plant reset to the first pose, ESN state carried on.

    Parameters
    ----------
    desired : (T, n_sig) desired position signals, normalized.
    gain : K, scalar or (R,).
    loop : the :class:`~skinny_mj.controllers.loop.Loop`: inputs, feedback controller or
        actuation hook, forward model, online learner (at step t >= 1, once u_error(t)
        is known, ``online.update(state(t-1), y_ESN(t-1), y_est(t-1))``), delay, buffers.
    noise : reservoir noise on (washout/learning) or off (evaluation/test).
    """
    feedback, hook, forward, online = loop.feedback, loop.hook, loop.forward, loop.online
    delay_steps, buffers = loop.delay_steps, loop.buffers

    def array(name: str, shape: tuple[int, ...], dtype=np.float64) -> np.ndarray:
        if buffers is None:
            return np.empty(shape, dtype)
        out = buffers.get(name)
        if out is None or out.shape != shape or out.dtype != dtype:
            out = buffers[name] = np.empty(shape, dtype)
        return out

    desired = np.asarray(desired, float)
    n_steps, n_runs = desired.shape[0], esn.n_runs
    gain = np.broadcast_to(np.asarray(gain, float), (n_runs,))[:, None]
    # Time-major buffers (T, R, ...): each step writes contiguous rows, not R rows a
    # whole movement apart (scattered first touches of fresh pages cost more than the
    # writes). The Rollout holds their (R, T, ...) views.
    if plant.n_runs != n_runs:
        raise ValueError(f"{n_runs} networks for {plant.n_runs} plant runs")
    n_sig, n_dof = plant.n_signals, plant.n_dof
    n_des = desired.shape[1] if loop.inputs == "desired+sensed" else 0
    sensed = array("sensed", (n_steps, n_runs, n_sig))
    true = array("true", (n_steps, n_runs, n_sig))
    first = plant.reset()
    angles0 = plant.joint_angles()  # the whole body's: more than n_dof when part is forced
    angles = array("angles", (n_steps, n_runs, angles0.shape[1]))
    u_error = array("u_error", (n_steps, n_runs, n_dof))
    commands = array("commands", (n_steps - 1, n_runs, n_dof))
    y_esn = array("y_esn", (n_steps - 1, n_runs, n_dof))
    states = array("states", (n_steps - 1, n_runs, esn.cfg.n_extended), esn.dtype)
    fm_states = None if forward is None else array(
        "fm_states", (n_steps - 1, n_runs, forward.esn.cfg.n_extended))
    predictions = None if forward is None else array("predictions", (n_steps, n_runs, n_sig))
    sensed[0] = first
    true[0] = plant.true_signals()
    angles[0] = angles0
    if forward is not None:
        predictions[0] = sensed[0]
        forward.begin(plant)
    # chained: the forward model's own p(t) stands in for the delayed s_in
    chained = forward is not None and delay_steps > 0 and forward.chained
    n_hook = 0 if hook is None else hook.n_inputs
    u_in = np.empty((n_runs, n_des + n_sig * (1 if forward is None else 2) + n_hook))
    ff = None if hook is None else array("feedforward", (n_steps - 1, n_runs, n_dof))
    if hook is not None:
        hook.begin(plant, n_steps)
    for t in range(n_steps - 1):
        s_in = sensed[max(t - delay_steps, 0)]
        if n_des:
            u_in[:, :n_des] = desired[t + 1]  # the ESN's input [d(t+1); s(t); p(t)]
        u_in[:, n_des:n_des + n_sig] = s_in
        if forward is not None:
            u_in[:, n_des + n_sig:u_in.shape[1] - n_hook] = predictions[t]
        if n_hook:
            u_in[:, -n_hook:] = hook.inputs(t, plant)
        y_esn[t] = esn.step(u_in, noise=noise, out_extended=states[t])
        u_error[t] = feedback.u_error(desired[t], sensed[t], plant) if hook is None \
            else hook.u_error(t, desired[t], sensed[t], plant)
        if online is not None and t > 0:  # y_est(t-1) needs u_error(t): one step late
            y_est = commands[t - 1] + u_error[t]  # less a hook's feed-forward, as Rollout.y_est
            online.update(states[t - 1], y_esn[t - 1], y_est if ff is None else y_est - ff[t - 1])
        command = commands[t]  # clip(y_esn + K u_error), in place
        np.multiply(gain, u_error[t], out=command)
        command += y_esn[t]
        if ff is not None:
            ff[t] = hook.feedforward(t, plant)
            command += ff[t]
        np.maximum(command, -1.0, out=command)  # np.clip, without its Python wrapper
        np.minimum(command, 1.0, out=command)
        if forward is not None:
            predictions[t + 1] = forward.step(predictions[t] if chained else s_in, command,
                                              noise=noise)
            fm_states[t] = forward.esn.extended
        sensed[t + 1] = plant.step(command)
        if hook is not None:
            hook.after_step(t, plant)
        true[t + 1] = plant.true_signals()
        angles[t + 1] = plant.joint_angles()
    u_error[-1] = feedback.u_error(desired[-1], sensed[-1], plant) if hook is None \
        else hook.u_error(n_steps - 1, desired[-1], sensed[-1], plant)
    if online is not None:
        y_est = commands[-1] + u_error[-1]
        online.update(states[-1], y_esn[-1], y_est if ff is None else y_est - ff[-1])
    return Rollout(*(None if a is None else np.swapaxes(a, 0, 1) for a in (
        commands, y_esn, u_error, sensed, true, angles, states, fm_states, predictions, ff)))
