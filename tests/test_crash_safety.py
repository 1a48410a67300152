"""Crash safety: a sweep killed with SIGKILL at random (seeded) points, several
times, then ``--resume``, ends with the results of an uninterrupted sweep; no finished
run is lost or redone, and no run file on disk is ever damaged.

The whole process group is killed (the parent and its loky workers: a power cut, the
OOM killer, ``kill -9 -PGID``). Default: a fake sweep of cheap runs; slow: the real
``skinny experiment paper-e --quick --rows table --workers 2``.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from skinny_mj.engine.stats import load_run

_ENV = {**os.environ, "MUJOCO_GL": "disabled", "OMP_NUM_THREADS": "1",
        "OPENBLAS_NUM_THREADS": "1"}

_FAKE = r"""
import sys, time
import numpy as np
from skinny_mj.engine.experiment import RunFailed, run_sweep
from skinny_mj.engine.study import Row, Study

def run_one(row, seed):
    time.sleep(0.03)
    if row.params["fail"] and seed % 3 == 0:
        return RunFailed("diverged on purpose")
    rng = np.random.default_rng(seed)
    return {"m": float(rng.normal(row.params["mu"])), "curve": rng.normal(size=4)}

rows = tuple(Row(f"r{i}", params={"mu": float(i), "fail": i == 2}) for i in range(4))
exp = Study("crash", rows, run_batch=lambda config, row, seeds: [run_one(row, s) for s in seeds],
            runs=8).build()
run_sweep(exp, sys.argv[1], workers=int(sys.argv[3]), resume=sys.argv[2] == "resume",
          progress=False, batch_size=0)
"""


def _timing_free(results: dict) -> dict:
    """results.json without what depends on the clock (wall times, *_wall_s metrics)."""
    rows = [{**{k: v for k, v in r.items() if k != "wall_s"},
             "metrics": {m: s for m, s in r["metrics"].items() if not m.endswith("wall_s")}}
            for r in results["rows"]]
    return {**results, "rows": rows}


def _snapshot(out: Path) -> dict[str, tuple[int, str]]:
    """Every run file: validated (a damaged one raises), with its mtime and finished_at."""
    snap = {}
    for path in sorted((out / "runs").glob("*.json")):
        rec = load_run(path)
        snap[path.name] = (path.stat().st_mtime_ns, rec["finished_at"])
    return snap


def _kill_trials(cmd: list[str], resume_cmd: list[str], out: Path, total: int, n_kills: int,
                 seed: int, timeout_s: float, max_delay_s: float) -> list[dict]:
    """Start ``cmd``, SIGKILL its group once ``k`` run files exist plus a random delay,
    then resume and kill again, ``n_kills`` times; then resume to the end. Returns one
    record per attempt; asserts that no finished run is redone or damaged."""
    rng = np.random.default_rng(seed)
    targets = np.sort(rng.choice(np.arange(1, total - 1), size=n_kills, replace=False))
    trials, before = [], {}
    for attempt, target in enumerate([*targets, None]):
        proc = subprocess.Popen(cmd if attempt == 0 else resume_cmd, env=_ENV,
                                start_new_session=True, stdout=subprocess.DEVNULL,
                                stderr=subprocess.PIPE)
        start, killed = time.monotonic(), False
        if target is not None:
            while proc.poll() is None and time.monotonic() - start < timeout_s:
                if len(list((out / "runs").glob("*.json"))) >= target:
                    time.sleep(float(rng.uniform(0.0, max_delay_s)))  # mid-run, mid-write
                    break
                time.sleep(0.01)
            if proc.poll() is None:
                os.killpg(proc.pid, signal.SIGKILL)
                killed = True
        _, stderr = proc.communicate(timeout=timeout_s)
        after = _snapshot(out)  # every file on disk validates: none half-written
        redone = [n for n, stamp in before.items() if after.get(n) != stamp]
        assert not redone, f"finished runs lost or redone: {redone}"
        trials.append({"attempt": attempt, "killed": killed, "files_before": len(before),
                       "files_after": len(after), "returncode": proc.returncode,
                       "tmp_leftovers": len(list((out / "runs").glob(".*.tmp")))})
        if not killed:
            assert proc.returncode == 0, stderr.decode()[-2000:]
        before = after
    return trials


def test_fake_sweep_killed_twice_resumes_to_the_same_results(tmp_path):
    script = tmp_path / "sweep.py"
    script.write_text(_FAKE)
    ref, out = tmp_path / "ref", tmp_path / "out"
    subprocess.run([sys.executable, str(script), str(ref), "fresh", "1"], env=_ENV,
                   check=True, stderr=subprocess.DEVNULL)
    trials = _kill_trials([sys.executable, str(script), str(out), "fresh", "2"],
                          [sys.executable, str(script), str(out), "resume", "2"],
                          out, total=32, n_kills=2, seed=15, timeout_s=120, max_delay_s=0.05)
    print(json.dumps(trials))
    assert [t["killed"] for t in trials] == [True, True, False]
    expected = json.loads((ref / "results.json").read_text())
    assert _timing_free(json.loads((out / "results.json").read_text())) == \
        _timing_free(expected)
    assert expected["n_failed"] > 0 and len(_snapshot(out)) == 32


@pytest.mark.slow
def test_paper_e_sweep_killed_at_random_points_resumes_to_the_same_results(tmp_path):
    """3 kills of a real sweep, then --resume (~2.5 min)."""
    base = ["skinny", "experiment", "paper-e", "--quick", "--rows", "table",
            "--workers", "2", "--quiet"]
    ref, out = tmp_path / "ref", tmp_path / "out"
    subprocess.run([*base, "--out", str(ref)], env=_ENV, check=True,
                   stdout=subprocess.DEVNULL)
    trials = _kill_trials([*base, "--out", str(out)], [*base, "--out", str(out), "--resume"],
                          out, total=12, n_kills=3, seed=15, timeout_s=400, max_delay_s=3.0)
    print(json.dumps(trials))
    assert sum(t["killed"] for t in trials) >= 1
    assert _timing_free(json.loads((out / "results.json").read_text())) == \
        _timing_free(json.loads((ref / "results.json").read_text()))
    for path in (ref / "runs").glob("*.json"):  # bit for bit, but for the clock
        a, b = load_run(path), load_run(out / "runs" / path.name)
        for rec in (a, b):
            for key in ("wall_s", "finished_at"):
                rec.pop(key)
            rec["metrics"].pop("train_wall_s", None)
        assert a == b
