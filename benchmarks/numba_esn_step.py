"""A compiled (numba) lockstep ESN step beside the package's NumPy ``ESN.step``.

    pip install numba && python benchmarks/numba_esn_step.py

Two compiled variants, each timed interleaved with ``ESN.step`` in one process (best of
rounds, CPU time of this process, so other work on a shared machine shifts both sides
less), same weights and inputs, outputs compared step by step. Reservoir noise is off on
both sides (its draws are the same NumPy calls on both; the compiled side still adds a
zero noise array, so it pays for the add that ``ESN.step`` skips):

- ``hybrid``: SciPy's CSR product (C, as ``ESN.step``), then one compiled loop adds
  W_in [u; 1] (vectorized over units: W_in stored transposed), NumPy's tanh (SIMD),
  then one compiled loop adds the noise and writes x and the extended state; readout
  by NumPy;
- ``fused``: the same, with tanh computed inside the compiled loop from ``expm1``
  (numba has no SIMD tanh without Intel's SVML), so the update is one compiled call.

The outputs differ from ``ESN.step`` by float rounding only (the W_in [u; 1] sum is
grouped differently from OpenBLAS's; the fused tanh is not NumPy's).
"""

from __future__ import annotations

import math
import os
import sys
import time

import numpy as np
from skinny_mj.controllers.esn import ESN, ESNConfig

try:
    import numba
    from scipy.sparse._sparsetools import csr_matvec
except ImportError:
    sys.exit("needs numba: pip install numba")


@numba.njit(cache=True, nogil=True, boundscheck=False)
def add_drive(pre, w_in_t, u1, scratch):
    """pre (R, N) += W_in u1, W_in given transposed (R, K, N)."""
    n_runs, n_cols, n = w_in_t.shape
    for r in range(n_runs):
        scratch[:] = 0.0
        for c in range(n_cols):
            uc = u1[r, c]
            for i in range(n):
                scratch[i] += w_in_t[r, c, i] * uc
        for i in range(n):
            pre[r, i] += scratch[i]


@numba.njit(cache=True, nogil=True, boundscheck=False)
def add_noise(x, noise, ext):
    n_runs, n = x.shape
    for r in range(n_runs):
        for i in range(n):
            x[r, i] += noise[r, i]
            ext[r, i] = x[r, i]


@numba.njit(cache=True, nogil=True, boundscheck=False)
def fused_update(pre, w_in_t, u1, noise, x, ext):
    """x = tanh(pre + W_in u1) + noise, written to x and ext, in one loop."""
    n_runs, n_cols, n = w_in_t.shape
    for r in range(n_runs):
        row = pre[r]
        for c in range(n_cols):
            uc = u1[r, c]
            for i in range(n):
                row[i] += w_in_t[r, c, i] * uc
        for i in range(n):
            e = math.expm1(-2.0 * abs(row[i]))
            v = math.copysign(-e / (2.0 + e), row[i]) + noise[r, i]
            x[r, i] = v
            ext[r, i] = v


def compiled_steps(esn: ESN, inputs: np.ndarray, fused: bool) -> np.ndarray:
    """Outputs (T, R, n_out) of the compiled step from the reset state."""
    n_runs, n = esn.n_runs, esn.cfg.n_reservoir
    a = esn.sparse_reservoir
    w_in_t = np.ascontiguousarray(np.swapaxes(esn.W_in, 1, 2))
    pre, x, scratch = np.zeros((n_runs, n)), np.zeros((n_runs, n)), np.empty(n)
    noise = np.zeros((n_runs, n))
    ext = np.empty((n_runs, esn.cfg.n_extended))
    y = np.empty((n_runs, esn.cfg.n_outputs, 1))
    out = np.empty((inputs.shape[0], n_runs, esn.cfg.n_outputs))
    for t, u in enumerate(inputs):
        ext[:, n:-1] = u
        ext[:, -1] = esn.cfg.bias
        pre.fill(0.0)
        csr_matvec(a.shape[0], a.shape[1], a.indptr, a.indices, a.data, x, pre)
        if fused:
            fused_update(pre, w_in_t, ext[:, n:], noise, x, ext)
        else:
            add_drive(pre, w_in_t, ext[:, n:], scratch)
            np.tanh(pre, out=pre)
            x, pre = pre, x
            add_noise(x, noise, ext)
        np.matmul(esn.W_out, ext[..., None], out=y)
        out[t] = np.tanh(y[..., 0])
    return out


def numpy_steps(esn: ESN, inputs: np.ndarray) -> np.ndarray:
    ext = np.empty((esn.n_runs, esn.cfg.n_extended))
    return np.stack([esn.step(u, out_extended=ext) for u in inputs])


def figure(n_runs: int, n_res: int, n_in: int, n_steps: int, repeats: int) -> dict:
    cfg = ESNConfig(n_inputs=n_in, n_outputs=4, n_reservoir=n_res, noise_level=0.0)
    inputs = np.random.default_rng(1).uniform(-1, 1, (n_steps, n_runs, n_in))
    w_out = np.random.default_rng(2).uniform(-0.1, 0.1, (n_runs, 4, cfg.n_extended))

    def fresh() -> ESN:
        esn = ESN(cfg, n_runs=n_runs, seed=0)
        esn.W_out[:] = w_out
        return esn

    sides = {"numpy": lambda e: numpy_steps(e, inputs),
             "hybrid": lambda e: compiled_steps(e, inputs, False),
             "fused": lambda e: compiled_steps(e, inputs, True)}
    outs, best = {}, dict.fromkeys(sides, np.inf)
    for _ in range(repeats):
        for key, fn in sides.items():
            esn = fresh()
            start = time.process_time()
            outs[key] = fn(esn)
            best[key] = min(best[key], time.process_time() - start)
    per = {k: v / n_steps * 1e6 for k, v in best.items()}
    return {"R": n_runs, "N": n_res, **{f"{k}_us": v for k, v in per.items()},
            **{f"{k}_diff": float(np.max(np.abs(outs[k] - outs["numpy"])))
               for k in ("hybrid", "fused")}}


def main() -> None:
    print(f"load average (1 min) {os.getloadavg()[0]:.2f}; numba {numba.__version__}")
    print(f"{'R':>3} {'N':>5} {'NumPy':>8} {'hybrid':>8} {'fused':>8}  (CPU us per lockstep "
          "step)  max |dy| hybrid, fused")
    for n_runs, n_res, n_in in ((20, 200, 16), (10, 1000, 24), (1, 1000, 16)):
        f = figure(n_runs, n_res, n_in, 256, 8)
        print(f"{f['R']:>3} {f['N']:>5} {f['numpy_us']:>8.1f} {f['hybrid_us']:>8.1f} "
              f"{f['fused_us']:>8.1f}  {f['hybrid_diff']:.1e}, {f['fused_diff']:.1e}")
    print(f"load average (1 min) {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
