"""Retarget captured arms onto Skinny by joint angles (not positions).

A capture's limbs are not Skinny's (CMU subject 05's forearms are short), so only
directions are carried over: each arm's upper-arm and forearm directions are expressed
in the subject's torso frame, and Skinny's joint angles are solved from them.

Torso frame (per frame): x from the right shoulder to the left one, z along the spine
(root -> mid-shoulders) made orthogonal to x, y = z cross x. A subject facing forward
then faces -y, as Skinny does, whatever the capture's world axes (y-up CMU, BVH, ...).

Angles (right arm; the left arm's directions are mirrored x -> -x first, because
body.py makes equal angles mirror images):

- 2D: abduction = angle of the upper arm in the x-z plane from straight down,
  atan2(-u_x, -u_z); elbow = the forearm's angle in that plane minus the abduction.
- 3D: with u = R_y(a) R_x(-b) (0, 0, -1) = (-sin a cos b, -sin b, -cos a cos b):
  abduction a = atan2(-u_x, -u_z), flexion b = asin(-u_y); the forearm in the upper
  arm's frame, f' = (R_y(a) R_x(-b))^T f = R_z(c) R_y(e) (0, 0, -1)
  = (-sin e cos c, -sin e sin c, -cos e) gives elbow e = acos(-f'_z) and rotation
  c = atan2(-f'_y, -f'_x).

An angle is undefined where its segment is nearly parallel to its hinge axis (2D: an
arm pointing straight forward has no frontal-plane angle; 3D: the rotation of a straight
arm, the abduction at +-90 deg flexion). Such samples are interpolated from their
well-conditioned neighbours and counted in the report (``interpolated_samples``).

Then: unwrap in time (continuous angles, the branch nearest the joint range), low-pass
(4th-order Butterworth, zero-phase ``sosfiltfilt``, default 6 Hz), resample to 50 Hz
(PCHIP), wrap into the 2 pi window centred on each joint range (so an arm pointing
across the body clips to the nearer limit on the circle), clip to the joint ranges and
report how much was clipped.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from skinny_mj.errors import SkinnyInputError
from skinny_mj.plant import body
from skinny_mj.trajectories import ik
from skinny_mj.trajectories.trajectory import DEFAULT_DT_S, Trajectory, excerpt

_MIRROR_X = np.array([-1.0, 1.0, 1.0])
ROTATION_MIN_ELBOW_RAD = np.deg2rad(15.0)  # below this bend the arm rotation is unobservable
MIN_PROJECTION = np.sin(np.deg2rad(20.0))  # frontal-plane share below which an angle is noise


@dataclass(frozen=True, eq=False)
class ArmClip:
    """World positions of both arms' joints in a capture (any units, any world axes).

    shoulder, elbow, wrist : (T, 2, 3), arms ordered right, left.
    root : (T, 3) a point low on the spine (pelvis / hips), for the torso's up direction.
    fps : capture rate, Hz.
    """

    shoulder: np.ndarray
    elbow: np.ndarray
    wrist: np.ndarray
    root: np.ndarray
    fps: float
    source: str = "capture"

    def __post_init__(self) -> None:
        t = self.shoulder.shape[0]
        for name in ("shoulder", "elbow", "wrist"):
            if getattr(self, name).shape != (t, 2, 3):
                raise ValueError(f"{name} must be (T, 2, 3)")
        if self.root.shape != (t, 3):
            raise ValueError("root must be (T, 3)")

    def __len__(self) -> int:
        return int(self.shoulder.shape[0])


@dataclass(frozen=True)
class RetargetReport:
    """What happened on the way from a source to Skinny's joint ranges.

    clipped_samples counts (step, DOF) values that were outside the joint range;
    clipped_steps counts steps with at least one; excesses are in degrees.
    """

    source: str
    dof: int
    source_fps: float
    source_frames: int
    steps: int
    cutoff_hz: float | None
    clipped_samples: int
    clipped_steps: int
    clipped_per_dof: dict[str, int]
    max_excess_deg: float
    max_excess_deg_per_dof: dict[str, float]
    interpolated_samples: int = 0

    def to_dict(self) -> dict:
        return asdict(self)

    def summary(self) -> str:
        return (
            f"{self.source}: {self.steps} steps, clipped {self.clipped_samples} samples "
            f"in {self.clipped_steps} steps (max {self.max_excess_deg:.1f} deg)"
        )


def range_excess(angles: np.ndarray, which: body.BodyLike) -> np.ndarray:
    """How far (T, n_dof) rad each angle lies outside its joint range (0 inside)."""
    lo, hi = body.body_of(which).joint_ranges().T
    return np.maximum(angles - hi, 0.0) + np.maximum(lo - angles, 0.0)


def clip_report(
    excess: np.ndarray,
    which: body.BodyLike,
    *,
    source: str,
    source_fps: float,
    source_frames: int | None = None,
    cutoff_hz: float | None = None,
    interpolated_samples: int = 0,
) -> RetargetReport:
    """Describe a clipping from its excess (T, n_dof) rad (see :func:`range_excess`)."""
    outside = excess > 0
    names = body.body_of(which).dof_names
    per_dof = excess.max(axis=0) if len(excess) else np.zeros(len(names))
    return RetargetReport(
        source=source,
        dof=len(names),
        source_fps=float(source_fps),
        source_frames=int(source_frames if source_frames is not None else len(excess)),
        steps=len(excess),
        cutoff_hz=cutoff_hz,
        clipped_samples=int(outside.sum()),
        clipped_steps=int(outside.any(axis=1).sum()),
        clipped_per_dof={n: int(c) for n, c in zip(names, outside.sum(axis=0), strict=True)},
        max_excess_deg=float(np.rad2deg(per_dof.max())),
        max_excess_deg_per_dof={
            n: round(float(np.rad2deg(e)), 3) for n, e in zip(names, per_dof, strict=True)
        },
        interpolated_samples=int(interpolated_samples),
    )


def _unit(v: np.ndarray) -> np.ndarray:
    n = np.linalg.norm(v, axis=-1, keepdims=True)
    return v / np.where(n > 1e-12, n, 1.0)


def torso_frame(clip: ArmClip) -> np.ndarray:
    """Torso axes (T, 3, 3) in world coordinates: rows x (right->left shoulder), y, z (up)."""
    x = _unit(clip.shoulder[:, 1] - clip.shoulder[:, 0])
    up = clip.shoulder.mean(axis=1) - clip.root
    z = _unit(up - np.sum(up * x, axis=-1, keepdims=True) * x)
    y = np.cross(z, x)
    return np.stack([x, y, z], axis=1)


def arm_directions(clip: ArmClip) -> tuple[np.ndarray, np.ndarray]:
    """Unit upper-arm and forearm directions (T, 2, 3) in the torso frame (right, left)."""
    frame = torso_frame(clip)
    upper = np.einsum("tij,tkj->tki", frame, clip.elbow - clip.shoulder)
    fore = np.einsum("tij,tkj->tki", frame, clip.wrist - clip.elbow)
    return _unit(upper), _unit(fore)


def _branch(x: np.ndarray, lo: float, hi: float) -> np.ndarray:
    """Unwrap ``x`` (T,) in time and shift it by 2 pi k so its mean is nearest the range."""
    x = np.unwrap(x)
    k = np.round(((lo + hi) / 2 - x.mean()) / (2 * np.pi))
    return x + 2 * np.pi * k


def _fill(x: np.ndarray, good: np.ndarray, lo: float, hi: float) -> np.ndarray:
    """Continuous version of the angle ``x`` (T,): unwrapped over the well-conditioned
    frames (``good``), linearly interpolated across the others (held at the ends)."""
    if good.all():
        return _branch(x, lo, hi)
    if not good.any():
        return np.full_like(x, (lo + hi) / 2)
    t = np.arange(len(x))
    return np.interp(t, t[good], _branch(x[good], lo, hi))


def wrap_to_range(angles: np.ndarray, which: body.BodyLike) -> np.ndarray:
    """Wrap angles (T, n_dof) rad into the 2 pi window centred on each joint range."""
    lo, hi = body.body_of(which).joint_ranges().T
    start = (lo + hi) / 2 - np.pi
    return np.mod(angles - start, 2 * np.pi) + start


def clip_continuous(angles: np.ndarray, which: body.BodyLike) -> tuple[np.ndarray, np.ndarray]:
    """Clip angles (T, n_dof) rad into the joint ranges without jumps.

    Each angle is wrapped into the 2 pi window centred on its range; a sample outside
    goes to the nearer limit on the circle. A run of outside samples that leaves
    through one limit and comes back through the other (the arm went round through
    the unreachable side) becomes a linear ramp between the two limits instead of a
    jump. Returns the clipped angles and the excess (T, n_dof) rad (0 inside).
    """
    lo, hi = body.body_of(which).joint_ranges().T
    w = wrap_to_range(angles, which)
    excess = np.maximum(w - hi, 0.0) + np.maximum(lo - w, 0.0)
    out = np.clip(w, lo, hi)
    for j in range(len(lo)):
        outside = excess[:, j] > 0
        edges = np.flatnonzero(np.diff(np.concatenate([[0], outside.astype(int), [0]])))
        for s, e in zip(edges[::2], edges[1::2], strict=True):
            first = out[s - 1, j] if s > 0 else out[s, j]
            last = out[e, j] if e < len(out) else out[e - 1, j]
            n = e - s
            out[s:e, j] = first + (last - first) * np.arange(1, n + 1) / (n + 1)
    return out, excess


#: The arms :func:`solve_angles` has a closed form for, by their hinges: Skinny's 2D and
#: 3D (and any body with the same hinges).
HINGES_2D = ("shoulder_abduction", "elbow_flexion")
HINGES_3D = ("shoulder_abduction", "shoulder_flexion", "shoulder_rotation", "elbow_flexion")


def _from_3d(upper: np.ndarray, fore: np.ndarray, skinny: body.Body) -> tuple[np.ndarray, int]:
    """Another body's start for the refinement: the 3D closed form's angle of each hinge
    named as one of Skinny's 3D hinges, 0 (clipped into range) for any other."""
    q3d, filled = solve_angles(upper, fore, "3d")
    joints = skinny.arms.joints
    out = np.zeros((upper.shape[0], skinny.dof))
    for k in range(2):
        for i, name in enumerate(joints):
            if name in HINGES_3D:
                out[:, k * len(joints) + i] = q3d[:, k * len(HINGES_3D) + HINGES_3D.index(name)]
    return out, filled


def solve_angles(upper: np.ndarray, fore: np.ndarray, which: body.BodyLike
                 ) -> tuple[np.ndarray, int]:
    """The body's joint angles (T, n_dof) rad from torso-frame directions (T, 2, 3).

    Continuous in time (unwrapped), not yet wrapped or clipped. An angle is undefined
    where its direction is nearly parallel to its hinge axis: the abduction (2D and 3D)
    when the upper arm points nearly straight forward or back (less than
    ``MIN_PROJECTION`` of it in the frontal plane), the 2D elbow likewise for the
    forearm, the 3D rotation when the elbow is nearly straight. Those samples are
    interpolated from their neighbours; the second value returned counts them.
    """
    skinny = body.body_of(which)
    planar = skinny.arms.joints == HINGES_2D
    if not planar and skinny.arms.joints != HINGES_3D:
        return _from_3d(upper, fore, skinny)
    dof = skinny.dof
    ranges = skinny.joint_ranges()
    n_arm = dof // 2
    out = np.empty((upper.shape[0], dof))
    filled = 0
    for k in range(2):
        u, f = upper[:, k], fore[:, k]
        if k == 1:
            u, f = u * _MIRROR_X, f * _MIRROR_X
        cols = slice(k * n_arm, (k + 1) * n_arm)
        r = ranges[cols]
        good_a = np.hypot(u[:, 0], u[:, 2]) >= MIN_PROJECTION
        a = _fill(np.arctan2(-u[:, 0], -u[:, 2]), good_a, *r[0])
        filled += int((~good_a).sum())
        if planar:
            good_e = np.hypot(f[:, 0], f[:, 2]) >= MIN_PROJECTION
            e = _fill(np.arctan2(-f[:, 0], -f[:, 2]) - a, good_e, *r[1])
            filled += int((~good_e).sum())
            out[:, cols] = np.stack([a, e], axis=1)
            continue
        b = np.arcsin(np.clip(-u[:, 1], -1.0, 1.0))
        ca, sa, cb, sb = np.cos(a), np.sin(a), np.cos(b), np.sin(b)
        # columns of R = R_y(a) R_x(-b); f' = R^T f
        r_x = np.stack([ca, np.zeros_like(a), -sa], axis=1)
        r_y = np.stack([-sa * sb, cb, -ca * sb], axis=1)
        r_z = np.stack([sa * cb, sb, ca * cb], axis=1)
        fl = np.stack([np.sum(r_x * f, 1), np.sum(r_y * f, 1), np.sum(r_z * f, 1)], axis=1)
        elbow = np.arccos(np.clip(-fl[:, 2], -1.0, 1.0))
        good_r = elbow >= ROTATION_MIN_ELBOW_RAD
        rot = _fill(np.arctan2(-fl[:, 1], -fl[:, 0]), good_r, *r[2])
        filled += int((~good_r).sum())
        out[:, cols] = np.stack([a, b, rot, elbow], axis=1)
    return out, filled


def solve_ik(upper: np.ndarray, fore: np.ndarray, which: body.BodyLike
             ) -> tuple[np.ndarray, np.ndarray]:
    """Joint angles (T, n_dof) rad and desired Cartesian signals (T, n_sig) for unit
    segment directions (T, 2, 3): :func:`solve_angles`, :func:`clip_continuous`, then
    :func:`skinny_mj.trajectories.ik.refine` (see :mod:`skinny_mj.trajectories.ik`)."""
    target = ik.target_signals(upper, fore, which)
    analytic, _ = solve_angles(upper, fore, which)
    clipped, _ = clip_continuous(analytic, which)
    return ik.refine(clipped, target, which), target


def lowpass(x: np.ndarray, fps: float, cutoff_hz: float) -> np.ndarray:
    """Zero-phase 4th-order Butterworth low-pass of ``x`` (T, n) sampled at ``fps`` Hz."""
    from scipy.signal import butter, sosfiltfilt

    if cutoff_hz is None or cutoff_hz >= fps / 2 or len(x) < 4:
        return x
    sos = butter(4, cutoff_hz, fs=fps, output="sos")
    padlen = min(3 * (2 * len(sos) + 1), len(x) - 1)
    return sosfiltfilt(sos, x, axis=0, padlen=padlen)


def resample_to(x: np.ndarray, fps: float, dt: float) -> np.ndarray:
    """Resample ``x`` (T, n) from ``fps`` Hz onto steps of ``dt`` s (PCHIP), start kept."""
    from scipy.interpolate import PchipInterpolator

    t_src = np.arange(len(x)) / fps
    n = int(np.floor(t_src[-1] / dt + 1e-9)) + 1
    if len(x) < 2:
        return x[:1].copy()
    return PchipInterpolator(t_src, x, axis=0)(np.arange(n) * dt)


def retarget(
    clip: ArmClip,
    which: body.BodyLike = "2d",
    *,
    cutoff_hz: float = 6.0,
    dt: float = DEFAULT_DT_S,
    window_s: tuple[float, float | None] | None = None,
    targets: str = "angles",
) -> tuple[Trajectory, RetargetReport]:
    """Joint-angle retargeting of a capture onto the body (see the module docstring).

    ``targets="positions"``: the subject's own unit segment vectors (low-passed
    and resampled the same way, renormalized; 2D: their frontal projection) become the
    explicit desired Cartesian signals, reachable or not, and the angles their inverse
    kinematics (:func:`skinny_mj.trajectories.ik.refine` from the clipped angles).

    ``window_s = (start_s, duration_s)`` keeps only that excerpt (duration None: to the
    end); it is cut after the low-pass and resampling (no filter edge effects) and
    before clipping, so the report counts the excerpt's clipping only.

    Returns the clipped trajectory at ``dt`` and a :class:`RetargetReport`.
    """
    skinny = body.body_of(which)
    if len(clip) < 2:
        raise SkinnyInputError(f"{clip.source}: need at least 2 frames, got {len(clip)}")
    pts = np.concatenate([clip.shoulder, clip.elbow, clip.wrist], axis=1)
    if not np.all(np.isfinite(pts)) or not np.all(np.isfinite(clip.root)):
        raise SkinnyInputError(f"{clip.source}: non-finite joint positions")
    upper, fore = arm_directions(clip)
    angles, filled = solve_angles(upper, fore, skinny)
    angles = resample_to(lowpass(angles, clip.fps, cutoff_hz), clip.fps, dt)
    name = Path(clip.source).stem
    if window_s is not None:
        part = excerpt(Trajectory(angles, dt, name, body=skinny.name), *window_s)
        angles, name = np.array(part.angles), part.name
    angles, excess = clip_continuous(angles, skinny)
    clipped = Trajectory(angles, dt, name, body=skinny.name)
    if targets == "positions":
        clipped = _position_targets(clipped, upper, fore, clip.fps, cutoff_hz, window_s)
    report = clip_report(
        excess,
        skinny,
        source=clip.source,
        source_fps=clip.fps,
        source_frames=len(clip),
        cutoff_hz=cutoff_hz,
        interpolated_samples=filled,
    )
    return clipped, report


def _position_targets(traj: Trajectory, upper: np.ndarray, fore: np.ndarray, fps: float,
                      cutoff_hz: float, window_s) -> Trajectory:
    """``traj`` (clipped angles at 50 Hz) with the capture's unit segment vectors as its
    explicit desired Cartesian signals and its angles refined onto them."""
    dirs = np.concatenate([upper, fore], axis=1).reshape(len(upper), -1)  # (T, 12)
    dirs = resample_to(lowpass(dirs, fps, cutoff_hz), fps, traj.dt)
    if window_s is not None:
        start = int(round(float(window_s[0]) / traj.dt))
        dirs = dirs[start:start + len(traj)]
    dirs = _unit(dirs.reshape(len(dirs), 2, 2, 3))
    target = ik.target_signals(dirs[:, 0], dirs[:, 1], traj.skinny)  # (upper, fore) x arms
    angles = ik.refine(traj.angles, target, traj.skinny)
    return Trajectory(angles, traj.dt, f"{traj.name}-positions", {"cartesian": target},
                      traj.body)
