"""Wall time of a torque FEL run against the kinematic run, measured back to back.

    MUJOCO_GL=disabled OMP_NUM_THREADS=1 python benchmarks/torque_wall.py [--reps 3]

Each repetition times, one after the other, a lockstep batch of 5 seeds of: the
kinematic run (velocity servo, paper E's schedule: 10 epochs x 5 cycles), the torque run
with the inertia-scaled FEL teacher as the dynamic study runs it (15 epochs x 5 cycles,
readout with forgetting), and the same torque run with 10 epochs (the kinematic run's
number of cycles). Reported: the best wall time per run of each, and the ratios
torque / kinematic per run and per cycle. Interleaving keeps a shared machine's load
about the same for both.
"""

from __future__ import annotations

import argparse
import os
import time

os.environ.setdefault("MUJOCO_GL", "disabled")

from skinny_mj.training.loop import TrainConfig, train_batch  # noqa: E402

ARM_FEL = {"actuation": "torque", "rule": "new", "rule.beta": 1.0, "rule.cycles": 3,
           "actuation.feedback": "inertia-pd", "rule.fit": "forgetting"}
CONFIGS = {"kinematic (10 epochs)": TrainConfig(),
           "torque FEL, inertia-scaled teacher (15 epochs)":
               TrainConfig().override({**ARM_FEL, "rule.epochs": 15}),
           "torque FEL, inertia-scaled teacher (10 epochs)":
               TrainConfig().override({**ARM_FEL, "rule.epochs": 10})}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--reps", type=int, default=3)
    args = parser.parse_args()
    seeds = list(range(5))
    best = {k: float("inf") for k in CONFIGS}
    for _ in range(args.reps):
        for label, cfg in CONFIGS.items():
            start = time.perf_counter()
            train_batch(cfg, seeds)
            best[label] = min(best[label], (time.perf_counter() - start) / len(seeds))
    kin = best["kinematic (10 epochs)"]
    for label, wall in best.items():
        cycles = (TrainConfig().rule.epochs if "10 epochs" in label else 15) * 5
        print(f"{label:48} {wall:6.2f} s per run, x{wall / kin:.2f} per run, "
              f"x{wall / kin * 50 / cycles:.2f} per cycle")


if __name__ == "__main__":
    main()
