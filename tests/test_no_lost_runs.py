"""No run is overwritten or lost in silence: an ``--out`` that holds results is refused
(one line, exit 2, naming it and ``--overwrite``) before any work, ``--overwrite``
replaces a run and nothing else, and default folders are new even for runs started in
the same second. A bad path the user gave is exit 2; a machine that cannot write is 1."""

from __future__ import annotations

import errno
import json
import os
import threading
import types
from pathlib import Path

import numpy as np
import pytest
from toy import toy

from skinny_mj import preflight
from skinny_mj.cli.parser import main
from skinny_mj.engine.experiment import Row, run_sweep
from skinny_mj.engine.folder import LOCK_NAME
from skinny_mj.engine.plan import Experiment

TINY = ["--reservoir", "20", "--cycles", "1", "--epochs", "1", "--quiet"]
MODEL = "general-2d-joint"  # a shipped model: `skinny test` needs no training first


def _never(*args, **kwargs):
    raise AssertionError("the work started although the output was refused")


def _refused(capsys, code: int, *needles: str) -> str:
    err = capsys.readouterr().err
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert code == 2, err
    assert len(lines) == 1 and "Traceback" not in err, err
    assert all(n in lines[0] for n in needles), lines[0]
    return lines[0]


def _a_run(folder: Path) -> dict[str, bytes]:
    """A folder that holds an earlier run (and a file of the user's), its bytes."""
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "metrics.json").write_text('{"seed": 99}\n')
    (folder / "model.npz").write_bytes(b"old model")
    (folder / "notes.txt").write_text("mine")
    return {p.name: p.read_bytes() for p in folder.iterdir()}


def _contents(folder: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in folder.iterdir()}


# -- a run's folder: train, demo, track, test ------------------------------------------------
@pytest.mark.parametrize("argv", [
    ["train", "--epochs", "1"],
    ["demo"],
    ["track"],
    ["test", "--model", MODEL],
])
def test_an_out_holding_a_run_is_refused_before_any_work(argv, tmp_path, monkeypatch, capsys):
    for name in ("skinny_mj.training.loop.train", "skinny_mj.training.loop.evaluate",
                 "skinny_mj.plant.task.load"):
        monkeypatch.setattr(name, _never)
    out = tmp_path / "run"
    before = _a_run(out)
    code = main([*argv, "--out", str(out)])
    _refused(capsys, code, str(out), "already holds a run", "--overwrite")
    assert _contents(out) == before


@pytest.mark.parametrize("overwrite", [[], ["--overwrite"]])
def test_a_folder_of_other_files_is_refused_even_with_overwrite(overwrite, tmp_path,
                                                               monkeypatch, capsys):
    monkeypatch.setattr("skinny_mj.training.loop.train", _never)
    (tmp_path / "thesis.tex").write_text("mine")
    code = main(["train", *TINY, "--out", str(tmp_path), *overwrite])
    _refused(capsys, code, str(tmp_path), "holds other files and no run")
    assert _contents(tmp_path) == {"thesis.tex": b"mine"}


def test_overwrite_replaces_the_run_and_keeps_the_users_files(tmp_path, capsys):
    out = tmp_path / "run"
    _a_run(out)
    assert main(["train", *TINY, "--seed", "4", "--out", str(out), "--overwrite"]) == 0
    assert json.loads((out / "metrics.json").read_text())["seed"] == 4
    assert (out / "model.npz").read_bytes() != b"old model"
    assert (out / "notes.txt").read_text() == "mine"
    assert f"-> {out}" in capsys.readouterr().out


def test_overwrite_by_a_failed_run_leaves_no_older_model_beside_it(tmp_path, capsys):
    out = tmp_path / "run"
    _a_run(out)
    code = main(["train", *TINY, "--spectral-radius", "100", "--out", str(out), "--overwrite"])
    assert code == 1, capsys.readouterr().err
    assert json.loads((out / "metrics.json").read_text())["failed"] is True
    assert sorted(p.name for p in out.iterdir()) == ["metrics.json", "notes.txt"]


def test_test_overwrite_never_deletes_the_model_it_tests(tmp_path, capsys):
    out = tmp_path / "run"
    assert main(["train", *TINY, "--out", str(out)]) == 0
    before = _contents(out)
    code = main(["test", "--model", str(out / "model.npz"), "--out", str(out), "--overwrite"])
    _refused(capsys, code, "model.npz", "--overwrite would delete the --model")
    assert _contents(out) == before


def test_an_empty_or_hidden_only_folder_is_taken(tmp_path, monkeypatch, capsys):
    out = tmp_path / "run"
    out.mkdir()
    (out / ".DS_Store").write_bytes(b"")
    assert main(["train", *TINY, "--out", str(out)]) == 0
    assert (out / "model.npz").is_file()


def test_a_run_written_into_out_while_this_one_ran_is_kept(tmp_path, monkeypatch, capsys):
    """The check is made again when the files are written, not only at the start."""
    from skinny_mj.training import loop

    out = tmp_path / "run"
    train = loop.train

    def train_while_another_writes(*args, **kwargs):
        outcome = train(*args, **kwargs)
        _a_run(out)
        return outcome

    monkeypatch.setattr(loop, "train", train_while_another_writes)
    code = main(["train", *TINY, "--out", str(out)])
    _refused(capsys, code, "already holds a run")
    assert (out / "model.npz").read_bytes() == b"old model"


# -- files: trajectory export, render, bench ------------------------------------------------
@pytest.mark.parametrize("argv", [
    ["trajectory", "export", "ym"],
    ["render"],
    ["bench", "--quick"],
])
def test_an_existing_output_file_is_refused_before_any_work(argv, tmp_path, monkeypatch,
                                                            capsys):
    monkeypatch.setattr("skinny_mj.plant.render.render_png", _never)
    monkeypatch.setattr("skinny_mj.cli.bench.run_with_bar", _never)
    path = tmp_path / ("out.npz" if argv[0] == "trajectory" else "out.png")
    path.write_bytes(b"mine")
    code = main([*argv, "--out", str(path)])
    _refused(capsys, code, str(path), "already exists", "--overwrite")
    assert path.read_bytes() == b"mine"


def test_trajectory_export_overwrite_replaces_the_file(tmp_path, capsys):
    from skinny_mj.trajectories import Trajectory

    path = tmp_path / "ym.npz"
    path.write_bytes(b"mine")
    assert main(["trajectory", "export", "ym", "--out", str(path), "--overwrite"]) == 0
    assert len(Trajectory.load(path)) == 240


# -- default folders ----------------------------------------------------------------------------
def test_default_folders_made_in_the_same_second_differ(tmp_path, monkeypatch):
    monkeypatch.setattr(preflight, "timestamp", lambda: "20261204-061500")
    made = [preflight.new_folder(tmp_path / "train") for _ in range(3)]
    assert [p.name for p in made] == ["20261204-061500", "20261204-061500-2",
                                      "20261204-061500-3"]
    assert sorted(p.name for p in made) == [p.name for p in made]  # sorted as started


def test_default_folders_made_at_once_by_many_threads_differ(tmp_path, monkeypatch):
    monkeypatch.setattr(preflight, "timestamp", lambda: "20261204-061500")
    made: list[Path] = []
    barrier = threading.Barrier(8)

    def make() -> None:
        barrier.wait()
        made.append(preflight.new_folder(tmp_path))

    threads = [threading.Thread(target=make) for _ in range(8)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert len(set(made)) == 8


def test_two_trains_in_the_same_second_keep_both_runs(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(preflight, "timestamp", lambda: "20261204-061500")
    assert main(["train", *TINY, "--seed", "1"]) == 0
    assert main(["train", *TINY, "--seed", "2"]) == 0
    runs = sorted((tmp_path / "results" / "train").iterdir())
    assert [p.name for p in runs] == ["20261204-061500", "20261204-061500-2"]
    assert [json.loads((p / "metrics.json").read_text())["seed"] for p in runs] == [1, 2]
    assert f"-> {Path('results/train/20261204-061500-2')}" in capsys.readouterr().out


def test_a_refused_default_run_leaves_no_folder(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert main(["track", "--trajectory", "no-such-movement"]) == 2
    assert not (tmp_path / "results" / "track").exists() or not any(
        (tmp_path / "results" / "track").iterdir())


def _fake() -> Experiment:
    def run_one(row: Row, seed: int) -> dict:
        return {"value": float(np.random.default_rng(seed).normal())}

    return toy("fake", (Row("a"),), run_one, runs=1, columns=("value",))


def test_two_default_sweeps_in_the_same_second_get_two_folders(tmp_path, monkeypatch,
                                                               capsys):
    from skinny_mj.engine import registry

    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(preflight, "timestamp", lambda: "20261204-061500")
    module = types.ModuleType("fake_study")
    module.build = lambda **options: _fake()  # type: ignore[attr-defined]
    monkeypatch.setattr(registry, "get", lambda name: module)
    for _ in range(2):
        assert main(["experiment", "fake", "--workers", "1", "--quiet"]) == 0
    run_sweep(_fake(), workers=1, progress=False)  # the library's default too
    folders = sorted(p.name for p in (tmp_path / "results" / "fake").iterdir())
    assert folders == ["20261204-061500", "20261204-061500-2", "20261204-061500-3"]
    assert "results: results/fake/20261204-061500-2" in capsys.readouterr().out


def test_a_sweep_written_into_out_since_the_command_started_is_kept(tmp_path, monkeypatch,
                                                                     capsys):
    """Two sweeps given the same new --out: the lock keeps them apart while both run,
    and the check made again under the lock keeps the later from replacing the earlier."""
    from skinny_mj.cli import commands
    from skinny_mj.engine import registry

    module = types.ModuleType("fake_study")
    module.build = lambda **options: _fake()  # type: ignore[attr-defined]
    monkeypatch.setattr(registry, "get", lambda name: module)
    out = tmp_path / "sweep"

    def another_sweep_ends_meanwhile(*args, **kwargs):
        run_sweep(_fake(), out, workers=1, progress=False)

    monkeypatch.setattr(commands, "check_sweep", another_sweep_ends_meanwhile)
    code = main(["experiment", "fake", "--workers", "1", "--quiet", "--out", str(out)])
    _refused(capsys, code, str(out), "already holds a sweep")
    assert (out / "results.json").is_file() and not (out / LOCK_NAME).exists()


# -- exit codes: the path given (2) or the machine (1) ------------------------------------------
@pytest.mark.parametrize("argv", [["train", *TINY], ["experiment", "fake", "--workers", "1"]])
@pytest.mark.parametrize("where", ["is a file", "under a file"])
def test_an_out_that_cannot_be_a_folder_is_exit_2_from_every_command(argv, where, tmp_path,
                                                                     monkeypatch, capsys):
    from skinny_mj.engine import registry

    module = types.ModuleType("fake_study")
    module.build = lambda **options: _fake()  # type: ignore[attr-defined]
    monkeypatch.setattr(registry, "get", lambda name: module)
    monkeypatch.setattr("skinny_mj.training.loop.train", _never)
    plain = tmp_path / "plain"
    plain.write_text("x")
    out = plain if where == "is a file" else plain / "run"
    _refused(capsys, main([*argv, "--out", str(out)]), str(plain))


@pytest.mark.parametrize("argv", [["train", *TINY], ["experiment", "fake", "--workers", "1"]])
def test_a_machine_that_cannot_write_is_exit_1_from_every_command(argv, tmp_path, monkeypatch,
                                                                  capsys):
    import skinny_mj.controllers._io

    from skinny_mj.engine import registry

    class NoSpace:  # the tempfile module of skinny_mj's atomic writes, on a full disk
        @staticmethod
        def mkstemp(prefix="", suffix="", dir=None):
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(dir))

    module = types.ModuleType("fake_study")
    module.build = lambda **options: _fake()  # type: ignore[attr-defined]
    monkeypatch.setattr(registry, "get", lambda name: module)
    monkeypatch.setattr(skinny_mj.controllers._io, "tempfile", NoSpace)
    monkeypatch.setattr("skinny_mj.training.loop.train", _never)
    code = main([*argv, "--out", str(tmp_path / "run")])
    err = capsys.readouterr().err
    assert code == 1 and err.count("\n") == 1 and "No space left" in err, err
