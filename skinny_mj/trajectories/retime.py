"""A movement's path and its re-timing: the geometry of local time scaling (no dynamics).

The **path** of a trajectory is the clamped cubic spline through its angles over its own
time, s = k dt for sample k (:func:`path_spline`: the spline the torque twin's inverse
dynamics differentiate, at rest at both ends); playing it with s(t) = t is the movement
as shipped, a **timing** s(t) with path speed ṡ < 1 plays it slower there. A
:class:`PathTiming` is a timing on a grid of path points: the path speed ṡ at each
point and a constant path acceleration s̈ between two (what time-optimal path
parameterization gives); :func:`resample` samples q(s(t)) every ``dt`` s, exactly
(s(t) is quadratic between grid points), and :func:`back_on_path` takes a re-timed
movement back to the path's own clock, to check that re-timing kept the path.

Pure NumPy/SciPy: the dynamics that choose the timing are the plant's
(:mod:`skinny_mj.plant.path_dynamics`); the time-optimal timing itself is
:func:`skinny_mj.training.feasible.retime`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from skinny_mj.errors import SkinnyInputError
from skinny_mj.trajectories.trajectory import Trajectory


def path_spline(traj: Trajectory):
    """The path of ``traj``: a ``scipy.interpolate.CubicSpline`` of its angles over
    s = dt * k (s in seconds of the movement as shipped), clamped (at rest) at both ends.
    """
    from scipy.interpolate import CubicSpline  # here: scipy.interpolate takes ~0.25 s

    if len(traj) < 2:
        raise SkinnyInputError(f"trajectory {traj.name!r}: a path needs 2 steps or more")
    s = traj.dt * np.arange(len(traj))
    return CubicSpline(s, traj.angles, axis=0, bc_type="clamped")


def path_grid(traj: Trajectory, points_per_step: int = 2) -> np.ndarray:
    """(N+1,) path points: each step of ``traj`` cut into ``points_per_step`` equal parts,
    from s = 0 to its last sample's s = (T-1) dt."""
    if int(points_per_step) < 1:
        raise SkinnyInputError(f"points_per_step must be >= 1, got {points_per_step}")
    n = (len(traj) - 1) * int(points_per_step)
    return np.linspace(0.0, traj.dt * (len(traj) - 1), n + 1)


@dataclass(frozen=True)
class PathTiming:
    """A timing of a path: path points ``s`` (N+1,) increasing, the path speed ``sd``
    (N+1,) >= 0 at each (ṡ = 1: as shipped), constant path acceleration between two.

    ``times`` (N+1,): when each point is reached, s; ``duration``: the last of them.
    """

    s: np.ndarray
    sd: np.ndarray

    def __post_init__(self) -> None:
        s, sd = np.asarray(self.s, float), np.asarray(self.sd, float)
        if s.ndim != 1 or s.shape != sd.shape or len(s) < 2:
            raise SkinnyInputError("a timing needs s and sd of one length >= 2")
        if not (np.all(np.isfinite(sd)) and np.all(sd >= 0) and np.all(np.diff(s) > 0)):
            raise SkinnyInputError("a timing needs increasing s and finite sd >= 0")
        if np.any((sd[:-1] == 0) & (sd[1:] == 0)):
            raise SkinnyInputError("a timing cannot rest between two path points")
        object.__setattr__(self, "s", s)
        object.__setattr__(self, "sd", sd)

    @property
    def sdd(self) -> np.ndarray:
        """(N,) the constant path acceleration between points: (ṡ²_{i+1} - ṡ²_i) / 2 ds."""
        return (self.sd[1:] ** 2 - self.sd[:-1] ** 2) / (2.0 * np.diff(self.s))

    @property
    def times(self) -> np.ndarray:
        """(N+1,) time at each path point, s: each interval takes 2 ds / (ṡ_i + ṡ_{i+1})."""
        return np.concatenate([[0.0], np.cumsum(2.0 * np.diff(self.s)
                                                / (self.sd[:-1] + self.sd[1:]))])

    @property
    def duration(self) -> float:
        """How long the timing takes, s."""
        return float(self.times[-1])

    def path_position(self, t: np.ndarray) -> np.ndarray:
        """s(t) at times ``t`` (clipped to [0, duration]): exact for constant path
        acceleration between points."""
        times = self.times
        t = np.clip(np.asarray(t, float), 0.0, times[-1])
        i = np.clip(np.searchsorted(times, t, side="right") - 1, 0, len(self.s) - 2)
        tau = t - times[i]
        s = self.s[i] + self.sd[i] * tau + 0.5 * self.sdd[i] * tau ** 2
        return np.where(t >= times[-1], self.s[-1], np.clip(s, self.s[i], self.s[i + 1]))

    def path_speed(self, t: np.ndarray) -> np.ndarray:
        """ṡ(t) at times ``t`` (clipped to [0, duration])."""
        times = self.times
        t = np.clip(np.asarray(t, float), 0.0, times[-1])
        i = np.clip(np.searchsorted(times, t, side="right") - 1, 0, len(self.s) - 2)
        return np.maximum(self.sd[i] + self.sdd[i] * (t - times[i]), 0.0)


def sample_times(timing: PathTiming, dt: float) -> np.ndarray:
    """The control times of ``timing``: 0, dt, ... until the first at or after its end
    (``ceil(duration / dt) + 1`` samples; the last holds the path's end)."""
    n = math.ceil(timing.duration / dt - 1e-9)
    return dt * np.arange(n + 1)


def resample(traj: Trajectory, timing: PathTiming, name: str | None = None) -> Trajectory:
    """``traj``'s path played with ``timing``, sampled every ``traj.dt`` s: q(s(k dt)).

    Explicit desired signals (``traj.desired``) are re-timed along with the angles
    (linear interpolation over s).
    """
    if not (np.isclose(timing.s[0], 0.0) and
            np.isclose(timing.s[-1], traj.dt * (len(traj) - 1))):
        raise SkinnyInputError(f"the timing covers s in [{timing.s[0]:g}, {timing.s[-1]:g}],"
                               f" not the path of {traj.name!r}")
    s = timing.path_position(sample_times(timing, traj.dt))
    angles = path_spline(traj)(s)
    desired = None
    if traj.desired:
        own = traj.dt * np.arange(len(traj))
        desired = {k: np.stack([np.interp(s, own, col) for col in np.asarray(v).T], axis=1)
                   for k, v in traj.desired.items()}
    return Trajectory(angles, traj.dt, name or traj.name, desired, traj.body)


def back_on_path(retimed: Trajectory, timing: PathTiming, original: Trajectory) -> np.ndarray:
    """(T, n_dof) ``retimed`` (made by :func:`resample` with ``timing``) read back on the
    path's own clock: its samples placed at their path positions s(k dt) and
    interpolated (cubic) at the original's samples s = k dt. Equal to the original's
    angles up to the interpolation error when the re-timing kept the path."""
    from scipy.interpolate import CubicSpline  # here: scipy.interpolate takes ~0.25 s

    s = timing.path_position(sample_times(timing, retimed.dt))
    keep = np.concatenate([[True], np.diff(s) > 1e-12])  # the held end: one sample
    spline = CubicSpline(s[keep], retimed.angles[keep], axis=0)
    return spline(original.dt * np.arange(len(original)))
