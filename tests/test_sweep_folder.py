"""Nothing lost in silence: ``--resume`` needs an existing sweep folder, a non-empty
``--out`` needs ``--overwrite`` (and holds a sweep), and a lock file stops a second
sweep in the same folder, naming who holds it; a stale lock is taken over."""

from __future__ import annotations

import json
import os
import socket
import subprocess
import sys
import types
from pathlib import Path

import numpy as np
import pytest
from toy import toy

from skinny_mj.engine import folder
from skinny_mj.engine.experiment import Row, run_sweep
from skinny_mj.engine.plan import Experiment
from skinny_mj.errors import SkinnyInputError


def _run_one(row: Row, seed: int) -> dict:
    return {"value": float(np.random.default_rng(seed).normal(row.params["mu"]))}


def _fake() -> Experiment:
    return toy("fake", (Row("a", params={"mu": 0.0}), Row("b", params={"mu": 1.0})), _run_one,
                      params={"k": 1}, runs=2, columns=("value",))


def _module() -> types.ModuleType:
    module = types.ModuleType("fake_paper", "A fake paper.")
    module.build = lambda **options: _fake()  # type: ignore[attr-defined]
    module.report = lambda results, out: "- none"  # type: ignore[attr-defined]
    return module


def _cli(monkeypatch, *argv: str) -> int:
    from skinny_mj.cli.parser import main
    from skinny_mj.engine import registry

    monkeypatch.setattr(registry, "get", lambda name: _module())
    return main(["experiment", "fake", "--workers", "1", *argv])


def _refused(monkeypatch, capsys, *argv: str) -> str:
    assert _cli(monkeypatch, *argv) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "Traceback" not in err, err
    return err


def _write_lock(out: Path, **holder) -> Path:
    out.mkdir(parents=True, exist_ok=True)
    path = out / folder.LOCK_NAME
    path.write_text(json.dumps({"pid": 1, "host": socket.gethostname(),
                                "started_at": "2026-01-01T00:00:00+00:00", **holder}))
    return path


def _dead_pid() -> int:
    proc = subprocess.Popen([sys.executable, "-c", "pass"])
    proc.wait()
    return proc.pid


# -- --resume and --out ------------------------------------------------------------------------
def test_resume_without_out_is_refused(monkeypatch, capsys, tmp_path):
    monkeypatch.chdir(tmp_path)
    err = _refused(monkeypatch, capsys, "--resume")
    assert "--resume needs --out" in err
    assert list(tmp_path.iterdir()) == []  # no new timestamped sweep started


@pytest.mark.parametrize("make", ["missing", "empty", "other files"])
def test_resume_of_a_folder_that_holds_no_sweep_is_refused(monkeypatch, capsys, tmp_path,
                                                          make):
    out = tmp_path / "out"
    if make != "missing":
        out.mkdir()
    if make == "other files":
        (out / "notes.txt").write_text("mine")
    err = _refused(monkeypatch, capsys, "--resume", "--out", str(out))
    assert "not a sweep's folder" in err
    assert (not out.exists()) if make == "missing" else \
        sorted(p.name for p in out.iterdir()) == (["notes.txt"] if make == "other files" else [])


def test_a_sweep_into_a_sweep_folder_needs_resume_or_overwrite(monkeypatch, capsys, tmp_path):
    out = tmp_path / "out"
    assert _cli(monkeypatch, "--out", str(out)) == 0
    capsys.readouterr()
    before = {p.name: p.read_bytes() for p in (out / "runs").iterdir()}
    err = _refused(monkeypatch, capsys, "--out", str(out))
    assert "already holds a sweep" in err and "--overwrite" in err and "--resume" in err
    assert {p.name: p.read_bytes() for p in (out / "runs").iterdir()} == before  # untouched
    assert _cli(monkeypatch, "--out", str(out), "--resume") == 0
    (out / "runs" / "stale-0.json").write_text("{}")  # a damaged leftover: --overwrite clears it
    assert _cli(monkeypatch, "--out", str(out), "--overwrite") == 0
    assert "stale-0.json" not in {p.name for p in (out / "runs").iterdir()}
    assert json.loads((out / "results.json").read_text())["n_runs"] == 4
    assert not (out / folder.LOCK_NAME).exists()  # released


def test_overwrite_never_empties_a_folder_that_holds_no_sweep(monkeypatch, capsys, tmp_path):
    (tmp_path / "thesis.tex").write_text("years of work")
    err = _refused(monkeypatch, capsys, "--out", str(tmp_path), "--overwrite")
    assert "holds other files and no sweep" in err
    assert (tmp_path / "thesis.tex").read_text() == "years of work"


def test_resume_and_overwrite_together_are_refused(monkeypatch, capsys, tmp_path):
    err = _refused(monkeypatch, capsys, "--out", str(tmp_path), "--resume", "--overwrite")
    assert "not both" in err


# -- the lock --------------------------------------------------------------------------------------
def test_a_live_lock_stops_a_second_sweep_and_names_its_holder(monkeypatch, capsys, tmp_path):
    holder = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    try:
        out = tmp_path / "out"
        lock = _write_lock(out, pid=holder.pid, started_at="2026-12-02T01:00:00+00:00")
        err = _refused(monkeypatch, capsys, "--out", str(out))
        assert f"pid {holder.pid} on {socket.gethostname()}, started " \
               "2026-12-02T01:00:00+00:00" in err
        with pytest.raises(SkinnyInputError, match=f"pid {holder.pid}"):
            run_sweep(_fake(), out, workers=1, progress=False)  # the engine checks it too
        assert lock.exists() and sorted(p.name for p in out.iterdir()) == [folder.LOCK_NAME]
        (out / "config.json").write_text("{}")  # the running sweep's: still the lock's line
        for extra in ((), ("--resume",), ("--overwrite",)):
            assert f"pid {holder.pid}" in _refused(monkeypatch, capsys, "--out", str(out), *extra)
    finally:
        holder.kill()
        holder.wait()


def test_a_lock_on_another_host_is_never_taken_over(tmp_path):
    _write_lock(tmp_path, pid=_dead_pid(), host="elsewhere.example")
    with pytest.raises(SkinnyInputError, match="on elsewhere.example"):
        run_sweep(_fake(), tmp_path, workers=1, progress=False)


def test_a_stale_lock_is_taken_over_with_a_line(monkeypatch, capsys, tmp_path):
    pid = _dead_pid()
    _write_lock(tmp_path, pid=pid)
    assert _cli(monkeypatch, "--out", str(tmp_path)) == 0
    err = capsys.readouterr().err
    assert f"removed a stale lock (pid {pid} on {socket.gethostname()}" in err
    assert not (tmp_path / folder.LOCK_NAME).exists()
    assert json.loads((tmp_path / "results.json").read_text())["n_runs"] == 4


def test_a_reused_pid_is_a_stale_lock(tmp_path):
    # our own parent is alive, but it started before the time recorded in the lock
    _write_lock(tmp_path, pid=os.getppid(), start_ticks="1")
    if folder._start_ticks(os.getppid()) in (None, "1"):
        pytest.skip("no /proc start times here")
    with folder.sweep_lock(tmp_path):
        holder = folder.read_lock(tmp_path / folder.LOCK_NAME)
        assert holder["pid"] == os.getpid()


def test_the_lock_is_held_while_the_sweep_runs_and_released_after(tmp_path):
    seen = []

    def run_one(row: Row, seed: int) -> dict:
        seen.append(folder.read_lock(tmp_path / folder.LOCK_NAME))
        return {"value": 1.0}

    exp = toy("fake", (Row("a"),), run_one, runs=2)
    run_sweep(exp, tmp_path, workers=1, progress=False)
    assert [h["pid"] for h in seen] == [os.getpid()] * 2
    assert seen[0]["host"] == socket.gethostname() and seen[0]["started_at"]
    assert not (tmp_path / folder.LOCK_NAME).exists()


def test_the_lock_is_released_when_the_sweep_raises(tmp_path):
    def run_one(row: Row, seed: int) -> dict:
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        run_sweep(toy("fake", (Row("a"),), run_one, runs=1), tmp_path, workers=1,
                  progress=False)
    assert not (tmp_path / folder.LOCK_NAME).exists()
