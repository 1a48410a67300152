"""Adaptation: a lasting change of the plant during performance, the feedback controller
left on and learning continuing online.

Each run trains paper E's experiment 5 (new method, β = 0.1, N = 200, YMCA; the
torque rows: the same on the torque twin, ``actuation=torque``, as
``experiments/dynamic/study.py``'s ``2d-ymca-fel-new``, no gravity feed-forward, so nothing
in the loop knows the change), then performs the movement cycle after cycle with
feedback gain K = ``gain`` and reservoir noise off: ``pre_cycles`` nominal cycles,
``change_cycles`` cycles with the plant changed (:class:`skinny_mj.plant.perturb.PerturbedPlant`),
then ``post_cycles`` cycles with the change undone (the study's parameters,
:data:`PARAMS`). Changes:

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

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
from skinny_mj.controllers import fel
from skinny_mj.controllers.metrics import position_nrmse
from skinny_mj.controllers.online import OnlineRLS
from skinny_mj.experiments.claims import claim_lines

from skinny_mj import training
from skinny_mj.engine.experiment import RunFailed
from skinny_mj.engine.study import Quick, Row, Study
from skinny_mj.plant import body
from skinny_mj.plots import learning_curve_png
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
#: The performance after training: feedback gain K, cycles nominal / changed / undone, the
#: changes' sizes (``offset_dof`` 1: the right elbow, ``body_of("2d").dof_names[1]``; the
#: forearm's length factor; the torque twin's payload in the right hand and its links'
#: mass factor) and RLS's forgetting and P_0 = I / ``rls_lambda``.
PARAMS = {"gain": 0.5, "pre_cycles": 2, "change_cycles": 8, "post_cycles": 4,
          "actuator_gain": 0.7, "offset": 0.1, "offset_dof": 1, "forearm": 1.2,
          "payload_kg": 1.0, "mass_scale": 1.2, "forgetting": 0.999, "rls_lambda": 1.0}


def perturbation(p: Mapping[str, Any], change: str, n_dof: int) -> dict:
    """:meth:`PerturbedPlant.set`'s arguments for ``change`` (``p``: the study's params)."""
    if change == "gain":
        return {"gain": p["actuator_gain"]}
    if change == "offset":
        offset = np.zeros(n_dof)
        offset[p["offset_dof"]] = p["offset"]
        return {"offset": offset}
    return {"forearm": {"forearm": p["forearm"]}, "payload": {"payload_kg": p["payload_kg"]},
            "mass": {"mass_scale": p["mass_scale"]}, "none": {}, "none-torque": {}}[change]


def _row(change: str, learner: str) -> Row:
    """Paper E exp. 5 (the base), on the torque twin for the torque changes."""
    torque = change in TORQUE_CHANGES or change == "none-torque"
    return Row(f"{change}-{learner}", {"actuation": "torque"} if torque else {},
               group=change if change in CHANGES and learner in LEARNERS else None,
               params={"change": change, "learner": learner})


def run_batch(config: TrainConfig, row: Row, seeds: list[int]) -> list:
    """Train the row's networks in lockstep, then perform cycle after cycle (pre,
    changed, undone) with the row's learner."""
    from skinny_mj.plant.perturb import PerturbedPlant  # MuJoCo: not at --help

    p = row.params
    change, learner = p["change"], p["learner"]
    run = training.build_run(config, seeds)
    trained = training.train_run(run).fel
    esn, plant = run.esn, PerturbedPlant(run.plant)
    hook = run.actuation.hook(run.training, run.max_speed_rad_s)
    desired_angles = run.training.position_signals("joint")
    alive = ~trained.failed
    online = None
    if learner == "rls":
        online = OnlineRLS(esn, p["forgetting"], p["rls_lambda"],
                           states=np.array(trained.last_rollout.states), runs=alive)
    loop = fel.Loop(hook=hook, online=online)
    pre, n_change = p["pre_cycles"], p["change_cycles"]
    n_cycles = pre + n_change + p["post_cycles"]
    curve = np.full((len(seeds), n_cycles), np.nan)
    angle_curve = curve.copy()
    esn.reset()
    for c in range(n_cycles):
        if c == pre:
            plant.set(**perturbation(p, change, plant.n_dof))
        elif c == pre + n_change:
            plant.undo()
        ro = fel.rollout(esn, plant, run.desired, p["gain"], loop,
                         noise=learner == "fel-noise")
        ok = np.array([r is None for r in fel.health(esn, ro)]) & alive
        alive &= ok
        curve[alive, c] = position_nrmse(ro.true_signals, run.desired)[alive]
        angles = body.body_of(config.plant.body).normalize_angles(ro.angles)
        angle_curve[alive, c] = position_nrmse(angles, desired_angles)[alive]
        if learner in ("fel", "fel-noise") and alive.any():  # as in training: the new method
            esn.fit(ro.states, fel.beta_target(ro.y_est, ro.y_esn, config.method.beta),
                    runs=alive)
    warnings = run.actuation.train_warnings(run) or 0  # the torque twin's, training and performance
    if warnings and len(seeds) > 1:  # one shared MjData: run the seeds alone
        raise training.PhysicsBatchError(
            f"MuJoCo warnings in a lockstep batch of {len(seeds)} runs")
    out: list = []
    for r in range(len(seeds)):
        if not alive[r] or warnings:
            out.append(RunFailed(trained.fail_reason[r] or (
                f"physics diverged: {warnings} MuJoCo warning(s)" if warnings
                else "diverged during performance")))
            continue
        out.append(summary(pre, n_change, curve[r], angle_curve[r]))
    return out


def summary(pre: int, n_change: int, curve: np.ndarray, angle_curve: np.ndarray) -> dict:
    """The table's numbers from one run's per-cycle position and angle error curves
    (``pre`` nominal + ``n_change`` changed + the undone cycles,)."""
    nominal = float(np.mean(curve[:pre]))
    changed = curve[pre:pre + n_change]
    within = np.flatnonzero(changed <= 1.2 * nominal)
    return {"nominal": nominal, "change_first": float(changed[0]),
            "change_last": float(changed[-1]),
            "recover_cycles": float(within[0] + 1 if within.size else n_change + 1),
            "undone_first": float(curve[pre + n_change]),
            "undone_last": float(curve[-1]),
            "angle_nominal": float(np.mean(angle_curve[:pre])),
            "angle_change_last": float(angle_curve[pre + n_change - 1]),
            "curve": [float(v) for v in curve], "angle_curve": [float(v) for v in angle_curve]}


def forearm_floor(config: TrainConfig, forearm: float) -> float:
    """Position NRMSE of the arm whose forearm is ``forearm`` x as long moving exactly
    along the desired angles of ``config``'s movement: the part of the ``forearm`` rows'
    error that no joint motion can remove."""
    from skinny_mj.plant.perturb import forearm_rows  # MuJoCo: not at --help

    dof, signals = config.plant.dof, config.plant.signals
    desired = training.load_trajectory(config)[0].position_signals(signals)
    reached = desired.copy()
    reached[:, forearm_rows(dof, signals)] *= forearm
    return float(position_nrmse(reached, desired))


def _curves(runs: list, rows: dict[str, str], key: str = "curve") -> dict[str, np.ndarray]:
    """label -> (R, cycles) of the ok runs of each row."""
    out = {label: np.array([r["metrics"][key] for r in runs
                            if r["row"] == row and r["status"] == "ok"])
           for label, row in rows.items()}
    return {k: v for k, v in out.items() if v.size}


def report(results, plan, out_dir: Path) -> str:
    """Error over cycles per change (mean ± sd over runs, per learner), the drift test,
    the forearm's floor, the claims."""
    out_dir = Path(out_dir)
    p = plan.params
    pre, n_change, gain = p["pre_cycles"], p["change_cycles"], p["gain"]
    n_cycles = pre + n_change + p["post_cycles"]
    runs = results.runs(status=None)
    xlabel = f"cycle (changed: {pre + 1}–{pre + n_change})"
    lines = []
    for c in CHANGES:
        curves = _curves(runs, {lr: f"{c}-{lr}" for lr in LEARNERS})
        if c == "forearm" and curves:  # the floor, drawn over the changed cycles
            floor = np.full(n_cycles, np.nan)
            floor[pre:pre + n_change] = forearm_floor(plan.base, p["forearm"])
            curves["floor (angles exact)"] = floor
        if c in TORQUE_CHANGES and curves:  # the control: RLS on the unchanged twin
            curves.update(_curves(runs, {"rls, no change": "none-torque-rls"}))
        if curves:
            png = learning_curve_png(
                out_dir / f"curve_{c}.png", curves, f"position NRMSE (K = {gain:g})",
                xlabel=xlabel, title=f"adaptation to '{c}'", log_y=True)
            lines.append(f"figure: {png.name}")
        if c == "forearm" and curves:
            angles = _curves(runs, {lr: f"{c}-{lr}" for lr in LEARNERS}, "angle_curve")
            png = learning_curve_png(
                out_dir / "curve_forearm_angles.png", angles,
                f"joint-angle NRMSE (K = {gain:g})", xlabel=xlabel,
                title="adaptation to 'forearm': joint angles", log_y=True)
            lines.append(f"figure: {png.name}")
            lines.append(f"forearm floor (desired angles followed exactly): "
                         f"{forearm_floor(plan.base, p['forearm']):.4f}")
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
            out_dir / "curve_noise.png", noise, f"position NRMSE (K = {gain:g})",
            xlabel=f"cycle ('gain' changed: {pre + 1}–{pre + n_change})",
            title="FEL cycles: reservoir noise off vs on", log_y=True)
        lines.append(f"figure: {png.name}")
        lines.append(claim_lines(out_dir, [
            ("gain: FEL cycles with reservoir noise end below FEL cycles without", "mean",
             "gain-fel-noise", "undone_last", "<", "mean", "gain-fel"),
            ("no change: FEL cycles with reservoir noise end below FEL cycles without",
             "mean", "none-fel-noise", "undone_last", "<", "mean", "none-fel"),
        ]))
    return "\n".join(lines)


STUDY = Study(
    name=NAME, description=__doc__, run_batch=run_batch, runs=10, params=PARAMS,
    # paper E exp. 5 (TrainConfig's defaults): new method, β = 0.1, N = 200, 10 epochs
    base=TrainConfig().override({"method.epochs": 10}),
    rows=tuple(_row(c, lr) for c, lr in [(c, lr) for c in CHANGES for lr in LEARNERS]
               + list(NOISE_ROWS) + list(CONTROL_ROWS)),
    groups={"velocity": [f"{c}-{lr}" for c in ("gain", "offset", "forearm")
                         for lr in LEARNERS] + [f"{c}-{lr}" for c, lr in NOISE_ROWS],
            "torque": [*TORQUE_CHANGES, *(f"{c}-{lr}" for c, lr in CONTROL_ROWS)],
            "noise": ["gain-fel", *(f"{c}-{lr}" for c, lr in NOISE_ROWS)]},
    columns=COLUMNS,
    # a smoke test: 2 runs of 2 training epochs, short phases
    quick=Quick({"method.epochs": 2}, runs=2,
                params={"pre_cycles": 1, "change_cycles": 2, "post_cycles": 1}),
    takes=(), report=report,  # the 2D YMCA of paper E: the changes are defined on it
)

