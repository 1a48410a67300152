"""The YMCA dance, synthesized: key poses joined by minimum-jerk moves with holds.

The thesis' recording (Pro Reflex, 313 steps at 50 Hz) is not public, so the letters are
built from anatomically plausible key poses (SPEC §2). Angle conventions are
``skinny_mj.plant.body``'s: 0 = arm hanging down, abduction pi/2 = horizontal, pi = straight
up; elbow flexion 0 = straight, positive folds the forearm on in the abduction
direction (over towards the head when the arm is raised). Both arms use the same
angles for a mirror-symmetric pose (body.py mirrors the left arm's axes).

The M and A poses were found by inverse kinematics on ``Body.arm_points`` (wrist
targets: top of the head at about z = 1.74 m for M; x = +-0.03 m, z = 1.86 m, i.e.
hands touching above the head, for A) and rounded; the tests check the geometry.
"""

from __future__ import annotations

import numpy as np

from skinny_mj.errors import SkinnyInputError
from skinny_mj.plant.body import BodyLike, body_of
from skinny_mj.trajectories.trajectory import DEFAULT_DT_S, Trajectory

YMCA_STEPS = 313  # 6.26 s at 50 Hz, as the thesis' recording

# 2D key poses, degrees: (right abduction, right elbow, left abduction, left elbow).
POSES_2D_DEG: dict[str, tuple[float, float, float, float]] = {
    # arms hanging, slightly away from the body, elbows a little bent
    "neutral": (8.0, 10.0, 8.0, 10.0),
    # Y: both arms straight up in a V (40 deg from vertical); elbows nearly straight
    "Y": (140.0, 5.0, 140.0, 5.0),
    # M: elbows out and up, forearms folded over so the wrists rest on top of the head
    "M": (152.3, 101.7, 152.3, 101.7),
    # C: the only asymmetric letter. Right arm raised and arched over the head towards
    # the left; left arm out below horizontal, forearm curving up: a C opening to the
    # dancer's left
    "C": (165.0, 60.0, 70.0, 50.0),
    # A: arms up, forearms inclined inwards, hands meeting above the head
    "A": (167.2, 69.7, 167.2, 69.7),
}

# 3D key poses, degrees, per arm (abduction, flexion, rotation, elbow), right then left.
# Flexion swings the arm forward (Skinny faces -y); rotation turns the elbow's bending
# plane about the upper arm, which lets the wrist come back over the head.
POSES_3D_DEG: dict[str, tuple[float, ...]] = {
    # arms hanging, slightly forward, elbows a little bent
    "neutral": (8.0, 5.0, 0.0, 10.0, 8.0, 5.0, 0.0, 10.0),
    # Y: V over the head, a little in front of the frontal plane, slight outward rotation
    "Y": (140.0, 12.0, 10.0, 6.0, 140.0, 12.0, 10.0, 6.0),
    # M: elbows out and forward, forearms rotated back so the wrists touch the head top
    "M": (156.0, 25.0, -20.5, 101.6, 156.0, 25.0, -20.5, 101.6),
    # C: right arm arched over the head, left arm forward-out curving up (asymmetric)
    "C": (165.0, 8.0, -20.0, 55.0, 75.0, 25.0, 30.0, 50.0),
    # A: hands meeting above and slightly in front of the head
    "A": (167.7, 12.0, -5.4, 68.3, 167.7, 12.0, -5.4, 68.3),
}

# Timing in steps of 0.02 s: (target pose, move steps, hold steps). The first pose is
# held for _START_HOLD steps; the last hold fills the sequence up to YMCA_STEPS.
_START_HOLD = 10
START_HOLD_STEPS = _START_HOLD  # public: the recorded-like YMCA (human.py) times from it
SCHEDULE: tuple[tuple[str, int, int], ...] = (
    ("Y", 30, 25),
    ("M", 30, 25),
    ("C", 30, 25),
    ("A", 30, 25),
    ("neutral", 40, 0),
)


def min_jerk(n: int) -> np.ndarray:
    """Minimum-jerk profile (n,) rising from 0 to 1 over n steps (excluding the start):
    s(tau) = 10 tau^3 - 15 tau^4 + 6 tau^5 at tau = 1/n, ..., 1."""
    tau = np.arange(1, n + 1) / n
    return tau**3 * (10.0 - 15.0 * tau + 6.0 * tau**2)


#: The key poses by the arm's hinges they are written for: any body whose arms have
#: Skinny's 2D or 3D hinges (the torque twins, a body with longer segments) dances them.
POSES_BY_JOINTS = {
    ("shoulder_abduction", "elbow_flexion"): POSES_2D_DEG,
    ("shoulder_abduction", "shoulder_flexion", "shoulder_rotation", "elbow_flexion"):
        POSES_3D_DEG,
}


def key_poses(body: BodyLike) -> dict[str, np.ndarray]:
    """Key poses {name: (n_dof,) rad} for a body with Skinny's 2D or 3D hinges."""
    skinny = body_of(body)
    table = POSES_BY_JOINTS.get(skinny.arms.joints)
    if table is None:
        raise SkinnyInputError(f"YMCA's key poses are written for arms with Skinny's 2D or "
                               f"3D hinges, not {', '.join(skinny.arms.joints)} (the "
                               f"{skinny.name} body): train this body on babbling or a "
                               "motion-capture clip")
    return {k: np.deg2rad(np.array(v, dtype=float)) for k, v in table.items()}


def letter_end_steps() -> dict[str, int]:
    """For each letter, the index one past the end of its hold (so ``angles[:end]``
    contains the movement from the start through that letter)."""
    ends, t = {}, _START_HOLD
    for pose, move, hold in SCHEDULE:
        t += move + hold
        ends.setdefault(pose, t)
    return ends


def ymca(body: BodyLike = "2d") -> Trajectory:
    """The synthesized YMCA dance for the body: 313 steps at 50 Hz, neutral -> Y -> M -> C
    -> A -> neutral."""
    skinny = body_of(body)
    poses = key_poses(skinny)
    current = poses["neutral"]
    parts = [np.tile(current, (_START_HOLD, 1))]
    for pose, move, hold in SCHEDULE:
        target = poses[pose]
        parts.append(current + min_jerk(move)[:, None] * (target - current))
        parts.append(np.tile(target, (hold, 1)))
        current = target
    angles = np.concatenate(parts)
    if len(angles) > YMCA_STEPS:
        raise AssertionError("YMCA schedule longer than 313 steps")
    angles = np.concatenate([angles, np.tile(current, (YMCA_STEPS - len(angles), 1))])
    return Trajectory(angles, DEFAULT_DT_S, "ymca", body=skinny.name)
