"""Feedback controller: position error -> motor error in command units, and gain schedules.

u_error is the one-step correction (SPEC §5): the command that, held for one control
step, would move the sensed position onto the desired one,

    u_error = J_c^+ (d(t) - s(t)),   J_c = J_rad * max_speed_rad_s * dt,

with J_rad the signal Jacobian (signal per radian) and J_c the plant's
``command_jacobian`` (signal per command over one step). In joint space J_rad is
diagonal and this is a scaled difference. The pseudo-inverse is damped least squares,
(J^T J + lambda^2 I)^-1 J^T: with lambda small against J's singular values it equals
the Moore-Penrose pseudo-inverse; it only matters near singularities (arm stretched,
gimbal alignment), where it keeps u_error bounded instead of exploding.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np


def joint_space_error(
    desired: np.ndarray,
    sensed: np.ndarray,
    signal_per_rad: np.ndarray,
    max_speed_rad_s: np.ndarray,
    dt: float,
) -> np.ndarray:
    """Joint-space u_error (R, n_dof): (d - s) / (signal_per_rad * max_speed * dt).

    ``desired``, ``sensed``: (R, n_dof) normalized joint angles; ``signal_per_rad``:
    (n_dof,) normalized units per radian (2 / range); ``max_speed_rad_s``: (n_dof,).
    """
    return (np.asarray(desired) - sensed) / (signal_per_rad * max_speed_rad_s * dt)


def jacobian_error(
    desired: np.ndarray, sensed: np.ndarray, command_jacobian: np.ndarray, damping: float = 1e-4
) -> np.ndarray:
    """Cartesian (general) u_error (R, n_dof) = damped pinv(J) (d - s).

    Parameters
    ----------
    desired, sensed : (R, n_sig) position signals, normalized.
    command_jacobian : (R, n_sig, n_dof) d signal / d command over one step.
    damping : lambda, in signal-per-command units (J's own units).
    """
    jac = np.asarray(command_jacobian, float)
    err = (np.asarray(desired) - sensed)[..., None]
    jt = np.swapaxes(jac, -1, -2)
    gram = jt @ jac + _damping_matrix(jac.shape[-1], damping)
    return np.linalg.solve(gram, jt @ err)[..., 0]


@functools.lru_cache(maxsize=16)
def _damping_matrix(n: int, damping: float) -> np.ndarray:
    out = damping**2 * np.eye(n)
    out.flags.writeable = False
    return out


def check_error_mode(mode: str, signal_per_rad, damping: float) -> None:
    """Validate how a feedback controller turns position errors into joint errors:
    ``mode`` "jacobian" or "joint" (the latter needs ``signal_per_rad``), ``damping`` >= 0.
    Shared by the velocity and the torque controllers."""
    if mode not in ("jacobian", "joint"):
        raise ValueError(f"feedback mode must be 'jacobian' or 'joint', got {mode!r}")
    if mode == "joint" and signal_per_rad is None:
        raise ValueError("joint-space feedback needs signal_per_rad")
    if damping < 0:
        raise ValueError(f"damping must be >= 0, got {damping}")


@dataclass(frozen=True)
class FeedbackController:
    """Turns position errors into motor errors for a plant.

    ``mode`` "jacobian" uses the plant's ``command_jacobian`` (any signals);
    "joint" is the diagonal special case for joint-angle signals whose
    normalization is ``signal_per_rad`` (n_dof,) per radian.
    """

    mode: str = "jacobian"
    damping: float = 1e-4
    signal_per_rad: tuple[float, ...] | None = None
    #: scalar on u_error (the thesis leaves its scale unstated); 1 = the
    #: one-step correction itself, and then no multiplication at all (bit for bit)
    gain: float = 1.0

    def __post_init__(self) -> None:
        check_error_mode(self.mode, self.signal_per_rad, self.damping)
        if not self.gain > 0:
            raise ValueError(f"u_error gain must be > 0, got {self.gain}")

    def u_error(self, desired: np.ndarray, sensed: np.ndarray, plant) -> np.ndarray:
        """u_error (R, n_dof) for desired (n_sig,) or (R, n_sig) and sensed (R, n_sig)."""
        if self.mode == "joint":
            out = joint_space_error(
                desired, sensed, np.asarray(self.signal_per_rad), plant.max_speed_rad_s, plant.dt
            )
        else:
            out = jacobian_error(desired, sensed, plant.command_jacobian(), self.damping)
        return out if self.gain == 1.0 else self.gain * out


    def stepper(self, plant) -> Callable[[int, np.ndarray, np.ndarray, np.ndarray], None]:
        """:meth:`u_error` built once for ``plant``'s loop: ``error(t, desired, sensed,
        out)`` writes u_error (R, n_dof) of state t into ``out``, the same numbers (t is
        the loop's step, which an actuation's own error may need; this one does not)."""
        gain = self.gain  # a product by 1.0 changes no bit: no branch per step
        if self.mode == "joint":
            # the divisor of joint_space_error, multiplied in the same order, once
            per_command = np.asarray(self.signal_per_rad) * plant.max_speed_rad_s * plant.dt

            def joint(t: int, desired: np.ndarray, sensed: np.ndarray,
                      out: np.ndarray) -> None:
                np.multiply(gain, np.subtract(desired, sensed) / per_command, out=out)
            return joint
        jacobian, solve = plant.command_jacobian, np.linalg.solve
        damping = _damping_matrix(plant.n_dof, self.damping)

        def damped(t: int, desired: np.ndarray, sensed: np.ndarray, out: np.ndarray) -> None:
            jac = np.asarray(jacobian(), float)  # jacobian_error's steps, the same numbers
            jt = np.swapaxes(jac, -1, -2)
            gram, err = np.add(jt @ jac, damping), np.subtract(desired, sensed)[..., None]
            np.multiply(gain, solve(gram, jt @ err)[..., 0], out=out)
        return damped


def linear_gain(epochs: int) -> np.ndarray:
    """K falling linearly from 1 to 0 over ``epochs`` (the last epoch has K = 0)."""
    _check_epochs(epochs)
    return np.linspace(1.0, 0.0, epochs) if epochs > 1 else np.ones(1)


def multiplicative_gain(epochs: int, factor: float = 0.9) -> np.ndarray:
    """K = factor**e for e = 0..E-1 (paper C: -10 % per epoch)."""
    _check_epochs(epochs)
    if not 0 < factor <= 1:
        raise ValueError(f"gain factor must be in (0, 1], got {factor}")
    return factor ** np.arange(epochs, dtype=float)


def fixed_gain(epochs: int, gain: float) -> np.ndarray:
    """The same K in every epoch (paper A: 0.65)."""
    _check_epochs(epochs)
    if gain < 0:
        raise ValueError(f"feedback gain must be >= 0, got {gain}")
    return np.full(epochs, float(gain))


def _check_epochs(epochs: int) -> None:
    if epochs < 1:
        raise ValueError(f"epochs must be >= 1, got {epochs}")
