"""The ``skinny`` command line as a user runs it: outputs, exit codes, one-line errors."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from skinny_mj.cli.parser import main
from skinny_mj.trajectories.samples import SAMPLE_ASF

CMU = SAMPLE_ASF.parent  # the CMU clips shipped with the package
DATA = Path(__file__).parent / "data"


def run_cli(*argv: str) -> subprocess.CompletedProcess:
    """Run the installed console script as a user would (new process, no stdin)."""
    env = {**os.environ, "MUJOCO_GL": "disabled", "OMP_NUM_THREADS": "1"}
    return subprocess.run(["skinny", *argv], capture_output=True, text=True, env=env,
                          stdin=subprocess.DEVNULL, timeout=600)


@pytest.mark.parametrize("command", ["demo", "track", "train", "test", "trajectory", "render",
                                     "experiment"])
def test_every_command_has_help(command, capsys):
    with pytest.raises(SystemExit) as exit_info:
        main([command, "--help"])
    assert exit_info.value.code == 0
    assert "usage: skinny" in capsys.readouterr().out


def test_version_prints_the_installed_distributions(capsys):
    from importlib.metadata import version

    with pytest.raises(SystemExit) as exit_info:
        main(["--version"])
    assert exit_info.value.code == 0
    assert capsys.readouterr().out == f"skinny {version('skinny-mj')}\n"


@pytest.mark.parametrize("dof", [4, 8])
def test_track_ymca_writes_metrics_and_recording(dof, tmp_path, capsys):
    out = tmp_path / "track"
    assert main(["track", "--dof", str(dof), "--out", str(out)]) == 0
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["dof"] == dof and metrics["steps"] == 313 and metrics["trajectory"] == "ymca"
    assert metrics["clipped_samples"] == 0
    assert 0.0 <= metrics["position_nrmse"] <= 0.01
    assert (out / "run.rrd").stat().st_size > 10_000
    assert "position NRMSE" in capsys.readouterr().out


def test_track_real_motion_capture_3d(tmp_path):
    out = tmp_path / "mocap"
    assert main(["track", "--dof", "8", "--trajectory", str(CMU / "md_03.amc"),
                 "--asf", str(CMU / "moderndance.asf"), "--out", str(out)]) == 0
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["steps"] == 181  # 434 frames at 120 Hz -> 50 Hz
    assert metrics["clipped_samples"] == metrics["retarget"]["clipped_samples"] > 0
    assert metrics["position_nrmse"] <= 0.01


@pytest.mark.parametrize("argv, needle", [
    (["track", "--trajectory", "no-such-movement"], "unknown movement"),
    (["track", "--trajectory", str(DATA / "bad_truncated.amc"),
      "--asf", str(DATA / "tiny.asf")], "bad_truncated.amc"),
    (["track", "--trajectory", "ymca", "--speed", "-1"], "speed"),
    (["train", "--beta", "1.5"], "--beta"),
    (["train", "--noise", "-0.1"], "--noise"),
    (["train", "--reservoir", "0"], "--reservoir"),
    (["test", "--model", "missing.npz"], "missing.npz"),
    (["train", "--dof", "4", "--body", "3d"], "--dof) is the 2d body and plant.body=3d"),
    (["train", "--body", "4d"], "unknown body '4d'; the bodies: 2d, 3d, 2d-torque, 3d-torque"),
    (["track", "--body", "2d-torque"], "the 2d-torque body is torque-driven"),
])
def test_bad_input_is_one_line_exit_2_and_writes_nothing(argv, needle, tmp_path):
    out = tmp_path / "out"
    result = run_cli(*argv, "--out", str(out))
    assert result.returncode == 2, result.stderr
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and needle in lines[0] and "Traceback" not in result.stderr
    assert not out.exists() or not any(out.iterdir())


def test_train_then_test_a_saved_model(tmp_path, capsys):
    trained = tmp_path / "train"
    assert main(["train", "--epochs", "2", "--seed", "3", "--out", str(trained)]) == 0
    metrics = json.loads((trained / "metrics.json").read_text())
    assert metrics["failed"] is False and metrics["seed"] == 3
    assert len(metrics["train"]["position_nrmse"]) == 2
    for key in ("position_nrmse", "motor_nrmse"):
        assert 0.0 < metrics["test"][key] < 1.0
    for name in ("model.npz", "run.rrd", "learning_curve.png"):
        assert (trained / name).stat().st_size > 0
    with np.load(trained / "model.npz", allow_pickle=False) as model:  # no pickle inside
        assert json.loads(str(model["metadata"]))["dof"] == 4

    tested = tmp_path / "test"
    assert main(["test", "--model", str(trained / "model.npz"), "--trajectory", "ymca",
                 "--seed", "3", "--out", str(tested)]) == 0
    again = json.loads((tested / "metrics.json").read_text())
    # Same network, same movement, same plant seed: the test is reproduced exactly.
    assert again["test"] == metrics["test"]

    other = tmp_path / "test-ym"
    assert main(["test", "--model", str(trained / "model.npz"), "--trajectory", "ym",
                 "--out", str(other)]) == 0
    assert json.loads((other / "metrics.json").read_text())["steps"] == 240


def test_diverging_network_is_recorded_as_failed(tmp_path):
    out = tmp_path / "diverged"
    result = run_cli("train", "--spectral-radius", "100", "--epochs", "2", "--out", str(out))
    assert result.returncode == 1
    assert "failed" in result.stderr and "Traceback" not in result.stderr
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["failed"] is True and "saturated" in metrics["fail_reason"]
    assert metrics["test"] == {"position_nrmse": None, "motor_nrmse": None}
    assert not (out / "model.npz").exists()


@pytest.mark.parametrize("suffix", [".npz", ".csv"])
def test_trajectory_export_round_trips(suffix, tmp_path, capsys):
    from skinny_mj.trajectories import Trajectory, get

    path = tmp_path / f"ym{suffix}"
    assert main(["trajectory", "export", "ym", "--dof", "8", "--out", str(path)]) == 0
    loaded = Trajectory.load(path)
    np.testing.assert_allclose(loaded.angles, get("ym", 8).angles, rtol=0, atol=1e-12)
    assert main(["trajectory", "list"]) == 0
    assert "y-pure" in capsys.readouterr().out


def test_demo_prints_the_table_and_where_the_recording_is(tmp_path):
    out = tmp_path / "demo"
    result = run_cli("demo", "--out", str(out))
    assert result.returncode == 0, result.stderr
    assert "test position NRMSE" in result.stdout and "paper" in result.stdout
    assert f"skinny view {out}" in result.stdout
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["config"]["method"] == "new" and metrics["config"]["learning_cycles"] == 3
    assert metrics["test"]["position_nrmse"] < 0.1


def test_render_writes_a_picture(tmp_path):
    pytest.importorskip("OpenGL")
    env = {**os.environ, "MUJOCO_GL": "egl"}
    probe = subprocess.run([sys.executable, "-c", "import mujoco.egl; mujoco.egl.GLContext(8, 8)"],
                           capture_output=True, env=env, timeout=120)
    if probe.returncode != 0:
        pytest.skip("no EGL on this machine (MUJOCO_GL=egl cannot make a context)")
    out = tmp_path / "skinny.png"
    result = subprocess.run(["skinny", "render", "--dof", "8", "--trajectory", "ymca",
                             "--frame", "150", "--width", "160", "--height", "120",
                             "--out", str(out)], capture_output=True, text=True, env=env,
                            timeout=300)
    assert result.returncode == 0, result.stderr
    import matplotlib.image

    image = matplotlib.image.imread(out)
    assert image.shape[:2] == (120, 160) and image.std() > 0.01


def test_train_true_target_architecture_3d(tmp_path):
    out = tmp_path / "tt"
    assert main(["train", "--dof", "8", "--method", "true-target", "--beta", "1",
                 "--out", str(out)]) == 0
    metrics = json.loads((out / "metrics.json").read_text())
    # Teacher-forced training fits its targets far better than the closed loop tests.
    assert metrics["train"]["motor_nrmse"] < metrics["test"]["motor_nrmse"]
    assert metrics["config"]["method"] == "true-target"
    assert (out / "run.rrd").is_file() and (out / "model.npz").is_file()
    assert not (out / "learning_curve.png").exists()  # no epochs, no curve


def test_a_reader_that_stops_early_is_no_error():
    """``skinny experiment list | head -1``: the closed pipe ends the command quietly."""
    env = {**os.environ, "MUJOCO_GL": "disabled", "OMP_NUM_THREADS": "1"}
    proc = subprocess.Popen([sys.executable, "-m", "skinny_mj.cli.parser", "experiment", "list"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=env)
    proc.stdout.close()  # the reader is gone before the first line is written
    err = proc.stderr.read().decode()
    assert proc.wait(timeout=120) == 0 and err == ""


def test_train_takes_the_torque_teacher_and_readout_fit_flags(tmp_path):
    out = tmp_path / "tq"
    assert main(["train", "--actuation", "torque", "--feedback", "inertia-pd", "--readout-fit",
                 "forgetting", "--readout-forgetting", "0.7", "--beta", "1", "--cycles", "1",
                 "--epochs", "1", "--reservoir", "30", "--out", str(out)]) == 0
    cfg = json.loads((out / "metrics.json").read_text())["config"]
    assert (cfg["actuation.feedback"], cfg["method.fit"], cfg["method.fit.forgetting"]) == \
        ("inertia-pd", "forgetting", 0.7)


def test_body_flags_name_a_body_and_dof_is_its_alias(tmp_path, capsys):
    """``--body NAME`` (the help lists the registered bodies) and ``--dof 4|8``, the same
    body by its number of hinges (with a torque actuation, its twin): the same run."""
    from skinny_mj.cli.config_files import train_config
    from skinny_mj.cli.parser import build_parser

    def config(*argv):
        return train_config(build_parser().parse_args(["train", *argv]))[0]

    assert config("--dof", "8") == config("--body", "3d") == config("plant.dof=8") \
        == config("--dof", "8", "--body", "3d")
    torque = config("--body", "2d-torque")
    assert torque.actuation.kind == "torque" and torque.plant.body == "2d-torque"
    assert config("--dof", "4", "--actuation", "torque") == config("--body", "2d",
                                                                   "--actuation", "torque")
    assert config("--dof", "4", "--actuation", "torque").plant.body == "2d-torque"
    with pytest.raises(SystemExit):
        main(["train", "--help"])
    assert "2d, 3d, 2d-torque, 3d-torque" in " ".join(capsys.readouterr().out.split())
    runs = {}
    for argv in (["--body", "2d-torque"], ["--dof", "4", "--actuation", "torque"]):
        out = tmp_path / argv[-1]
        assert main(["train", *argv, "--epochs", "1", "--quiet", "--out", str(out)]) == 0
        runs[argv[-1]] = json.loads((out / "metrics.json").read_text())
    first, second = runs.values()
    assert first["config"]["plant.body"] == "2d-torque" and first["test"] == second["test"]
    with np.load(out / "model.npz", allow_pickle=False) as model:
        assert json.loads(str(model["metadata"]))["body"] == "2d-torque"


def test_a_torque_body_trains_its_own_defaults_unless_a_preset_is_given(tmp_path):
    """``skinny train --actuation torque`` (or a torque body) with no --preset starts from
    the torque body's defaults (:data:`TORQUE_DEFAULTS`, per body), under --config and the
    flags; the velocity body, the presets and TrainConfig() keep theirs."""
    from skinny_mj.cli.config_files import train_config
    from skinny_mj.cli.parser import build_parser
    from skinny_mj.training.config import TrainConfig
    from skinny_mj.training.presets import preset_fields, torque_defaults

    def config(*argv):
        return train_config(build_parser().parse_args(["train", *argv]))[0]

    two, three = (TrainConfig().override(torque_defaults(d)) for d in (4, 8))
    assert config("--actuation", "torque") == config("--body", "2d-torque") == two
    assert config("--body", "3d", "--actuation", "torque") == config("--dof", "8",
                                                                     "--actuation", "torque") \
        == config("--body", "3d-torque") == three
    assert (two.torque.feedback, two.torque.sensing.velocity, two.method.beta) == \
        ("inertia-pd", "observer", 1.0)
    assert (three.esn.n_reservoir, three.torque.omega) == (500, 20.0)
    given = config("--actuation", "torque", "--feedback", "pd", "--epochs", "3")
    assert given == two.override({"actuation.feedback": "pd", "method.epochs": 3})
    assert config() == TrainConfig()
    assert TrainConfig().override({"actuation": "torque"}).torque.feedback == "pd"
    assert config("--preset", "general", "--actuation", "torque") == \
        TrainConfig().override(preset_fields("general", "torque"))
    bare = tmp_path / "bare.json"
    bare.write_text(json.dumps({"actuation": "torque", "method.epochs": 2}))
    assert config("--config", str(bare)) == two.override({"method.epochs": 2})
