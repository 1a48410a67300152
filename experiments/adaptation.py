"""Adaptation: a lasting change of the plant during performance, the feedback controller
left on and learning continuing online.

Each run trains paper E's experiment 5 (new method, β = 0.1, N = 200, YMCA; the
torque rows: the same on the torque twin, ``actuation=torque``, as
``experiments/dynamic/study.py``'s ``2d-ymca-fel-new``, no gravity feed-forward, so nothing
in the loop knows the change), then performs the movement cycle after cycle with
feedback gain K = ``gain`` and reservoir noise off: ``pre`` nominal cycles, ``change``
cycles with the plant changed (:class:`skinny_mj.plant.perturb.PerturbedPlant`), then
``post`` cycles with the change undone. Changes:

- ``gain``: every actuator's effect x 0.7, "actuator gain −30 %";
- ``offset``: a constant +0.1 (10 % of full-scale speed) on the right elbow's command;
- ``forearm``: the right forearm x ``forearm`` (1.2) as long, a :class:`mujoco.MjSpec`
  variant of the body swapped into the running model; the desired signals are the
  same Cartesian targets and the feedback controller keeps the nominal Jacobian. The
  Cartesian signals are segment vectors over the nominal lengths, so the right
  forearm's two signals read 1.2 x its direction: that part of the error (the
  ``floor``, what the long arm scores moving exactly along the desired angles) no
  joint motion can remove, and it is orthogonal to every Jacobian column, so neither
  the feedback nor FEL's target sees it; the angle columns score the rest;
- torque twin: ``payload``: 1 kg at the right hand's centre of mass; ``mass``: every
  arm link's mass and inertia x 1.2 (:func:`skinny_mj.training.torque.perturb`,
  swapped into the running model between cycles).

Learners (rows ``<change>-<learner>``):

- ``frozen``: the trained readout, unchanged;
- ``fel``: after every cycle, one FEL fit of the new method (β = 0.1) on that cycle,
  as in training (:meth:`skinny_mj.controllers.esn.ESN.fit`);
- ``rls``: an RLS readout update every control step inside the loop
  (:class:`skinny_mj.controllers.online.OnlineRLS` through
  :func:`skinny_mj.controllers.fel.rollout`'s
  ``online`` hook; target y_est(t−1), forgetting ``forgetting``, P_0 from the last
  training evaluation cycle's states with λ = ``rls_lambda``);
- ``fel-noise`` (rows ``gain-fel-noise``, ``none-fel``, ``none-fel-noise``; ``none``:
  no change at all): FEL cycles with the training's reservoir noise on in every
  cycle, to test whether the ``fel`` rows' drift comes from refitting on noise-free
  states;
- ``none-torque-rls``: RLS on the torque twin left unchanged, the control for the torque
  rows (what RLS gains without any change).

Metrics: position NRMSE of every cycle (the run file keeps the curve), the nominal
error (mean of the pre cycles), the first and last changed cycle's error, cycles to
recover (first changed cycle within 1.2 x the nominal error; change + 1 = never), and the
first and last undone cycle's error; the same joint-angle NRMSE (normalized angles
against the movement's), nominal and last changed. 10 runs per row, in lockstep.
"""

from __future__ import annotations

import functools
import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from skinny_mj.experiments.claims import claim_lines

from skinny_mj.engine.experiment import Experiment, Row, RunFailed
from skinny_mj.engine.sweep import one_of_batch
from skinny_mj.training.config import TrainConfig

NAME = "adaptation"
CHANGES = ("gain", "offset", "forearm", "payload", "mass")
TORQUE_CHANGES = ("payload", "mass")  # on the torque twin
LEARNERS = ("frozen", "fel", "rls")
#: the drift test: FEL cycles with reservoir noise on, with the gain change and without
NOISE_ROWS = (("gain", "fel-noise"), ("none", "fel"), ("none", "fel-noise"))
#: the torque twin's control: RLS on the unchanged plant (what RLS gains without a change)
CONTROL_ROWS = (("none-torque", "rls"),)
COLUMNS = {"nominal": "nominal", "change_first": "1st changed", "change_last": "last changed",
           "recover_cycles": "cycles to recover", "undone_first": "1st undone",
           "undone_last": "last undone", "angle_nominal": "angle: nominal",
           "angle_change_last": "angle: last changed"}


@dataclass(frozen=True)
class Config:
    epochs: int = 10
    gain: float = 0.5
    pre: int = 2
    change: int = 8
    post: int = 4
    actuator_gain: float = 0.7
    offset: float = 0.1
    offset_dof: int = 1  # the right elbow (body.dof_names(4)[1])
    beta: float = 0.1
    forgetting: float = 0.999
    rls_lambda: float = 1.0
    runs: int = 10
    forearm: float = 1.2  # right forearm length x this
    payload_kg: float = 1.0  # torque twin: in the right hand
    mass_scale: float = 1.2  # torque twin: every arm link


def perturbation(cfg: Config, change: str, n_dof: int) -> dict:
    """:meth:`PerturbedPlant.set`'s arguments for ``change``."""
    if change == "gain":
        return {"gain": cfg.actuator_gain}
    if change == "offset":
        offset = np.zeros(n_dof)
        offset[cfg.offset_dof] = cfg.offset
        return {"offset": offset}
    return {"forearm": {"forearm": cfg.forearm}, "payload": {"payload_kg": cfg.payload_kg},
            "mass": {"mass_scale": cfg.mass_scale}, "none": {}, "none-torque": {}}[change]


def train_config(cfg: Config, change: str) -> TrainConfig:
    """Paper E exp. 5, on the torque twin for the torque changes."""
    if change in TORQUE_CHANGES or change == "none-torque":
        return TrainConfig().override({"actuation": "torque", "rule.epochs": cfg.epochs})
    return TrainConfig().override({"rule.epochs": cfg.epochs})


def train_configs(cfg: Config, row: Row) -> dict[str, TrainConfig]:
    """The training of ``row`` (its change's :func:`train_config`), for the sweep's memory
    estimate."""
    return {"train": train_config(cfg, row.params["change"])}


def run_batch(cfg: Config, row: Row, seeds: list[int]) -> list:
    from skinny_mj.controllers import fel
    from skinny_mj.controllers.metrics import position_nrmse
    from skinny_mj.controllers.online import OnlineRLS

    from skinny_mj.plant import body
    from skinny_mj.plant.perturb import PerturbedPlant
    from skinny_mj.training import torque
    from skinny_mj.training.loop import PhysicsBatchError, build_run, train_run

    change, learner = row.params["change"], row.params["learner"]
    tc = train_config(cfg, change)
    run = build_run(tc, seeds)
    trained = train_run(run).fel
    esn, plant = run.esn, PerturbedPlant(run.plant)
    hook = torque.hook_for(tc, run.training, run.max_speed_rad_s)
    desired_angles = run.training.position_signals("joint")
    alive = ~trained.failed
    online = None
    if learner == "rls":
        online = OnlineRLS(esn, cfg.forgetting, cfg.rls_lambda,
                           states=np.array(trained.last_rollout.states), runs=alive)
    n_cycles = cfg.pre + cfg.change + cfg.post
    curve = np.full((len(seeds), n_cycles), np.nan)
    angle_curve = curve.copy()
    esn.reset()
    for c in range(n_cycles):
        if c == cfg.pre:
            plant.set(**perturbation(cfg, change, plant.n_dof))
        elif c == cfg.pre + cfg.change:
            plant.undo()
        ro = fel.rollout(esn, plant, run.desired, cfg.gain, noise=learner == "fel-noise",
                         online=online, hook=hook)
        ok = np.array([r is None for r in fel.health(esn, ro)]) & alive
        alive &= ok
        curve[alive, c] = position_nrmse(ro.true_signals, run.desired)[alive]
        angles = body.normalize_angles(ro.angles, tc.plant.dof)
        angle_curve[alive, c] = position_nrmse(angles, desired_angles)[alive]
        if learner in ("fel", "fel-noise") and alive.any():
            esn.fit(ro.states, fel.beta_target(ro.y_est, ro.y_esn, cfg.beta), runs=alive)
    warnings = torque.train_warnings(run) or 0  # the torque twin's, training and performance
    if warnings and len(seeds) > 1:  # one shared MjData: run the seeds alone
        raise PhysicsBatchError(f"MuJoCo warnings in a lockstep batch of {len(seeds)} runs")
    out: list = []
    for r in range(len(seeds)):
        if not alive[r] or warnings:
            out.append(RunFailed(trained.fail_reason[r] or (
                f"physics diverged: {warnings} MuJoCo warning(s)" if warnings
                else "diverged during performance")))
            continue
        out.append(summary(cfg, curve[r], angle_curve[r]))
    return out


def summary(cfg: Config, curve: np.ndarray, angle_curve: np.ndarray) -> dict:
    """The table's numbers from one run's per-cycle position and angle error curves
    (pre + change + post,)."""
    nominal = float(np.mean(curve[:cfg.pre]))
    changed = curve[cfg.pre:cfg.pre + cfg.change]
    within = np.flatnonzero(changed <= 1.2 * nominal)
    return {"nominal": nominal, "change_first": float(changed[0]),
            "change_last": float(changed[-1]),
            "recover_cycles": float(within[0] + 1 if within.size else cfg.change + 1),
            "undone_first": float(curve[cfg.pre + cfg.change]),
            "undone_last": float(curve[-1]),
            "angle_nominal": float(np.mean(angle_curve[:cfg.pre])),
            "angle_change_last": float(angle_curve[cfg.pre + cfg.change - 1]),
            "curve": [float(v) for v in curve], "angle_curve": [float(v) for v in angle_curve]}


def run_one(cfg: Config, row: Row, seed: int) -> dict:
    return dict(one_of_batch(functools.partial(run_batch, cfg), row, seed))


def build(quick: bool = False, movement: str | None = None, asf: str | None = None,
          dof: int | None = None, signals: str | None = None) -> Experiment:
    """The sweep (paper E exp 5 on the 2D YMCA: ``movement`` etc. are not used);
    ``quick``: 2 runs of 2 training epochs, short phases."""
    cfg = Config(epochs=2, pre=1, change=2, post=1, runs=2) if quick else Config()
    every = tuple(Row(f"{c}-{lr}", {"change": c, "learner": lr})
                  for c, lr in [(c, lr) for c in CHANGES for lr in LEARNERS]
                  + list(NOISE_ROWS) + list(CONTROL_ROWS))
    groups = {c: tuple(f"{c}-{lr}" for lr in LEARNERS) for c in CHANGES}
    groups["velocity"] = tuple(r.row_id for r in every
                               if train_config(cfg, r.params["change"]).torque is None)
    groups["torque"] = tuple(r.row_id for r in every if r.row_id not in groups["velocity"])
    groups["noise"] = ("gain-fel", *(f"{c}-{lr}" for c, lr in NOISE_ROWS))
    return Experiment(name=NAME, rows=every, groups=groups,
                      run_one=functools.partial(run_one, cfg), config=cfg, runs=cfg.runs,
                      table_columns=COLUMNS, run_batch=functools.partial(run_batch, cfg))


def forearm_floor(cfg: Config) -> float:
    """Position NRMSE of the long-forearm arm moving exactly along the desired angles:
    the part of the ``forearm`` rows' error that no joint motion can remove."""
    from skinny_mj.controllers.metrics import position_nrmse

    from skinny_mj.plant.perturb import forearm_rows
    from skinny_mj.training.parts import load_trajectory

    tc = train_config(cfg, "forearm")
    dof, signals = tc.plant.dof, tc.plant.signals
    desired = load_trajectory(tc)[0].position_signals(signals)
    reached = desired.copy()
    reached[:, forearm_rows(dof, signals)] *= cfg.forearm
    return float(position_nrmse(reached, desired))


def _curves(runs: list, rows: dict[str, str], key: str = "curve") -> dict[str, np.ndarray]:
    """label -> (R, cycles) of the ok runs of each row."""
    out = {label: np.array([r["metrics"][key] for r in runs
                            if r["row"] == row and r["status"] == "ok"])
           for label, row in rows.items()}
    return {k: v for k, v in out.items() if v.size}


def report(results: dict, out_dir: Path) -> str:
    """Error over cycles per change (mean ± sd over runs, per learner), the drift test,
    the forearm's floor, the claims."""
    from skinny_mj.engine.stats import load_runs
    from skinny_mj.plots import learning_curve_png

    out_dir = Path(out_dir)
    cfg = Config(**json.loads((out_dir / "config.json").read_text())["config"])
    runs = load_runs(out_dir)
    xlabel = f"cycle (changed: {cfg.pre + 1}–{cfg.pre + cfg.change})"
    lines = []
    for c in CHANGES:
        curves = _curves(runs, {lr: f"{c}-{lr}" for lr in LEARNERS})
        if c == "forearm" and curves:  # the floor, drawn over the changed cycles
            floor = np.full(cfg.pre + cfg.change + cfg.post, np.nan)
            floor[cfg.pre:cfg.pre + cfg.change] = forearm_floor(cfg)
            curves["floor (angles exact)"] = floor
        if c in TORQUE_CHANGES and curves:  # the control: RLS on the unchanged twin
            curves.update(_curves(runs, {"rls, no change": "none-torque-rls"}))
        if curves:
            png = learning_curve_png(
                out_dir / f"curve_{c}.png", curves, f"position NRMSE (K = {cfg.gain:g})",
                xlabel=xlabel, title=f"adaptation to '{c}'", log_y=True)
            lines.append(f"figure: {png.name}")
        if c == "forearm" and curves:
            angles = _curves(runs, {lr: f"{c}-{lr}" for lr in LEARNERS}, "angle_curve")
            png = learning_curve_png(
                out_dir / "curve_forearm_angles.png", angles,
                f"joint-angle NRMSE (K = {cfg.gain:g})", xlabel=xlabel,
                title="adaptation to 'forearm': joint angles", log_y=True)
            lines.append(f"figure: {png.name}")
            lines.append(f"forearm floor (desired angles followed exactly): "
                         f"{forearm_floor(cfg):.4f}")
        lines.append(claim_lines(out_dir, [
            (f"{c}: RLS ends the change with less error than the frozen model", "mean",
             f"{c}-rls", "change_last", "<", "mean", f"{c}-frozen"),
            (f"{c}: RLS recovers in fewer cycles than repeated FEL cycles", "mean",
             f"{c}-rls", "recover_cycles", "<", "mean", f"{c}-fel"),
            (f"{c}: RLS's first changed cycle beats FEL's", "mean", f"{c}-rls",
             "change_first", "<", "mean", f"{c}-fel"),
            (f"{c}: after the undo, RLS's last cycle is as good as the frozen model's",
             "mean", f"{c}-rls", "undone_last", "<=", "mean", f"{c}-frozen"),
        ]))
    noise = _curves(runs, {f"{c}, {lr}": f"{c}-{lr}"
                           for c, lr in (("gain", "fel"), *NOISE_ROWS)})
    if noise:
        png = learning_curve_png(
            out_dir / "curve_noise.png", noise, f"position NRMSE (K = {cfg.gain:g})",
            xlabel=f"cycle ('gain' changed: {cfg.pre + 1}–{cfg.pre + cfg.change})",
            title="FEL cycles: reservoir noise off vs on", log_y=True)
        lines.append(f"figure: {png.name}")
        lines.append(claim_lines(out_dir, [
            ("gain: FEL cycles with reservoir noise end below FEL cycles without", "mean",
             "gain-fel-noise", "undone_last", "<", "mean", "gain-fel"),
            ("no change: FEL cycles with reservoir noise end below FEL cycles without",
             "mean", "none-fel-noise", "undone_last", "<", "mean", "none-fel"),
        ]))
    return "\n".join(lines)
