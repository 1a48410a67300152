"""Control steps per second of ``env.step`` (dm_control) and of BatchPlant, against bare
``mj_step`` x substeps on the same model. Prints a table of rates and ratios.

    MUJOCO_GL=disabled OMP_NUM_THREADS=1 python benchmarks/bench_env_step.py [--quick]
"""

from __future__ import annotations

import argparse
import os
import time
from dataclasses import dataclass

os.environ.setdefault("MUJOCO_GL", "disabled")

import mujoco  # noqa: E402
import numpy as np  # noqa: E402

from skinny_mj.plant import body  # noqa: E402
from skinny_mj.plant.adapters import BatchPlant  # noqa: E402
from skinny_mj.plant.task import load  # noqa: E402


@dataclass(frozen=True)
class Movement:
    angles: np.ndarray
    dof: int
    dt: float = 0.02


def movement(dof: int, n_steps: int) -> Movement:
    t = np.linspace(0.0, n_steps * 0.02, n_steps + 1)[:, None]
    lo, hi = body.joint_ranges(dof).T
    return Movement(lo + (hi - lo) * (0.5 + 0.4 * np.sin(2.0 * t + np.arange(dof))), dof)


def rate(fn, n: int, repeats: int) -> float:
    """Best-of-``repeats`` calls per second of ``fn`` called n times."""
    best = np.inf
    for _ in range(repeats):
        start = time.perf_counter()
        for _ in range(n):
            fn()
        best = min(best, time.perf_counter() - start)
    return n / best


def bench(dof: int, actuation: str, n: int, repeats: int) -> dict:
    traj = movement(dof, n + 1)
    env = load(dof, "cartesian", traj, actuation=actuation)
    env.reset()
    action = np.full(dof, 0.1)
    env_rate = rate(lambda: env.step(action), n, repeats) if n else 0.0
    env.reset()

    plant = BatchPlant(dof, "cartesian", traj, n_runs=1, actuation=actuation)
    plant.reset()
    cmd = action[None]
    plant_rate = rate(lambda: plant.step(cmd), n, repeats)

    model = plant.model
    data = mujoco.MjData(model)
    substeps = plant.n_substeps
    raw_rate = rate(lambda: mujoco.mj_step(model, data, substeps), n, repeats)
    return {"dof": dof, "actuation": actuation, "substeps": substeps, "env": env_rate,
            "plant": plant_rate, "raw": raw_rate}


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--quick", action="store_true", help="short runs (smoke test)")
    args = parser.parse_args(argv)
    n, repeats = (300, 2) if args.quick else (3000, 5)
    rows = [bench(d, a, n, repeats) for d in (4, 8) for a in ("velocity", "torque")]
    print(f"{'dof':>3} {'actuation':>9} {'substeps':>8} {'env.step/s':>11} "
          f"{'BatchPlant/s':>12} {'mj_step x sub/s':>15} {'env/raw':>8} {'plant/raw':>9}")
    for r in rows:
        print(f"{r['dof']:>3} {r['actuation']:>9} {r['substeps']:>8} {r['env']:>11.0f} "
              f"{r['plant']:>12.0f} {r['raw']:>15.0f} {r['env'] / r['raw']:>8.3f} "
              f"{r['plant'] / r['raw']:>9.3f}")


if __name__ == "__main__":
    main()
