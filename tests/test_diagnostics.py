"""Diagnostics go through ``logging`` (the ``skinny_mj`` loggers): a program using the
package sees the warnings by default and silences them with one ``setLevel``; under
``skinny`` they are plain lines on stderr, ``--log-level`` chooses which, and results
stay on stdout."""

from __future__ import annotations

import json
import logging
import os
import socket
import subprocess
import sys
import types
from pathlib import Path

import numpy as np
from toy import toy

from skinny_mj.cli.parser import main
from skinny_mj.engine import folder, registry
from skinny_mj.engine.experiment import Row


def _stale_lock(out: Path) -> int:
    """A lock left in ``out`` by a process that is gone; its pid."""
    proc = subprocess.Popen([sys.executable, "-c", "pass"])
    proc.wait()
    out.mkdir(parents=True, exist_ok=True)
    (out / folder.LOCK_NAME).write_text(json.dumps({
        "pid": proc.pid, "host": socket.gethostname(), "started_at": "2026-01-01T00:00:00"}))
    return proc.pid


def test_a_library_warning_is_a_log_record_of_skinny_mj(tmp_path, caplog):
    pid = _stale_lock(tmp_path)
    with folder.sweep_lock(tmp_path):
        pass
    (record,) = [r for r in caplog.records if r.name.startswith("skinny_mj")]
    assert record.name == "skinny_mj.engine.folder" and record.levelno == logging.WARNING
    assert f"removed a stale lock (pid {pid}" in record.getMessage()


def test_a_library_user_silences_the_warnings_with_one_set_level(tmp_path, caplog):
    _stale_lock(tmp_path)
    logger = logging.getLogger("skinny_mj")
    level = logger.level
    logger.setLevel(logging.ERROR)
    try:
        with folder.sweep_lock(tmp_path):
            pass
    finally:
        logger.setLevel(level)
    assert not [r for r in caplog.records if r.name.startswith("skinny_mj")]


def test_without_logging_configured_warnings_show_on_stderr_until_silenced(tmp_path):
    code = ("import json, logging, os, socket, sys\n"
            "from skinny_mj.engine import folder\n"
            "lock = {'pid': 2**22 + 7, 'host': socket.gethostname(), 'started_at': 'x'}\n"
            "for k, d in enumerate(sys.argv[1:]):\n"
            "    os.makedirs(d)\n"
            "    open(os.path.join(d, folder.LOCK_NAME), 'w').write(json.dumps(lock))\n"
            "    if k:\n"
            "        logging.getLogger('skinny_mj').setLevel(logging.ERROR)\n"
            "    with folder.sweep_lock(d):\n"
            "        pass\n")
    done = subprocess.run([sys.executable, "-c", code, str(tmp_path / "a"), str(tmp_path / "b")],
                          capture_output=True, text=True, timeout=300, cwd=tmp_path,
                          env={**os.environ, "MUJOCO_GL": "disabled"})
    assert done.returncode == 0, done.stderr
    lines = done.stderr.splitlines()
    assert len(lines) == 1 and "removed a stale lock" in lines[0], done.stderr
    assert str(tmp_path / "a") in lines[0]  # the first; the second was silenced


# -- under `skinny` -----------------------------------------------------------------------------
def _fake_study(monkeypatch) -> None:
    def run_one(row: Row, seed: int) -> dict:
        return {"value": float(np.random.default_rng(seed).normal())}

    module = types.ModuleType("fake_study")
    module.build = lambda **options: toy(  # type: ignore[attr-defined]
        "fake", (Row("a"), Row("b")), run_one, runs=2, columns=("value",))
    monkeypatch.setattr(registry, "get", lambda name: module)


def _sweep(monkeypatch, out: Path, *level: str) -> int:
    _fake_study(monkeypatch)
    return main([*level, "experiment", "fake", "--workers", "1", "--quiet", "--out", str(out)])


def test_the_cli_prints_warnings_as_plain_lines_and_results_on_stdout(tmp_path, monkeypatch,
                                                                      capsys):
    pid = _stale_lock(tmp_path / "s")
    assert _sweep(monkeypatch, tmp_path / "s") == 0
    captured = capsys.readouterr()
    assert captured.err.splitlines() == [
        f"removed a stale lock (pid {pid} on {socket.gethostname()}, started "
        f"2026-01-01T00:00:00; that process is no longer running): "
        f"{tmp_path / 's' / folder.LOCK_NAME}"]
    assert "results: " in captured.out and "stale" not in captured.out


def test_log_level_error_hides_the_warnings_and_info_shows_progress(tmp_path, monkeypatch,
                                                                    capsys):
    _stale_lock(tmp_path / "quiet")
    assert _sweep(monkeypatch, tmp_path / "quiet", "--log-level", "error") == 0
    assert capsys.readouterr().err == ""
    assert _sweep(monkeypatch, tmp_path / "loud", "--log-level", "info") == 0
    assert f"fake: 4 run(s) of 2 row(s) on 1 worker(s) -> {tmp_path / 'loud'}" in \
        capsys.readouterr().err


def test_the_cli_leaves_the_logger_as_it_found_it(tmp_path, monkeypatch, capsys):
    logger = logging.getLogger("skinny_mj")
    before = logger.level, logger.propagate, list(logger.handlers)
    assert _sweep(monkeypatch, tmp_path / "s", "--log-level", "debug") == 0
    assert (logger.level, logger.propagate, list(logger.handlers)) == before
