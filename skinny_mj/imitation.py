"""Motion-imitation metrics of one test beside the position NRMSE, shared by
``skinny test`` and ``skinny experiment generalization``.

DTW NRMSE (:mod:`skinny_mj.dtw`, needs dtaidistance), the fraction of steps within 5° of
the target per joint, RMS error per joint (deg), the timing lag (cross-correlation
shift), and how much of the movement asks for more than the network's full scale.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from controllers.metrics import fraction_within, nrmse, rmse_per_signal, timing_lag
from skinny_mj import body

__all__ = ["WITHIN_DEG", "imitation_metrics", "saturation"]

#: Tolerance of the "within" fraction, degrees.
WITHIN_DEG = 5.0


def saturation(angles: np.ndarray, dt: float, max_speed_rad_s: np.ndarray) -> float:
    """Fraction of true-command samples (T-1, n_dof) with |c| > 1 before clipping: the
    steps the movement (T, n_dof) rad asks faster than full scale (n_dof,) rad/s."""
    raw = np.diff(angles, axis=0) / (np.asarray(max_speed_rad_s) * dt)
    return float(np.mean(np.abs(raw) > 1.0 + 1e-9))


def imitation_metrics(outcome, dof: int, *, dtw: bool = True) -> dict[str, Any]:
    """One run's figures on one test (a :class:`skinny_mj.training.TestOutcome`):
    ``position_nrmse``, ``motor_nrmse``, ``dtw_nrmse`` (position signals, 1 s band;
    None when dtaidistance is missing), ``within5`` (mean over joints) and
    ``within5_per_joint``, ``rmse_deg`` and ``rmse_deg_per_joint``, ``lag_s`` (positive
    = the produced movement is late), ``cartesian_position_nrmse`` (the produced joint
    angles scored on Cartesian signals). Step 0 (the shared first pose) is not scored."""
    from skinny_mj.dtw import available, dtw_nrmse

    test = outcome.trajectory
    produced, wanted = outcome.rollout.angles[0], test.angles
    within = fraction_within(produced[1:], wanted[1:], np.radians(WITHIN_DEG))
    rmse = np.degrees(rmse_per_signal(produced[1:], wanted[1:]))
    max_lag = min(25, (len(test) - 1) // 3)
    out: dict[str, Any] = {
        "position_nrmse": outcome.position_nrmse, "motor_nrmse": outcome.motor_nrmse,
        "within5": float(within.mean()), "within5_per_joint": [float(v) for v in within],
        "rmse_deg": float(rmse.mean()), "rmse_deg_per_joint": [float(v) for v in rmse],
        "lag_s": timing_lag(body.normalize_angles(produced, dof),
                            body.normalize_angles(wanted, dof), max_lag) * test.dt,
    }
    # the same produced movement scored on Cartesian segment vectors, whatever signals the
    # network saw, so joint- and Cartesian-signal models compare on one scale
    cart = body.position_signals(produced, dof, "cartesian")
    out["cartesian_position_nrmse"] = float(nrmse(cart[1:], test.position_signals(
        "cartesian")[1:]))
    if dtw:
        out["dtw_nrmse"] = dtw_nrmse(outcome.rollout.true_signals[0][1:],
                                     outcome.desired[1:]) if available() else None
    return out
