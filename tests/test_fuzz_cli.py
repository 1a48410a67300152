"""Fuzzing ``skinny`` itself: random argv lists, in process.

Each case ends in exit 0, a one-line error (exit 2 bad input, exit 1 environment), or
argparse's usage error (exit 2), or reaches the long work, which is stubbed out here
(training, the task, the sweep, the renderer raise :class:`_Reached`): a traceback or
any other exception fails the test, and no ``.tmp`` leftover of an atomic write may stay
in the output folder. Examples: ``FUZZ_EXAMPLES`` of tests/test_fuzz.py.
"""

from __future__ import annotations

import contextlib
import io
import os
import tempfile
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("hypothesis")
from hypothesis import HealthCheck, given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

from skinny_mj.cli.parser import main  # noqa: E402
from skinny_mj.trajectories import Trajectory, ymca  # noqa: E402

LONG = os.environ.get("HYPOTHESIS_PROFILE") == "ci-long"
FUZZ = settings(max_examples=800 if LONG else 25, deadline=None, database=None,
                suppress_health_check=list(HealthCheck))

NUMBERS = ["0", "1", "2", "4", "8", "-1", "-5", "0.5", "1e309", "-1e309", "nan", "inf",
           "abc", "", "3.5", "99999999999999999999", "1e-320", "10", "0x10"]
NAMES = ["ymca", "ymca@0.5", "ymca@abc", "ymca@0", "y-pure", "nope", "../../x", "/abs/x",
         "md_02", "x.amc@start=-1", "file.csv@start=1,duration=0", "", "list", "paper-e",
         "paper-zz", "1,2", "table", "fig3,nope", "ymca@", " , ", "babble:", "babble:seed=-1",
         "babble:duration=1e12", "set:", "set:ymca++y", "set:ymca+nope", "md_02.amc@start",
         "method.epochs=2", "plant.dof=8", "local", "tcp://", "bogus"]


class _Reached(Exception):
    """The command got past every check to its long work (stubbed): a correct result."""


def _stub(*args, **kwargs):
    raise _Reached


@pytest.fixture(scope="module")
def files(tmp_path_factory) -> dict[str, str]:
    """Input files the argv may name: valid, damaged, absent, a folder, a plain file."""
    root = tmp_path_factory.mktemp("inputs")
    Trajectory(ymca(4).angles[:20], name="../../escape").save(root / "ok.csv")
    Trajectory(ymca(8).angles[:20], name="/abs/escape").save(root / "ok8.npz")
    (root / "bad.csv").write_text("# dt=0.02\na,b\n1,2\n")
    (root / "bad.npz").write_bytes(b"PK\x03\x04 not a zip")
    (root / "model.npz").write_bytes(np.zeros(3).tobytes())
    (root / "latin.bvh").write_bytes(b"HIERARCHY\n\xe9\xff\n")
    (root / "plain").write_text("x")
    (root / "empty.npz").write_bytes(b"")
    (root / "empty.json").write_text("")
    (root / "86_02.amc").write_text("1\n")  # a clip with no skeleton of its subject beside
    lines = (root / "ok.csv").read_text().splitlines()
    (root / "onerow.csv").write_text("\n".join(lines[:3]) + "\n")
    (root / "folder.npz").mkdir()
    return {"ok.csv": str(root / "ok.csv"), "ok8.npz": str(root / "ok8.npz"),
            "bad.csv": str(root / "bad.csv"), "bad.npz": str(root / "bad.npz"),
            "model": str(root / "model.npz"), "latin.bvh": str(root / "latin.bvh"),
            "missing": str(root / "missing.npz"), "folder": str(root),
            "under-a-file": str(root / "plain" / "x.npz"), "empty.npz": str(root / "empty.npz"),
            "empty.json": str(root / "empty.json"), "86_02.amc": str(root / "86_02.amc"),
            "onerow.csv": str(root / "onerow.csv"), "folder.npz": str(root / "folder.npz")}


COMMANDS = {
    "train": ["--dof", "--signals", "--trajectory", "--speed", "--reps", "--method", "--beta",
              "--cycles", "--epochs", "--reservoir", "--spectral-radius", "--noise",
              "--readout", "--ridge", "--sensor-noise", "--seed", "--asf", "--bogus",
              "--config"],
    "track": ["--dof", "--signals", "--trajectory", "--speed", "--reps", "--sensor-noise",
              "--seed", "--asf"],
    "test": ["--model", "--trajectory", "--speed", "--reps", "--sensor-noise", "--seed"],
    "trajectory export": ["--dof", "--speed", "--reps", "--asf"],
    "experiment": ["--runs", "--workers", "--rows", "--movement", "--dof", "--signals",
                   "--scheduler", "--asf", "--config", "--protocol"],
    "sweep": ["--runs", "--rows", "--study", "--row", "--config", "--scheduler", "--workers"],
    "render": ["--dof", "--trajectory", "--frame", "--width", "--height"],
}


@st.composite
def argvs(draw, files: dict[str, str], out: str) -> list[str]:
    command = draw(st.sampled_from(sorted(COMMANDS)))
    argv = command.split()
    if command in ("trajectory export", "experiment", "sweep"):
        argv.append(draw(st.sampled_from(NAMES + list(files.values()))))
    if command == "train" and draw(st.booleans()):  # KEY=VALUE overrides beside the flags
        argv.append(draw(st.sampled_from(["method.epochs=2", "plant.dof=8", "esn=1", "=1",
                                          "movement.trajectory=", "method.epochs=x"])))
    values = st.sampled_from(NUMBERS) | st.sampled_from(NAMES) \
        | st.sampled_from(sorted(files.values())) | st.text(max_size=6)
    for flag in draw(st.lists(st.sampled_from(COMMANDS[command]), max_size=4)):
        argv += [flag, draw(values)]
    if command == "trajectory export":
        argv += ["--out", draw(st.sampled_from([f"{out}/t.csv", f"{out}/t.npz", f"{out}/t.txt",
                                                files["under-a-file"]]))]
    elif command != "test" or draw(st.booleans()):
        argv += ["--out", draw(st.sampled_from([out + "/o", files["under-a-file"],
                                                f"{out}/o.png"]))]
    if draw(st.integers(0, 9)) == 0:
        argv.insert(draw(st.integers(0, len(argv))), draw(st.text(max_size=5)))
    return argv


def _run(argv: list[str]) -> tuple[int | str, str]:
    err = io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        try:
            code: int | str = main(argv)
        except SystemExit as exc:  # argparse: usage error (2) or --help (0)
            code = exc.code if isinstance(exc.code, int) else 2
        except _Reached:
            code = "reached"
    return code, err.getvalue()


@FUZZ
@given(data=st.data())
def test_fuzz_cli_argv(data, files, monkeypatch):
    for module, name in [
        ("skinny_mj.training.loop", "train"),
        ("skinny_mj.training.loop", "evaluate"),
        ("skinny_mj.plant.task", "load"),
        ("skinny_mj.engine.experiment", "run_sweep"),
        ("skinny_mj.plant.render", "render_png"),
    ]:
        monkeypatch.setattr(f"{module}.{name}", _stub)
    monkeypatch.chdir(tempfile.gettempdir())  # a default results/ would land here
    with tempfile.TemporaryDirectory() as out:
        argv = data.draw(argvs(files, out))
        code, stderr = _run(argv)
        assert "Traceback" not in stderr, (argv, stderr)
        assert code in (0, 1, 2, "reached"), (argv, code, stderr)
        lines = [ln for ln in stderr.splitlines() if ln.strip()]
        if code in (1, 2):
            assert lines and lines[-1].startswith(("skinny", "usage:")), (argv, stderr)
            assert len(lines) == 1 or lines[0].startswith("usage:"), (argv, stderr)
        leftovers = [p for p in Path(out).rglob("*") if p.name.endswith(".tmp")]
        assert not leftovers, (argv, leftovers)
