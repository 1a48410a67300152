"""Trajectory value, synthesized YMCA, derived movements and trajectory files."""

import subprocess
import sys

import numpy as np
import pytest

from skinny_mj.errors import SkinnyInputError
from skinny_mj.plant import body
from skinny_mj.trajectories import (
    Trajectory,
    excerpt,
    get,
    key_poses,
    letter_end_steps,
    load_movement,
    names,
    ymca,
)
from skinny_mj.trajectories.patterns import PATTERNS

DOFS = (4, 8)
MARGIN_RAD = np.deg2rad(2.0)
# about where a 1.75 m person's crown is
HEAD_TOP_Z_M = body.body_of("2d").shoulder_positions()[0, 2] + 0.30


def _elbow_cols(dof):
    return [i for i, n in enumerate(body.body_of(dof).dof_names) if n.endswith("elbow_flexion")]


# -- the Trajectory value ------------------------------------------------------------


@pytest.mark.parametrize(
    "angles",
    [np.zeros((10, 5)), np.zeros(4), np.zeros((0, 4)), np.full((3, 4), np.nan), [["a"] * 4]],
)
def test_trajectory_rejects_bad_angles(angles):
    with pytest.raises(SkinnyInputError):
        Trajectory(angles)


@pytest.mark.parametrize("dt", [0.0, -0.02, float("inf")])
def test_trajectory_rejects_bad_dt(dt):
    with pytest.raises(SkinnyInputError):
        Trajectory(np.zeros((3, 4)), dt)


def test_trajectory_is_immutable_and_basic_properties():
    t = Trajectory(np.zeros((50, 8)), 0.02, "still")
    assert len(t) == 50 and t.dof == 8 and t.dof_names == body.body_of(8).dof_names
    assert t.duration_s == pytest.approx(1.0)
    with pytest.raises(ValueError):
        t.angles[0, 0] = 1.0
    assert np.all(t.max_speed_rad_s() == 0)


@pytest.mark.parametrize("dof", DOFS)
@pytest.mark.parametrize("signals", ["joint", "cartesian"])
def test_position_signals_shape_and_range(dof, signals):
    sig = ymca(dof).position_signals(signals)
    assert sig.shape == (313, body.body_of(dof).n_signals(signals))
    assert np.all(np.abs(sig) <= 1.0 + 1e-12)


def test_velocities_and_max_speed():
    q = np.outer(np.arange(11) * 0.02, [1.0, -2.0, 0.5, 0.0])  # constant rates, rad/s
    t = Trajectory(q)
    np.testing.assert_allclose(t.velocities(), np.tile([1.0, -2.0, 0.5, 0.0], (10, 1)))
    np.testing.assert_allclose(t.max_speed_rad_s(), [1.0, 2.0, 0.5, 0.0])


def test_repeat_reverse_concat():
    y = ymca(4)
    assert len(y.repeat(5)) == 5 * 313
    np.testing.assert_array_equal(y.repeat(3).angles[313:626], y.angles)
    np.testing.assert_array_equal(y.reversed().angles, y.angles[::-1])
    both = y + y.reversed()
    assert len(both) == 626 and np.array_equal(both.angles[-1], y.angles[0])
    with pytest.raises(SkinnyInputError):
        y + ymca(8)
    with pytest.raises(SkinnyInputError):
        y.concat(Trajectory(y.angles, 0.01))
    for bad in (0, -1, 2.5, True):
        with pytest.raises(SkinnyInputError):
            y.repeat(bad)


@pytest.mark.parametrize("speed, steps", [(0.5, 626), (1.5, 209), (2.0, 156), (1.0, 313)])
def test_resample_lengths_endpoints_ranges(speed, steps):
    y = ymca(4)
    r = y.resample(speed)
    assert len(r) == steps
    np.testing.assert_allclose(r.angles[[0, -1]], y.angles[[0, -1]], atol=1e-12)
    lo, hi = body.body_of(4).joint_ranges().T
    assert np.all((r.angles >= lo) & (r.angles <= hi))
    # faster playback -> proportionally faster joints (same path)
    np.testing.assert_allclose(r.max_speed_rad_s(), speed * y.max_speed_rad_s(), rtol=0.05)


@pytest.mark.parametrize("speed", [0, -1, 10.5, float("nan"), "fast"])
def test_resample_rejects_bad_speed(speed):
    with pytest.raises(SkinnyInputError):
        ymca(4).resample(speed)


def test_clip_to_range_counts_samples():
    q = np.zeros((5, 4))
    q[1, 0], q[2, 1], q[2, 3] = -0.1, 4.0, 3.5
    clipped, n = Trajectory(q).clip_to_range()
    assert n == 3
    assert clipped.angles[1, 0] == 0.0 and clipped.angles[2, 1] == pytest.approx(np.pi)
    same, n0 = ymca(4).clip_to_range()
    assert n0 == 0 and np.array_equal(same.angles, ymca(4).angles)


def test_excerpt():
    part = excerpt(ymca(4), 1.0, 2.0)
    assert len(part) == 100
    np.testing.assert_array_equal(part.angles, ymca(4).angles[50:150])
    with pytest.raises(SkinnyInputError):
        excerpt(ymca(4), 5.0, 2.0)


# -- YMCA -----------------------------------------------------------------------------


@pytest.mark.parametrize("dof", DOFS)
def test_ymca_length_ranges_continuity(dof):
    y = ymca(dof)
    assert len(y) == 313 and y.dt == 0.02 and y.duration_s == pytest.approx(6.26)
    lo, hi = body.body_of(dof).joint_ranges().T
    for pose in key_poses(dof).values():
        assert np.all(pose >= lo + MARGIN_RAD) and np.all(pose <= hi - MARGIN_RAD)
    assert np.all((y.angles >= lo + MARGIN_RAD) & (y.angles <= hi - MARGIN_RAD))
    np.testing.assert_array_equal(y.angles[0], y.angles[-1])  # starts and ends neutral
    speed = y.velocities()
    assert np.abs(speed[[0, -1]]).max() == 0.0
    assert np.abs(np.diff(y.angles, axis=0)).max() < 0.2  # rad per step
    acc = np.diff(y.angles, 2, axis=0) / y.dt**2
    assert np.abs(acc).max() < 100.0  # rad/s^2: min-jerk, no kinks between segments
    assert np.all(y.max_speed_rad_s()[_elbow_cols(dof)] > 0.5)  # elbows really move


@pytest.mark.parametrize("dof", DOFS)
def test_ymca_letters_geometry(dof):
    poses = key_poses(dof)
    pts = {k: body.body_of(dof).arm_points(q) for k, q in poses.items()}  # (2 arms, 3 points, 3)
    shoulder = body.body_of("2d").shoulder_positions()
    # A: hands meet above the head
    wr = pts["A"][:, 2]
    assert np.linalg.norm(wr[0] - wr[1]) < 0.08
    assert np.all(wr[:, 2] > HEAD_TOP_Z_M) and np.all(wr[:, 2] < HEAD_TOP_Z_M + 0.2)
    # M: wrists on top of the head, elbows out beyond the shoulders
    wm, em = pts["M"][:, 2], pts["M"][:, 1]
    assert np.all(np.abs(wm[:, 0]) < 0.12) and np.all(np.abs(wm[:, 2] - HEAD_TOP_Z_M) < 0.06)
    assert np.all(np.abs(em[:, 0]) > np.abs(shoulder[:, 0]) + 0.05)
    # Y: a V, wrists well above and outside the shoulders
    wy = pts["Y"][:, 2]
    assert np.all(wy[:, 2] > shoulder[:, 2] + 0.3)
    assert np.all(np.abs(wy[:, 0]) > np.abs(shoulder[:, 0]) + 0.2)
    # symmetric letters are mirror images, C is not
    mirror = np.array([-1.0, 1.0, 1.0])
    for letter in ("Y", "M", "A"):
        np.testing.assert_allclose(pts[letter][1], pts[letter][0] * mirror, atol=1e-12)
    assert np.abs(pts["C"][1] - pts["C"][0] * mirror).max() > 0.2


def test_ymca_3d_uses_flexion_and_rotation():
    y = ymca(8)
    names8 = body.body_of(8).dof_names
    for part in ("shoulder_flexion", "shoulder_rotation"):
        cols = [i for i, n in enumerate(names8) if n.endswith(part)]
        assert np.abs(y.angles[:, cols]).max() > np.deg2rad(5)


# -- derived movements -----------------------------------------------------------------


def test_bimanual_patterns_are_regenerated_at_a_speed_not_resampled():
    slow = get("bimanual-phase90@0.5", 8)
    assert len(slow) - 1 == 2 * (len(get("bimanual-phase90", 8)) - 1)
    np.testing.assert_allclose(slow.angles[::2], get("bimanual-phase90", 8).angles, atol=1e-12)


def test_names_and_unknown_name():
    family = {"ymca", "y", "y-pure", "ym", "mirror-right", "mirror-left",
              "ymca-smooth", "ymca-recorded", "ymca-recorded-unit2d"}  # the recorded-like data
    assert set(names()) == family | {f"bimanual-{p}" for p in PATTERNS}
    with pytest.raises(SkinnyInputError, match="valid names: ymca"):
        get("macarena", 4)
    with pytest.raises(SkinnyInputError):
        get("ymca", 6)


@pytest.mark.parametrize("dof", DOFS)
def test_y_and_ym_go_there_and_back(dof):
    full = ymca(dof)
    for name, letter in (("y", "Y"), ("ym", "M")):
        t = get(name, dof)
        end = letter_end_steps()[letter]
        assert len(t) == 2 * end
        np.testing.assert_array_equal(t.angles[:end], full.angles[:end])
        np.testing.assert_array_equal(t.angles[end:], full.angles[:end][::-1])
        np.testing.assert_array_equal(t.angles[-1], t.angles[0])  # ends where it started
    assert letter_end_steps()["Y"] < letter_end_steps()["M"]


@pytest.mark.parametrize("dof", DOFS)
def test_y_pure_has_constant_elbows(dof):
    y, pure = get("y", dof), get("y-pure", dof)
    elbows = _elbow_cols(dof)
    others = [i for i in range(dof) if i not in elbows]
    assert np.ptp(y.angles[:, elbows], axis=0).max() > 0  # y has a little elbow motion
    assert np.ptp(pure.angles[:, elbows], axis=0).max() == 0.0
    np.testing.assert_array_equal(pure.angles[:, others], y.angles[:, others])


@pytest.mark.parametrize("dof", DOFS)
@pytest.mark.parametrize("side", ["right", "left"])
def test_mirrors_are_symmetric(dof, side):
    t = get(f"mirror-{side}", dof)
    pts = body.body_of(dof).arm_points(t.angles)  # (T, 2, 3, 3)
    np.testing.assert_allclose(pts[:, 1], pts[:, 0] * [-1.0, 1.0, 1.0], atol=1e-12)
    src = 0 if side == "right" else 1
    n_arm = dof // 2
    np.testing.assert_array_equal(
        t.angles[:, :n_arm], ymca(dof).angles[:, src * n_arm : (src + 1) * n_arm]
    )


def test_speed_suffix_and_reps():
    assert len(get("ymca@0.5", 4)) == 626
    assert len(get("ymca", 4, speed=0.5)) == 626
    assert len(get("ymca@1.5", 8, reps=5)) == 5 * 209
    assert len(get("y", 4, reps=10)) == 10 * len(get("y", 4))
    assert get("ymca@0.5", 4, reps=2).name == "ymca@0.5x2"
    for bad in ("ymca@0", "ymca@abc", "ymca@20"):
        with pytest.raises(SkinnyInputError):
            get(bad, 4)
    with pytest.raises(SkinnyInputError):
        get("ymca@0.5", 4, speed=2.0)


def test_load_movement_by_name_reports_no_clipping():
    traj, report = load_movement("ym@1.5", 8, reps=2)
    assert len(traj) == 2 * round(240 / 1.5)
    assert report.clipped_samples == 0 and report.max_excess_deg == 0.0
    with pytest.raises(SkinnyInputError, match="valid names"):
        load_movement("nope", 4)


# -- files ----------------------------------------------------------------------------


@pytest.mark.parametrize("dof", DOFS)
@pytest.mark.parametrize("suffix", [".npz", ".csv"])
def test_file_round_trip_is_exact(tmp_path, dof, suffix):
    rng = np.random.default_rng(7)
    lo, hi = body.body_of(dof).joint_ranges().T
    t = Trajectory(rng.uniform(lo, hi, size=(37, dof)), 0.02, "random")
    path = t.save(tmp_path / f"t{suffix}")
    back = Trajectory.load(path)
    assert np.array_equal(back.angles, t.angles)
    assert back.dt == t.dt and back.name == "random" and back.dof == dof
    loaded, report = load_movement(path, dof)
    assert np.array_equal(loaded.angles, t.angles) and report.clipped_samples == 0
    assert [p.name for p in tmp_path.iterdir()] == [f"t{suffix}"]  # no temp files left


def test_csv_without_comment_uses_defaults(tmp_path):
    p = tmp_path / "hand.csv"
    p.write_text(",".join(body.body_of(4).dof_names) + "\n0,0.1,0,0.1\n0.1,0.2,0.1,0.2\n")
    t = Trajectory.load(p)
    assert len(t) == 2 and t.dt == 0.02 and t.name == "hand"


def test_loaded_file_is_clipped_and_reported(tmp_path):
    q = np.full((4, 4), 0.5)
    q[2, 0] = -0.2
    path = Trajectory(q).save(tmp_path / "out.npz")
    traj, report = load_movement(path, 4)
    assert traj.angles[2, 0] == 0.0
    assert report.clipped_samples == 1
    assert report.max_excess_deg == pytest.approx(np.rad2deg(0.2))


_HEADER4 = ",".join(body.body_of(4).dof_names)


@pytest.mark.parametrize(
    "text, line, match",
    [
        (f"# dt=0.02\n{_HEADER4}\n0,0,0,0\n0,nan,0,0\n", 4, "NaN"),
        (f"{_HEADER4}\n0,0,0,0\n0,0,inf,0\n", 3, "NaN or infinite"),
        (f"{_HEADER4}\n0,0,0,0\n0,0,0\n", 3, "3 columns"),
        (f"{_HEADER4}\n0,0,x,0\n", 2, "not a number"),
        ("a,b,c,d\n0,0,0,0\n", 1, "header"),
        (",".join(body.body_of(4).dof_names[:3]) + "\n0,0,0\n", 1, "header"),
    ],
)
def test_bad_csv_names_file_and_line(tmp_path, text, line, match):
    p = tmp_path / "bad.csv"
    p.write_text(text)
    with pytest.raises(SkinnyInputError, match=match) as info:
        Trajectory.load(p)
    assert info.value.line == line and info.value.path == p
    assert str(info.value).startswith(f"{p}:{line}:")


def test_bad_npz_files(tmp_path):
    cases = {
        "shape.npz": dict(angles=np.zeros((5, 3)), meta=np.array("{}")),
        "nan.npz": dict(angles=np.full((5, 4), np.inf), meta=np.array("{}")),
        "nometa.npz": dict(angles=np.zeros((5, 4))),
        "badjson.npz": dict(angles=np.zeros((5, 4)), meta=np.array("{not json")),
        "pickle.npz": dict(angles=np.array([{"a": 1}], dtype=object), meta=np.array("{}")),
    }
    for name, arrays in cases.items():
        p = tmp_path / name
        np.savez(p, **arrays)
        with pytest.raises(SkinnyInputError) as info:
            Trajectory.load(p)
        assert info.value.path == p, name
    (tmp_path / "junk.npz").write_bytes(b"not a zip")
    with pytest.raises(SkinnyInputError):
        Trajectory.load(tmp_path / "junk.npz")
    # a zip entry needing a newer zip version than zipfile reads (NotImplementedError)
    data = bytearray(ymca(4).save(tmp_path / "v.npz").read_bytes())
    data[data.find(b"PK\x01\x02") + 6] = 64  # central directory: version needed, 6.4
    (tmp_path / "v.npz").write_bytes(bytes(data))
    with pytest.raises(SkinnyInputError, match="not a readable trajectory npz"):
        Trajectory.load(tmp_path / "v.npz")


def test_dof_mismatch_and_missing_file(tmp_path):
    p = ymca(4).save(tmp_path / "y.npz")
    with pytest.raises(SkinnyInputError, match="DOF mismatch"):
        Trajectory.load(p, 8)
    with pytest.raises(SkinnyInputError, match="DOF mismatch"):
        load_movement(p, 8)
    with pytest.raises(SkinnyInputError, match="no such"):
        load_movement(tmp_path / "missing.csv", 4)
    with pytest.raises(SkinnyInputError):
        ymca(4).save(tmp_path / "y.txt")


def test_package_imports_no_dm_control_and_mujoco_only_to_read_a_body():
    """Importing the movements loads no simulator; making one reads its body's MJCF (with
    MuJoCo's MjSpec, :mod:`skinny_mj.mjcf`), never dm_control."""
    code = (
        "import sys, skinny_mj.trajectories as t; "
        "assert not {'mujoco', 'dm_control'} & set(sys.modules), 'imported'; "
        "t.get('ymca', 8); t.load_movement('tests/data/arms.bvh', 4); "
        "bad = [m for m in ('dm_control',) if m in sys.modules]; "
        "sys.exit(1 if bad or 'skinny_mj.mjcf' not in sys.modules else 0)"
    )
    from pathlib import Path

    root = Path(__file__).resolve().parents[1]
    assert subprocess.run([sys.executable, "-c", code], cwd=root).returncode == 0
