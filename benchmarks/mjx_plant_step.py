"""Skinny's physics step batched in MJX (MuJoCo's JAX backend) on this CPU, beside
MuJoCo's C step of the same batch.

    pip install "jax[cpu]" mujoco-mjx==<the pinned mujoco version> trimesh
    MUJOCO_GL=disabled python benchmarks/mjx_plant_step.py

For B copies of the one-robot 2D model (4 DOF) at its first pose with zero controls:
MJX's ``step`` vmapped over the batch and jitted, B steps in one call (as a GPU run would
make them), against ``mujoco.rollout`` stepping B ``MjData`` in C. Both sides timed in
one process, interleaved, best of rounds; the joint angles after the steps compared.
"""

from __future__ import annotations

import os
import sys
import time

os.environ.setdefault("MUJOCO_GL", "disabled")
os.environ.setdefault("XLA_FLAGS", "--xla_cpu_multi_thread_eigen=false "
                      "intra_op_parallelism_threads=1")

import mujoco  # noqa: E402
import numpy as np  # noqa: E402
from mujoco import rollout  # noqa: E402

from skinny_mj.plant.model import load_model  # noqa: E402

N_STEPS = 50


def figure(batch: int, repeats: int) -> dict:
    import jax
    from mujoco import mjx

    jax.config.update("jax_enable_x64", True)
    model = load_model(4)
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    mx = mjx.put_model(model)
    dx = jax.vmap(lambda _: mjx.put_data(model, data))(np.arange(batch))

    @jax.jit
    def run(d):
        return jax.lax.fori_loop(0, N_STEPS, lambda _, s: jax.vmap(mjx.step, (None, 0))(mx, s), d)

    run(dx).qpos.block_until_ready()
    spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
    state = np.empty((batch, mujoco.mj_stateSize(model, spec)))
    for r in range(batch):
        mujoco.mj_getState(model, data, state[r], spec)
    runner = rollout.Rollout(nthread=0)
    out: dict = {}

    def c_side():
        out["c"] = runner.rollout([model] * batch, data, state,
                                  np.zeros((batch, N_STEPS, model.nu)), nstep=N_STEPS)[0]

    def mjx_side():
        out["mjx"] = np.asarray(run(dx).qpos)

    best = {"c": np.inf, "mjx": np.inf}
    for _ in range(repeats):
        for key, fn in (("c", c_side), ("mjx", mjx_side)):
            start = time.perf_counter()
            fn()
            best[key] = min(best[key], time.perf_counter() - start)
    runner.close()
    qpos_c = out["c"][:, -1, 1:1 + model.nq]  # the state starts with time
    per = {k: v / (N_STEPS * batch) * 1e6 for k, v in best.items()}
    return {"B": batch, "c_us": per["c"], "mjx_us": per["mjx"],
            "max_qpos_diff": float(np.max(np.abs(qpos_c - out["mjx"])))}


def main() -> None:
    try:
        from mujoco import mjx  # noqa: F401
    except ImportError as err:
        sys.exit(f"needs MJX ({err}): pip install 'jax[cpu]' mujoco-mjx trimesh")
    print(f"load average (1 min) {os.getloadavg()[0]:.2f}")
    print(f"{'B':>5} {'C (us per robot-step)':>22} {'MJX on CPU':>11}  max |dq|")
    for batch in (20, 1000):
        f = figure(batch, 3)
        print(f"{f['B']:>5} {f['c_us']:>22.2f} {f['mjx_us']:>11.2f}  {f['max_qpos_diff']:.1e}")
    print(f"load average (1 min) {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
