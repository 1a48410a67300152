"""What RLS's in-place update saves: :meth:`skinny_mj.controllers.readout.RLS.update`
against the update as it was (kept below as the reference: two fresh (R, D, D) arrays
per sample, and P kept in the layout a copy of the broadcast P_0 has, the runs' axis
innermost, when only some runs are updated, as the FEL readout does), on the 3D arm's
RLS readout (R = 10 lockstep runs, D = 541: 500 units, 40 inputs, bias; forgetting 0.8
per 312-sample cycle, every run updated through ``runs``), interleaved in one process.

    MUJOCO_GL=disabled OMP_NUM_THREADS=1 python benchmarks/rls_update.py [--samples 100]

Prints the seconds per sample of each (best of ``--repeats`` rounds), their ratio, and
the largest relative difference of W between the two after the samples (``runs``
given, and ``runs=None``): not bit for bit, since a matrix-vector product with P rounds
differently in the two layouts.
"""

from __future__ import annotations

import argparse
import functools
import time

import numpy as np
from skinny_mj.controllers.readout import RLS


class RLSBefore:
    """RLS as it was (the reference): P copied from P_0 in its own layout."""

    def __init__(self, n_runs: int, d: int, forgetting: float):
        self.W, self.forgetting = np.zeros((n_runs, 8, d)), forgetting
        self.P = np.array(np.broadcast_to(np.eye(d) / 1e-2, (n_runs, d, d)), np.float64)


def update_before(rls: RLSBefore, x: np.ndarray, target: np.ndarray,
                  runs: np.ndarray | None = None) -> None:
    """The update before it worked in place (the reference)."""
    px = np.matmul(rls.P, x[..., None])[..., 0]
    gain = px / (rls.forgetting + np.sum(x * px, axis=1))[:, None]
    err = target - np.matmul(rls.W, x[..., None])[..., 0]
    new_p = (rls.P - gain[:, :, None] * px[:, None, :]) / rls.forgetting
    if runs is None:
        rls.W += err[:, :, None] * gain[:, None, :]
        rls.P = new_p
    else:
        rls.W[runs] += err[runs][:, :, None] * gain[runs][:, None, :]
        rls.P[runs] = new_p[runs]


def _data(n_runs: int, d: int, samples: int, seed: int = 0):
    rng = np.random.default_rng(seed)
    x = np.tanh(rng.standard_normal((samples, n_runs, d)))
    x[..., -1] = 1.0
    return x, rng.standard_normal((samples, n_runs, 8))


def _rls(n_runs: int, d: int, forgetting: float) -> RLS:
    return RLS(np.zeros((n_runs, 8, d)), 1e-2, forgetting)


def _step_before(rls: RLSBefore, x, s, runs, t: int) -> None:
    update_before(rls, x[t], s[t], runs)


def _step_after(rls: RLS, x, s, runs, t: int) -> None:
    rls.update(x[t], s[t], runs)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--runs", type=int, default=10)
    parser.add_argument("--dim", type=int, default=541)
    parser.add_argument("--samples", type=int, default=100)
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    g = 0.8 ** (1 / 312)
    x, s = _data(args.runs, args.dim, args.samples)
    every = np.ones(args.runs, bool)
    rel = {}
    for label, runs in (("runs given", every), ("runs=None", None)):
        old, new = RLSBefore(args.runs, args.dim, g), _rls(args.runs, args.dim, g)
        for t in range(args.samples):
            update_before(old, x[t], s[t], runs)
            new.update(x[t], s[t], runs)
        rel[label] = float(np.abs(old.W - new.W).max() / np.abs(old.W).max())
    best = {"before": np.inf, "in place": np.inf}
    for _ in range(args.repeats):
        for label in best:  # interleaved: both see the same machine load
            if label == "before":
                rls_old = RLSBefore(args.runs, args.dim, g)
                step = functools.partial(_step_before, rls_old, x, s, every)
            else:
                step = functools.partial(_step_after, _rls(args.runs, args.dim, g), x, s, every)
            start = time.perf_counter()
            for t in range(args.samples):
                step(t)
            best[label] = min(best[label], (time.perf_counter() - start) / args.samples)
    print(f"R = {args.runs}, D = {args.dim}, {args.samples} samples, best of {args.repeats}")
    for label, sec in best.items():
        print(f"{label}: {1e3 * sec:.2f} ms per sample")
    print(f"before / in place: {best['before'] / best['in place']:.2f}x")
    print("largest |W_before - W_in_place| / max |W_before|: "
          + ", ".join(f"{k} {v:.1e}" for k, v in rel.items()))


if __name__ == "__main__":
    main()
