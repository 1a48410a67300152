"""Paper B's bimanual coordination patterns as movements (a forced leading arm, a lagging one).

Paper B ("Learning bimanual coordination patterns for rhythmic movements", ICANN 2010)
§3: "simply raising and lowering the arms, with no movement in the elbow joint". The
pattern (relative phase, frequency ratio, amplitude ratio) defines the lagging arm's
target as a function of the leading arm's phase, so when the leader changes speed the
target changes with it: the movement at speed s is generated anew at that speed (not
resampled), which is what a rhythmic pattern means.

Library names: ``bimanual-<pattern>`` (``bimanual-phase90``, ``bimanual-freq1-2`` ...),
with a speed suffix as any movement (``bimanual-phase0@1.5``). In 3D (8 DOF) the
shoulder abduction swings as in 2D; shoulder flexion and rotation are held at 0 and the
elbows at their fixed flexion on both arms (our choice: the paper is 2D only).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from skinny_mj.plant import body
from skinny_mj.trajectories.trajectory import DEFAULT_DT_S, Trajectory

PREFIX = "bimanual-"


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

    leading : which arm's part is the leader's ("right" or "left").
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
    dt: float = DEFAULT_DT_S

    @property
    def lagging(self) -> str:
        return "left" if self.leading == "right" else "right"


def pattern_angles(pattern: Pattern, movement: Movement = Movement(), speed: float = 1.0,
                   which: body.BodyLike = "2d") -> np.ndarray:
    """Joint angles (T, n_dof) rad of one cycle of ``pattern`` with the leader at
    ``speed``, for the body ``which``.

    Leader shoulder abduction: c - A cos(ψ), ψ = 2π t speed / period (starts at the
    bottom). Lagging: c - a A cos(ψ f - Φ), f the frequency ratio, a the amplitude
    ratio, Φ the phase lag. Elbows at ``elbow_deg``, any other DOF at 0.
    """
    names = body.body_of(which).dof_names
    periods = pattern.leader_cycles * int(np.ceil(movement.min_leader_periods
                                                  / pattern.leader_cycles))
    n_steps = int(round(periods * movement.period_s / (speed * movement.dt))) + 1
    psi = np.linspace(0.0, 2 * np.pi * periods, n_steps)
    c, amp = np.radians(movement.center_deg), np.radians(movement.amplitude_deg)
    lead = c - amp * np.cos(psi)
    lag = c - pattern.amplitude_ratio * amp * np.cos(
        pattern.frequency_ratio * psi - np.radians(pattern.phase_deg))
    q = np.zeros((n_steps, len(names)))
    for i, name in enumerate(names):
        if name.endswith("elbow_flexion"):
            q[:, i] = np.radians(movement.elbow_deg)
    q[:, names.index(f"{movement.leading}_shoulder_abduction")] = lead
    q[:, names.index(f"{movement.lagging}_shoulder_abduction")] = lag
    return q


def pattern_trajectory(name: str, which: body.BodyLike = "2d", speed: float = 1.0,
                       movement: Movement = Movement()) -> Trajectory:
    """The library movement ``bimanual-<pattern>`` at ``speed`` for the body ``which``."""
    pattern = PATTERNS[name.removeprefix(PREFIX)]
    label = name + (f"@{speed:g}" if speed != 1.0 else "")
    return Trajectory(pattern_angles(pattern, movement, speed, which), movement.dt, label,
                      body=body.body_of(which).name)


def names() -> tuple[str, ...]:
    return tuple(PREFIX + p for p in PATTERNS)
