"""The lockstep ESN step of R runs in JAX (CPU) beside this package's NumPy step.

    python benchmarks/jax_esn_step.py            # needs: pip install "jax[cpu]"

Per figure, both sides are timed interleaved in one process (best of rounds), with the
same weights and inputs, and their states are compared:

- ``step``: one control step at a time, as the closed loop with the MuJoCo plant needs
  (the plant steps between two ESN steps): ``ESN.step`` vs a jitted JAX step called
  once per step (dense W, since JAX's sparse matrix-vector product is slower on CPU);
- ``scan``: T driven steps in one call (no plant in the loop: a forward model's
  pre-training, a reservoir benchmark): ``ESN.run`` vs ``jax.lax.scan`` of the step.
"""

from __future__ import annotations

import itertools
import os
import sys

import numpy as np
from skinny_mj.controllers.esn import ESN, ESNConfig

from skinny_mj.cli.bench_timing import interleaved


def figure(n_runs: int, n_res: int, n_steps: int, repeats: int, dense: bool) -> dict:
    import jax
    import jax.numpy as jnp

    jax.config.update("jax_enable_x64", True)
    n_in = 16
    cfg = ESNConfig(n_inputs=n_in, n_outputs=4, n_reservoir=n_res, noise_level=0.0)
    esn = ESN(cfg, n_runs=n_runs, seed=0)
    esn.W_out[:] = np.random.default_rng(2).uniform(-0.1, 0.1, esn.W_out.shape)
    inputs = np.random.default_rng(1).uniform(-1, 1, (n_runs, n_steps, n_in))
    w, w_in, w_out = (jnp.asarray(a) for a in (esn.W, esn.W_in, esn.W_out))

    # W as padded neighbour lists (ELL: per row its nonzeros' columns and values, padded
    # with zeros to the longest row), the sparse layout a GPU kernel would use
    k_max = int(max(np.count_nonzero(esn.W[r], axis=1).max() for r in range(n_runs)))
    cols = np.zeros((n_runs, n_res, k_max), np.int32)
    vals = np.zeros((n_runs, n_res, k_max))
    for r in range(n_runs):
        for i in range(n_res):
            nz = np.flatnonzero(esn.W[r, i])
            cols[r, i, :nz.size], vals[r, i, :nz.size] = nz, esn.W[r, i, nz]
    cols, vals = jnp.asarray(cols), jnp.asarray(vals)
    runs = jnp.arange(n_runs)[:, None, None]

    def step(x, u):
        u1 = jnp.concatenate([u, jnp.ones((n_runs, 1))], axis=1)
        wx = jnp.einsum("rij,rj->ri", w, x) if dense else jnp.sum(vals * x[runs, cols], -1)
        x = jnp.tanh(wx + jnp.einsum("rik,rk->ri", w_in, u1))
        ext = jnp.concatenate([x, u1], axis=1)
        return x, jnp.tanh(jnp.einsum("rod,rd->ro", w_out, ext))

    step_jit = jax.jit(step)
    scan_jit = jax.jit(lambda x0, us: jax.lax.scan(step, x0, us)[1])
    us = jnp.asarray(np.swapaxes(inputs, 0, 1))
    x0 = jnp.zeros((n_runs, n_res))
    step_jit(x0, us[0])[1].block_until_ready()
    scan_jit(x0, us).block_until_ready()
    ext = np.empty((n_runs, cfg.n_extended))

    def ours_step():
        esn.reset()
        for t in range(n_steps):
            esn.step(inputs[:, t], noise=False, out_extended=ext)
        return esn.y

    def jax_step():
        x = x0
        for t in range(n_steps):
            x, y = step_jit(x, us[t])
        return np.asarray(y)

    def ours_run():
        esn.reset()
        return esn.run(inputs, noise=False)[0]

    def jax_scan():
        return np.asarray(scan_jit(x0, us))

    diff = max(float(np.max(np.abs(ours_step() - jax_step()))),
               float(np.max(np.abs(ours_run() - np.swapaxes(jax_scan(), 0, 1)))))
    best = interleaved({"ours_step": ours_step, "jax_step": jax_step, "ours_run": ours_run,
                        "jax_scan": jax_scan}, repeats)
    per = {k: v / n_steps * 1e6 for k, v in best.items()}
    return {"R": n_runs, "W": "dense" if dense else "ELL", "N": n_res, "steps": n_steps,
            **{f"{k}_us": v for k, v in per.items()},
            "step_ratio": per["jax_step"] / per["ours_step"],
            "scan_ratio": per["jax_scan"] / per["ours_run"], "max_output_diff": diff,
            "jax": jax.__version__, "device": str(jax.devices()[0])}


def main() -> None:
    # one CPU thread, as the package's runs (the machine's other core runs another worker)
    os.environ.setdefault("XLA_FLAGS", "--xla_cpu_multi_thread_eigen=false "
                          "intra_op_parallelism_threads=1")
    try:
        import jax  # noqa: F401
    except ImportError:
        sys.exit("needs JAX: pip install 'jax[cpu]'")
    print(f"load average (1 min) {os.getloadavg()[0]:.2f}")
    print(f"{'R':>3} {'N':>5} {'JAX W':>5} {'ours step':>10} {'jax step':>9} {'ours run':>9} "
          f"{'jax scan':>9}  (us per lockstep step)  max |dy|")
    for (n_runs, n_res), dense in itertools.product(((1, 200), (20, 200), (1, 1000), (10, 1000)),
                                                    (True, False)):
        f = figure(n_runs, n_res, 300, 5, dense)
        print(f"{f['R']:>3} {f['N']:>5} {f['W']:>5} {f['ours_step_us']:>10.1f} "
              f"{f['jax_step_us']:>9.1f} {f['ours_run_us']:>9.1f} {f['jax_scan_us']:>9.1f}  "
              f"{f['max_output_diff']:.1e}")
    print(f"load average (1 min) {os.getloadavg()[0]:.2f}; jax {f['jax']} on {f['device']}")


if __name__ == "__main__":
    main()
