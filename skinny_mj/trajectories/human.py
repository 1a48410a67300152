"""A recorded-like YMCA: a person's 3D performance, captured as markers, the thesis's way.

The thesis's data (§3.1.2) was a human dancing the YMCA, recorded by a Pro Reflex system
at 200 Hz (every 4th sample kept: 313 steps at 50 Hz); its signals were the human's
normalized elbow and wrist vectors, not a robot's kinematics. That recording is not
public, so this module synthesizes one, every parameter stated with its source:

- **Body** (:data:`HEIGHT_M`, ratios of height from Drillis & Contini 1966, as tabulated
  in Winter, *Biomechanics and Motor Control of Human Movement*, 4th ed. 2009, Fig. 4.1):
  upper arm 0.186 H, forearm 0.146 H, biacromial width 0.259 H, shoulder height 0.818 H.
  The shoulder marker sits on the acromion, :data:`GH_BELOW_ACROMION_M` above the
  glenohumeral joint centre the humerus turns about (about 5 cm: Campbell et al. 2009,
  J Biomech 42:1527, MRI estimates of the joint centre below the acromion; scaled by
  H / 1.75 m). With per-segment normalization the segment lengths cancel; the
  proportions act through this marker offset, which tilts the acromion-to-elbow vector
  away from the humerus by up to atan(0.05 / 0.33) = 9 deg depending on the pose.
- **Letters**: ``ymca.POSES_3D_DEG`` performed by the person's arm, each performance's
  pose jittered (Gaussian, :data:`POSE_JITTER_DEG` per joint: an assumption; a dancer
  does not hit a letter twice alike).
- **Moves**: minimum-jerk (Flash & Hogan 1985, J Neurosci 5:1688) between letters, each
  duration x (1 + :data:`DURATION_CV` z), z ~ N(0, 1), clipped to +-30 % (an assumed
  10 % coefficient of variation); the holds absorb the difference, total 6.26 s.
- **No exact holds**: slow drift, an Ornstein-Uhlenbeck process on every joint angle
  (SD :data:`DRIFT_SD_DEG`, time constant :data:`DRIFT_TAU_S`: assumptions, stated as
  such); physiological tremor at the elbow and wrist markers, a sinusoid of
  :data:`TREMOR_AMPLITUDE_M` per axis at a frequency drawn in :data:`TREMOR_HZ` per arm
  (8-12 Hz; amplitude: about 30 um at rest and 4-5x with the arm extended, Growdon et al.
  2000, Electromyogr Clin Neurophysiol 40:295; 0.01 g modal peak, Wade et al. 1982,
  Arch Neurol 39:358, i.e. 25 um at 10 Hz).
- **Capture**: markers at :data:`CAPTURE_HZ`, Gaussian noise :data:`MARKER_NOISE_M` per
  coordinate (about 1 mm: the accuracy order of commercial optical systems, Richards
  1999, Hum Mov Sci 18:589), every :data:`DECIMATE`-th sample kept, no filter (the
  thesis: "only every fourth sample").

Representations (§3.1.2): each segment vector (acromion -> elbow, elbow -> wrist) divided
by its own length; 3D Cartesian = those unit vectors; 2D Cartesian = their frontal
(x, z) projection, shorter than 1 where a segment leaves the frontal plane, so not
always reachable by Skinny; 2D joint angles = the angles of that projection. The joint
angles of the trajectory are the inverse kinematics (:mod:`skinny_mj.trajectories.ik`),
the true commands' source. Deterministic for a seed.
"""

from __future__ import annotations

import functools

import numpy as np

from skinny_mj.plant import body
from skinny_mj.trajectories.retarget import solve_ik
from skinny_mj.trajectories.trajectory import DEFAULT_DT_S, Trajectory
from skinny_mj.trajectories.ymca import (
    SCHEDULE,
    START_HOLD_STEPS,
    YMCA_STEPS,
    key_poses,
    min_jerk,
)

HEIGHT_M = 1.75
UPPER_ARM_OF_HEIGHT, FOREARM_OF_HEIGHT = 0.186, 0.146
BIACROMIAL_OF_HEIGHT, SHOULDER_HEIGHT_OF_HEIGHT = 0.259, 0.818
GH_BELOW_ACROMION_M = 0.05
POSE_JITTER_DEG = 3.0
DURATION_CV = 0.10
DRIFT_SD_DEG, DRIFT_TAU_S = 2.0, 0.5
TREMOR_HZ, TREMOR_AMPLITUDE_M = (8.0, 12.0), 1e-4
CAPTURE_HZ, DECIMATE = 200.0, 4
MARKER_NOISE_M = 1e-3
DEFAULT_SEED = 0


def _schedule(rng: np.random.Generator) -> list[tuple[str, int, int]]:
    """(pose, move, hold) in capture samples: SCHEDULE x DECIMATE, moves jittered,
    holds scaled so the whole lasts exactly YMCA_STEPS x DECIMATE samples."""
    total = YMCA_STEPS * DECIMATE
    moves = [int(round(m * DECIMATE * (1 + np.clip(DURATION_CV * rng.standard_normal(),
                                                    -0.3, 0.3)))) for _, m, _ in SCHEDULE]
    holds = np.array([START_HOLD_STEPS] + [h for *_, h in SCHEDULE], float) * DECIMATE
    free = total - sum(moves)
    holds = np.floor(holds * free / holds.sum()).astype(int)
    holds[-1] += free - holds.sum()  # the last hold fills up to the exact length
    return [("neutral", 0, int(holds[0]))] + [
        (pose, moves[i], int(holds[i + 1])) for i, (pose, _, _) in enumerate(SCHEDULE)]


def performance_angles(seed: int = DEFAULT_SEED) -> np.ndarray:
    """The person's joint angles (T_capture, 8) rad at CAPTURE_HZ (3D convention of
    ``skinny_mj.plant.body``): jittered letters, minimum-jerk moves, drift on top."""
    rng = np.random.default_rng(np.random.SeedSequence([int(seed), 12]))
    poses = {k: v + np.deg2rad(POSE_JITTER_DEG) * rng.standard_normal(v.shape)
             for k, v in key_poses(8).items()}
    current, parts = poses["neutral"], []
    for pose, move, hold in _schedule(rng):
        target = poses[pose]
        if move:
            parts.append(current + min_jerk(move)[:, None] * (target - current))
        parts.append(np.tile(target, (hold, 1)))
        current = target
    q = np.concatenate(parts)
    a = np.exp(-1.0 / (CAPTURE_HZ * DRIFT_TAU_S))  # OU step, stationary SD DRIFT_SD_DEG
    kick = np.sqrt(1 - a * a) * np.deg2rad(DRIFT_SD_DEG) * rng.standard_normal(q.shape)
    drift = np.empty_like(q)
    drift[0] = np.deg2rad(DRIFT_SD_DEG) * rng.standard_normal(q.shape[1])
    for t in range(1, len(q)):
        drift[t] = a * drift[t - 1] + kick[t]
    return q + drift


def markers(seed: int = DEFAULT_SEED, height_m: float = HEIGHT_M) -> np.ndarray:
    """Captured marker positions (T_capture, 2 arms, 3 markers: acromion, elbow, wrist,
    3) in metres, world = torso frame (z up, facing -y), at CAPTURE_HZ, with tremor and
    marker noise."""
    q = performance_angles(seed)
    rng = np.random.default_rng(np.random.SeedSequence([int(seed), 13]))
    performer = body.body_of("3d")  # the performance's angles are Skinny's 3D hinges'
    unit = performer.segment_vectors(q) / performer.lengths_m()[:, None]  # directions only
    half, top = BIACROMIAL_OF_HEIGHT * height_m / 2, SHOULDER_HEIGHT_OF_HEIGHT * height_m
    acromion = np.array([[-half, 0.0, top], [half, 0.0, top]])
    gh = acromion - [0.0, 0.0, GH_BELOW_ACROMION_M * height_m / 1.75]
    elbow = gh + UPPER_ARM_OF_HEIGHT * height_m * unit[:, :, 0]
    wrist = elbow + FOREARM_OF_HEIGHT * height_m * unit[:, :, 1]
    t = np.arange(len(q)) / CAPTURE_HZ
    freq = rng.uniform(*TREMOR_HZ, size=(2, 1, 1))
    phase = rng.uniform(0, 2 * np.pi, size=(2, 2, 3))  # per arm, marker, axis
    tremor = TREMOR_AMPLITUDE_M * np.sin(2 * np.pi * freq[None, :, :, 0, None]
                                         * t[:, None, None, None] + phase[None])
    pts = np.stack([np.broadcast_to(acromion, elbow.shape), elbow, wrist], axis=2)
    pts[:, :, 1:] += tremor * np.array([0.5, 1.0])[None, None, :, None]  # wrist > elbow
    return pts + MARKER_NOISE_M * rng.standard_normal(pts.shape)


def ymca_recorded(which: body.BodyLike = "2d", seed: int = DEFAULT_SEED, *,
                  unit_2d: bool = False) -> Trajectory:
    """The recorded-like YMCA for the body: 313 steps at 50 Hz; explicit desired Cartesian
    signals (the person's normalized vectors, reachable or not); angles = their IK.

    ``unit_2d``: the other reading of §3.1.2 for 2D, the frontal projection normalized
    to unit length per frame (so the 2D targets are reachable up to marker effects);
    default: unit 3D vectors, then projected (the issue's reading)."""
    skinny = body.body_of(which)
    angles, target = _solved(skinny, seed, unit_2d)
    name = "ymca-recorded" + ("-unit2d" if unit_2d else "") \
        + ("" if seed == DEFAULT_SEED else f"-s{seed}")
    return Trajectory(angles.copy(), DEFAULT_DT_S, name, {"cartesian": target.copy()},
                      skinny.name)


@functools.lru_cache(maxsize=16)
def _solved(skinny: body.Body, seed: int, unit_2d: bool) -> tuple[np.ndarray, np.ndarray]:
    """The markers' IK (about 1 s), once per process and (body, seed, reading); the
    caller gets copies, so the cached arrays are never changed."""
    pts = markers(seed)[::DECIMATE]
    seg = np.stack([pts[:, :, 1] - pts[:, :, 0], pts[:, :, 2] - pts[:, :, 1]], axis=2)
    if unit_2d and skinny.planar:
        seg[..., 1] = 0.0  # the frontal projection, then normalized below
    seg = seg / np.linalg.norm(seg, axis=-1, keepdims=True)
    return solve_ik(seg[:, :, 0], seg[:, :, 1], skinny)
