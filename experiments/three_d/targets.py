"""How good is FEL's estimated target on each body? (why paper C's recipe fails in 3D)

Paper C's original target y_est(t) = u(t) + u_error(t+1) is fitted as it is (β = 1) by
an interpolating readout, so whatever noise it carries the network learns. This module
runs one cycle of YMCA with the feedback controller alone (K = 1, the untrained network's
readout zeroed) under paper C's plant and command scale, on the 2D and the 3D body, with
joint-angle and Cartesian signals, with paper C's sensor noise (0.01) and without, and
prints per DOF the RMS of y_est − the true command beside the RMS of the true command,
the sensor noise's part of that error as a multiple of the true command, and the fraction
of commands clipped at full scale::

    MUJOCO_GL=disabled OMP_NUM_THREADS=1 python -m skinny_mj.experiments.three_d.targets
"""

from __future__ import annotations

import json

import numpy as np
from skinny_mj.controllers.fel import rollout
from skinny_mj.controllers.metrics import nrmse
from skinny_mj.experiments.paper_c import study as paper_c

from skinny_mj.plant import body
from skinny_mj.training.loop import build_run

BODIES = ((4, "joint"), (4, "cartesian"), (8, "joint"), (8, "cartesian"))


def target_noise(dof: int, signals: str, sensor_noise: float, seed: int = 0) -> dict:
    """One feedback-only cycle of YMCA: y_est's error per DOF against the true commands."""
    tc = paper_c.STUDY.config("ymca", body=dof, signals=signals).override({
        "esn.n_reservoir": 50, "method": "original", "plant.sensor_noise": sensor_noise})
    run = build_run(tc, [seed])
    run.esn.W_out[:] = 0.0  # the feedback controller alone
    ro = rollout(run.esn, run.plant, run.desired, 1.0, noise=False)
    err = ro.y_est[0] - run.true_commands
    return {"dof": dof, "signals": signals, "sensor_noise": sensor_noise,
            "full_scale_rad_s": dict(zip(body.body_of(dof).dof_names,
                                         np.round(run.max_speed_rad_s, 2).tolist(), strict=True)),
            "y_est_nrmse": float(nrmse(ro.y_est[0][None], run.true_commands)[0]),
            "rms_error_per_dof": np.round(np.sqrt(np.mean(err**2, axis=0)), 3).tolist(),
            "rms_true_command_per_dof": np.round(
                np.sqrt(np.mean(run.true_commands**2, axis=0)), 3).tolist(),
            "clipped_fraction": float(np.mean(np.abs(ro.commands[0]) >= 1.0 - 1e-9))}


def main() -> None:
    """Per body: both runs, and the sensor noise's part of y_est's error per DOF (the two
    RMS errors' difference in quadrature) as a multiple of the true command's RMS."""
    for dof, signals in BODIES:
        noisy, clean = (target_noise(dof, signals, n) for n in (0.01, 0.0))
        part = np.sqrt(np.maximum(np.square(noisy["rms_error_per_dof"])
                                  - np.square(clean["rms_error_per_dof"]), 0.0))
        ratio = part / np.asarray(clean["rms_true_command_per_dof"])
        print(json.dumps({"noisy": noisy, "clean": clean,
                          "noise_part_over_true_command": dict(zip(
                              body.body_of(dof).dof_names, np.round(ratio, 2).tolist(),
                              strict=True))}),
              flush=True)


if __name__ == "__main__":
    main()
