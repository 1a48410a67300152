"""Environment steps per second of ``SkinnyVectorEnv`` (N robots in one MuJoCo model) vs
N ``SkinnyEnv`` stepped one after another in a Python loop (and Gymnasium's
``SyncVectorEnv`` of them), measured in one run and printed as ratios. Goal: >= 5x at N = 64.

    MUJOCO_GL=disabled OMP_NUM_THREADS=1 python benchmarks/bench_vector_env.py [--quick]
"""

from __future__ import annotations

import argparse
import os
import time

os.environ.setdefault("MUJOCO_GL", "disabled")

import gymnasium  # noqa: E402
import numpy as np  # noqa: E402

from skinny_mj.gym.env import SkinnyEnv  # noqa: E402
from skinny_mj.gym.vector import SkinnyVectorEnv  # noqa: E402


def best_seconds(fn, repeats: int) -> float:
    best = np.inf
    for _ in range(repeats):
        start = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - start)
    return best


def bench(dof: int, actuation: str, num_envs: int, n_steps: int, repeats: int) -> dict:
    """Env steps/s (num_envs x n_steps per timed call) of the three ways, best of
    ``repeats``, the ways interleaved so that a load spike hits them alike."""
    kwargs = {"dof": dof, "actuation": actuation}
    vector = SkinnyVectorEnv(num_envs, **kwargs)
    singles = [SkinnyEnv(**kwargs) for _ in range(num_envs)]
    sync = gymnasium.vector.SyncVectorEnv(
        [lambda: SkinnyEnv(**kwargs) for _ in range(num_envs)])
    n_steps = min(n_steps, vector.n_steps)  # one episode: no reset inside the timing
    # full random torques can make the torque twin diverge (a PhysicsError): 0.3 of scale
    amp = 1.0 if actuation == "velocity" else 0.3
    actions = np.random.default_rng(0).uniform(-amp, amp, (n_steps, num_envs, dof))

    def run_vector():
        vector.reset(seed=0)
        for a in actions:
            vector.step(a)

    def run_singles():
        for i, env in enumerate(singles):
            env.reset(seed=i)
        for a in actions:
            for env, a_i in zip(singles, a, strict=True):
                env.step(a_i)

    def run_sync():
        sync.reset(seed=0)
        for a in actions:
            sync.step(a)

    best = {"vector": np.inf, "singles": np.inf, "sync": np.inf}
    for _ in range(repeats):
        for name, fn in (("vector", run_vector), ("singles", run_singles), ("sync", run_sync)):
            best[name] = min(best[name], best_seconds(fn, 1))
    work = num_envs * n_steps
    rates = {name: work / s for name, s in best.items()}
    return {"dof": dof, "actuation": actuation, "N": num_envs, "steps": n_steps, **rates,
            "ratio": rates["vector"] / rates["singles"],
            "ratio_sync": rates["vector"] / rates["sync"]}


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--num-envs", type=int, default=64)
    parser.add_argument("--quick", action="store_true", help="short runs (smoke test)")
    args = parser.parse_args(argv)
    n_steps, repeats = (40, 1) if args.quick else (150, 3)
    rows = [bench(d, a, args.num_envs, n_steps, repeats)
            for d in (4, 8) for a in ("velocity", "torque")]
    print(f"{'dof':>3} {'actuation':>9} {'N':>4} {'steps':>5} {'vector/s':>10} "
          f"{'N singles/s':>11} {'sync/s':>9} {'vector/singles':>14} {'vector/sync':>11}")
    for r in rows:
        print(f"{r['dof']:>3} {r['actuation']:>9} {r['N']:>4} {r['steps']:>5} "
              f"{r['vector']:>10.0f} {r['singles']:>11.0f} {r['sync']:>9.0f} "
              f"{r['ratio']:>13.1f}x {r['ratio_sync']:>10.1f}x")
    print("env steps per second (one step of one robot); goal vector/singles >= 5x at N = 64")


if __name__ == "__main__":
    main()
