"""Why paper C's network does not learn Y in 3D: per-joint errors and learned loop gains.

Trains ``paper-c-3d``'s network on one training movement (its row, with ``--set KEY=VALUE``
overrides, e.g. ``esn.n_reservoir=300``) and measures, per joint and run:

- the position error at every epoch's evaluation cycle (the training curve, K > 0) and in
  the test (K = 0): per-joint RMS of the normalized angle error / 2, whose mean over the
  joints is the position NRMSE;
- the learned loop: the readout's mean d command / d input along the test (one step, as
  :func:`skinny_mj.experiments.paper_c.elbows.jacobian`) times the plant's signal per
  command per step, i.e. each joint's gain on its own SENSED angle as a fraction of the
  dead-beat inverse model's (1: one step closes the error, 0: no correction) and on its
  own DESIRED angle (dead-beat: 1); and the largest |eigenvalue| of the linearized
  one-step error map I + c J_sensed (< 1: the still joints return to the set point);
- the readout's cycle-to-cycle generalization: each learning cycle's readout predicting the
  NEXT learning cycle's target from that cycle's states (fresh reservoir and sensor noise,
  the same movement), per joint, RMS(prediction − target) / RMS(target), mean over the
  epochs of each window of :data:`WINDOWS` (1: no better than predicting 0; the readout
  interpolates its own cycle's samples exactly);
- the readout's noise gain: the RMS command each joint gets from the reservoir noise
  alone (sqrt(var of the noise) x the norm of the joint's readout row on the reservoir
  units, through the tanh's slope at 0), beside the RMS of the joint's true command.

``--plant`` instead measures the plant alone at the training movement's poses (every 10th
step): each joint's one-step response to a command as a fraction of the ideal integrator's
(full scale x command x dt) and its drift under a zero command, deg.

Prints one JSON line per call::

    MUJOCO_GL=disabled OMP_NUM_THREADS=1 python -m skinny_mj.experiments.paper_c.why_3d \\
        --row y --seeds 0 1 2 --set esn.n_reservoir=300
"""

from __future__ import annotations

import argparse
import json

import numpy as np
from skinny_mj.controllers.metrics import rmse_per_signal
from skinny_mj.experiments import paper_c_3d
from skinny_mj.experiments.paper_c import study as paper_c
from skinny_mj.experiments.paper_c.elbows import jacobian

from skinny_mj.errors import SkinnyInputError
from skinny_mj.plant import body
from skinny_mj.training.loop import build_run, evaluate, train_run
from skinny_mj.training.overrides import parse_value

#: Epoch windows of the cycle-to-cycle generalization error.
WINDOWS = ((0, 10), (10, 20), (20, 50), (50, 150))
#: Epochs whose per-joint training error is printed (those the run has).
CURVE_EPOCHS = (0, 5, 10, 15, 20, 30, 50, 100, 149)


def per_joint_error(true_signals: np.ndarray, desired: np.ndarray) -> np.ndarray:
    """(R, n_dof) RMS over t = 1..T-1 of the normalized angle error / 2 (position NRMSE's
    per-signal term) for true_signals (R, T, n_dof) and desired (T, n_dof)."""
    return rmse_per_signal(np.asarray(true_signals)[:, 1:], desired[1:]) / 2.0


def signal_per_command(run) -> np.ndarray:
    """(n_dof,) normalized signal one full-scale command moves a joint in one step."""
    dof = run.cfg.plant.dof
    return 2.0 / np.ptp(body.body_of(dof).joint_ranges(), axis=1) * run.max_speed_rad_s \
        * run.trajectory.dt


def loop_gains(run, r: int, rollout) -> dict:
    """Run ``r``'s learned gains along a test ``rollout`` (see the module docstring)."""
    dof = run.cfg.plant.dof
    jac = jacobian(run.esn, r, rollout.states[0], rollout.y_esn[0], 2 * dof)
    c = signal_per_command(run)
    sensed = jac[:, dof:] * c[:, None]
    loop = np.abs(np.linalg.eigvals(np.eye(dof) + sensed))
    return {"sensed_gain": np.round(-np.diag(sensed), 3).tolist(),
            "desired_gain": np.round(np.diag(jac[:, :dof]) * c, 3).tolist(),
            "max_loop_eig": round(float(loop.max()), 3)}


def noise_gain(run, r: int) -> list[float]:
    """Per joint: RMS command from the reservoir noise alone (run ``r``'s readout)."""
    cfg = run.esn.cfg
    std = cfg.noise_level / np.sqrt(12.0) if cfg.noise_kind == "uniform" else cfg.noise_level
    w = run.esn.W_out[r][:, :cfg.n_reservoir]
    return np.round(std * np.linalg.norm(w, axis=1), 4).tolist()


def analyse(row: str, overrides: dict, seeds: list[int], epochs: int | None = None,
            study=paper_c_3d.STUDY) -> dict:
    """Train ``row`` of ``study`` (paper-c-3d, or paper-c for the 2D contrast) with
    ``overrides`` on ``seeds`` and measure it."""
    cfg = study.config(row).override(overrides)
    if epochs is not None:
        cfg = cfg.override({"method.epochs": epochs})
    run = build_run(cfg, seeds)
    curve: list[np.ndarray] = []
    last = cfg.learning_cycles + 1
    held_out: list[tuple[int, np.ndarray]] = []  # (epoch, (R, n_dof)) relative errors
    previous: list[np.ndarray] = []  # the last learning cycle's readout

    def observe(epoch: int, cycle: int, ro, y_used) -> None:
        if cycle == last:
            curve.append(per_joint_error(ro.true_signals, run.desired))
        if y_used is None:
            return
        if previous:
            pred = np.einsum("rtd,rod->rto", ro.states, previous[0])
            if run.esn.cfg.readout_activation == "tanh":
                pred = np.tanh(pred)
            err = np.sqrt(np.mean((pred - y_used) ** 2, axis=1))
            held_out.append((epoch, err / np.sqrt(np.mean(y_used**2, axis=1))))
        previous[:] = [run.esn.W_out.copy()]

    fel = train_run(run, observe=observe).fel
    test = paper_c.load(paper_c.MOVEMENTS[row], cfg.plant.dof)
    outcomes = evaluate(run, test)
    true_rms = np.sqrt(np.mean(outcomes[0].true_commands**2, axis=0))
    runs = []
    for r, oc in enumerate(outcomes):
        out = {"seed": seeds[r], "test_position_nrmse": oc.position_nrmse,
               "train_curve": {e: round(float(fel.position_nrmse[r, e]), 4)
                               for e in CURVE_EPOCHS if e < len(curve)},
               "train_per_joint": {e: np.round(curve[e][r], 3).tolist()
                                   for e in CURVE_EPOCHS if e < len(curve)},
               "noise_command_rms": noise_gain(run, r),
               "next_cycle_error": {f"{lo}-{hi}": np.round(np.mean(
                   [e[r] for ep, e in held_out if lo <= ep < hi], axis=0), 3).tolist()
                   for lo, hi in WINDOWS if any(lo <= ep < hi for ep, _ in held_out)}}
        if not oc.failed:
            out["test_per_joint"] = np.round(
                per_joint_error(oc.rollout.true_signals, oc.desired)[0], 3).tolist()
            out.update(loop_gains(run, r, oc.rollout))
        runs.append(out)
    joints = list(body.body_of(cfg.plant.body).dof_names)
    return {"row": row, "overrides": overrides, "joints": joints,
            "true_command_rms": np.round(true_rms, 4).tolist(), "runs": runs}


def plant_response(row: str, every: int = 10) -> dict:
    """The 3D plant at ``row``'s poses: per joint the min and max one-step response to a
    0.05 command / the ideal, and the largest drift (deg) under a zero command."""
    run = build_run(paper_c_3d.STUDY.config(row).override({"plant.sensor_noise": 0.0,
                                                           "esn.n_reservoir": 1}), [0])
    plant, dof, step = run.plant, run.cfg.plant.dof, 0.05
    ideal = step * run.max_speed_rad_s * run.trajectory.dt
    ratios, drift = [], []
    for q in run.trajectory.angles[::every]:
        row_ratio = []
        for joint in [None, *range(dof)]:
            plant.reset()
            plant.set_joint_angles(q[None])
            command = np.zeros((1, dof))
            if joint is not None:
                command[0, joint] = step
            plant.step(command)
            moved = plant.joint_angles()[0] - q
            if joint is None:
                drift.append(np.abs(moved))
            else:
                row_ratio.append(moved[joint] / ideal[joint])
        ratios.append(row_ratio)
    return {"row": row, "response_min": np.round(np.min(ratios, 0), 4).tolist(),
            "response_max": np.round(np.max(ratios, 0), 4).tolist(),
            "zero_command_drift_deg": np.round(np.degrees(np.max(drift, 0)), 4).tolist()}


def main(argv: list[str] | None = None) -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--row", default="y", choices=tuple(paper_c.MOVEMENTS))
    p.add_argument("--seeds", type=int, nargs="+", default=[0])
    p.add_argument("--epochs", type=int, default=None, help="default: the study's (150)")
    p.add_argument("--set", nargs="*", default=[], metavar="KEY=VALUE",
                   help="config overrides, e.g. esn.n_reservoir=300")
    p.add_argument("--plant", action="store_true", help="measure the plant alone")
    p.add_argument("--2d", dest="two_d", action="store_true",
                   help="paper C's own 2D network instead (the contrast)")
    a = p.parse_args(argv)
    if a.plant:
        print(json.dumps(plant_response(a.row)))
        return
    study = paper_c.STUDY if a.two_d else paper_c_3d.STUDY
    base = study.config(a.row)
    overrides = {}
    for item in a.set:
        key, sep, text = item.partition("=")
        if not sep:
            p.error(f"--set takes KEY=VALUE, got {item!r}")
        try:
            overrides[key] = parse_value(base, key, text)
        except SkinnyInputError as err:
            p.error(str(err))
    print(json.dumps(analyse(a.row, overrides, a.seeds, a.epochs, study)))


if __name__ == "__main__":
    main()
