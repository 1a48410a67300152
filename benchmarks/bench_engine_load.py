"""The experiment engine under load: a sweep of many trivial runs.

Each measurement runs in a fresh subprocess (so ``ru_maxrss`` is that sweep's alone)
and prints one line: runs, workers, the parent's peak RSS and its growth over the
baseline after imports (MB), and the engine's overhead per run
(wall time / runs, ms; the run itself costs ~10 us, so this is scheduling, the JSON
write, the progress bar and the final aggregate).

    MUJOCO_GL=disabled OMP_NUM_THREADS=1 python benchmarks/bench_engine_load.py \
        [--runs 10000] [--workers 1 2] [--out /tmp/load]

Goal: the parent's peak RSS <= 300 MB at 10 000 runs, flat in the run count.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
from pathlib import Path

_CHILD = r"""
import json, resource, sys, time
from skinny_mj.engine.experiment import Experiment, Row, run_sweep

def run_one(row, seed):  # trivial: the cost measured is the engine's
    return {"x": float(seed % 997) / 997.0, "row_mu": row.params["mu"]}

n_runs, workers, out = int(sys.argv[1]), int(sys.argv[2]), sys.argv[3]
n_rows = 10
exp = Experiment("load", tuple(Row(f"r{i}", {"mu": float(i)}) for i in range(n_rows)),
                 run_one, runs=n_runs // n_rows)
def rss_mb():
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
base = rss_mb()
start = time.perf_counter()
results = run_sweep(exp, out, workers=workers, progress=False)
wall = time.perf_counter() - start
assert results["n_ok"] == n_runs, results["n_ok"]
print(json.dumps({"runs": n_runs, "workers": workers, "wall_s": wall,
                  "ms_per_run": 1e3 * wall / n_runs, "parent_peak_rss_mb": rss_mb(),
                  "parent_baseline_rss_mb": base, "parent_growth_mb": rss_mb() - base}))
"""


def measure(runs: int, workers: int, out: Path) -> dict:
    """One sweep of ``runs`` trivial runs in a fresh process; its figures as a dict."""
    proc = subprocess.run([sys.executable, "-c", _CHILD, str(runs), str(workers), str(out)],
                          capture_output=True, text=True, check=False)
    if proc.returncode != 0:
        raise RuntimeError(f"load sweep failed:\n{proc.stderr}")
    return json.loads(proc.stdout.strip().splitlines()[-1])


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, nargs="+", default=[10_000])
    parser.add_argument("--workers", type=int, nargs="+", default=[1, 2])
    parser.add_argument("--out", type=Path, help="keep the sweeps here (default: a temp dir)")
    args = parser.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        root = args.out or Path(tmp)
        print("| runs | workers | parent peak RSS (MB) | growth (MB) | ms / run | wall (s) |")
        print("|---|---|---|---|---|---|")
        for runs in args.runs:
            for workers in args.workers:
                m = measure(runs, workers, root / f"load-{runs}-w{workers}")
                print(f"| {runs} | {workers} | {m['parent_peak_rss_mb']:.1f} | "
                      f"{m['parent_growth_mb']:.1f} | {m['ms_per_run']:.2f} | "
                      f"{m['wall_s']:.1f} |", flush=True)


if __name__ == "__main__":
    main()
