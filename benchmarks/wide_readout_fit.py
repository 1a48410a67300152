"""The readout fits of FEL: their share of a sweep, batching the R runs' solves, and a
cheaper solve for wide states (T < D), beside the package's QR solve.

    python benchmarks/wide_readout_fit.py                      # the solves alone
    python benchmarks/wide_readout_fit.py --row paper-a:hybrid-d4 --runs 2

Without ``--row``, on reservoir states of the papers' sizes (R runs, T = 312 steps),
CPU ms per fit of all R runs, best of rounds:

- ``loop``: the package's :func:`~skinny_mj.controllers.readout.pinv_solve`, one LAPACK
  QR per run;
- ``stacked``: tall M only, one ``np.linalg.qr(mode="r")`` call on the stacked
  [M | S] of all runs (R_M and Q^T S for every run at once), then the same small solves:
  the R runs' factorizations batched into one NumPy call;
- ``gram``: wide M only, :func:`gram_solve` per run: M^T (M M^T)^-1 S by Cholesky of the
  (T, T) Gram matrix, one step of iterative refinement (the QR route where M is not safely
  of full row rank).

Each is compared with ``np.linalg.pinv(M) @ S`` (largest difference over the largest
readout weight). With ``--row STUDY:ROW``, that row's runs are trained twice in this
process (``--workers 1``), with the package's solve and with the Gram route patched in;
the script prints each sweep's CPU time, the share of it in the readout fits, and the
largest relative difference between the two sweeps' run metrics.
"""

from __future__ import annotations

import argparse
import json
import os
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
from skinny_mj.controllers import readout
from skinny_mj.controllers.esn import ESN, ESNConfig

#: The Gram route's limit on the estimated condition number of M (its Cholesky factor's):
#: its rounding before the refinement step is about cond(M)^2 x eps.
GRAM_DIRECT_COND = 1e4
QR_WIDE = readout.pinv_solve_wide  # the package's solve for wide M
SHAPES = ((20, 200, 0.5), (10, 1000, 0.1))  # (R, N, spectral radius): papers E, A and C
N_STEPS, N_INPUTS, N_OUTPUTS = 312, 12, 4


def gram_solve(m: np.ndarray, s: np.ndarray) -> np.ndarray | None:
    """M^+ S of one wide M (T, D) of full row rank, S (T, n): M^T G^-1 S with G = M M^T
    by Cholesky (LAPACK ``dsyrk``, ``dpotrf``), then one refinement step (the residual
    S - M W solved again with the same factor). None when M is not safely of full row
    rank (the factor's estimated condition number above :data:`GRAM_DIRECT_COND`) or not
    finite."""
    import scipy.linalg

    lapack = scipy.linalg.lapack
    m_t = m.T  # Fortran-ordered (D, T): dsyrk reads it without a copy
    chol, info = lapack.dpotrf(scipy.linalg.blas.dsyrk(1.0, m_t, trans=1), lower=0, clean=1,
                               overwrite_a=1)
    if info != 0:
        return None
    rcond, _ = lapack.dtrcon(chol, norm="1")
    if not rcond * GRAM_DIRECT_COND > 1.0:  # (also NaN)
        return None
    w = m_t @ lapack.dpotrs(chol, s)[0]
    w += m_t @ lapack.dpotrs(chol, s - m @ w)[0]
    return w


def gram_pinv_solve(m: np.ndarray, s: np.ndarray) -> np.ndarray:
    """:func:`~skinny_mj.controllers.readout.pinv_solve` with the Gram route for wide M."""
    if m.shape[1] >= m.shape[2]:
        return readout.pinv_solve(m, s)
    out = np.empty((m.shape[0], m.shape[2], s.shape[-1]))
    for r in range(m.shape[0]):
        w = gram_solve(m[r], s[r])
        out[r] = QR_WIDE(m[r:r + 1], s[r:r + 1])[0] if w is None else w
    return out


def stacked_pinv_solve(m: np.ndarray, s: np.ndarray) -> np.ndarray:
    """Tall M: the R runs' QR of [M | S] in one stacked NumPy call, then the small solves."""
    d = m.shape[2]
    r = np.linalg.qr(np.concatenate([m, s], axis=2), mode="r")
    return np.stack([readout.small_solver(np.asfortranarray(r[k, :d, :d]))(r[k, :d, d:])
                     for k in range(m.shape[0])])


def states(n_runs: int, n_reservoir: int, radius: float) -> tuple[np.ndarray, np.ndarray]:
    """Extended states (R, T, D) of an ESN driven by smooth inputs, and targets."""
    rng = np.random.default_rng(0)
    esn = ESN(ESNConfig(N_INPUTS, N_OUTPUTS, n_reservoir=n_reservoir, spectral_radius=radius,
                        noise_level=0.2), n_runs, seed=1)
    t = np.linspace(0.0, 20.0, N_STEPS)[None, :, None]
    u = np.sin(t * rng.uniform(0.5, 2.0, (1, 1, N_INPUTS))) \
        + 0.01 * rng.standard_normal((n_runs, N_STEPS, N_INPUTS))
    _, m = esn.run(u)
    return m, 0.3 * rng.standard_normal((n_runs, N_STEPS, N_OUTPUTS))


def best_cpu_ms(fn: Callable[[], object], rounds: int = 5) -> float:
    times = []
    for _ in range(rounds):
        start = time.process_time()
        fn()
        times.append(time.process_time() - start)
    return 1e3 * min(times)


def solves() -> None:
    print("| R x N | T x D | loop (ms) | stacked (ms) | gram (ms) | max |dW| / max |W| "
          "(loop, other) vs pinv |")
    print("|---|---|---|---|---|---|")
    for n_runs, n_res, radius in SHAPES:
        m, s = states(n_runs, n_res, radius)
        ref = np.linalg.pinv(m) @ s
        scale = np.abs(ref).max()
        other = stacked_pinv_solve if m.shape[1] >= m.shape[2] else gram_pinv_solve
        got = {"loop": readout.pinv_solve(m, s), "other": other(m, s)}
        err = ", ".join(f"{np.abs(w - ref).max() / scale:.1e}" for w in got.values())
        loop = best_cpu_ms(lambda m=m, s=s: readout.pinv_solve(m, s))
        ms = best_cpu_ms(lambda m=m, s=s, f=other: f(m, s))
        cols = (f"{ms:.1f}", "-") if other is stacked_pinv_solve else ("-", f"{ms:.1f}")
        same = " (bit for bit)" if np.array_equal(got["loop"], got["other"]) else ""
        print(f"| {n_runs} x {n_res} | {m.shape[1]} x {m.shape[2]} | {loop:.1f} | "
              f"{cols[0]} | {cols[1]} | {err}{same} |")


def _metrics(folder: Path) -> dict[str, dict]:
    return {p.name: json.loads(p.read_text())["metrics"]
            for p in sorted((folder / "runs").glob("*.json"))}


def _differences(a, b, path: str = ""):
    """(relative difference, metric path) of every number that differs."""
    if isinstance(a, dict):
        for k in a:
            if "wall" not in k and "cpu" not in k:
                yield from _differences(a[k], b.get(k), f"{path}.{k}")
    elif isinstance(a, list):
        for i, (x, y) in enumerate(zip(a, b, strict=False)):
            yield from _differences(x, y, f"{path}[{i}]")
    elif isinstance(a, float) and isinstance(b, float) and a != b:
        yield abs(a - b) / max(abs(a), abs(b)), path


def sweep_twice(study_row: str, runs: int) -> None:
    from skinny_mj.engine import registry
    from skinny_mj.engine.experiment import run_sweep

    study, row = study_row.split(":")
    exp = registry.get(study).build()
    package_solve, spent = readout.pinv_solve, [0.0]

    def timed(m, s):  # every pinv fit (the ESN's and the forward model's)
        start = time.process_time()
        try:
            return package_solve(m, s)
        finally:
            spent[0] += time.process_time() - start

    with tempfile.TemporaryDirectory(prefix="wide-fit-") as tmp:
        for name, wide in (("qr", QR_WIDE), ("gram", gram_pinv_solve)):
            readout.pinv_solve, readout.pinv_solve_wide = timed, wide
            spent[0], start = 0.0, time.process_time()
            try:
                run_sweep(exp, Path(tmp) / name, rows=[row], runs=runs, workers=1,
                          progress=False)
            finally:
                readout.pinv_solve, readout.pinv_solve_wide = package_solve, QR_WIDE
            cpu = time.process_time() - start
            print(f"{name}: {study_row}, {runs} runs: {cpu:.1f} s CPU, readout fits "
                  f"{spent[0]:.1f} s ({100 * spent[0] / cpu:.0f} %)")
        a, b = _metrics(Path(tmp) / "qr"), _metrics(Path(tmp) / "gram")
        diffs = sorted((d for k in a for d in _differences(a[k], b[k])), reverse=True)
    print(f"{len(diffs)} metric values differ; the largest relative differences:")
    for rel, path in diffs[:5]:
        print(f"  {rel:.2e} {path}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--row", help="also train STUDY:ROW with both solves, e.g. "
                        "paper-a:hybrid-d4")
    parser.add_argument("--runs", type=int, default=2)
    args = parser.parse_args()
    print(f"OMP_NUM_THREADS={os.environ.get('OMP_NUM_THREADS')}, load {os.getloadavg()[0]:.1f}")
    solves()
    if args.row:
        sweep_twice(args.row, args.runs)


if __name__ == "__main__":
    main()
