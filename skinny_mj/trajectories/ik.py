"""Inverse kinematics of desired segment directions onto Skinny's joint angles.

The thesis's true commands came from an inverse kinematics of the recorded positions
(Tolani & Badler's for 3D, thesis §3.1.3). Here (:func:`skinny_mj.trajectories.retarget.
solve_ik`): the analytic solution of :func:`~skinny_mj.trajectories.retarget.solve_angles`
(the frontal-plane angles in 2D, the closed form of the 3D shoulder and elbow), made
continuous and clipped into the joint ranges, then refined by :func:`refine`: damped least
squares on ``skinny_mj.plant.body``'s Cartesian signals with the joint limits enforced by
projection. Where the target is reachable the analytic solution is already exact and the
refinement leaves it; where it is not (a segment out of the frontal plane in 2D, a pose
beyond a joint limit in 3D) it moves to the nearest reachable signals.
"""

from __future__ import annotations

import numpy as np

from skinny_mj.plant import body

#: Damping lambda (signal units per radian) and iterations of the least-squares refinement.
DLS_DAMPING = 0.05
DLS_ITERATIONS = 30
DLS_MAX_STEP_RAD = 0.03  # per iteration: at most 0.9 rad from the analytic start
#: A target is "unreachable" where Skinny's best pose leaves a segment signal this far
#: (normalized units = fraction of the segment's length) from it: 5x the sensor noise SD.
UNREACHABLE_TOL = 0.05


def target_signals(upper: np.ndarray, fore: np.ndarray, which: body.BodyLike) -> np.ndarray:
    """Desired Cartesian signals (T, n_sig) from unit segment directions (T, 2, 3) in the
    torso frame: 3D the x, y, z of each unit vector; 2D its frontal projection (x, z),
    whose length is below 1 where the segment leaves the frontal plane."""
    comps = body.body_of(which).cartesian_components()
    seg = np.stack([upper, fore], axis=2)[..., comps]  # (T, arms, segments, comps)
    return seg.reshape(seg.shape[0], -1)


def refine(angles: np.ndarray, target: np.ndarray, which: body.BodyLike,
           iterations: int = DLS_ITERATIONS, damping: float = DLS_DAMPING) -> np.ndarray:
    """Projected damped least squares: joint angles (T, n_dof) rad, started at ``angles``,
    that bring the body's ``cartesian_signals`` nearest to ``target`` (T, n_sig) inside
    the joint ranges. Each step: dq = (J^T J + lambda^2 I)^-1 J^T (target - s(q)),
    limited to DLS_MAX_STEP_RAD per joint, q clipped."""
    skinny = body.body_of(which)
    lo, hi = skinny.joint_ranges().T
    q = np.clip(np.array(angles, dtype=float), lo, hi)
    eye = damping**2 * np.eye(skinny.dof)
    for _ in range(iterations):
        err = target - skinny.cartesian_signals(q)
        jac = skinny.signal_jacobian(q, "cartesian")
        jt = np.swapaxes(jac, -1, -2)
        dq = np.linalg.solve(jt @ jac + eye, (jt @ err[..., None]))[..., 0]
        # a trust region: each step solved alone must stay in its neighbours' basin
        # (unbounded steps send ill-conditioned samples to the far joint limit: jumps)
        q = np.clip(q + np.clip(dq, -DLS_MAX_STEP_RAD, DLS_MAX_STEP_RAD), lo, hi)
    return q


def residual(angles: np.ndarray, target: np.ndarray, which: body.BodyLike) -> np.ndarray:
    """Per step (T,), the largest distance between a target segment signal and the one
    the body's ``angles`` reach (normalized units, per segment)."""
    skinny = body.body_of(which)
    diff = target - skinny.cartesian_signals(angles)
    nc = len(skinny.cartesian_components())
    return np.linalg.norm(diff.reshape(diff.shape[0], -1, nc), axis=-1).max(axis=1)

