"""The floors under two of ``skinny bench``'s goals: the control step and the torque run.

    MUJOCO_GL=disabled python benchmarks/compute_floors.py [--rounds 5] [--torque-runs 5]

**The control step** (``skinny bench``'s ``control_step_over_physics``: R = 20 lockstep
runs, N = 200, the YMCA movement, ``fel.rollout``), timed in one process beside its parts,
interleaved round after round, median CPU time of the rounds, µs per control step:

- ``control``: the whole step (``fel.rollout``, noise on), as ``skinny bench`` times it;
- ``batch_physics`` / ``separate_physics``: the bare physics in C (``mujoco.rollout``) of
  the R-robot model the step uses, and of R separate ``MjData`` (the two floors of
  ``skinny bench``);
- ``plant_physics``: ``mj_step2`` + ``mj_step1`` on the plant's own data, called from
  Python once per step, as ``BatchPlant.step`` calls them (no servo, no signals);
- ``esn_step``: ``ESN.step`` alone (the same network, noise on);
- ``esn_floor``: of it, only SciPy's sparse kernel and tanh on the (R N) states;
- ``noise_draws``: of it, only the uniform draws of the reservoir noise (R generators,
  256 steps at a time, as ``ESN`` draws them): fixed by the random streams;
- ``plant_step``: ``BatchPlant.step`` alone (servo, physics, sensed signals with noise);
- ``plant_reads``: the true signals and joint angles the rollout records each step;
- ``feedback``: the feedback's ``u_error`` alone (segment Jacobian + damped solve);
- ``ufunc_call``: one in-place NumPy ufunc on an (R, 4) array: the least a NumPy call of
  this loop's sizes costs, to set beside the statements per step (counted with
  ``sys.settrace``).

**The torque run** (``torque_over_kinematic``: ``dynamic``'s ``2d-ymca-fel-arm`` over
``2d-ymca-kinematic``): both trained for one epoch on ``--torque-runs`` seeds in lockstep,
interleaved, median CPU time; the rollouts of each counted and timed (time inside ``fel.rollout``
against the rest: fits and bookkeeping); the physics of one control step of each plant
timed bare in C (``mujoco.rollout``, the batch model, its substeps and integrator).
The whole run's ratio is (rollouts per run ratio) x (time per rollout ratio), plus fits.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from collections.abc import Callable

import mujoco
import numpy as np
from mujoco import rollout as mj_rollout
from scipy.sparse._sparsetools import csr_matvec
from skinny_mj.controllers import fel
from skinny_mj.controllers.feedback import FeedbackController

from skinny_mj.cli.bench import N_RUNS, _lockstep_parts
from skinny_mj.cli.bench_floor import separate_robots
from skinny_mj.plant.adapters import BatchPlant


def medians(fns: dict[str, Callable[[], object]], rounds: int) -> dict[str, float]:
    """Median CPU time (s) of each callable over ``rounds`` interleaved rounds: on a
    shared machine the wall time also counts the time other processes held the core."""
    times: dict[str, list[float]] = {k: [] for k in fns}
    for _ in range(rounds):
        for key, fn in fns.items():
            start = time.process_time()
            fn()
            times[key].append(time.process_time() - start)
    return {k: float(np.median(v)) for k, v in times.items()}


def _bare_physics(plant: BatchPlant, n_steps: int) -> Callable[[], object]:
    """``mujoco.rollout`` of the plant's own batch model from its current state, zero
    controls, ``n_steps`` control steps (each ``plant.n_substeps`` physics steps)."""
    spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
    state = np.empty((1, mujoco.mj_stateSize(plant.model, spec)))
    mujoco.mj_getState(plant.model, plant.data, state[0], spec)
    data, runner = mujoco.MjData(plant.model), mj_rollout.Rollout(nthread=0)
    nstep = n_steps * plant.n_substeps
    ctrl = np.zeros((1, nstep, plant.model.nu))
    return lambda: runner.rollout([plant.model], data, state, ctrl, nstep=nstep)


def statements_per_step(fn: Callable[[], object], n_steps: int) -> float:
    """Python lines executed per control step inside the package (``sys.settrace``)."""
    count = [0]
    root = os.path.dirname(os.path.dirname(fel.__file__))

    def tracer(frame, event, arg):
        if not frame.f_code.co_filename.startswith(root):
            return None
        if event == "line":
            count[0] += 1
        return tracer

    sys.settrace(tracer)
    try:
        fn()
    finally:
        sys.settrace(None)
    return count[0] / n_steps


def control_floor(n_steps: int, rounds: int) -> dict:
    traj, speed, desired, esn, plant = _lockstep_parts(N_RUNS, n_steps)
    steps = len(desired) - 1
    plant.reset()
    physics = _bare_physics(plant, steps)
    one, single_data, single = separate_robots(plant)
    runner = mj_rollout.Rollout(nthread=0)
    sep_ctrl = np.zeros((N_RUNS, steps, one.nu))

    def plant_physics() -> None:
        for _ in range(steps):
            mujoco.mj_step2(plant.model, plant.data)
            mujoco.mj_step1(plant.model, plant.data)

    u = np.random.default_rng(0).uniform(-1, 1, (N_RUNS, esn.cfg.n_inputs))
    ext = np.empty((N_RUNS, esn.cfg.n_extended))

    def esn_steps() -> None:
        for _ in range(steps):
            esn.step(u, noise=True, out_extended=ext)

    a = esn.sparse_reservoir
    args = (a.shape[0], a.shape[1], a.indptr, a.indices, a.data)
    x = np.tanh(u[:, :1] * np.ones((N_RUNS, esn.cfg.n_reservoir))).ravel()

    def esn_floor() -> None:
        out = np.empty_like(x)
        for _ in range(steps):
            out.fill(0.0)
            csr_matvec(*args, x, out)
            np.tanh(out, out=out)

    rngs = [np.random.default_rng(r) for r in range(N_RUNS)]
    block = np.empty((256, esn.cfg.n_reservoir))

    def noise_draws() -> None:  # the reservoir noise of every run, drawn 256 steps at once
        for _ in range(-(-steps // 256)):
            for g in rngs:
                g.random(out=block)

    feedback = FeedbackController()
    sensed = plant.reset()

    def feedback_calls() -> None:
        for t in range(steps):
            feedback.u_error(desired[t], sensed, plant)

    command = np.zeros((N_RUNS, plant.n_dof))

    def plant_steps() -> None:  # the servo, the physics, the sensed signals (with noise)
        plant.reset()
        for _ in range(steps):
            plant.step(command)

    def plant_reads() -> None:
        for _ in range(steps):
            plant.true_signals()
            plant.joint_angles()

    small, small_out = np.ones((N_RUNS, 4)), np.empty((N_RUNS, 4))

    def ufunc_calls() -> None:
        for _ in range(steps):
            np.multiply(small, 0.5, out=small_out)

    buf: dict = {}

    def control() -> None:
        fel.rollout(esn, plant, desired, 0.5, noise=True, buffers=buf)

    control()
    lines = statements_per_step(control, steps)
    med = medians({
        "control": control,
        "batch_physics": physics,
        "separate_physics": lambda: runner.rollout([one] * N_RUNS, single_data, single,
                                                   sep_ctrl, nstep=steps),
        "plant_physics": lambda: (plant.reset(), plant_physics()),
        "plant_step": plant_steps, "plant_reads": plant_reads,
        "esn_step": esn_steps, "esn_floor": esn_floor, "noise_draws": noise_draws,
        "feedback": feedback_calls,
        "ufunc_call": ufunc_calls,
    }, rounds)
    runner.close()
    return {"R": N_RUNS, "N": esn.cfg.n_reservoir, "steps": steps,
            "statements_per_step": lines,
            "us_per_step": {k: v / steps * 1e6 for k, v in med.items()}}


def torque_floor(n_runs: int, rounds: int) -> dict:
    from skinny_mj.engine import registry
    from skinny_mj.training.loop import train_batch

    study = registry.get("dynamic")
    configs = {"torque": study.config("2d-ymca-fel-arm"),
               "kinematic": study.config("2d-ymca-kinematic")}
    epochs = {k: c.rule.epochs for k, c in configs.items()}
    configs = {k: c.override({"rule.epochs": 1}) for k, c in configs.items()}
    seeds = list(range(n_runs))
    inside: dict[str, list[list]] = {k: [] for k in configs}  # per round: [rollouts, s]
    original = fel.rollout
    current = ["torque"]

    def timed_rollout(*a, **kw):
        start = time.process_time()
        try:
            return original(*a, **kw)
        finally:
            inside[current[0]][-1][0] += 1
            inside[current[0]][-1][1] += time.process_time() - start

    def run(key: str) -> Callable[[], object]:
        def go() -> None:
            current[0] = key
            inside[key].append([0, 0.0])
            train_batch(configs[key], seeds)
        return go

    fel.rollout = timed_rollout
    try:
        med = medians({k: run(k) for k in configs}, rounds)
    finally:
        fel.rollout = original
    traj_plants = {}
    for key, actuation in (("torque", "torque"), ("kinematic", "velocity")):
        traj, speed, *_ = _lockstep_parts(1, 312)
        plant = BatchPlant(4, "cartesian", traj, n_runs=n_runs, actuation=actuation,
                           max_speed_rad_s=speed)
        plant.reset()
        traj_plants[key] = (plant.n_substeps, _bare_physics(plant, len(traj) - 1),
                            len(traj) - 1)
    phys = medians({k: v[1] for k, v in traj_plants.items()}, rounds)
    out = {"R": n_runs, "epochs_of_the_rows": epochs, "one_epoch_s": med,
           "rollouts_per_epoch": {k: v[0][0] for k, v in inside.items()},
           "s_inside_rollouts": {k: float(np.median([r[1] for r in v]))
                                 for k, v in inside.items()},
           "substeps": {k: v[0] for k, v in traj_plants.items()},
           "physics_us_per_control_step": {k: phys[k] / traj_plants[k][2] * 1e6
                                           for k in phys}}
    per_rollout = {k: out["s_inside_rollouts"][k] / out["rollouts_per_epoch"][k]
                   for k in configs}
    out["per_rollout_ratio"] = per_rollout["torque"] / per_rollout["kinematic"]
    out["physics_ratio"] = (out["physics_us_per_control_step"]["torque"]
                            / out["physics_us_per_control_step"]["kinematic"])
    out["rollout_count_ratio"] = (epochs["torque"] * out["rollouts_per_epoch"]["torque"]) / (
        epochs["kinematic"] * out["rollouts_per_epoch"]["kinematic"])
    out["predicted_run_ratio"] = (
        epochs["torque"] * med["torque"]) / (epochs["kinematic"] * med["kinematic"])
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--torque-runs", type=int, default=5)
    parser.add_argument("--skip-torque", action="store_true")
    args = parser.parse_args()
    print(f"load average (1 min) {os.getloadavg()[0]:.2f} on {os.cpu_count()} CPUs")
    c = control_floor(312, args.rounds)
    us = c["us_per_step"]
    print(f"\ncontrol step, R = {c['R']}, N = {c['N']}: µs per step (median of {args.rounds})")
    for key, value in us.items():
        print(f"  {key:<17} {value:9.2f}   x{value / us['batch_physics']:.2f} batch physics")
    print(f"  control / separate physics x{us['control'] / us['separate_physics']:.2f}; "
          f"{c['statements_per_step']:.0f} package statements per step")
    if not args.skip_torque:
        t = torque_floor(args.torque_runs, args.rounds)
        print(f"\ntorque vs kinematic, R = {t['R']}, one epoch each (median of {args.rounds})")
        for key in ("one_epoch_s", "rollouts_per_epoch", "s_inside_rollouts", "substeps",
                    "physics_us_per_control_step", "epochs_of_the_rows"):
            print(f"  {key:<28} " + ", ".join(f"{k} {v:.4g}" for k, v in t[key].items()))
        for key in ("physics_ratio", "per_rollout_ratio", "rollout_count_ratio",
                    "predicted_run_ratio"):
            print(f"  {key:<28} {t[key]:.2f}")
    print(f"\nload average (1 min) {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
