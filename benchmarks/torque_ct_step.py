"""Does computed torque keep its accuracy on a cheaper physics step? The textbook
computed-torque controller (``feedback="ct"``, omega 15 rad/s, zeta 1, 50 Hz) on the
torque twin with its integrator and step replaced, against the twin as it is (RK4 at
5 ms, 4 substeps per 20 ms control step).

    MUJOCO_GL=disabled OMP_NUM_THREADS=1 python benchmarks/torque_ct_step.py

Per body (2D, 3D) and movement (YMCA, the recorded-like YMCA): joint-angle and
Cartesian position NRMSE of one seed, mean |tau|, and the wall time of the whole run (build,
test; best of 3). The model's integrator and step are module constants of
:mod:`skinny_mj.plant.model`, replaced here for the run (nothing is cached).
"""

from __future__ import annotations

import os
import time

os.environ.setdefault("MUJOCO_GL", "disabled")

import mujoco  # noqa: E402

from skinny_mj.plant import model as skinny_model  # noqa: E402
from skinny_mj.training.loop import TrainConfig, train  # noqa: E402
from skinny_mj.training.torque import joint_nrmse  # noqa: E402

RK4, IMPLICITFAST = mujoco.mjtIntegrator.mjINT_RK4, mujoco.mjtIntegrator.mjINT_IMPLICITFAST
#: label: (integrator, timestep s); the first is the twin as it is
STEPS = {"RK4 5 ms (the twin)": (RK4, 0.005), "RK4 10 ms": (RK4, 0.01),
         "RK4 20 ms": (RK4, 0.02), "implicitfast 5 ms": (IMPLICITFAST, 0.005),
         "implicitfast 2 ms": (IMPLICITFAST, 0.002)}


def main() -> None:
    saved = skinny_model.TORQUE_INTEGRATOR, skinny_model.TORQUE_TIMESTEP_S
    print("| step | body | movement | joint NRMSE | position NRMSE | mean \\|τ\\| (N m) | "
          "max \\|τ\\|/limit | warnings | wall per run (s) |")
    print("|---|---|---|---|---|---|---|---|---|")
    try:
        for label, (integrator, dt) in STEPS.items():
            skinny_model.TORQUE_INTEGRATOR, skinny_model.TORQUE_TIMESTEP_S = integrator, dt
            for dof in (4, 8):
                for mv in ("ymca", "ymca-recorded"):
                    cfg = TrainConfig().override({
                        "actuation": "torque", "plant.dof": dof, "movement.trajectory": mv,
                        "rule": "none", "test.gain": 1.0, "actuation.feedback": "ct"})
                    walls = []
                    for _ in range(3):
                        start = time.perf_counter()
                        o = train(cfg, 0)
                        walls.append(time.perf_counter() - start)
                    tq = o.metrics["test"]["torque"]
                    body = "2D" if dof == 4 else "3D"
                    print(f"| {label} | {body} | {mv} | {joint_nrmse(o):.4f} | "
                          f"{o.metrics['test']['position_nrmse']:.4f} | "
                          f"{tq['mean_abs_torque_nm']:.2f} | {tq['max_commanded_ratio']:.3f} | "
                          f"{tq['warnings']} | {min(walls):.2f} |", flush=True)
    finally:
        skinny_model.TORQUE_INTEGRATOR, skinny_model.TORQUE_TIMESTEP_S = saved


if __name__ == "__main__":
    main()
