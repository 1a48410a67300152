"""NRMSE as the thesis computes it, batched over runs.

NRMSE = sqrt(MSE) / (y_max - y_min), per signal over time, then averaged over
signals (SPEC §3/§5). Signals live in (-1, 1), so the range is 2: 0 is perfect,
about 0.5 random, 1 opposite.
"""

from __future__ import annotations

import numpy as np


def nrmse(actual: np.ndarray, target: np.ndarray, value_range: float = 2.0) -> np.ndarray:
    """Mean over signals of sqrt(mean over time of (actual - target)^2) / value_range.

    Parameters
    ----------
    actual : (..., T, n) produced signals (leading axes, e.g. runs, are kept).
    target : broadcastable to ``actual``, e.g. (T, n) shared by all runs.

    Returns
    -------
    (...) NRMSE, one value per leading index (a float for 2-D input).
    """
    # contiguous first: a lockstep batch's (R, T, n) views then sum each run in the order
    # a single run's array does (a no-op for one run), so batch == single bit for bit
    diff = np.ascontiguousarray(actual, float) - np.asarray(target, float)
    per_signal = np.sqrt(np.mean(diff**2, axis=-2)) / value_range
    return per_signal.mean(axis=-1)


def position_nrmse(true_signals: np.ndarray, desired: np.ndarray) -> np.ndarray:
    """Position error (R,): noise-free plant signals (R, T, n_sig) at t = 1..T-1 vs
    desired (T, n_sig) at the same steps (t = 0 is the shared first pose)."""
    return nrmse(np.asarray(true_signals)[..., 1:, :], np.asarray(desired)[1:])


def motor_nrmse(commands: np.ndarray, true_commands: np.ndarray) -> np.ndarray:
    """Motor error (R,): commands (R, T-1, n_dof) vs true commands (T-1, n_dof)."""
    return nrmse(commands, true_commands)


# -- motion-imitation metrics beside NRMSE -----------------------------------
def fraction_within(actual: np.ndarray, target: np.ndarray, tolerance: float) -> np.ndarray:
    """Per signal, the fraction of steps with |actual - target| <= ``tolerance``.

    Parameters
    ----------
    actual : (..., T, n) e.g. produced joint angles, rad.
    target : broadcastable to ``actual``, e.g. desired (T, n) angles, rad.
    tolerance : in the signals' unit (5° = ``np.radians(5)`` for angles).

    Returns
    -------
    (..., n) fractions in [0, 1].
    """
    diff = np.abs(np.asarray(actual, float) - np.asarray(target, float))
    return np.mean(diff <= tolerance, axis=-2)


def rmse_per_signal(actual: np.ndarray, target: np.ndarray) -> np.ndarray:
    """(..., n) root mean square error over time per signal (e.g. per joint, rad)."""
    diff = np.asarray(actual, float) - np.asarray(target, float)
    return np.sqrt(np.mean(diff**2, axis=-2))


def timing_lag(actual: np.ndarray, target: np.ndarray, max_lag: int) -> int:
    """The shift (steps) by which ``actual`` trails ``target``: the lag in
    [-max_lag, max_lag] maximizing the cross-correlation of the mean-removed signals,
    summed over signals (positive = actual late).

    Parameters
    ----------
    actual, target : (T, n) one run's signals, T > 2 max_lag.
    max_lag : largest shift tried, steps.
    """
    a = np.asarray(actual, float)
    b = np.broadcast_to(np.asarray(target, float), a.shape)
    a, b = a - a.mean(axis=0), b - b.mean(axis=0)
    t = a.shape[0]
    if t <= 2 * max_lag:
        raise ValueError(f"timing_lag needs T > 2 max_lag, got T={t}, max_lag={max_lag}")
    # mean over the overlap (not the sum) so long and short overlaps compare fairly
    score = [np.mean(a[k:] * b[:t - k]) if k >= 0 else np.mean(a[:t + k] * b[-k:])
             for k in range(-max_lag, max_lag + 1)]
    return int(np.argmax(score)) - max_lag


def torque_use(applied_nm: np.ndarray, velocity_rad_s: np.ndarray,
               dt: float) -> dict[str, np.ndarray]:
    """Per-run torque use (each (R,)) of applied torques ``applied_nm`` (R, T, n_dof) N m
    and the joint velocities ``velocity_rad_s`` (R, T, n_dof) rad/s they act on, ``dt`` s
    per step: ``torque_rms_nm``, the RMS torque over steps and DOFs, N m; ``abs_work_j``,
    the mechanical work magnitude sum over steps and DOFs of |tau qd| dt, J."""
    tau = np.asarray(applied_nm, float)
    power = np.abs(tau * np.asarray(velocity_rad_s, float)).sum(axis=2)
    return {"torque_rms_nm": np.sqrt(np.mean(tau**2, axis=(1, 2))),
            "abs_work_j": power.sum(axis=1) * dt}
