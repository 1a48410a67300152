"""Motion-imitation metrics of one test beside the position NRMSE, shared by
``skinny test`` and ``skinny experiment generalization``, and a movement's statistics as
a target to imitate (``skinny trajectory show``: what is reachable, the NRMSE floor).

DTW NRMSE (:mod:`skinny_mj.training.dtw`, needs dtaidistance), the fraction of steps within 5° of
the target per joint, RMS error per joint (deg), the timing lag (cross-correlation
shift), and how much of the movement asks for more than the network's full scale.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from skinny_mj.controllers.metrics import (
    fraction_within,
    nrmse,
    position_nrmse,
    rmse_per_signal,
    timing_lag,
)
from skinny_mj.plant.body import BodyLike, body_of
from skinny_mj.training.dtw import available, dtw_nrmse
from skinny_mj.trajectories import Trajectory, ik

__all__ = ["ROBOT_METRICS", "TORQUE_METRICS", "WITHIN_DEG", "imitation_metrics", "lag_s",
           "movement_stats", "robot_metrics", "saturation"]

#: The run files' figures a roboticist reads (:func:`robot_metrics`), beside the NRMSEs
#: (the torque body's ``torque_rms_nm`` and ``abs_work_j`` are in the test's ``torque``
#: figures, :meth:`skinny_mj.controllers.torque_fel.TorqueLoop.metrics`).
ROBOT_METRICS = ("rms_error_deg", "peak_error_deg", "hand_error_cm", "peak_hand_error_cm",
                 "lag_s")
#: The torque body's torque use of a test (its ``torque`` figures): RMS torque (N m) and
#: mechanical work magnitude sum |tau qd| dt (J).
TORQUE_METRICS = ("torque_rms_nm", "abs_work_j")


#: Tolerance of the "within" fraction, degrees.
WITHIN_DEG = 5.0


def saturation(angles: np.ndarray, dt: float, max_speed_rad_s: np.ndarray) -> float:
    """Fraction of true-command samples (T-1, n_dof) with |c| > 1 before clipping: the
    steps the movement (T, n_dof) rad asks faster than full scale (n_dof,) rad/s."""
    raw = np.diff(angles, axis=0) / (np.asarray(max_speed_rad_s) * dt)
    return float(np.mean(np.abs(raw) > 1.0 + 1e-9))


def lag_s(produced: np.ndarray, wanted: np.ndarray, which: BodyLike, dt: float) -> float:
    """The timing lag of ``produced`` (T, n_dof) rad behind ``wanted`` (T, n_dof) rad, the
    body ``which``'s angles, in s (steps ``dt`` apart; positive = late): the
    cross-correlation shift of the normalized angles, searched up to 25 steps or a third
    of the movement."""
    max_lag = min(25, (len(wanted) - 1) // 3)
    skinny = body_of(which)
    return timing_lag(skinny.normalize_angles(produced),
                      skinny.normalize_angles(wanted), max_lag) * dt


def robot_metrics(produced: np.ndarray, wanted: np.ndarray, which: BodyLike,
                  dt: float) -> dict[str, float]:
    """A test's errors in a roboticist's units, for the body ``which``'s produced joint
    angles ``produced`` (T, >= n_dof) rad (extra columns ignored) against the movement's
    ``wanted`` (T, n_dof) rad, steps ``dt`` s apart. Step 0 (the shared first pose) is not
    scored.

    ``rms_error_deg``: RMS joint-angle error over joints and steps, degrees;
    ``peak_error_deg``: the largest |joint-angle error|, degrees; ``hand_error_cm`` /
    ``peak_hand_error_cm``: RMS over arms and steps / largest distance between the
    produced and the desired hand (the wrist, the forearm's end, by the body's forward
    kinematics, :meth:`~skinny_mj.plant.body.Body.arm_points`), cm; ``lag_s``: the timing lag
    (cross-correlation shift of the normalized angles, as :func:`imitation_metrics`;
    positive = the produced movement is late), s."""
    skinny = body_of(which)
    produced = np.asarray(produced, dtype=float)[..., :skinny.dof]
    wanted = np.asarray(wanted, dtype=float)
    err = produced[1:] - wanted[1:]
    hand = skinny.arm_points(produced)[..., 2, :] - skinny.arm_points(wanted)[..., 2, :]
    dist_cm = 100.0 * np.linalg.norm(hand[1:], axis=-1)  # (T-1, 2 arms)
    return {"rms_error_deg": float(np.degrees(np.sqrt(np.mean(err**2)))),
            "peak_error_deg": float(np.degrees(np.abs(err).max())),
            "hand_error_cm": float(np.sqrt(np.mean(dist_cm**2))),
            "peak_hand_error_cm": float(dist_cm.max()),
            "lag_s": lag_s(produced, wanted, skinny, dt)}


def imitation_metrics(outcome, which: BodyLike, *, dtw: bool = True) -> dict[str, Any]:
    """One run's figures on one test (a :class:`skinny_mj.training.loop.TestOutcome`) of
    the body ``which``:
    ``position_nrmse``, ``motor_nrmse``, ``dtw_nrmse`` (position signals, 1 s band;
    None when dtaidistance is missing), ``within5`` (mean over joints) and
    ``within5_per_joint``, ``rmse_deg`` (the mean over joints of each joint's RMS error;
    not :func:`robot_metrics`'s ``rms_error_deg``, the RMS over joints and steps, which the
    commands print) and ``rmse_deg_per_joint``, ``lag_s`` (positive
    = the produced movement is late), ``cartesian_position_nrmse`` (the produced joint
    angles scored on Cartesian signals). Step 0 (the shared first pose) is not scored."""
    test = outcome.trajectory
    produced, wanted = outcome.rollout.angles[0], test.angles
    within = fraction_within(produced[1:], wanted[1:], np.radians(WITHIN_DEG))
    rmse = np.degrees(rmse_per_signal(produced[1:], wanted[1:]))
    out: dict[str, Any] = {
        "position_nrmse": outcome.position_nrmse, "motor_nrmse": outcome.motor_nrmse,
        "within5": float(within.mean()), "within5_per_joint": [float(v) for v in within],
        "rmse_deg": float(rmse.mean()), "rmse_deg_per_joint": [float(v) for v in rmse],
        "lag_s": lag_s(produced, wanted, which, test.dt),
    }
    # the same produced movement scored on Cartesian segment vectors, whatever signals the
    # network saw, so joint- and Cartesian-signal models compare on one scale
    skinny = body_of(which)
    cart = skinny.position_signals(produced, "cartesian")
    out["cartesian_position_nrmse"] = float(nrmse(cart[1:], test.position_signals(
        "cartesian", skinny)[1:]))
    if dtw:
        out["dtw_nrmse"] = dtw_nrmse(outcome.rollout.true_signals[0][1:],
                                     outcome.desired[1:]) if available() else None
    return out


def movement_stats(traj: Trajectory) -> dict[str, float]:
    """Statistics of a movement (``skinny trajectory show``): steps, still steps (every
    joint slower than 0.05 rad/s; and exactly still), peak joint speed (rad/s), the
    fraction of steps whose Cartesian target Skinny cannot reach (IK residual >
    ``ik.UNREACHABLE_TOL``) and the residual's mean, the position NRMSE of the best
    reachable pose (a floor no controller beats), and the 8-12 Hz band RMS of the
    Cartesian targets (tremor + marker noise), normalized units."""
    from scipy.signal import butter, sosfiltfilt

    target = traj.position_signals("cartesian")
    speed = np.abs(np.diff(traj.angles, axis=0)).max(axis=1) / traj.dt
    res = ik.residual(traj.angles, target, traj.skinny)
    reached = traj.skinny.cartesian_signals(traj.angles)
    sos = butter(4, [8.0, 12.0], btype="band", fs=1.0 / traj.dt, output="sos")
    band = sosfiltfilt(sos, target, axis=0) if len(target) > 30 else np.zeros_like(target)
    return {"steps": len(traj), "still_steps": int((speed < 0.05).sum()),
            "exactly_still_steps": int((speed == 0).sum()),
            "peak_joint_speed_rad_s": float(speed.max()),
            "unreachable_fraction": float((res > ik.UNREACHABLE_TOL).mean()),
            "mean_ik_residual": float(res.mean()),
            "reachable_floor_position_nrmse": float(position_nrmse(reached[None], target)[0]),
            "tremor_band_rms": float(np.sqrt(np.mean(band**2)))}
