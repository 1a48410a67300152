"""Do the torque twin's joint limits hold? Every joint driven into each of its limits at
full torque, and the bang-bang stress episodes of ``torque_stability_check.py``, with the
twin's limits (:data:`skinny_mj.plant.model.TORQUE_LIMIT_SOLREF` and
``TORQUE_LIMIT_SOLIMP``), the same without the impedance ramp (MuJoCo's default solimp),
and MuJoCo's default limit (solref 20 ms, critically damped: the twin's limits before).

    MUJOCO_GL=disabled OMP_NUM_THREADS=1 python benchmarks/torque_limits_check.py [--runs 20]

Drive: the arm at rest at mid-range, the driven joint 0.02 rad inside its opposite
limit (so it crosses its whole range), its motor at +-1 (full torque toward the limit)
for 2 s, every other motor at 0 (those joints hang under gravity). Reported per arm: the
worst angle past any limit over the drives (rad), the driven joint's speed at impact
(its largest |qd|, rad/s), and where it rests after 2 s of pushing (rad past the limit).
Stress: ``--runs`` episodes of 10 s from random poses, every motor at +-1 with a random
sign held 1 or 1-5 control steps (failed = a MuJoCo warning).
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

os.environ.setdefault("MUJOCO_GL", "disabled")

import mujoco  # noqa: E402
import numpy as np  # noqa: E402

sys.path.insert(0, str(Path(__file__).parent))
from torque_stability_check import CONTROL_DT_S, episodes  # noqa: E402

from skinny_mj.plant.body import by_dof  # noqa: E402
from skinny_mj.plant.model import TORQUE_LIMIT_SOLREF, load_model  # noqa: E402

DRIVE_S = 2.0
MUJOCO_SOLIMP = (0.9, 0.95, 0.001, 0.5, 2.0)
#: label: joint (solref, solimp) (None: the twin's own)
LIMITS = {"the twin": None,
          "5 ms, MuJoCo's default solimp": (TORQUE_LIMIT_SOLREF, MUJOCO_SOLIMP),
          "MuJoCo's default (20 ms)": ((0.02, 1.0), MUJOCO_SOLIMP)}


def model_with(dof: int, limits) -> mujoco.MjModel:
    model = load_model(by_dof(dof, "torque"))
    if limits is not None:
        model.jnt_solref[:], model.jnt_solimp[:] = limits
    return model


def drive(model: mujoco.MjModel, joint: int, sign: float) -> tuple[float, float, float]:
    """(worst angle past any limit, the joint's peak |qd|, its rest past the limit)."""
    data = mujoco.MjData(model)
    lo, hi = model.jnt_range.T
    data.qpos[:] = 0.5 * (lo + hi)
    data.qpos[joint] = lo[joint] + 0.02 if sign > 0 else hi[joint] - 0.02
    mujoco.mj_forward(model, data)
    data.ctrl[:] = 0.0
    data.ctrl[joint] = sign
    sub = int(round(CONTROL_DT_S / model.opt.timestep))
    over = speed = 0.0
    for _ in range(int(round(DRIVE_S / CONTROL_DT_S))):
        mujoco.mj_step(model, data, sub)
        if any(w.number for w in data.warning):
            return np.inf, np.inf, np.inf
        over = max(over, float(np.max(np.maximum(lo - data.qpos, data.qpos - hi))))
        speed = max(speed, abs(float(data.qvel[joint])))
    rest = float(data.qpos[joint] - hi[joint] if sign > 0 else lo[joint] - data.qpos[joint])
    return over, speed, rest


def drives(model: mujoco.MjModel) -> tuple[float, float, float]:
    """Worst past a limit, fastest impact, deepest rest over every joint and direction."""
    res = np.array([drive(model, j, s) for j in range(model.njnt) for s in (-1.0, 1.0)])
    return tuple(float(v) for v in res.max(axis=0))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--runs", type=int, default=20, help="stress episodes per hold")
    args = parser.parse_args()
    print(f"the twin's joint solref: {TORQUE_LIMIT_SOLREF}\n")
    print("| arm | limits | drive: past a limit (rad) | impact speed (rad/s) | rest past the "
          "limit (rad) | stress 1: failed / n, past a limit (rad) | stress 1–5: failed / n,"
          " past a limit (rad) |")
    print("|---|---|---|---|---|---|---|")
    for dof in (4, 8):
        for label, limits in LIMITS.items():
            model = model_with(dof, limits)
            over, speed, rest = drives(model)
            stress = [episodes(model, args.runs, hold) for hold in (1, 5)]
            cells = [f"{f} / {args.runs}, {o}" for f, _, o, _ in stress]
            print(f"| {'2D' if dof == 4 else '3D'} | {label} | {over:.3f} | {speed:.0f} | "
                  f"{rest:.4f} | {cells[0]} | {cells[1]} |", flush=True)


if __name__ == "__main__":
    main()
