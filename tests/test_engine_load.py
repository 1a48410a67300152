"""Load: the parent's memory does not grow with the run records of a sweep.

A fresh process runs 800 trivial runs, each with a 400-float trace in its run file
(~9 KB a run); the parent's peak RSS over its baseline must stay far below what holding
every record takes (measured 14.4 MB for these 800; 10 000 trivial runs took 62 MB of
parent peak RSS on 2 workers).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys

_CHILD = r"""
import json, resource, sys
import numpy as np
from skinny_mj.engine.experiment import run_sweep
from skinny_mj.engine.study import Row, Study

def run_batch(config, row, seeds):
    return [{"x": float(seed % 97), "trace": np.random.default_rng(seed).normal(size=400)}
            for seed in seeds]

rows = tuple(Row(f"r{i}") for i in range(5))
exp = Study("load", rows, run_batch=run_batch, runs=160).build()
rss = lambda: resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
warm = Study("load", rows, run_batch=run_batch, runs=2).build()  # imports, first writes
run_sweep(warm, sys.argv[1], workers=1, progress=False, batch_size=0)  # room to grow
base = rss()
results = run_sweep(exp, sys.argv[2], workers=1, progress=False, batch_size=0)
print(json.dumps({"growth_mb": rss() - base, "n_ok": results["n_ok"]}))
"""


def test_sweep_memory_does_not_grow_with_its_run_records(tmp_path):
    env = {**os.environ, "MUJOCO_GL": "disabled", "OMP_NUM_THREADS": "1"}
    proc = subprocess.run([sys.executable, "-c", _CHILD, str(tmp_path / "warm"),
                           str(tmp_path / "load")], env=env, capture_output=True, text=True,
                          check=True)
    figures = json.loads(proc.stdout.strip().splitlines()[-1])
    assert figures["n_ok"] == 800
    # measured: 0.6 MB; holding every record (load_runs) instead: 14.4 MB
    assert figures["growth_mb"] < 5.0, figures
