"""The plant protocol the training engine talks to, and a pure-NumPy toy plant.

``skinny_mj.plant.adapters`` implements :class:`Plant` over MuJoCo; :class:`ToyPlant` is a
kinematic stand-in (a joint-space integrator with clipping at the limits) for tests
and for users without MuJoCo. Both hold R independent copies stepping in lockstep.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Protocol, runtime_checkable

import numpy as np


@runtime_checkable
class Plant(Protocol):
    """R independent plants stepping in lockstep (a command is a normalized velocity)."""

    n_runs: int
    n_dof: int
    n_signals: int
    dt: float
    max_speed_rad_s: np.ndarray  # (n_dof,) joint speed of a command of 1

    def reset(self) -> np.ndarray:
        """Back to the first pose; returns sensed signals (R, n_sig) at t = 0."""
        ...

    def step(self, command: np.ndarray) -> np.ndarray:
        """Apply commands (R, n_dof) in [-1, 1] for one step; returns sensed (R, n_sig)."""
        ...

    def true_signals(self) -> np.ndarray:
        """Noise-free position signals (R, n_sig)."""
        ...

    def joint_angles(self) -> np.ndarray:
        """Joint angles (R, n_joints) rad: n_joints = n_dof, or more when part of the
        body is forced rather than commanded (paper B's leading arm)."""
        ...

    def command_jacobian(self) -> np.ndarray:
        """d signal / d command over one step, (R, n_sig, n_dof)."""
        ...


class ToyPlant:
    """Kinematic toy plant: q += clip(c, -1, 1) * max_speed * dt, clipped to the limits.

    Parameters
    ----------
    n_runs : R copies.
    q0_rad : (n_dof,) first pose.
    limits_rad : (n_dof, 2) joint ranges; signals normalize q to [-1, 1] over them.
    max_speed_rad_s : (n_dof,) speed of a command of 1.
    dt : control step in s.
    signal_map : "joint" (normalized angles), "linear" (``matrix`` @ normalized
        angles) or "planar_arm" (pairs (shoulder, elbow) per arm -> x, z of
        elbow-rel-shoulder and wrist-rel-elbow in segment lengths, like 2D Skinny).
    matrix : (n_sig, n_dof) for "linear".
    sensor_noise_std : std of Gaussian sensor noise (normalized units).
    seed / rngs : per-run noise generators (run r equals a single plant with rngs[r]).
    """

    def __init__(
        self,
        n_runs: int,
        q0_rad: np.ndarray,
        limits_rad: np.ndarray,
        max_speed_rad_s: np.ndarray,
        dt: float = 0.02,
        signal_map: str = "joint",
        matrix: np.ndarray | None = None,
        sensor_noise_std: float = 0.01,
        seed: int | None = None,
        rngs: Sequence[np.random.Generator] | None = None,
    ) -> None:
        self.q0 = np.asarray(q0_rad, float)
        self.n_runs, self.n_dof, self.dt = n_runs, self.q0.size, float(dt)
        self.limits = np.asarray(limits_rad, float).reshape(self.n_dof, 2)
        self.max_speed_rad_s = np.broadcast_to(
            np.asarray(max_speed_rad_s, float), (self.n_dof,)
        ).copy()
        if signal_map not in ("joint", "linear", "planar_arm"):
            raise ValueError(f"signal_map must be joint, linear or planar_arm: {signal_map!r}")
        if signal_map == "linear" and (matrix is None or np.shape(matrix)[1] != self.n_dof):
            raise ValueError("signal_map 'linear' needs matrix of shape (n_sig, n_dof)")
        if signal_map == "planar_arm" and self.n_dof % 2:
            raise ValueError("planar_arm needs (shoulder, elbow) pairs: n_dof must be even")
        if sensor_noise_std < 0:
            raise ValueError(f"sensor noise std must be >= 0, got {sensor_noise_std}")
        self.signal_map = signal_map
        self.matrix = None if matrix is None else np.asarray(matrix, float)
        self.n_signals = {"joint": self.n_dof, "linear": 0, "planar_arm": 2 * self.n_dof}[
            signal_map
        ] or self.matrix.shape[0]
        self.sensor_noise_std = float(sensor_noise_std)
        if rngs is None:
            rngs = [np.random.default_rng(s) for s in np.random.SeedSequence(seed).spawn(n_runs)]
        self.rngs = list(rngs)
        self.reset()

    # -- kinematics ------------------------------------------------------------------
    def _scale(self) -> np.ndarray:
        return 2.0 / (self.limits[:, 1] - self.limits[:, 0])

    def signals_of(self, q: np.ndarray) -> np.ndarray:
        """Noise-free signals (..., n_sig) of joint angles q (..., n_dof) rad."""
        q_norm = (q - self.limits[:, 0]) * self._scale() - 1.0
        if self.signal_map == "joint":
            return q_norm
        if self.signal_map == "linear":
            return q_norm @ self.matrix.T
        theta, phi = q[..., 0::2], q[..., 1::2]
        side = np.where(np.arange(theta.shape[-1]) % 2 == 0, -1.0, 1.0)  # right arm on -x
        out = np.stack(
            [side * np.sin(theta), -np.cos(theta),
             side * np.sin(theta + phi), -np.cos(theta + phi)], axis=-1
        )
        return out.reshape(*q.shape[:-1], self.n_signals)

    def signal_jacobian(self, q: np.ndarray) -> np.ndarray:
        """d signal / d angle (..., n_sig, n_dof) per radian."""
        if self.signal_map == "joint":
            return np.broadcast_to(np.diag(self._scale()), (*q.shape[:-1], self.n_dof, self.n_dof))
        if self.signal_map == "linear":
            j = self.matrix * self._scale()
            return np.broadcast_to(j, (*q.shape[:-1], *j.shape))
        jac = np.zeros((*q.shape[:-1], self.n_signals, self.n_dof))
        for arm in range(self.n_dof // 2):
            side = -1.0 if arm % 2 == 0 else 1.0
            th, ph = q[..., 2 * arm], q[..., 2 * arm + 1]
            r = 4 * arm
            jac[..., r, 2 * arm] = side * np.cos(th)
            jac[..., r + 1, 2 * arm] = np.sin(th)
            for col in (2 * arm, 2 * arm + 1):
                jac[..., r + 2, col] = side * np.cos(th + ph)
                jac[..., r + 3, col] = np.sin(th + ph)
        return jac

    # -- protocol --------------------------------------------------------------------
    def _sense(self) -> np.ndarray:
        clean = self.true_signals()
        if self.sensor_noise_std == 0:
            return clean
        noise = np.stack([g.standard_normal(self.n_signals) for g in self.rngs])
        return clean + self.sensor_noise_std * noise

    def reset(self) -> np.ndarray:
        self.q = np.tile(self.q0, (self.n_runs, 1))
        return self._sense()

    def step(self, command: np.ndarray) -> np.ndarray:
        c = np.clip(np.asarray(command, float).reshape(self.n_runs, self.n_dof), -1.0, 1.0)
        self.q = np.clip(self.q + c * self.max_speed_rad_s * self.dt, *self.limits.T)
        return self._sense()

    def true_signals(self) -> np.ndarray:
        return self.signals_of(self.q)

    def joint_angles(self) -> np.ndarray:
        return self.q.copy()

    def command_jacobian(self) -> np.ndarray:
        return self.signal_jacobian(self.q) * (self.max_speed_rad_s * self.dt)


def toy_movement(
    n_steps: int = 120, n_dof: int = 4, seed: int = 0, dt: float = 0.02, margin: float = 0.2
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A smooth random joint trajectory for a toy plant with ranges [0, pi].

    Returns
    -------
    q_rad : (n_steps, n_dof) joint angles inside [margin, pi - margin].
    max_speed_rad_s : (n_dof,) 2x the fastest speed in the movement (papers D/E).
    true_commands : (n_steps - 1, n_dof) the commands that reproduce ``q_rad`` exactly.
    """
    rng = np.random.default_rng(seed)
    t = np.linspace(0.0, 1.0, n_steps)[:, None]
    freqs = rng.integers(1, 3, (1, n_dof))
    phase = rng.uniform(0, 2 * np.pi, (1, n_dof))
    amp = 0.8 * (np.pi / 2 - margin)
    q = np.pi / 2 + amp * np.sin(2 * np.pi * freqs * t + phase)
    dq = np.diff(q, axis=0)
    max_speed = 2.0 * np.max(np.abs(dq), axis=0) / dt
    return q, max_speed, dq / (max_speed * dt)
