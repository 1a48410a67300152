"""A second hidden set of bad inputs, each refused in one line with exit 2 (or, for the
machine, exit 1) and nothing written; the Python API and the gym envs raise a
:class:`SkinnyInputError` for the same. Each case was once a traceback, a silent
acceptance or a misleading message."""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pytest

from skinny_mj.cli.parser import main
from skinny_mj.errors import SkinnyInputError
from skinny_mj.trajectories import Trajectory, ymca

DATA = Path(__file__).parent / "data"


def _one_line(argv, capsys, code: int = 2) -> str:
    try:
        got = main(argv)
    except SystemExit as exc:  # argparse's usage error
        got = exc.code
    err = capsys.readouterr().err.strip()
    assert got == code, (got, err)
    assert err.count("\n") == 0 and "Traceback" not in err, err
    return err


def _shipped(name: str) -> Path:
    from skinny_mj.training.presets import model_path

    return model_path(name)


@pytest.fixture(scope="module")
def bad(tmp_path_factory) -> Path:
    """Damaged inputs (``{bad}`` in the argv below)."""
    root = tmp_path_factory.mktemp("hidden")
    Trajectory(ymca(4).angles[:40], name="t4").save(root / "t4.npz")
    Trajectory(ymca(4).angles[:40], name="t4").save(root / "t4.csv")
    with np.load(root / "t4.npz") as data:
        angles, meta = data["angles"], json.loads(str(data["meta"]))

    def npz(name: str, arr=angles, **changes) -> None:
        np.savez(root / name, angles=arr, meta=np.array(json.dumps({**meta, **changes})))

    npz("complex.npz", angles.astype(complex))
    npz("dofstr.npz", dof="4")
    npz("dtstr.npz", dt="x")
    np.savez(root / "pickled.npz", angles=np.array([object(), 1], dtype=object),
             meta=np.array(json.dumps(meta)))
    (root / "csv_as.npz").write_text((root / "t4.csv").read_text())
    csv = (root / "t4.csv").read_text()
    (root / "dtinf.csv").write_text(csv.replace("dt=0.02", "dt=inf"))
    # motion capture
    amc = (DATA / "tiny.amc").read_text()
    (root / "gap.amc").write_text(re.sub(r"^3\n", "7\n", amc, count=1, flags=re.M))
    (root / "tiny.asf").write_text((DATA / "tiny.asf").read_text())
    bvh = (DATA / "arms.bvh").read_text()
    head, motion = bvh.split("MOTION")
    lines = motion.strip().splitlines()
    (root / "frames.bvh").write_text(head + "MOTION\nFrames: 999\n" + "\n".join(lines[1:]) + "\n")
    (root / "notime.bvh").write_text(head + "MOTION\n" + lines[0] + "\n")
    # recordings
    (root / "empty.rrd").write_bytes(b"")
    (root / "short.rrd").write_bytes(b"RRF2\x00\x00")
    header = b"RRF2\x00)\x00\x00\x01\x02\x00\x00"  # then a message claiming 96 bytes, with 4
    (root / "cut.rrd").write_bytes(header + (1).to_bytes(8, "little")
                                   + (96).to_bytes(8, "little") + b"abcd")
    (root / "folder").mkdir()
    (root / "folder" / "run.rrd").write_bytes((root / "cut.rrd").read_bytes())
    chan = bvh.replace("CHANNELS 3 Zrotation Xrotation Yrotation",
                       "CHANNELS 9 Zrotation Xrotation Yrotation", 1)
    (root / "chan9.bvh").write_text(chan)
    (root / "ghost.amc").write_text(amc.replace("rhumerus", "ghostbone"))
    (root / "list.json").write_text("[1, 2]")
    (root / "trunc.json").write_text('{"esn.n_reservoir": 2')
    # JSON files that are no training config
    for name, data in [
        ("nested.json", {"esn": {"n_reservoir": 20}}),
        ("test_metrics.json", {"model": "m.npz", "seed": 0, "test": {"position_nrmse": 0.1}}),
        ("track_metrics.json", {"position_nrmse": 0.0, "max_speed_rad_s": [1.0] * 4}),
        ("bench.json", {"quick": True, "load_avg_start": [0.0, 0.0, 0.0]}),
        ("results.json", {"experiment": "paper-e", "n_runs": 2, "rows": []}),
    ]:
        (root / name).write_text(json.dumps(data))
    # models
    with np.load(_shipped("general-2d-joint")) as data:
        arrays = dict(data)
    w = arrays["W_out"].copy()
    w.flat[0] = np.nan
    np.savez(root / "nan_w.npz", **{**arrays, "W_out": w})
    np.savez(root / "complex_w.npz", **{**arrays, "W_out": arrays["W_out"].astype(complex)})
    np.savez(root / "object_w.npz", **{**arrays, "W_out": arrays["W_out"].astype(object)})
    return root


LONG = "x" * 300


@pytest.mark.parametrize("argv,culprit", [
    # movement files
    (["track", "--trajectory", "{bad}/complex.npz"], "complex.npz: angles must be real "
                                                     "numbers, got dtype complex128"),
    (["track", "--trajectory", "{bad}/dofstr.npz"], "dofstr.npz: meta dof must be a whole "
                                                    "number, got '4'"),
    (["track", "--trajectory", "{bad}/dtstr.npz"], "dt must be a finite number > 0 s, got 'x'"),
    (["track", "--trajectory", "{bad}/dtinf.csv"], "dt must be a finite number > 0 s, got 'inf'"),
    (["track", "--trajectory", "{bad}/csv_as.npz"], "csv_as.npz: not a readable trajectory "
                                                    "npz (not an .npz archive)"),
    (["track", "--trajectory", "{bad}/pickled.npz"], "pickled.npz: not a readable trajectory "
                                                     "npz (it holds pickled Python objects"),
    (["track", "--trajectory", "{bad}/gap.amc", "--asf", "{bad}/tiny.asf"],
     "gap.amc:17: frame 7 follows frame 2"),
    (["track", "--trajectory", "{bad}/frames.bvh"], "MOTION says 999 frames, the file has 40"),
    (["track", "--trajectory", "{bad}/notime.bvh"], "MOTION has no 'Frame Time:' line"),
    (["track", "--trajectory", "{bad}/t4.csv@start=1e308"], "excerpt 1e+308 s to the end is "
                                                            "outside 't4'"),
    (["track", "--trajectory", "{bad}/t4.csv@start=0,duration=1e308"], "excerpt 0 s + "
                                                                       "1e+308 s is outside"),
    # numbers and names the file system or the plant cannot take
    (["track", "--sensor-noise", "1e308"], "sensor noise must be in [0, 10]"),
    (["train", "plant.sensor_noise=1e308"], "sensor noise must be in [0, 10]"),
    (["sweep", "method.epochs=1,,2"], "method.epochs: an empty value in '1,,2'"),
    (["sweep", "method.epochs=1", "method.epochs=2"], "method.epochs is given twice"),
    (["sweep", "esn.spectral_radius=0.5", "--runs", "nan"], "--runs: must be a whole number "
                                                             ">= 1, got 'nan'"),
    (["experiment", "paper-e", "--workers", "x"], "--workers: must be a whole number >= 1, "
                                                   "got 'x'"),
    (["render", "--width", "1e9"], "--width: must be a whole number >= 1, got '1e9'"),
    # config files of the wrong kind
    (["train", "--config", "{bad}/nested.json"], "nested.json: config keys are flat and "
                                                 "dotted: write \"esn.n_reservoir\""),
    (["train", "--config", "{bad}/test_metrics.json"], "this is a `skinny test` run's "
                                                       "metrics.json, which holds no training"),
    (["train", "--config", "{bad}/track_metrics.json"], "a `skinny track` run's metrics.json"),
    (["train", "--config", "{bad}/bench.json"], "this is `skinny bench`'s results"),
    (["sweep", "method.epochs=1,2", "--config", "{bad}/results.json"], "a sweep's results.json"),
    # already refused in one line when probed: kept as guards
    (["track", "--trajectory", "{bad}/chan9.bvh"], "chan9.bvh:9: CHANNELS says 9 but names 3"),
    (["track", "--trajectory", "{bad}/ghost.amc", "--asf", "{bad}/tiny.asf"],
     "unknown bone 'ghostbone' (not in tiny.asf)"),
    (["track", "--trajectory", "set:set:ymca+y"], "bad training set 'set:set:ymca+y'"),
    (["track", "--trajectory", "babble:duration=-1"], "babble duration must be > 0 s"),
    (["track", "--trajectory", "babble:bogus=1"], "bad babble name 'babble:bogus=1'"),
    (["trajectory", "export", "ymca"], "o: export writes .npz or .csv"),  # --out o: no suffix
    (["sweep", "method.epochs="], "a sweep axis is KEY=VALUE[,VALUE...], got 'method.epochs='"),
    (["train", "--config", "{bad}/list.json"], "list.json: a config file holds a JSON object"),
    (["train", "--config", "{bad}/trunc.json"], "trunc.json: not a JSON config file"),
    (["train", "esn.n_reservoir=abc"], "esn.n_reservoir must be a whole number, got 'abc'"),
    (["train", "method.beta=[1]"], "method.beta must be a number, got '[1]'"),
    (["train", "esn.a.b=1"], "unknown config key 'esn.a.b'"),
    (["train", "x="], "unknown config key 'x'"),
    (["train", "--beta", "-0"], "beta must be in (0, 1], got -0.0"),
    (["train", "--speed", "1e308"], "speed must be in (0, 10], got 1e+308"),
    # models for `skinny test`
    (["test", "--model", "{bad}/t4.csv"], "t4.csv: not a model written by `skinny train` "
                                          "(not an .npz archive)"),
    (["test", "--model", "{bad}/nan_w.npz"], "nan_w.npz: the weights W_out hold nan at"),
    (["test", "--model", "{bad}/complex_w.npz"], "the weights W_out are complex128"),
    (["test", "--model", "{bad}/object_w.npz"], "object_w.npz: not a model written by `skinny "
                                                "train` (it holds pickled Python objects"),
])
def test_cli_refuses_in_one_line_naming_the_culprit(argv, culprit, bad, capsys, tmp_path,
                                                    monkeypatch):
    monkeypatch.chdir(tmp_path)
    argv = [a.format(bad=bad) for a in argv]
    err = _one_line([*argv, "--out", str(tmp_path / "o")], capsys)
    assert culprit in err, err
    assert "allow_pickle" not in err  # numpy's advice to unpickle is not ours to give
    assert list(tmp_path.iterdir()) == []  # nothing written


@pytest.mark.parametrize("argv", [
    ["train", "--out", "{tmp}/" + LONG],
    ["track", "--out", "{tmp}/" + LONG + "/run"],
    ["trajectory", "export", "ymca", "--out", "{tmp}/" + LONG + ".csv"],
    ["bench", "--quick", "--out", "{tmp}/" + LONG + ".json"],
])
def test_an_out_name_too_long_is_bad_input_not_the_machine(argv, capsys, tmp_path):
    err = _one_line([a.format(tmp=tmp_path) for a in argv], capsys)
    assert "--out: the name xxxx" in err and "is 30" in err and "bytes, more than the" in err
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("command", ["demo", "track", "train", "test --model m.npz",
                                     "trajectory export ymca", "experiment paper-e", "sweep x=1",
                                     "bench", "render"])
def test_an_empty_out_is_refused_not_taken_as_here(command, capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    err = _one_line([*command.split(), "--out", ""], capsys)
    assert "--out: '' names no file or folder" in err
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("argv", [
    ["track", "--out", "a\0b"],
    ["trajectory", "export", "ymca", "--out", "a\0b.csv"],
    ["train", "--config", "c\0.json"],
])
def test_a_nul_byte_in_a_name_is_one_line(argv, capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    err = _one_line(argv, capsys)
    assert "NUL byte" in err or "no such config file" in err
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("name,says", [
    ("empty.rrd", "empty.rrd: empty"),
    ("short.rrd", "short.rrd: not a rerun recording (no RRF header)"),
    ("cut.rrd", "cut.rrd: truncated recording: a message runs past the end of the file"),
    ("folder", "run.rrd: truncated recording"),
])
def test_view_refuses_an_empty_or_truncated_recording(name, says, bad, capsys):
    err = _one_line(["view", str(bad / name)], capsys)
    assert says in err


def test_view_web_refuses_one_port_for_both_servers(bad, capsys):
    err = _one_line(["view", str(bad / "t4.npz"), "--web", "--web-port", "9876", "--grpc-port",
                     "9876"], capsys)
    assert "--web-port 9876 and --grpc-port 9876 are one port" in err


def test_render_writes_only_png(capsys, tmp_path, monkeypatch):
    monkeypatch.setenv("MUJOCO_GL", "egl")  # past the rendering check; nothing is drawn
    for name in ("r.jpg", "r"):
        err = _one_line(["render", "--out", str(tmp_path / name)], capsys)
        assert "render writes a PNG: give a name ending in .png" in err
    assert list(tmp_path.iterdir()) == []


def test_a_bogus_mujoco_gl_is_one_line_exit_1(capsys, tmp_path, monkeypatch):
    monkeypatch.setenv("MUJOCO_GL", "bogus")
    err = _one_line(["track", "--out", str(tmp_path / "o")], capsys, code=1)
    assert "MUJOCO_GL='bogus' is not a rendering backend" in err
    assert list(tmp_path.iterdir()) == []


def test_an_empty_mujoco_gl_is_taken_as_unset(monkeypatch, capsys):
    monkeypatch.setenv("MUJOCO_GL", "")
    assert main(["trajectory", "list"]) == 0
    import os

    assert os.environ["MUJOCO_GL"] == "disabled"  # not glfw, which warns without a display
    capsys.readouterr()


def test_a_speed_for_no_memory_says_its_steps_in_a_readable_number(capsys, tmp_path):
    from skinny_mj import preflight

    if preflight.available_bytes() is None:
        pytest.skip("this system does not say how much memory is free")
    err = _one_line(["trajectory", "export", "ymca@1e-300", "--out",
                     str(tmp_path / "x.npz")], capsys)
    assert "3.13e+302 steps of ymca" in err and len(err) < 300


# -- the Python API and the gym envs ------------------------------------------------------------
def _gym(**kwargs):
    pytest.importorskip("gymnasium")
    from skinny_mj.gym.env import SkinnyEnv

    return SkinnyEnv(trajectory="ymca", **kwargs)


def _stepped(action):
    env = _gym()
    env.reset(seed=0)
    return env.step(action)


def _vector(num_envs=2, seed=None):
    pytest.importorskip("gymnasium")
    from skinny_mj.gym.vector import SkinnyVectorEnv

    env = SkinnyVectorEnv(num_envs=num_envs, trajectory="ymca")
    return env.reset(seed=seed)


@pytest.mark.parametrize("call,culprit", [
    (lambda: __import__("skinny_mj").load(trajectory=np.zeros((5, 4)) + 1j),
     "angles must be real numbers, got complex128"),
    (lambda: __import__("skinny_mj").load(sensor_noise=1e308), "sensor_noise must be in [0, 10]"),
    (lambda: Trajectory(np.zeros((3, 4)), dt=True), "dt must be a finite number > 0 s"),
    (lambda: Trajectory(np.zeros((3, 4)), dt="x"), "dt must be a finite number > 0 s"),
    (lambda: __import__("skinny_mj").load(speed_factor=float("inf")),
     "speed_factor must be a finite number > 0, got inf"),
    (lambda: Trajectory(np.zeros((3, 4))).save("x\0.csv"), "holds a NUL byte"),
    (lambda: _gym().reset(seed=-1), "seed must be None or a whole number >= 0, got -1"),
    (lambda: _gym().reset(seed=1.5), "seed must be None or a whole number >= 0, got 1.5"),
    (lambda: _stepped(np.zeros((1, 4))), "action must be (4,) numbers, got shape (1, 4)"),
    (lambda: _stepped(np.zeros(3)), "action must be (4,) numbers, got shape (3,)"),
    (lambda: _stepped("a"), "action must be (4,) numbers"),
    (lambda: _stepped(np.zeros(4) + 1j), "real numbers, got complex"),
    (lambda: _gym(render_mode="bogus"), "render_mode must be None or 'rgb_array'"),
    (lambda: _gym(width=0), "width must be a whole number of pixels >= 1, got 0"),
    (lambda: _vector(num_envs=0), "num_envs must be a whole number >= 1, got 0"),
    (lambda: _vector(seed=-1), "seed must be None or a whole number >= 0, got -1"),
    (lambda: _vector(seed=[0, -1]), "seed must be None or a whole number >= 0, got -1"),
    (lambda: _vector(seed=[1]), "need 2 int seeds, got [1]"),
    (lambda: _vector(num_envs=2.5), "num_envs must be a whole number >= 1, got 2.5"),
])
def test_the_api_and_gym_raise_a_skinny_input_error(call, culprit):
    with pytest.raises(SkinnyInputError) as caught:
        call()
    assert isinstance(caught.value, ValueError) and culprit in str(caught.value)


def test_valid_gym_calls_still_work():
    env = _gym()
    env.reset(seed=0)
    env.step([0.1, 0.0, 0.0, 0.0])  # a list of 4
    env.step(np.full(4, 5.0, dtype=np.float32))  # clipped by the task
    obs, _ = _vector(seed=[0, 1])
    assert obs.shape[0] == 2


@pytest.mark.parametrize("argv,says", [
    (["experiment", "paper-d", "--quick"], "holds a sweep of experiment 'paper-e', not "
                                           "'paper-d'; resume it with `skinny experiment "
                                           "paper-e --resume`"),
    (["experiment", "paper-e", "--quick"], "holds a different sweep of 'paper-e': its config"),
])
def test_resume_names_the_study_or_what_differs(argv, says, capsys, tmp_path):
    out = tmp_path / "sw"
    out.mkdir()
    config = {"experiment": "paper-e", "config": {}, "rows": [], "base_seed": 0}
    (out / "config.json").write_text(json.dumps(config))
    err = _one_line([*argv, "--resume", "--workers", "1", "--out", str(out)], capsys)
    assert says in err
    assert json.loads((out / "config.json").read_text()) == config  # untouched
    assert sorted(p.name for p in out.iterdir()) == ["config.json"]
