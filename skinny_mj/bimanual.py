"""Bimanual coordination (paper B): a forced leading arm and an ESN-driven lagging arm.

Paper B ("Learning bimanual coordination patterns for rhythmic movements", ICANN 2010)
§3: "the control system controls only the movement of the lagging arm; the movement of
the leading arm is forced. The input to the system is the current states (the arms'
joint angles), while the output is the motor command to the lagging arm" (Fig. 2:
K = 4 input nodes, L = 100 internal nodes, N = 2 output nodes). Eqs. (1)-(3)::

    v(t+1) = plant(u_inverse(t) + K u_feedback(t), u_leading_arm(t))
    x(t+1) = f(W_in v(t+1) + W x(t))                       (no output feedback)
    u_inverse(t+1) = f_out(W_out [v(t+1); x(t+1)])

So the inverse model sees no desired position at all: "the desired next state is
implicit in the state of the leading arm". The lagging arm's desired trajectory is
used only by the feedback controller and, through it, by feedback-error learning.

The movement (paper B §3): "simply raising and lowering the arms, with no movement in
the elbow joint", 2D body, joint-angle signals. The pattern (relative phase,
frequency ratio, amplitude ratio) defines the lagging arm's target as a function of
the leading arm's phase, so when the leader changes speed the target changes with it:
a test at speed s is the whole 4-DOF movement played s times as fast.

Step order (SPEC §5, as :mod:`controllers.fel`): sense s(t) (R, 4); ESN input s(t);
u_error(t) from (d(t), s(t)); command = clip(y_ESN + K u_error, -1, 1) for the lagging
arm, the ideal command for the leading arm; y_est(t) = command(t) + u_error(t+1).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from controllers.esn import ESN
from controllers.feedback import FeedbackController
from controllers.fel import FELConfig, Rollout
from controllers.metrics import motor_nrmse, position_nrmse
from skinny_mj.ideal import ideal_command, true_commands
from skinny_mj.plant import BatchPlant
from skinny_mj.trajectories import Trajectory

ARM_DOFS = {"right": (0, 1), "left": (2, 3)}  # body.dof_names(4) order


@dataclass(frozen=True)
class Pattern:
    """A coordination pattern of the lagging arm relative to the leading arm (paper B §2).

    phase_deg : the lagging arm's phase lag Φ, degrees (0 in-phase, 180 anti-phase).
    leader_cycles, lagger_cycles : frequency ratio; "1:2" = the leader moves once
        while the lagging arm moves twice.
    amplitude_ratio : lagging / leading shoulder amplitude ("2:1": twice as far).
    """

    phase_deg: float = 0.0
    leader_cycles: int = 1
    lagger_cycles: int = 1
    amplitude_ratio: float = 1.0

    @property
    def frequency_ratio(self) -> float:
        """Lagging / leading frequency."""
        return self.lagger_cycles / self.leader_cycles


#: Paper B §4: relative phase 0°, 90°, 180°; frequency 1:2, 1:3, 2:3, 3:5; amplitude 2:1.
PATTERNS: dict[str, Pattern] = {
    "phase0": Pattern(0.0),
    "phase90": Pattern(90.0),
    "phase180": Pattern(180.0),
    "freq1-2": Pattern(0.0, 1, 2),
    "freq1-3": Pattern(0.0, 1, 3),
    "freq2-3": Pattern(0.0, 2, 3),
    "freq3-5": Pattern(0.0, 3, 5),
    "amp2-1": Pattern(0.0, 1, 1, 2.0),
}


@dataclass(frozen=True)
class Movement:
    """The basic movement: both shoulders raised and lowered, elbows still (paper B §3).

    The paper gives no numbers; these keep the 2:1 amplitude pattern inside the
    0°-180° joint range and give one training cycle about the length of YMCA (6 s).

    leading : which arm is forced ("right" or "left").
    period_s : the leading arm's period at speed 1, s.
    min_leader_periods : a cycle holds the smallest multiple of ``leader_cycles``
        leader periods that is >= this (whole periods of both arms, 2:3 -> 4).
    center_deg, amplitude_deg : the leader's shoulder swings center ± amplitude.
    elbow_deg : both elbows' fixed flexion (off the 0° limit, so holding it still is
        a control task, not a joint stop).
    dt : control step, s.
    """

    leading: str = "right"
    period_s: float = 2.0
    min_leader_periods: int = 3
    center_deg: float = 90.0
    amplitude_deg: float = 40.0
    elbow_deg: float = 20.0
    dt: float = 0.02

    @property
    def lagging(self) -> str:
        return "left" if self.leading == "right" else "right"


def pattern_angles(pattern: Pattern, movement: Movement = Movement(),
                   speed: float = 1.0) -> np.ndarray:
    """Joint angles (T, 4) rad of one cycle of ``pattern`` with the leader at ``speed``.

    Leader shoulder: c - A cos(ψ), ψ = 2π t speed / period (starts at the bottom).
    Lagging shoulder: c - a A cos(ψ f - Φ), f the frequency ratio, a the amplitude
    ratio, Φ the phase lag: the lagging arm's target is a function of the leader's
    phase ψ, so at another speed the same pattern is simply played faster or slower.
    """
    periods = pattern.leader_cycles * int(np.ceil(movement.min_leader_periods
                                                  / pattern.leader_cycles))
    n_steps = int(round(periods * movement.period_s / (speed * movement.dt))) + 1
    psi = np.linspace(0.0, 2 * np.pi * periods, n_steps)
    c, amp = np.radians(movement.center_deg), np.radians(movement.amplitude_deg)
    lead = c - amp * np.cos(psi)
    lag = c - pattern.amplitude_ratio * amp * np.cos(
        pattern.frequency_ratio * psi - np.radians(pattern.phase_deg))
    q = np.full((n_steps, 4), np.radians(movement.elbow_deg))
    q[:, ARM_DOFS[movement.leading][0]] = lead
    q[:, ARM_DOFS[movement.lagging][0]] = lag
    return q


def pattern_trajectory(pattern: Pattern, movement: Movement = Movement(),
                       speed: float = 1.0, name: str = "bimanual") -> Trajectory:
    """:func:`pattern_angles` as a :class:`Trajectory`."""
    return Trajectory(pattern_angles(pattern, movement, speed), movement.dt,
                      f"{name}@{speed:g}")


class BimanualPlant:
    """Plant-protocol view of a :class:`BatchPlant` (R runs) whose controlled DOFs are
    the lagging arm's two joints; the leading arm follows its movement exactly.

    Signals are all four normalized joint angles (both arms), so ``n_signals`` = 4,
    ``n_dof`` = 2; ``command_jacobian`` (R, 4, 2) has zero rows for the leading arm,
    so a Jacobian feedback controller corrects the lagging arm's error only.

    Parameters
    ----------
    angles : (T, 4) the whole movement, rad (the leader's part is enforced).
    movement : which arm leads.
    max_speed_rad_s : (4,) full-scale speeds of the body, rad/s.
    n_runs, seeds, sensor_noise : as :class:`BatchPlant`.
    """

    def __init__(self, angles: np.ndarray, movement: Movement, max_speed_rad_s: np.ndarray,
                 n_runs: int = 1, seeds: list[int] | None = None, sensor_noise: float = 0.01):
        self.angles = np.asarray(angles, float)
        self.lead = np.array(ARM_DOFS[movement.leading])
        self.lag = np.array(ARM_DOFS[movement.lagging])
        self.body = BatchPlant(4, "joint", Trajectory(self.angles, movement.dt), n_runs=n_runs,
                               seeds=seeds, sensor_noise=sensor_noise,
                               max_speed_rad_s=max_speed_rad_s)
        self.n_runs, self.n_dof, self.n_signals = n_runs, 2, 4
        self.dt = self.body.dt
        self.full_max_speed_rad_s = np.asarray(self.body.max_speed_rad_s, float)
        self.max_speed_rad_s = self.full_max_speed_rad_s[self.lag]
        self._t = 0

    def reset(self) -> np.ndarray:
        self._t = 0
        return self.body.reset()

    def leader_command(self) -> np.ndarray:
        """Ideal command (R, 2) that puts the leading arm on its next pose."""
        target = self.angles[min(self._t + 1, len(self.angles) - 1), self.lead]
        q = self.body.joint_angles()[:, self.lead]
        return ideal_command(target, q, self.full_max_speed_rad_s[self.lead], self.dt)

    def step(self, command: np.ndarray) -> np.ndarray:
        full = np.empty((self.n_runs, 4))
        full[:, self.lead] = self.leader_command()
        full[:, self.lag] = np.asarray(command, float).reshape(self.n_runs, 2)
        self._t += 1
        return self.body.step(full)

    def true_signals(self) -> np.ndarray:
        return self.body.true_signals()

    def joint_angles(self) -> np.ndarray:
        """The lagging arm's joint angles (R, 2) rad."""
        return self.body.joint_angles()[:, self.lag]

    def all_joint_angles(self) -> np.ndarray:
        """Both arms' joint angles (R, 4) rad, body order."""
        return self.body.joint_angles()

    def command_jacobian(self) -> np.ndarray:
        return self.body.command_jacobian()[:, :, self.lag]


def rollout(esn: ESN, plant: BimanualPlant, desired: np.ndarray, gain: float, *,
            noise: bool, feedback: FeedbackController | None = None) -> Rollout:
    """One cycle: plant reset to the first pose, ESN state carried on.

    desired : (T, 4) normalized joint angles of both arms (the leader's rows only
        matter for plotting: its feedback rows are zero). ESN input = s(t) (R, 4).
    """
    feedback = feedback or FeedbackController()
    n_steps, n_runs = len(desired), plant.n_runs
    sensed = np.empty((n_runs, n_steps, 4))
    true = np.empty_like(sensed)
    angles = np.empty((n_runs, n_steps, 4))
    u_error = np.empty((n_runs, n_steps, 2))
    commands = np.empty((n_runs, n_steps - 1, 2))
    y_esn = np.empty_like(commands)
    states = np.empty((n_runs, n_steps - 1, esn.cfg.n_extended))
    sensed[:, 0] = plant.reset()
    true[:, 0], angles[:, 0] = plant.true_signals(), plant.all_joint_angles()
    for t in range(n_steps - 1):
        y_esn[:, t] = esn.step(sensed[:, t], noise=noise)
        states[:, t] = esn.extended
        u_error[:, t] = feedback.u_error(desired[t], sensed[:, t], plant)
        commands[:, t] = np.clip(y_esn[:, t] + gain * u_error[:, t], -1.0, 1.0)
        sensed[:, t + 1] = plant.step(commands[:, t])
        true[:, t + 1], angles[:, t + 1] = plant.true_signals(), plant.all_joint_angles()
    u_error[:, -1] = feedback.u_error(desired[-1], sensed[:, -1], plant)
    return Rollout(commands, y_esn, u_error, sensed, true, angles, states)


def _failed(esn: ESN, ro: Rollout) -> np.ndarray:
    bad = np.array([r is not None for r in esn.diverged()])
    return bad | ~np.isfinite(ro.commands).all(axis=(1, 2))


def lagging_nrmse(ro: Rollout, desired: np.ndarray, plant: BimanualPlant) -> np.ndarray:
    """Position NRMSE (R,) of the lagging arm's noise-free joint signals."""
    return position_nrmse(ro.true_signals[:, :, plant.lag], desired[:, plant.lag])


@dataclass
class BimanualTrain:
    """Training curve: lagging-arm position NRMSE (R, E) of each epoch's evaluation
    cycle (feedback on), gains (E,), failed (R,) and the last evaluation rollout."""

    position_nrmse: np.ndarray
    gains: np.ndarray
    failed: np.ndarray
    last_rollout: Rollout


def train(esn: ESN, plant: BimanualPlant, desired: np.ndarray, cfg: FELConfig,
          feedback: FeedbackController | None = None) -> BimanualTrain:
    """FEL as in paper B §3: per epoch reset, washout, ``learning_cycles`` cycles that
    refit W_out to β y_est + (1-β) y_ESN (eq. 6), one evaluation cycle; K per epoch
    from ``cfg.gains()``. desired : (T, 4) normalized joint angles."""
    gains, beta = cfg.gains(), cfg.effective_beta
    curve = np.full((plant.n_runs, cfg.epochs), np.nan)
    failed = np.zeros(plant.n_runs, bool)
    ro = None
    for epoch, gain in enumerate(gains):
        esn.reset()
        for cycle in range(cfg.learning_cycles + 2):
            learning = 0 < cycle <= cfg.learning_cycles
            evaluation = cycle == cfg.learning_cycles + 1
            ro = rollout(esn, plant, desired, gain, noise=not evaluation, feedback=feedback)
            failed |= _failed(esn, ro)
            esn.x[failed], esn.W_out[failed] = 0.0, 0.0  # silence, exclude from fits
            if learning:
                esn.fit(ro.states, beta * ro.y_est + (1.0 - beta) * ro.y_esn, runs=~failed)
        curve[~failed, epoch] = lagging_nrmse(ro, desired, plant)[~failed]
    return BimanualTrain(curve, gains, failed, ro)


@dataclass
class BimanualEval:
    """Test at one speed: lagging position and motor NRMSE (R,), failed (R,), rollout."""

    position_nrmse: np.ndarray
    motor_nrmse: np.ndarray
    failed: np.ndarray
    rollout: Rollout
    desired: np.ndarray


def evaluate(esn: ESN, plant: BimanualPlant, desired: np.ndarray) -> BimanualEval:
    """Paper B §3: "one additional epoch with only two cycles, the initialization cycle
    and the evaluation cycle", K = 0 (and no reservoir noise, no learning)."""
    esn.reset()
    rollout(esn, plant, desired, 0.0, noise=False)
    ro = rollout(esn, plant, desired, 0.0, noise=False)
    failed = _failed(esn, ro)
    truth = true_commands(plant.angles, plant.full_max_speed_rad_s, plant.dt)[:, plant.lag]
    pos = np.where(failed, np.nan, lagging_nrmse(ro, desired, plant))
    mot = np.where(failed, np.nan, motor_nrmse(ro.commands, truth))
    return BimanualEval(pos, mot, failed, ro, desired)


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
