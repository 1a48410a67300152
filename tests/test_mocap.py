"""Motion capture: ASF/AMC and BVH readers, retargeting by joint angles, bad files."""

import shutil
from pathlib import Path

import numpy as np
import pytest

from skinny_mj.errors import SkinnyInputError
from skinny_mj.plant import body
from skinny_mj.trajectories import ArmClip, load_movement, retarget
from skinny_mj.trajectories.asf_amc import load_asf_amc, parse_asf
from skinny_mj.trajectories.bvh import load_bvh, parse_bvh
from skinny_mj.trajectories.mocap_common import classify_arm_bone
from skinny_mj.trajectories.retarget import clip_continuous, solve_angles
from skinny_mj.trajectories.samples import SAMPLE_ASF

DATA = Path(__file__).parent / "data"
CMU = SAMPLE_ASF.parent  # the CMU clips shipped with the package
DOFS = (4, 8)


def _random_poses(dof, n, rng):
    lo, hi = body.body_of(dof).joint_ranges().T
    q = rng.uniform(lo + 0.1, hi - 0.1, size=(n, dof))
    if dof == 8:  # the rotation is only observable with a bent elbow
        q[:, [3, 7]] = rng.uniform(0.4, 2.5, size=(n, 2))
    return q


def _clip_from_poses(q, dof, rot, shift):
    """An ArmClip of Skinny itself in pose q (T, dof), seen in a rotated/shifted world."""
    pts = body.body_of(dof).arm_points(q)  # (T, 2, 3, 3) Skinny frame
    root = np.broadcast_to([0.0, 0.0, 0.9], (len(q), 3))

    def world(p):
        return p @ rot.T + shift

    return ArmClip(world(pts[:, :, 0]), world(pts[:, :, 1]), world(pts[:, :, 2]), world(root), 50.0)


# -- retargeting maths -----------------------------------------------------------------


@pytest.mark.parametrize("dof", DOFS)
def test_solve_angles_inverts_body_kinematics(dof):
    rng = np.random.default_rng(1)
    q = _random_poses(dof, 100, rng)
    seg = body.body_of(dof).segment_vectors(q)
    unit = seg / np.linalg.norm(seg, axis=-1, keepdims=True)
    for t in range(len(q)):  # frame by frame: no help from temporal continuity
        got, filled = solve_angles(unit[t : t + 1, :, 0], unit[t : t + 1, :, 1], dof)
        np.testing.assert_allclose(got[0], q[t], atol=1e-9)


@pytest.mark.parametrize("dof", DOFS)
def test_retarget_is_invariant_to_world_pose_and_segment_lengths(dof):
    rng = np.random.default_rng(2)
    # a smooth movement, so the low-pass filter leaves it nearly untouched
    key = _random_poses(dof, 2, rng)
    s = (1 - np.cos(np.linspace(0, np.pi, 100))) / 2
    q = key[0] + s[:, None] * (key[1] - key[0])
    a, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    rot = a * np.sign(np.linalg.det(a))  # a proper rotation: the capture's world axes
    clip = _clip_from_poses(q, dof, rot, shift=np.array([3.0, -1.0, 0.5]))
    # scale the forearms: retargeting uses directions only
    wrist = clip.elbow + 0.6 * (clip.wrist - clip.elbow)
    clip = ArmClip(clip.shoulder, clip.elbow, wrist, clip.root, 50.0)
    traj, report = retarget(clip, dof, cutoff_hz=6.0)
    assert len(traj) == 100 and report.clipped_samples == 0
    np.testing.assert_allclose(traj.angles, q, atol=np.deg2rad(0.5))


def test_clip_continuous_ramps_instead_of_jumping():
    # right abduction goes down, across the body, round and back in from the top
    lo, hi = body.body_of(4).joint_ranges()[0]
    path = np.concatenate([np.linspace(0.5, -0.5, 20), np.linspace(-0.5, -3.5, 20)])
    q = np.zeros((40, 4))
    q[:, 0], q[:, 1:] = path, 0.3
    out, excess = clip_continuous(q, 4)
    assert np.all((out[:, 0] >= lo) & (out[:, 0] <= hi))
    assert np.abs(np.diff(out[:, 0])).max() < np.pi / 10  # no jump from 0 to pi
    assert out[-1, 0] == pytest.approx(2 * np.pi - 3.5)  # came back in on the top side
    assert excess[:, 1:].max() == 0 and np.rad2deg(excess[:, 0].max()) <= 90.0 + 1e-9


# -- name matching -----------------------------------------------------------------------


@pytest.mark.parametrize(
    "name, expected",
    [
        ("lhumerus", ("left", "upper")),
        ("rradius", ("right", "forearm")),
        ("lwrist", ("left", "hand")),
        ("RightArm", ("right", "upper")),
        ("LeftForeArm", ("left", "forearm")),
        ("mixamorig:LeftHand", ("left", "hand")),
        ("rShldr", ("right", "upper")),
        ("upperarm_l", ("left", "upper")),
        ("LeftShoulder", None),
        ("lowerback", None),
        ("rtoes", None),
        ("Hips", None),
    ],
)
def test_classify_arm_bone(name, expected):
    assert classify_arm_bone(name) == expected


# -- the hand-made files ---------------------------------------------------------------------


@pytest.mark.parametrize("dof", DOFS)
def test_bvh_arms_recover_known_angles(dof):
    clip = load_bvh(DATA / "arms.bvh")
    assert clip.fps == pytest.approx(40.0) and len(clip) == 40
    traj, report = retarget(clip, dof)
    assert len(traj) == 49 and report.clipped_samples == 0  # 0.975 s at 50 Hz
    t = np.arange(49) * 0.02 / 0.975  # 0..1 over the clip, as the file was written
    abduction, elbow = np.deg2rad(30 + 120 * t), np.deg2rad(20 + 60 * t)
    cols = {4: ([0, 2], [1, 3]), 8: ([0, 4], [3, 7])}[dof]
    for c in cols[0]:
        np.testing.assert_allclose(traj.angles[:, c], abduction, atol=np.deg2rad(0.5))
    for c in cols[1]:
        np.testing.assert_allclose(traj.angles[:, c], elbow, atol=np.deg2rad(0.5))
    if dof == 8:  # arms move in the frontal plane: no flexion, no rotation
        assert np.abs(traj.angles[:, [1, 2, 5, 6]]).max() < np.deg2rad(0.5)


def test_bvh_structure():
    motion = parse_bvh(DATA / "arms.bvh")
    names = [j.name for j in motion.joints]
    assert names[0] == "Hips" and "LeftForeArm" in names and "LeftHand_end" in names
    assert motion.values.shape == (40, 6 + 3 * 10)


def test_asf_amc_tiny_skeleton_crlf_and_known_angles():
    assert b"\r\n" in (DATA / "tiny.asf").read_bytes()
    skeleton = parse_asf(DATA / "tiny.asf")
    assert skeleton.length_scale_m == pytest.approx(0.0254 / 0.45)
    assert skeleton.bones["lhumerus"].length_m == pytest.approx(5 * 0.0254 / 0.45)
    traj, report = load_movement(DATA / "tiny.amc", 4, asf=DATA / "tiny.asf")
    t = np.arange(len(traj)) * 0.02 * 120 / 23  # frame index / 23 -> 0..1
    # (0.2 s of capture: the 6 Hz filter's edge transients leave up to ~2 deg)
    np.testing.assert_allclose(traj.angles[:, 0], np.deg2rad(50 + 80 * t), atol=np.deg2rad(2))
    np.testing.assert_allclose(traj.angles[:, 3], np.deg2rad(20 + 50 * t), atol=np.deg2rad(2))
    assert report.source_frames == 24 and report.clipped_samples == 0


def test_asf_axis_conjugates_the_rotation(tmp_path):
    """A bone's rotation is C M C^-1: with axis (0, 90, 0) the AMC's rx turns the left
    upper arm about C x = -z (world), i.e. lowers it (C^-1 M C would raise it)."""
    asf = (DATA / "tiny.asf").read_text()
    head, _, tail = asf.partition("name lhumerus")
    tail = tail.replace("axis 0 0 0  XYZ", "axis 0 90 0  XYZ", 1)
    (tmp_path / "c.asf").write_text(head + "name lhumerus" + tail)
    frame = ["root 0 17 0 0 0 0", "lowerback 0 0 0", "lhumerus 30 0 0", "lradius 20"]
    frame += ["rhumerus 0 0 0", "rradius 0"]
    text = "\n".join(line for i in range(1, 13) for line in [str(i), *frame]) + "\n"
    (tmp_path / "c.amc").write_text(text)
    traj, _ = load_movement(tmp_path / "c.amc", 4, asf=tmp_path / "c.asf")
    np.testing.assert_allclose(np.rad2deg(traj.angles[:, 2]), 60.0, atol=1e-6)
    np.testing.assert_allclose(np.rad2deg(traj.angles[:, 0]), 90.0, atol=1e-6)


def test_amc_finds_its_subjects_skeleton_beside_it_and_no_other(tmp_path, caplog):
    shutil.copy(DATA / "tiny.amc", tmp_path / "86_02.amc")
    with pytest.raises(SkinnyInputError, match="no skeleton 86.asf of its subject:"):
        load_movement(tmp_path / "86_02.amc", 4)
    shutil.copy(DATA / "tiny.asf", tmp_path / "12.asf")  # another subject's: never taken
    with pytest.raises(SkinnyInputError, match="no skeleton 86.asf .*beside it: 12.asf.*--asf"):
        load_movement(tmp_path / "86_02.amc", 4)
    shutil.copy(DATA / "tiny.asf", tmp_path / "86.asf")
    with caplog.at_level("WARNING", logger="skinny_mj"):
        traj, _ = load_movement(tmp_path / "86_02.amc", 4)
    assert len(traj) == 10
    assert f"86_02.amc: skeleton {tmp_path / '86.asf'} (beside it" in caplog.text
    with caplog.at_level("INFO", logger="skinny_mj"):
        traj, _ = load_movement(tmp_path / "86_02.amc", 4, asf=tmp_path / "12.asf")  # given
    assert len(traj) == 10
    assert f"86_02.amc: skeleton {tmp_path / '12.asf'} (given)" in caplog.messages
    shutil.copy(DATA / "tiny.amc", tmp_path / "md_05.amc")  # the shipped clips' subject
    shutil.copy(DATA / "tiny.asf", tmp_path / "moderndance.asf")
    assert len(load_movement(tmp_path / "md_05.amc", 4)[0]) == 10
    caplog.clear()
    with caplog.at_level("INFO", logger="skinny_mj"):
        load_movement("md_03.amc", 4)  # a shipped clip: its own skeleton, said quietly
    assert [(r.levelname, r.getMessage().endswith("(the shipped clips')"))
            for r in caplog.records] in ([], [("INFO", True)])  # once per process


def test_fps_override_changes_duration():
    traj, report = load_movement(DATA / "tiny.amc", 4, asf=DATA / "tiny.asf", fps=60.0)
    assert report.source_fps == 60.0 and len(traj) == 20  # 23 / 60 s at 50 Hz


# -- malformed files ---------------------------------------------------------------------------


@pytest.mark.parametrize(
    "amc, asf, line, match",
    [
        ("bad_truncated.amc", "tiny.asf", 164, "truncated"),
        ("bad_count.amc", "tiny.asf", 7, "has 2 values"),
        ("bad_token.amc", "tiny.asf", 8, "not a number"),
        ("tiny.amc", "noarms.asf", None, "no arm bones"),
    ],
)
def test_bad_asf_amc(amc, asf, line, match):
    with pytest.raises(SkinnyInputError, match=match) as info:
        load_movement(DATA / amc, 4, asf=DATA / asf)
    assert info.value.line == line
    assert info.value.path.name == (asf if line is None else amc)


def test_bad_bvh_channel_count():
    with pytest.raises(SkinnyInputError, match="CHANNELS says 3") as info:
        load_movement(DATA / "bad_channels.bvh", 4)
    assert info.value.line == 17 and info.value.path.name == "bad_channels.bvh"


@pytest.mark.parametrize(
    "edit, match",
    [
        (lambda lines: lines[:-1], "frames"),  # fewer frames than announced
        (lambda lines: lines[:-1] + [lines[-1].rsplit(" ", 1)[0]], "expected 36 numbers"),
        (lambda lines: lines[:-1] + [" ".join(["nan"] + lines[-1].split()[1:])], "non-finite"),
        (lambda lines: [ln.replace("LeftArm", "LeftWing") for ln in lines], "no arm bones"),
    ],
)
def test_bad_bvh_motion(tmp_path, edit, match):
    lines = (DATA / "arms.bvh").read_text().splitlines()
    (tmp_path / "x.bvh").write_text("\n".join(edit(lines)) + "\n")
    with pytest.raises(SkinnyInputError, match=match) as info:
        load_movement(tmp_path / "x.bvh", 4)
    assert info.value.path.name == "x.bvh"


# -- the shared CMU clips -------------------------------------------------------------------------


@pytest.mark.parametrize("clip_name, frames", [("md_02", 1123), ("md_03", 434)])
@pytest.mark.parametrize("dof", DOFS)
def test_cmu_clips_retarget(clip_name, frames, dof):
    traj, report = load_movement(CMU / f"{clip_name}.amc", dof, asf=CMU / "moderndance.asf")
    assert report.source_frames == frames and report.source_fps == 120.0
    assert len(traj) == int((frames - 1) / 120 / 0.02 + 1e-9) + 1
    lo, hi = body.body_of(dof).joint_ranges().T
    assert np.all(np.isfinite(traj.angles))
    assert np.all((traj.angles >= lo) & (traj.angles <= hi))
    # plausible: a dancer is mostly inside Skinny's ranges; excess is bounded by the wrap
    # (2D elbows clip most: a forward-bending elbow's frontal projection is noise
    # around straight, and the negative half clips to 0)
    assert 0 < report.clipped_samples < 0.4 * traj.angles.size
    assert report.max_excess_deg <= 90.0 + 1e-6
    assert sum(report.clipped_per_dof.values()) == report.clipped_samples
    assert np.all(traj.max_speed_rad_s() < 40.0)  # rad/s, no jumps
    # the arms really move over a good part of their range
    assert np.all(np.ptp(traj.angles[:, [0, dof // 2]], axis=0) > np.deg2rad(90))


def test_cmu_skeleton_arms_and_torso():
    clip = load_asf_amc(CMU / "moderndance.asf", CMU / "md_03.amc")
    upper = np.linalg.norm(clip.elbow - clip.shoulder, axis=-1)
    fore = np.linalg.norm(clip.wrist - clip.elbow, axis=-1)
    # bone lengths are constant and in metres (humerus 5.4 units * 0.0564 m)
    np.testing.assert_allclose(upper, np.broadcast_to(upper[0], upper.shape), rtol=1e-9)
    assert 0.25 < upper[0, 0] < 0.35 and fore[0, 0] < upper[0, 0]  # the short forearms
    # y-up capture: the spine (root -> shoulders) mostly points up in the world
    spine = clip.shoulder.mean(axis=1) - clip.root
    assert np.median(spine[:, 1] / np.linalg.norm(spine, axis=1)) > 0.9


@pytest.mark.parametrize(
    "edit, line, match",
    [
        (lambda t: t.replace("lradius 20.0000", "lhand 20.0000", 1), 7, "unknown bone 'lhand'"),
        (lambda t: t.replace("lowerback 0 0 0\n", "", 1), 3, "truncated, missing lowerback"),
        (
            lambda t: t.replace("rradius -20.0000\n", "rradius -20.0000\nrradius 1\n", 1),
            10,
            "twice",
        ),
    ],
)
def test_bad_amc_variants(tmp_path, edit, line, match):
    text = (DATA / "tiny.amc").read_text()
    (tmp_path / "x.amc").write_text(edit(text))
    with pytest.raises(SkinnyInputError, match=match) as info:
        load_movement(tmp_path / "x.amc", 4, asf=DATA / "tiny.asf")
    assert info.value.line == line


def test_bad_asf_number(tmp_path):
    text = (DATA / "tiny.asf").read_text().replace("length 5", "length five", 1)
    (tmp_path / "x.asf").write_text(text)
    with pytest.raises(SkinnyInputError, match="not a number") as info:
        parse_asf(tmp_path / "x.asf")
    assert info.value.line == text.splitlines().index("     length five") + 1
