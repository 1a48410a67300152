"""Recordings (rerun .rrd) and PNG figures: contents read back, determinism, validity."""

from __future__ import annotations

import shutil
import subprocess

import numpy as np
import pytest

from skinny_mj.errors import SkinnyInputError
from skinny_mj.plant import body
from skinny_mj.recording import read_recording_series, recording_entities, write_recording

RERUN_CLI = shutil.which("rerun")


def _run(n_steps: int = 60, dof: int = 4, signals: str = "cartesian", seed: int = 0,
         curves: bool = True) -> dict:
    rng = np.random.default_rng(seed)
    lo, hi = body.body_of(dof).joint_ranges().T
    t = np.linspace(0.0, 1.0, n_steps)[:, None]
    desired = lo + (hi - lo) * (0.5 + 0.4 * np.sin(2 * np.pi * t * np.arange(1, dof + 1)))
    actual = np.clip(desired + 0.02 * rng.standard_normal(desired.shape), lo, hi)
    n_sig = body.body_of(dof).n_signals(signals)
    kw = dict(
        dt=0.02, which=dof, dof_names=body.body_of(dof).dof_names,
        signal_names=body.body_of(dof).signal_names(signals),
        desired_angles=desired, actual_angles=actual,
        commands=rng.uniform(-1, 1, (n_steps - 1, dof)),
        desired_signals=body.body_of(dof).position_signals(desired, signals),
        actual_signals=body.body_of(dof).position_signals(actual, signals),
        sensed_signals=body.body_of(dof).position_signals(actual, signals)
        + 0.01 * rng.standard_normal((n_steps, n_sig)),
        title="unit test", metadata={"seed": seed, "position_nrmse": 0.01},
    )
    if curves:
        kw["curves"] = {"position_nrmse": np.linspace(0.5, 0.05, 10),
                        "motor_nrmse": rng.uniform(0, 1, (3, 10))}
    return kw


@pytest.mark.parametrize("dof", [4, 8])
def test_series_round_trip_through_rerun_reader(tmp_path, dof):
    kw = _run(dof=dof)
    path = write_recording(tmp_path / "run.rrd", **kw)
    names = body.body_of(dof).dof_names
    for i, name in enumerate(names):
        side, joint = name.split("_", 1)
        base = f"/skinny/{side}/{joint}"
        np.testing.assert_allclose(read_recording_series(path, f"{base}/desired"),
                                   np.degrees(kw["desired_angles"][:, i]))
        np.testing.assert_allclose(read_recording_series(path, f"{base}/actual"),
                                   np.degrees(kw["actual_angles"][:, i]))
        np.testing.assert_allclose(read_recording_series(path, f"{base}/command"),
                                   kw["commands"][:, i])
    sig = kw["signal_names"][-1]
    np.testing.assert_allclose(read_recording_series(path, f"/signals/{sig}/sensed"),
                               kw["sensed_signals"][:, -1])
    np.testing.assert_allclose(read_recording_series(path, "/curves/position_nrmse"),
                               kw["curves"]["position_nrmse"])
    np.testing.assert_allclose(read_recording_series(path, "/curves/motor_nrmse/run_2"),
                               kw["curves"]["motor_nrmse"][2])


def test_recording_holds_pose_info_and_a_blueprint(tmp_path):
    from rerun.chunk import RrdReader

    path = write_recording(tmp_path / "run.rrd", **_run())
    entities = recording_entities(path)
    for entity in ("/pose/desired", "/pose/actual", "/pose/torso", "/pose/head", "/info"):
        assert entity in entities
    reader = RrdReader(str(path))
    blueprint_entities = {c.entity_path for c in reader.stream(store=reader.blueprints()[0])}
    assert "/viewport" in blueprint_entities
    assert any(e.startswith("/view/") for e in blueprint_entities)
    # the pose has one row per step and two strips (arms) of three points each
    rows = [c for c in reader.stream() if c.entity_path == "/pose/actual" and not c.is_static]
    assert sum(c.num_rows for c in rows) == 60


def test_same_inputs_same_recording_and_different_inputs_differ(tmp_path):
    from rerun.chunk import RrdReader

    a = write_recording(tmp_path / "a.rrd", **_run(seed=1))
    b = write_recording(tmp_path / "b.rrd", **_run(seed=1))
    c = write_recording(tmp_path / "c.rrd", **_run(seed=2))
    rid = [RrdReader(str(p)).recordings()[0].recording_id for p in (a, b, c)]
    assert rid[0] == rid[1] != rid[2]
    if RERUN_CLI is None:
        pytest.skip("rerun CLI not on PATH")
    same = subprocess.run([RERUN_CLI, "rrd", "compare", str(a), str(b)], capture_output=True)
    assert same.returncode == 0, same.stderr.decode()[-2000:]
    differ = subprocess.run([RERUN_CLI, "rrd", "compare", str(a), str(c)], capture_output=True)
    assert differ.returncode != 0


@pytest.mark.skipif(RERUN_CLI is None, reason="rerun CLI not on PATH")
def test_rerun_rrd_verify_passes(tmp_path):
    path = write_recording(tmp_path / "run.rrd", **_run(dof=8, curves=False))
    out = subprocess.run([RERUN_CLI, "rrd", "verify", str(path)], capture_output=True)
    assert out.returncode == 0, out.stderr.decode()[-2000:]


def test_bad_shapes_raise_and_write_nothing(tmp_path):
    kw = _run()
    kw["commands"] = kw["commands"][:-1]
    with pytest.raises(SkinnyInputError, match="commands"):
        write_recording(tmp_path / "run.rrd", **kw)
    kw = _run()
    kw["actual_angles"] = kw["actual_angles"].copy()
    kw["actual_angles"][3, 1] = np.nan
    with pytest.raises(SkinnyInputError, match="NaN"):
        write_recording(tmp_path / "run.rrd", **kw)
    assert list(tmp_path.iterdir()) == []


def test_reading_a_missing_series_is_a_clear_error(tmp_path):
    path = write_recording(tmp_path / "run.rrd", **_run(curves=False))
    with pytest.raises(SkinnyInputError, match="no scalar series"):
        read_recording_series(path, "/skinny/right/nothing/actual")


# ---------------------------------------------------------------- figures


def _assert_png_has_content(path):
    import matplotlib.image as mpimg

    image = mpimg.imread(path)
    assert image.ndim == 3 and image.shape[0] > 100 and image.shape[1] > 100
    gray = image[..., :3].mean(axis=-1)
    assert (gray < 0.9).mean() > 0.005  # ink, not a blank page
    assert gray.std() > 0.02


def test_figures_are_written_and_not_blank(tmp_path):
    from skinny_mj import plots

    rng = np.random.default_rng(0)
    p1 = plots.learning_curve_png(tmp_path / "curve.png",
                                  {"orig": rng.uniform(0, 1, (5, 10)),
                                   "new": np.linspace(0.4, 0.02, 10)}, "NRMSE")
    p2 = plots.boxplot_png(tmp_path / "box.png",
                           {"exp1": list(rng.uniform(0.3, 0.5, 20)),
                            "exp2": list(rng.uniform(0.0, 0.2, 20))},
                           "position NRMSE", reference={"exp1": 0.4, "exp2": 0.1088})
    p3 = plots.line_sweep_png(tmp_path / "sweep.png", [50, 100, 200, 400],
                              {"orig": rng.uniform(0, 1, (5, 4))}, "N", "NRMSE", log_x=True)
    p4 = plots.heatmap_png(tmp_path / "heat.png", rng.uniform(0, 1, (3, 4)),
                           ["a", "b", "c"], ["w", "x", "y", "z"], "test")
    for p in (p1, p2, p3, p4):
        _assert_png_has_content(p)
    assert sorted(q.name for q in tmp_path.iterdir()) == \
        ["box.png", "curve.png", "heat.png", "sweep.png"]


def test_figure_input_errors(tmp_path):
    from skinny_mj import plots

    with pytest.raises(SkinnyInputError):
        plots.heatmap_png(tmp_path / "h.png", np.zeros((2, 2)), ["a"], ["b", "c"])
    with pytest.raises(SkinnyInputError):
        plots.line_sweep_png(tmp_path / "s.png", [1, 2, 3], {"a": np.zeros((2, 4))}, "x", "y")
    assert list(tmp_path.iterdir()) == []
