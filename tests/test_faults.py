"""Environment and numerical faults: each ends in one line and the right exit
code (1: the machine, 2: the input), before the long work where it can be checked, with
nothing half-written; a diverging run is a failed run with its reason and the sweep goes
on. Paths into other folders never appear in a command's output.
"""

from __future__ import annotations

import errno
import json
import os
import signal
from pathlib import Path

import numpy as np
import pytest
import skinny_mj.controllers._io
from toy import toy

from skinny_mj.cli.parser import main
from skinny_mj.engine.experiment import Row, RunFailed, run_sweep
from skinny_mj.errors import SkinnyEnvironmentError


def _never(*args, **kwargs):
    raise AssertionError("the long work started although the fault was known before it")


def _one_line_error(capsys, code: int, expected: int, needle: str) -> str:
    err = capsys.readouterr().err
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert code == expected, err
    assert len(lines) == 1 and "Traceback" not in err and needle in lines[0], err
    return lines[0]


def _fake_tempfile(error: int, spare_probe: bool = False):
    """A tempfile module for skinny_mj.controllers._io whose mkstemp fails with ``error``."""
    import tempfile

    class Fake:
        @staticmethod
        def mkstemp(prefix="", suffix="", dir=None):
            if spare_probe and ".skinny-write-probe" in prefix:
                return tempfile.mkstemp(prefix=prefix, suffix=suffix, dir=dir)
            raise OSError(error, os.strerror(error), str(dir))

    return Fake


def test_output_under_a_file_fails_before_training(tmp_path, monkeypatch, capsys):
    (tmp_path / "plain").write_text("x")
    monkeypatch.setattr("skinny_mj.training.loop.train", _never)
    code = main(["train", "--epochs", "1", "--out", str(tmp_path / "plain" / "run")])
    _one_line_error(capsys, code, 2, "Not a directory")  # the path given: input


@pytest.mark.parametrize("error", [errno.EACCES, errno.EROFS, errno.ENOSPC])
def test_unwritable_or_full_output_fails_before_training(error, tmp_path, monkeypatch,
                                                         capsys):
    monkeypatch.setattr(skinny_mj.controllers._io, "tempfile", _fake_tempfile(error))
    monkeypatch.setattr("skinny_mj.training.loop.train", _never)
    code = main(["train", "--epochs", "1", "--out", str(tmp_path / "run")])
    _one_line_error(capsys, code, 1, os.strerror(error))
    assert not (tmp_path / "run").exists()


def test_a_disk_that_fills_during_the_command_leaves_no_partial_file(tmp_path, monkeypatch,
                                                                     capsys):
    monkeypatch.setattr(skinny_mj.controllers._io, "tempfile",
                        _fake_tempfile(errno.ENOSPC, spare_probe=True))
    out = tmp_path / "t.npz"
    code = main(["trajectory", "export", "ymca", "--out", str(out)])
    _one_line_error(capsys, code, 1, "No space left")
    assert list(tmp_path.iterdir()) == []


def test_nearly_full_disk_is_refused_before_the_work(tmp_path, monkeypatch, capsys):
    import shutil
    from collections import namedtuple

    usage = namedtuple("usage", "total used free")
    monkeypatch.setattr(shutil, "disk_usage", lambda p: usage(1 << 30, 1 << 30, 4096))
    monkeypatch.setattr("skinny_mj.training.loop.train", _never)
    code = main(["train", "--out", str(tmp_path / "run")])
    _one_line_error(capsys, code, 1, "is full")


@pytest.mark.parametrize("gl", ["bogus", "EGL2"])
def test_an_unknown_rendering_backend_is_one_line_exit_1(gl, tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("MUJOCO_GL", gl)
    code = main(["render", "--out", str(tmp_path / "x.png")])
    _one_line_error(capsys, code, 1, "MUJOCO_GL")
    assert not list(tmp_path.iterdir())


def test_a_failing_gl_context_is_one_line_exit_1(tmp_path, monkeypatch, capsys):
    import mujoco

    def no_context(*args, **kwargs):
        raise mujoco.FatalError("an OpenGL platform library has not been loaded")

    monkeypatch.setattr(mujoco, "Renderer", no_context)
    monkeypatch.setenv("MUJOCO_GL", "egl")  # asked for; mujoco's context still fails
    code = main(["render", "--out", str(tmp_path / "x.png")])
    _one_line_error(capsys, code, 1, "no OpenGL rendering backend")
    assert not list(tmp_path.iterdir())


def test_a_missing_model_folder_is_an_environment_error(tmp_path, monkeypatch, capsys):
    from skinny_mj.plant.body import body_of

    monkeypatch.setenv("SKINNY_MJ_MODELS", str(tmp_path / "nowhere"))
    with pytest.raises(SkinnyEnvironmentError, match="SKINNY_MJ_MODELS"):
        body_of("2d").path()


def _dies_on(seed_to_kill: int | None):
    def run_one(row: Row, seed: int) -> dict:
        if seed == seed_to_kill:
            os.kill(os.getpid(), signal.SIGKILL)  # the OOM killer, kill -9
        return {"m": float(seed % 101)}

    return run_one


def test_a_killed_worker_is_reported_and_resume_recovers(tmp_path):
    from skinny_mj.engine.experiment import run_seed

    victim = run_seed(0, "b", 3)
    rows = (Row("a"), Row("b"))
    exp = toy("kill", rows, _dies_on(victim), runs=6)
    with pytest.raises(SkinnyEnvironmentError, match="worker process died.*--resume"):
        run_sweep(exp, tmp_path, workers=2, progress=False)
    kept = {p.name: p.stat().st_mtime_ns for p in (tmp_path / "runs").glob("*.json")}
    assert f"b-{victim}.json" not in kept
    healed = toy("kill", rows, _dies_on(None), runs=6)
    results = run_sweep(healed, tmp_path, workers=2, resume=True, progress=False)
    assert results["n_ok"] == 12
    assert all((tmp_path / "runs" / n).stat().st_mtime_ns == t for n, t in kept.items())


def test_unreachable_dask_scheduler_is_one_line_exit_1(tmp_path, monkeypatch, capsys):
    pytest.importorskip("dask.distributed")
    import skinny_mj.engine.sweep

    monkeypatch.setattr(skinny_mj.engine.sweep, "DASK_CONNECT_TIMEOUT_S", 1)
    exp = toy("dask", (Row("a"),), _dies_on(None), runs=1)
    with pytest.raises(SkinnyEnvironmentError, match="cannot reach the Dask scheduler"):
        run_sweep(exp, tmp_path, workers=1, scheduler="tcp://127.0.0.1:1", progress=False)
    assert not list((tmp_path / "runs").iterdir())


# -- numerical faults ---------------------------------------------------------------------
def _train_row(row: Row, seed: int) -> dict:
    """One real (tiny) training per run; a diverged network is a RunFailed."""
    from skinny_mj.training.config import TrainConfig
    from skinny_mj.training.loop import train

    fel = row.overrides.get("method", "new") in ("original", "new")
    outcome = train(TrainConfig().override({"esn.n_reservoir": 20, "movement.trajectory": "y",
                                            **({"method.epochs": 1} if fel else {}),
                                            **row.overrides}), seed)
    if outcome.failed:
        raise RunFailed(outcome.fail_reason)
    return {"position_nrmse": outcome.test.position_nrmse}


def test_diverging_runs_are_failed_with_reasons_and_the_sweep_goes_on(tmp_path):
    rows = (Row("ok", {"esn.readout": "ridge", "esn.ridge_lambda": 1e-4, "esn.noise_level": 0.0}),
            Row("huge-radius", {"esn.spectral_radius": 1e6}),
            Row("huge-noise", {"esn.noise_level": 1e308}),  # inf states
            Row("singular-fit", {"method": "true-target", "esn.noise_level": 1e308}))  # NaN solve
    results = run_sweep(toy("numfaults", rows, _train_row, runs=1), tmp_path,
                        workers=1, progress=False)
    by_row = {r["row"]: r for r in results["rows"]}
    assert by_row["ok"]["n_ok"] == 1 and results["n_error"] == 0
    for name in ("huge-radius", "huge-noise", "singular-fit"):
        (failure,) = by_row[name]["failures"]
        assert by_row[name]["n_failed"] == 1 and failure["fail_reason"], by_row[name]
    table = (tmp_path / "table.md").read_text()
    assert "| huge-radius | 1 / 1 |" in table and "| ok | 0 / 1 |" in table


def test_singular_readout_solves_give_finite_or_nan_never_raise():
    from skinny_mj.controllers.readout import pinv_solve, ridge_solve

    targets = np.ones((1, 50, 4))
    assert np.all(pinv_solve(np.zeros((1, 50, 21)), targets) == 0.0)  # all-zero states
    assert np.all(ridge_solve(np.zeros((50, 21)), targets[0], 0.0) == 0.0)
    assert np.all(np.isnan(pinv_solve(np.full((1, 50, 21), np.nan), targets)))


def test_an_unstable_torque_plant_counts_warnings_and_does_not_crash():
    from skinny_mj.plant.adapters import BatchPlant
    from skinny_mj.trajectories import get

    plant = BatchPlant("2d-torque", "joint", get("ymca", 4), n_runs=2, seeds=[1, 2])
    plant.model.actuator_gear[:, 0] *= 1e12  # motors no arm survives
    plant.model.jnt_actfrcrange *= 1e12
    plant.reset()
    for _ in range(20):
        sensed = plant.step(np.ones((2, 4)))
    assert plant.warning_count() > 0  # MuJoCo reset the blown-up state, and said so
    assert np.all(np.isfinite(sensed))


# -- security -----------------------------------------------------------------------------
def test_no_loader_reads_pickles():
    """Every np.load in the package and the controllers refuses pickles."""
    root = Path(__file__).resolve().parents[1]
    for path in [*root.glob("skinny_mj/**/*.py"), *root.glob("controllers/*.py"),
                 *root.glob("experiments/*.py")]:
        for no, line in enumerate(path.read_text().splitlines(), 1):
            if "np.load(" in line and not line.lstrip().startswith("#"):
                assert "allow_pickle=False" in line, f"{path}:{no}: {line.strip()}"


@pytest.mark.parametrize("name", ["../../escape", "/abs/escape", "..", "a/../../b"])
def test_names_from_files_and_configs_cannot_leave_the_output_folder(name, tmp_path, capsys):
    from skinny_mj.errors import SkinnyInputError
    from skinny_mj.trajectories import Trajectory, ymca

    with pytest.raises(SkinnyInputError):
        Row(name)
    with pytest.raises(SkinnyInputError):
        toy(name, (Row("a"),), _dies_on(None))
    movement = tmp_path / "in" / "m.npz"
    Trajectory(ymca(4).angles[:30], name=name).save(movement)
    out = tmp_path / "deep" / "out"
    before = set(tmp_path.rglob("*"))
    assert main(["track", "--trajectory", str(movement), "--out", str(out)]) == 0
    written = set(tmp_path.rglob("*")) - before
    assert written and all(out in p.parents or p == out or p in out.parents
                           for p in written), written
    assert json.loads((out / "metrics.json").read_text())["trajectory"] == str(movement)


_SLOW_SWEEP = """
import os, sys, time
from pathlib import Path
from skinny_mj.cli.parser import _on_sigterm, _terminate
from skinny_mj.engine.experiment import run_sweep
from skinny_mj.engine.study import Row, Study

def run_batch(config, row, seeds):
    Path(sys.argv[1], f"worker-{os.getpid()}").touch()
    time.sleep(120)
    return [{"m": 0.0} for _ in seeds]

if __name__ == "__main__":
    _on_sigterm(_terminate)  # as `skinny` does
    slow = Study("slow", (Row("a"),), run_batch=run_batch, runs=2).build()
    run_sweep(slow, Path(sys.argv[1]) / "out", workers=2, progress=False, batch_size=1)
"""


def test_sigterm_stops_a_sweeps_workers_and_releases_its_lock(tmp_path):
    """``kill PID`` on a sweep: the command ends as an interrupt (Terminated), its worker
    processes do not run on (orphaned, each finishing its run), and no lock is left."""
    import subprocess
    import sys
    import time

    script = tmp_path / "slow_sweep.py"
    script.write_text(_SLOW_SWEEP)
    proc = subprocess.Popen([sys.executable, str(script), str(tmp_path)],
                            stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.monotonic() + 120
        while len(list(tmp_path.glob("worker-*"))) < 2 and time.monotonic() < deadline:
            time.sleep(0.2)
        workers = [int(p.name.split("-")[1]) for p in tmp_path.glob("worker-*")]
        assert len(workers) == 2 and proc.poll() is None, "the sweep's runs did not start"
        proc.send_signal(signal.SIGTERM)
        err = proc.communicate(timeout=60)[1]
        assert proc.returncode != 0 and "Terminated" in err, err
        deadline = time.monotonic() + 30
        while any(_alive(pid) for pid in workers) and time.monotonic() < deadline:
            time.sleep(0.2)
        assert not any(_alive(pid) for pid in workers), "a worker runs on after SIGTERM"
        assert not (tmp_path / "out" / "sweep.lock").exists()
    finally:  # a failed check leaves no process behind
        proc.kill()
        for p in tmp_path.glob("worker-*"):
            if _alive(pid := int(p.name.split("-")[1])):
                os.kill(pid, signal.SIGKILL)


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    return Path(f"/proc/{pid}/stat").read_text().split()[2] != "Z"  # a zombie is gone
