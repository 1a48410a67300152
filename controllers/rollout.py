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

from collections.abc import Callable
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
        return self.targets(0)

    def targets(self, lead: int) -> np.ndarray:
        """FEL's target with the error ``lead`` steps later: command(t) + u_error(t + 1 +
        lead) (the last ``lead`` steps take the cycle's last error), less a hook's
        feed-forward, (R, T-1, n_dof). ``lead = 0``: :attr:`y_est`."""
        error = self.u_error[:, 1 + lead:]
        if lead:
            last = np.repeat(self.u_error[:, -1:], min(lead, self.commands.shape[1]), axis=1)
            error = np.concatenate([error, last], axis=1)[:, :self.commands.shape[1]]
        y = self.commands + error
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
    ff = None if hook is None else array("feedforward", (n_steps - 1, n_runs, n_dof))
    if hook is not None:
        hook.begin(plant, n_steps)
    # Built once: the ESN input [d(t+1); s_in(t); p(t); hook] is written straight into
    # the state record (the desired part of every step at once), and each part's step is
    # a callable bound to its arrays.
    u_in = esn.inputs_of(states)  # (T-1, R, n_in) views
    if u_in.shape[2] != n_des + n_sig * (1 if forward is None else 2) + n_hook:
        raise ValueError(f"the network takes {u_in.shape[2]} inputs, the loop makes "
                         f"{n_des + n_sig * (1 if forward is None else 2) + n_hook}")
    if n_des:
        u_in[:, :, :n_des] = desired[1:, None]
    sensed_in = u_in[:, :, n_des:n_des + n_sig]
    esn_step = esn.stepper(noise)
    error = feedback.stepper(plant) if hook is None else _hook_error(hook, plant)
    advance = _advance(plant)
    if hook is None and forward is None and online is None:  # the plain loop, lean
        for t in range(n_steps - 1):
            sensed_in[t] = sensed[max(t - delay_steps, 0)]
            esn_step(states[t], y_esn[t])
            error(t, desired[t], sensed[t], u_error[t])
            # the command clip(y_esn + K u_error), in place
            np.add(np.multiply(gain, u_error[t], out=commands[t]), y_esn[t], out=commands[t])
            np.minimum(np.maximum(commands[t], -1.0, out=commands[t]), 1.0, out=commands[t])
            advance(commands[t], sensed[t + 1], true[t + 1], angles[t + 1])
    else:  # the same steps with every part
        for t in range(n_steps - 1):
            sensed_in[t] = sensed[max(t - delay_steps, 0)]
            _extra_inputs(t, u_in[t, :, n_des + n_sig:], predictions, hook, plant)
            esn_step(states[t], y_esn[t])
            error(t, desired[t], sensed[t], u_error[t])
            if online is not None and t > 0:  # y_est(t-1) needs u_error(t): one step late
                y_est = commands[t - 1] + u_error[t]  # less a hook's feed-forward (Rollout)
                if ff is not None:
                    y_est -= ff[t - 1]
                online.update(states[t - 1], y_esn[t - 1], y_est)
            command = commands[t]  # clip(y_esn + K u_error), in place
            np.multiply(gain, u_error[t], out=command)
            command += y_esn[t]
            if ff is not None:
                ff[t] = hook.feedforward(t, plant)
                command += ff[t]
            np.maximum(command, -1.0, out=command)  # np.clip, without its Python wrapper
            np.minimum(command, 1.0, out=command)
            if forward is not None:
                predictions[t + 1] = forward.step(predictions[t] if chained else
                                                  sensed[max(t - delay_steps, 0)], command,
                                                  noise=noise)
                fm_states[t] = forward.esn.extended
            advance(command, sensed[t + 1], true[t + 1], angles[t + 1])
            if hook is not None:  # after the plant's signals are recorded (it only reads)
                hook.after_step(t, plant)
    error(n_steps - 1, desired[-1], sensed[-1], u_error[-1])
    if online is not None:
        y_est = commands[-1] + u_error[-1]
        online.update(states[-1], y_esn[-1], y_est if ff is None else y_est - ff[-1])
    return Rollout(*(None if a is None else np.swapaxes(a, 0, 1) for a in (
        commands, y_esn, u_error, sensed, true, angles, states, fm_states, predictions, ff)))


def _extra_inputs(t: int, out: np.ndarray, predictions: np.ndarray | None, hook, plant
                  ) -> None:
    """The ESN inputs after [d(t+1); s_in(t)]: the forward model's p(t), then the hook's."""
    n_fm = 0 if predictions is None else predictions.shape[2]
    if n_fm:
        out[:, :n_fm] = predictions[t]
    if hook is not None and hook.n_inputs:
        out[:, n_fm:] = hook.inputs(t, plant)


def _hook_error(hook, plant) -> Callable[[int, np.ndarray, np.ndarray, np.ndarray], None]:
    """A hook's motor error at state t, into ``out``."""
    def error(t: int, desired: np.ndarray, sensed: np.ndarray, out: np.ndarray) -> None:
        out[...] = hook.u_error(t, desired, sensed, plant)
    return error


def _advance(plant) -> Callable[[np.ndarray, np.ndarray, np.ndarray, np.ndarray], None]:
    """``advance(command, sensed, true, angles)``: step the plant and write the new state's
    sensed and true signals and joint angles; the plant's own ``step_into`` if it has one."""
    fused = getattr(plant, "step_into", None)
    if fused is not None:
        return fused

    def advance(command: np.ndarray, sensed: np.ndarray, true: np.ndarray,
                angles: np.ndarray) -> None:
        sensed[...] = plant.step(command)
        true[...] = plant.true_signals()
        angles[...] = plant.joint_angles()
    return advance
