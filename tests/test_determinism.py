"""Determinism: the same seed gives the same run files, byte for byte but for
the clock (``wall_s``, ``finished_at``, ``*_wall_s`` metrics), across processes, worker
counts, joblib and Dask, and lockstep vs one run at a time.

Already covered elsewhere: results.json across workers 1/2 and Dask on a fake sweep
(tests/test_experiment.py), lockstep == single training bit for bit
(tests/test_fastpath.py). Here: the run FILES, and a real paper sweep (slow).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from toy import toy

from skinny_mj.engine.experiment import Row, run_sweep

_CLOCK = ("wall_s", "finished_at")


def _files(out: Path) -> dict[str, str]:
    """name -> the run file's JSON text without what the clock sets."""
    files = {}
    for path in sorted((out / "runs").glob("*.json")):
        rec = json.loads(path.read_text())
        for key in _CLOCK:
            rec.pop(key, None)
        rec["metrics"] = {k: v for k, v in rec["metrics"].items() if not k.endswith("wall_s")}
        files[path.name] = json.dumps(rec, sort_keys=True)
    return files


def _noisy(row: Row, seed: int) -> dict:
    rng = np.random.default_rng(seed)
    x = rng.normal(row.params["mu"], 1.0, size=100)
    return {"mean": float(x.mean()), "trace": x[:3]}


def test_run_files_are_identical_across_worker_counts(tmp_path):
    exp = toy("det", (Row("a", params={"mu": 0.0}), Row("b", params={"mu": 2.0})), _noisy, runs=4)
    run_sweep(exp, tmp_path / "w1", workers=1, progress=False)
    run_sweep(exp, tmp_path / "w2", workers=2, progress=False)
    assert _files(tmp_path / "w1") == _files(tmp_path / "w2") and len(_files(tmp_path / "w1")) == 8


@pytest.mark.slow
def test_paper_e_run_files_identical_across_processes_workers_dask_and_lockstep(tmp_path):
    pytest.importorskip("dask.distributed")
    from skinny_mj.engine import registry

    exp = registry.get("paper-e").build(quick=True)
    kw = {"rows": ["5"], "runs": 2, "progress": False}
    run_sweep(exp, tmp_path / "lockstep", workers=1, **kw)
    run_sweep(exp, tmp_path / "single", workers=1, batch_size=0, **kw)
    run_sweep(exp, tmp_path / "joblib2", workers=2, **kw)
    run_sweep(exp, tmp_path / "dask2", workers=2, scheduler="local", **kw)
    env = {**os.environ, "MUJOCO_GL": "disabled", "OMP_NUM_THREADS": "1"}
    subprocess.run(["skinny", "experiment", "paper-e", "--quick", "--rows", "5", "--runs", "2",
                    "--workers", "1", "--quiet", "--out", str(tmp_path / "cli")], env=env,
                   check=True, stdout=subprocess.DEVNULL)
    ref = _files(tmp_path / "lockstep")
    assert len(ref) == 2
    for other in ("single", "joblib2", "dask2", "cli"):
        assert _files(tmp_path / other) == ref, other


_THREADS_PROBE = """
import hashlib
from dataclasses import replace
from threadpoolctl import threadpool_info
from skinny_mj.training.config import TrainConfig
from skinny_mj.training.loop import train
out = train(TrainConfig().override(method__epochs=3), 3)
blas = max(i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas")
print(blas, out.test.position_nrmse.hex(),
      hashlib.sha256(out.esn.W_out.tobytes()).hexdigest())
"""


def test_training_gives_the_same_bits_with_one_or_two_blas_threads():
    """The process's BLAS thread count (here 1 or 2, set as a user's shell would) must not
    reach a run: OpenBLAS's threaded kernels sum in another order (metrics ~1e-14 apart
    before the run pinned its BLAS to one thread)."""
    results = {}
    for n in ("1", "2"):
        env = {**os.environ, "MUJOCO_GL": "disabled", "OMP_NUM_THREADS": n,
               "OPENBLAS_NUM_THREADS": n, "MKL_NUM_THREADS": n}
        out = subprocess.run([sys.executable, "-c", _THREADS_PROBE], env=env, check=True,
                             capture_output=True, text=True).stdout.split()
        assert int(out[0]) == int(n)  # the pool the process had outside the run
        results[n] = out[1:]
    assert results["1"] == results["2"]
