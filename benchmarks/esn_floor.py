"""The floor of an ESN state loop, beside ``ESN.run`` and reservoirpy's ``Reservoir.run``.

    pip install reservoirpy numba   # both optional; a side that is missing is skipped
    python benchmarks/esn_floor.py [--steps 1000] [--rounds 7]

One run (R = 1), N = 200 and N = 1000, 16 inputs, float64, no noise, the same weights on
every side. Each side produces the (T, N) reservoir states from zero; all sides are timed
in one process, interleaved (round after round, each side once per round), and the
median (and best) of the rounds is reported, in CPU and wall µs per step. The sides:

- ``ours``: :meth:`ESN.run` (the driven path: the input drive of all steps in one
  product, then per step SciPy's CSR kernel adds W x in place and tanh runs in place);
- ``reservoirpy``: ``Reservoir.run`` (per step ``W @ s`` on a CSR matrix, ``Win @ u``,
  ``+ bias``, tanh, the leak blend);
- ``floor_csr_u``: the least a loop on reservoirpy's own product pays per step: SciPy's
  CSR kernel called directly (no ``@`` dispatch), ``W_in [u; 1]`` as one dense product,
  tanh in place;
- ``floor_csr``: the same with the input drive of all steps in one product beforehand;
- ``floor_csc``: the same with SciPy's CSC kernel (the same bits as CSR);
- ``dense``: ``floor_csr`` with W dense (BLAS ``dgemv``): other bits, reported;
- ``ell_numba``: the whole loop compiled (numba): W as padded rows ("ELL", each row's
  terms added in CSR's column order, the loop over rows innermost so that it can be
  vectorized), the C library's tanh (reported: the largest difference from ``ours``);
- ``ell_numba_nptanh``: the compiled ELL product per step, NumPy's tanh.

``reservoirpy / floor_csr_u`` is the largest speed-up over reservoirpy any loop built on
the same SciPy product and NumPy tanh can reach.
"""

from __future__ import annotations

import argparse
import math
import os
import time
from collections.abc import Callable

import numpy as np
from scipy.sparse._sparsetools import csc_matvec, csr_matvec
from skinny_mj.controllers.esn import ESN, ESNConfig

from skinny_mj.cli.bench_floor import sparse_tanh_loop

try:
    import numba
except ImportError:
    numba = None

N_IN = 16


def _ell(csr) -> tuple[np.ndarray, np.ndarray]:
    """W (N, N) CSR as padded rows, column-major (K, N): term k of every row. A short
    row repeats its last column with weight 0 (adds +0.0 to a finite sum: same bits)."""
    n = csr.shape[0]
    counts = np.diff(csr.indptr)
    k = int(counts.max())
    cols, vals = np.zeros((k, n), np.int64), np.zeros((k, n))
    for i in range(n):
        lo, hi = csr.indptr[i], csr.indptr[i + 1]
        cols[: hi - lo, i], vals[: hi - lo, i] = csr.indices[lo:hi], csr.data[lo:hi]
        cols[hi - lo:, i] = csr.indices[hi - 1] if hi > lo else 0
    return cols, vals


if numba is not None:
    @numba.njit(cache=True, boundscheck=False)
    def _ell_add(cols, vals, x, out):
        """out += W x, each row's terms added to it in column order (as SciPy's CSR
        kernel adds them), vectorized over rows."""
        acc = out.copy()
        for k in range(cols.shape[0]):
            for i in range(out.shape[0]):
                acc[i] += vals[k, i] * x[cols[k, i]]
        out[:] = acc

    @numba.njit(cache=True, boundscheck=False)
    def _ell_loop(cols, vals, rows):
        """rows (T, N) hold the drive; row t becomes x(t) = tanh(drive + W x(t-1))."""
        n = rows.shape[1]
        x = np.zeros(n)
        acc = np.zeros(n)
        for t in range(rows.shape[0]):
            acc[:] = rows[t]
            for k in range(cols.shape[0]):
                for i in range(n):
                    acc[i] += vals[k, i] * x[cols[k, i]]
            for i in range(n):
                x[i] = math.tanh(acc[i])
                rows[t, i] = x[i]


def sides(n_res: int, inputs: np.ndarray) -> dict[str, Callable[[], np.ndarray]]:
    """Each side: a callable returning the (T, N) states from zero."""
    esn = ESN(ESNConfig(n_inputs=N_IN, n_outputs=4, n_reservoir=n_res), seed=0)
    csr = esn.sparse_reservoir
    csc = csr.tocsc()
    w_dense = np.ascontiguousarray(esn.W[0])
    w_in = np.ascontiguousarray(esn.W_in[0])  # (N, n_in + 1), last column: bias weights
    u1 = np.concatenate([inputs, np.full((len(inputs), 1), esn.cfg.bias)], axis=1)
    n_steps = len(inputs)

    def ours() -> np.ndarray:
        esn.reset()
        return esn.run(inputs[None], noise=False)[1][0, :, :n_res]

    def dense() -> np.ndarray:
        rows = u1 @ w_in.T
        x, tmp = np.zeros(n_res), np.empty(n_res)
        for t in range(n_steps):
            row = rows[t]
            np.matmul(w_dense, x, out=tmp)
            row += tmp
            np.tanh(row, out=row)
            x = row
        return rows

    out = {"ours": ours, "floor_csr_u": sparse_tanh_loop(csr_matvec, csr, w_in, u1, True),
           "floor_csr": sparse_tanh_loop(csr_matvec, csr, w_in, u1),
           "floor_csc": sparse_tanh_loop(csc_matvec, csc, w_in, u1), "dense": dense}
    try:
        from reservoirpy.nodes import Reservoir

        theirs = Reservoir(units=n_res, lr=1.0, W=csr, Win=w_in[:, :-1],
                           bias=w_in[:, -1] * esn.cfg.bias, input_dim=N_IN)
        theirs.initialize(np.zeros((1, N_IN)))

        def rpy() -> np.ndarray:
            theirs.reset()
            return theirs.run(inputs)
        out["reservoirpy"] = rpy
    except ImportError:
        pass
    if numba is not None:
        cols, vals = _ell(csr)

        def ell_compiled() -> np.ndarray:
            rows = u1 @ w_in.T
            _ell_loop(cols, vals, rows)
            return rows

        def ell_nptanh() -> np.ndarray:
            rows = u1 @ w_in.T
            x = np.zeros(n_res)
            for t in range(n_steps):
                row = rows[t]
                _ell_add(cols, vals, x, row)
                np.tanh(row, out=row)
                x = row
            return rows
        out["ell_numba"] = ell_compiled
        out["ell_numba_nptanh"] = ell_nptanh
    return out


def figure(n_res: int, n_steps: int, rounds: int) -> dict:
    inputs = np.random.default_rng(1).uniform(-1, 1, (n_steps, N_IN))
    fns = sides(n_res, inputs)
    ref = fns["ours"]()
    diff = {k: float(np.max(np.abs(fn() - ref))) for k, fn in fns.items()}  # also warms up
    cpu = {k: [] for k in fns}
    wall = {k: [] for k in fns}
    for _ in range(rounds):
        for key, fn in fns.items():
            c0, w0 = time.process_time(), time.perf_counter()
            fn()
            cpu[key].append((time.process_time() - c0) / n_steps * 1e6)
            wall[key].append((time.perf_counter() - w0) / n_steps * 1e6)
    return {"N": n_res, "steps": n_steps, "rounds": rounds, "max_diff_vs_ours": diff,
            "cpu_us_median": {k: float(np.median(v)) for k, v in cpu.items()},
            "cpu_us_best": {k: float(np.min(v)) for k, v in cpu.items()},
            "wall_us_median": {k: float(np.median(v)) for k, v in wall.items()}}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--steps", type=int, default=1000)
    parser.add_argument("--rounds", type=int, default=7)
    parser.add_argument("--sizes", type=int, nargs="+", default=[200, 1000])
    args = parser.parse_args()
    print(f"load average (1 min) {os.getloadavg()[0]:.2f} on {os.cpu_count()} CPUs")
    for n_res in args.sizes:
        f = figure(n_res, args.steps, args.rounds)
        med, best, wall = f["cpu_us_median"], f["cpu_us_best"], f["wall_us_median"]
        print(f"\nN = {n_res}: µs per step, median of {args.rounds} interleaved rounds "
              f"(CPU; best CPU; median wall); max |Δx| vs ours")
        for key in med:
            print(f"  {key:<17} {med[key]:8.2f} {best[key]:8.2f} {wall[key]:8.2f}   "
                  f"{f['max_diff_vs_ours'][key]:.1e}")
        if "reservoirpy" in med:
            rp = med["reservoirpy"]
            print("  reservoirpy over: " + ", ".join(f"{k} {rp / v:.2f}x" for k, v in
                                                      med.items() if k != "reservoirpy"))
    print(f"\nload average (1 min) {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
