"""``skinny bench``: where the time goes, as ratios measured within one process.

Every figure times both of its sides in the same process, interleaved (A, B, A, B, ...,
best of each), so a machine shared with other work shifts both sides alike; the load
average at the start and end is recorded with the figures. Goals:

| figure | goal |
|---|---|
| ``esn_run_vs_reservoirpy`` N = 200 / 1000 (our steps/s over theirs) | >= 2 / >= 3 |
| ``control_step_over_physics`` (R = 20 lockstep step over bare C physics) | <= 3 |
| ``lockstep_speedup`` (20 runs one at a time over the same 20 in lockstep) | >= 3 |
| ``fast_vs_naive`` (naive run-step cost over the fast path's) | >= 6 |
| ``paper_e_full_s`` (complete paper-E table, 2 cores) | <= 20 s |
| ``torque_over_kinematic`` (a torque FEL run over the kinematic run) | <= 2 |
| ``mackey_glass`` N = 1000, log10 NRMSE_84 | <= -4.5 |

The speed figures are here; the accuracy one (Mackey-Glass) is in
:mod:`skinny_mj.cli.bench_mackey_glass`, the goals and the printed table in
:mod:`skinny_mj.cli.bench_summary`.
"""

from __future__ import annotations

import functools
import os
import resource
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from skinny_mj.cli.bench_floor import (
    control_step_floor,
    esn_state_floor,
    package_lines_per_step,
    separate_robots,
)
from skinny_mj.cli.bench_mackey_glass import mackey_glass
from skinny_mj.cli.bench_summary import BENCH_EXTRA, GOALS, summary, table
from skinny_mj.cli.bench_timing import interleaved
from skinny_mj.controllers import fel
from skinny_mj.controllers.esn import ESN, ESNConfig
from skinny_mj.engine import registry
from skinny_mj.engine.experiment import default_workers, run_sweep
from skinny_mj.engine.results import test_figures
from skinny_mj.plant import task
from skinny_mj.plant.adapters import BatchPlant, EnvPlant
from skinny_mj.plant.ideal import max_speeds
from skinny_mj.training import loop
from skinny_mj.training.config import TrainConfig
from skinny_mj.trajectories import excerpt, get

__all__ = ["GOALS", "RUN_STEPS", "control_step_over_physics", "esn_run_vs_reservoirpy",
           "fast_vs_naive", "lockstep_speedup", "paper_e_full_s", "run", "run_with_bar",
           "summary", "table", "torque_over_kinematic"]
N_RUNS = 20  # R of the lockstep figures


def _movement(n_steps: int):
    traj = get("ymca", 4)
    return excerpt(traj, 0.0, n_steps * traj.dt) if n_steps < len(traj) - 1 else traj


# -- figures --------------------------------------------------------------------------
def esn_run_vs_reservoirpy(n_reservoir: int, n_steps: int, repeats: int) -> dict:
    """Our ESN's state loop (``ESN.run``, one run) vs reservoirpy 0.4's ``Reservoir.run``:
    same weights, same input (T, 16), float64; checks the two produce the same states.
    Also our R = 20 lockstep throughput (run-steps/s), the rate a sweep sees, and
    reservoirpy's time over the floor (:mod:`skinny_mj.cli.bench_floor`): the most any loop
    on SciPy's sparse product can gain over reservoirpy."""
    try:
        import reservoirpy
        from reservoirpy.nodes import Reservoir
    except ImportError:
        return {"skipped": f"needs reservoirpy, the bench extra: {BENCH_EXTRA}"}
    n_in = 16
    esn = ESN(ESNConfig(n_inputs=n_in, n_outputs=4, n_reservoir=n_reservoir), seed=0)
    # reservoirpy takes W as CSR, the format ours multiplies by
    w = esn.W[0] if esn.sparse_reservoir is None else esn.sparse_reservoir
    theirs = Reservoir(units=n_reservoir, lr=1.0, W=w, Win=esn.W_in[0, :, :-1],
                       bias=esn.W_in[0, :, -1] * esn.cfg.bias, input_dim=n_in)
    theirs.initialize(np.zeros((1, n_in)))
    inputs = np.random.default_rng(1).uniform(-1, 1, (n_steps, n_in))

    def ours() -> np.ndarray:
        esn.reset()
        return esn.run(inputs[None], noise=False)[1][0, :, :n_reservoir]

    def rpy() -> np.ndarray:
        theirs.reset()
        return theirs.run(inputs)

    lockstep = ESN(esn.cfg, n_runs=N_RUNS, seed=0)
    batch_inputs = np.broadcast_to(inputs, (N_RUNS, *inputs.shape))

    def ours_lockstep() -> None:
        lockstep.reset()
        lockstep.run(batch_inputs, noise=False)

    max_diff = float(np.max(np.abs(ours() - rpy())))
    floor = esn_state_floor(esn, inputs)  # SciPy's kernel + tanh, nothing else
    best = interleaved({"ours": ours, "reservoirpy": rpy, "lockstep": ours_lockstep}
                       | ({} if floor is None else {"floor": floor}), repeats)
    return {"N": n_reservoir, "steps": n_steps, "ours_steps_s": n_steps / best["ours"],
            "reservoirpy_steps_s": n_steps / best["reservoirpy"],
            "ratio": best["reservoirpy"] / best["ours"], "max_state_diff": max_diff,
            "ours_lockstep_R20_run_steps_s": N_RUNS * n_steps / best["lockstep"],
            "lockstep_ratio": N_RUNS * best["reservoirpy"] / best["lockstep"],
            "reservoirpy_over_floor": best["reservoirpy"] / best.get("floor", np.nan),
            "reservoirpy_version": reservoirpy.__version__}


def _lockstep_parts(n_runs: int, n_steps: int, seed: int = 0):
    traj = _movement(n_steps)
    speed = max_speeds(traj.angles, traj.dt)
    desired = traj.position_signals("cartesian")
    cfg = TrainConfig()  # paper E exp. 5: desired next + sensed in, one command per DOF out
    esn = ESN(cfg.esn_config(2 * desired.shape[1], cfg.plant.dof), n_runs=n_runs, seed=seed)
    plant = BatchPlant(4, "cartesian", traj, n_runs=n_runs, seeds=range(n_runs),
                       max_speed_rad_s=speed)
    return traj, speed, desired, esn, plant


def control_step_over_physics(n_steps: int, repeats: int) -> dict:
    """One full control step of R = 20 runs in lockstep (physics + ESN N = 200 +
    feedback + FEL bookkeeping, ``fel.rollout``) vs the bare physics of that step,
    stepped in C by ``mujoco.rollout`` with no Python in between, two ways:

    - ``physics_step_us`` (the goal's floor): R ``MjData`` of the one-robot model;
    - ``batch_physics_step_us``: the R-robot model the fast path actually steps
      (:func:`skinny_mj.plant.model.load_batch_model`), cheaper per robot, so a stricter floor.

    Both start at the movement's first pose and hold it (zero servo ctrl; no joint
    limit is active, as in the control loop). Timed in the same rounds: the step's floor
    (:func:`skinny_mj.cli.bench_floor.control_step_floor`: the batch physics, then per step
    the sparse product, tanh and reservoir noise of every run). Also counted: the
    package's Python lines per control step (``python_lines_per_step``)."""
    import mujoco
    from mujoco import rollout as mj_rollout

    _, _, desired, esn, plant = _lockstep_parts(N_RUNS, n_steps)
    plant.reset()
    spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
    steps = (len(desired) - 1) * plant.n_substeps
    one, single_data, single_state = separate_robots(plant)
    batch, batch_data = plant.model, mujoco.MjData(plant.model)
    batch_state = np.empty((1, mujoco.mj_stateSize(batch, spec)))
    mujoco.mj_getState(batch, plant.data, batch_state[0], spec)
    runner = mj_rollout.Rollout(nthread=0)
    loop = fel.Loop().with_buffers()  # the rollout arrays, reused as fel.train does

    def batch_physics() -> None:
        runner.rollout([batch], batch_data, batch_state, np.zeros((1, steps, batch.nu)),
                       nstep=steps)

    floor = control_step_floor(esn, batch_physics, len(desired) - 1)
    best = interleaved({
        "control": lambda: fel.rollout(esn, plant, desired, 0.5, loop, noise=True),
        "physics": lambda: runner.rollout([one] * N_RUNS, single_data, single_state,
                                          np.zeros((N_RUNS, steps, one.nu)), nstep=steps),
        "batch_physics": batch_physics,
    } | ({} if floor is None else {"floor": floor}), repeats)
    runner.close()
    per = {k: v / (len(desired) - 1) for k, v in best.items()}
    lines = package_lines_per_step(
        lambda k: fel.rollout(esn, plant, desired[:k + 1], 0.5, loop, noise=True),
        len(desired) - 1)
    return {"R": N_RUNS, "substeps": plant.n_substeps, "control_step_us": per["control"] * 1e6,
            "physics_step_us": per["physics"] * 1e6,
            "batch_physics_step_us": per["batch_physics"] * 1e6,
            "floor_step_us": per.get("floor", np.nan) * 1e6,
            "ratio": per["control"] / per["physics"],
            "ratio_vs_batch_physics": per["control"] / per["batch_physics"],
            "floor_vs_batch_physics": per.get("floor", np.nan) / per["batch_physics"],
            "python_lines_per_step": lines}


def lockstep_speedup(epochs: int, repeats: int) -> dict:
    """R = 20 paper-E exp-5 trainings (``epochs`` epochs) + tests in lockstep
    (``train_batch``) vs the same 20 one at a time (``train``); checks identical results."""
    cfg = TrainConfig().override({"method.epochs": epochs})
    seeds = list(range(N_RUNS))
    out: dict[str, list] = {}
    best = interleaved({
        "lockstep": lambda: out.__setitem__("batch", loop.train_batch(cfg, seeds)),
        "one_at_a_time": lambda: out.__setitem__("single", [loop.train(cfg, s) for s in seeds]),
    }, repeats)
    identical = all(test_figures(a) == test_figures(b) and a.train == b.train
                    for a, b in zip(out["batch"], out["single"], strict=True))
    return {"R": N_RUNS, "epochs": epochs, "lockstep_s": best["lockstep"],
            "one_at_a_time_s": best["one_at_a_time"],
            "ratio": best["one_at_a_time"] / best["lockstep"], "identical": identical}


def fast_vs_naive(n_steps: int, repeats: int) -> dict:
    """Per run-step cost: the naive path (dm_control ``env.step`` through ``EnvPlant``
    and a one-run Python ESN, ``fel.rollout``) vs the fast path (R = 20 lockstep)."""
    traj, speed, desired, esn, plant = _lockstep_parts(N_RUNS, n_steps)
    env_plant = EnvPlant(task.load(4, "cartesian", traj, max_speed_rad_s=speed, seed=0))
    one = ESN(esn.cfg, n_runs=1, seed=0)
    loops = (fel.Loop().with_buffers(), fel.Loop().with_buffers())  # as fel.train does
    best = interleaved({
        "fast": lambda: fel.rollout(esn, plant, desired, 0.5, loops[0], noise=True),
        "naive": lambda: fel.rollout(one, env_plant, desired, 0.5, loops[1], noise=True),
    }, repeats)
    steps = len(desired) - 1
    fast, naive = best["fast"] / (steps * N_RUNS), best["naive"] / steps
    return {"R": N_RUNS, "fast_run_step_us": fast * 1e6, "naive_run_step_us": naive * 1e6,
            "ratio": naive / fast}


def torque_over_kinematic(n_runs: int, repeats: int, epochs: int | None = None) -> dict:
    """Wall time of a torque FEL run over a kinematic one, both the dynamic study's own
    rows: ``2d-ymca-fel-arm`` (the torque twin, inertia-scaled PD teacher, 15 epochs of 5
    cycles) over ``2d-ymca-kinematic`` (the velocity servo, paper E's 10 epochs of 5
    cycles), ``n_runs`` seeds in lockstep each, timed interleaved (best of ``repeats``);
    ``epochs`` shortens both to that many (a smoke test of this figure)."""
    study = registry.get("dynamic")
    configs = {"torque": study.config("2d-ymca-fel-arm"),
               "kinematic": study.config("2d-ymca-kinematic")}
    if epochs is not None:
        configs = {k: c.override({"method.epochs": epochs}) for k, c in configs.items()}
    seeds = list(range(n_runs))
    best = interleaved({k: functools.partial(loop.train_batch, c, seeds)
                        for k, c in configs.items()}, repeats)
    return {"R": n_runs, **{f"{k}_epochs": c.method.epochs for k, c in configs.items()},
            "torque_s": best["torque"], "kinematic_s": best["kinematic"],
            "ratio": best["torque"] / best["kinematic"]}


def paper_e_full_s(workers: int | None = None, quick: bool = False,
                   out_dir: Path | None = None, only: tuple[str, ...] | None = None) -> dict:
    """Wall time of the complete paper-E table (Table 1 rows 1-6, the paper's 20 runs
    each = 120 runs; ``only`` picks other rows) on ``workers`` processes (default: all
    cores) through the engine's fast path, with the peak resident memory of this
    process and of the largest worker. ``quick`` runs ``build(quick=True)`` instead (a
    smoke test of this figure, not the figure)."""
    module = registry.get("paper-e")
    if only is None:
        only = tuple(getattr(module, "TABLE_1", {"1": 0, "2": 0, "3": 0, "4": 0, "5": 0,
                                                 "6": 0}))

    workers = default_workers(workers)
    exp = module.build(quick=quick)
    with tempfile.TemporaryDirectory(prefix="skinny-bench-") as tmp:
        out = Path(out_dir or tmp)
        start = time.perf_counter()
        results = run_sweep(exp, out, rows=list(only), workers=workers, progress=False)
        wall = time.perf_counter() - start
        n_runs = len(list((out / "runs").glob("*.json")))
    n_rows = sum(1 for row in results["rows"] if row["n"] + row["n_error"] > 0)
    return {"wall_s": wall, "workers": workers, "quick": quick, "rows": n_rows,
            "runs": n_runs, **peak_memory_mib()}


def peak_memory_mib() -> dict:
    """Peak resident memory (MiB): this process, and the largest of its worker
    processes (still-running joblib workers read from /proc, finished ones from
    ``getrusage``)."""
    own = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    child = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024
    for pid in _descendants(os.getpid()):
        try:
            text = Path(f"/proc/{pid}/status").read_text()
        except OSError:
            continue
        for line in text.splitlines():
            if line.startswith("VmHWM:"):
                child = max(child, int(line.split()[1]) / 1024)
    return {"peak_rss_self_mib": own, "peak_rss_worker_mib": child}


def _descendants(root: int) -> list[int]:
    parents: dict[int, list[int]] = {}
    for entry in Path("/proc").glob("[0-9]*"):
        try:
            fields = (entry / "stat").read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        parents.setdefault(int(fields[1]), []).append(int(entry.name))
    out, todo = [], [root]
    while todo:
        kids = parents.get(todo.pop(), [])
        out += kids
        todo += kids
    return out


# -- the command ------------------------------------------------------------------------
#: The figures :func:`run` measures, in order (its ``progress`` is called with each).
RUN_STEPS = ("esn_run_vs_reservoirpy", "control_step_over_physics", "lockstep_speedup",
             "fast_vs_naive", "mackey_glass", "paper_e_full_s", "torque_over_kinematic")


def run(quick: bool = False, workers: int | None = None,
        progress: Callable[[str], None] | None = None) -> dict:
    """Every figure; ``quick`` = shorter timings, fewer trials, no ``paper_e_full_s``.
    ``progress(name)`` is called before each of :data:`RUN_STEPS` (for a bar)."""
    tick = progress or (lambda name: None)
    reps = 2 if quick else 5
    steps = 100 if quick else 312
    figures: dict[str, Any] = {"quick": quick, "load_avg_start": os.getloadavg()}
    tick(RUN_STEPS[0])
    figures["esn_run_vs_reservoirpy"] = [
        esn_run_vs_reservoirpy(n, 300 if quick else 1000, reps) for n in (200, 1000)]
    tick(RUN_STEPS[1])
    figures["control_step_over_physics"] = control_step_over_physics(steps, reps)
    tick(RUN_STEPS[2])
    figures["lockstep_speedup"] = lockstep_speedup(1, 1 if quick else 2)
    tick(RUN_STEPS[3])
    figures["fast_vs_naive"] = fast_vs_naive(steps, reps)
    tick(RUN_STEPS[4])
    figures["mackey_glass"] = mackey_glass(1000, 2 if quick else 10)
    tick(RUN_STEPS[5])
    figures["paper_e_full_s"] = ({"skipped": "not run with --quick"} if quick
                                 else paper_e_full_s(workers))
    tick(RUN_STEPS[6])
    figures["torque_over_kinematic"] = (torque_over_kinematic(2, 1, epochs=1) if quick
                                        else torque_over_kinematic(10, 1))
    figures["load_avg_end"] = os.getloadavg()
    figures["cpu_count"] = os.cpu_count()
    figures["summary"] = summary(figures)
    return figures


def run_with_bar(quick: bool = False, workers: int | None = None, show: bool = True) -> dict:
    """:func:`run` with a tqdm bar over :data:`RUN_STEPS` on stderr (``show``)."""
    import sys

    from tqdm import tqdm

    with tqdm(total=len(RUN_STEPS), desc="bench", unit="figure", file=sys.stderr,
              disable=not show, leave=False) as bar:
        def tick(name: str) -> None:
            bar.set_postfix_str(name)  # the steps before ``name`` are done
            bar.update(RUN_STEPS.index(name) - bar.n)

        return run(quick=quick, workers=workers, progress=tick)
