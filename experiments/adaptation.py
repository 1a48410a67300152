"""Adaptation: a lasting change of the plant during performance, the feedback controller
left on and learning continuing online (issue 16, item 4).

Each run trains paper E's experiment 5 (new method, β = 0.1, N = 200, YMCA), then
performs the movement cycle after cycle with feedback gain K = ``gain`` and reservoir
noise off: ``pre`` nominal cycles, ``change`` cycles with the plant changed
(:class:`skinny_mj.perturb.PerturbedPlant`: ``gain`` = every actuator's effect x 0.7,
"actuator gain −30 %"; ``offset`` = a constant +0.1 (10 % of full-scale speed) on the
right elbow's command), then ``post`` cycles with the change undone. Learners (rows
``<change>-<learner>``):

- ``frozen``: the trained readout, unchanged;
- ``fel``: after every cycle, one FEL fit of the new method (β = 0.1) on that cycle,
  as in training (:meth:`controllers.esn.ESN.fit`);
- ``rls``: an RLS readout update every control step inside the loop
  (:class:`controllers.online.OnlineRLS` through :func:`controllers.fel.rollout`'s
  ``online`` hook; target y_est(t−1), forgetting ``forgetting``, P_0 from the last
  training evaluation cycle's states with λ = ``rls_lambda``).

Metrics: position NRMSE of every cycle (the run file keeps the curve), the nominal
error (mean of the pre cycles), the first and last changed cycle's error, cycles to
recover (first changed cycle within 1.2 x the nominal error; change + 1 = never), and the
first and last undone cycle's error. 10 runs per row, in lockstep.
Not built (said so in docs/results/beyond.md): the longer forearm (an MjSpec variant)
and the torque body's payload and heavier links.
"""

from __future__ import annotations

import functools
import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from experiments.claims import claim_lines
from skinny_mj.config import TrainConfig
from skinny_mj.experiment import Experiment, Row, RunFailed
from skinny_mj.sweep import one_of_batch

NAME = "adaptation"
CHANGES = ("gain", "offset")
LEARNERS = ("frozen", "fel", "rls")
COLUMNS = {"nominal": "nominal", "change_first": "1st changed", "change_last": "last changed",
           "recover_cycles": "cycles to recover", "undone_first": "1st undone",
           "undone_last": "last undone"}


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


def perturbation(cfg: Config, change: str, n_dof: int) -> dict:
    if change == "gain":
        return {"gain": cfg.actuator_gain}
    offset = np.zeros(n_dof)
    offset[cfg.offset_dof] = cfg.offset
    return {"offset": offset}


def run_batch(cfg: Config, row: Row, seeds: list[int]) -> list:
    from controllers import fel
    from controllers.metrics import position_nrmse
    from controllers.online import OnlineRLS
    from skinny_mj.perturb import PerturbedPlant
    from skinny_mj.training import build_run, train_run

    change, learner = row.params["change"], row.params["learner"]
    run = build_run(TrainConfig(epochs=cfg.epochs), seeds)
    trained = train_run(run).fel
    esn, plant = run.esn, PerturbedPlant(run.plant)
    alive = ~trained.failed
    online = None
    if learner == "rls":
        online = OnlineRLS(esn, cfg.forgetting, cfg.rls_lambda,
                           states=np.array(trained.last_rollout.states), runs=alive)
    n_cycles = cfg.pre + cfg.change + cfg.post
    curve = np.full((len(seeds), n_cycles), np.nan)
    esn.reset()
    for c in range(n_cycles):
        if c == cfg.pre:
            plant.set(**perturbation(cfg, change, plant.n_dof))
        elif c == cfg.pre + cfg.change:
            plant.undo()
        ro = fel.rollout(esn, plant, run.desired, cfg.gain, noise=False, online=online)
        ok = np.array([r is None for r in fel.health(esn, ro)]) & alive
        alive &= ok
        curve[alive, c] = position_nrmse(ro.true_signals, run.desired)[alive]
        if learner == "fel" and alive.any():
            esn.fit(ro.states, cfg.beta * ro.y_est + (1 - cfg.beta) * ro.y_esn, runs=alive)
    out: list = []
    for r in range(len(seeds)):
        if not alive[r]:
            out.append(RunFailed(trained.fail_reason[r] or "diverged during performance"))
            continue
        out.append(summary(cfg, curve[r]))
    return out


def summary(cfg: Config, curve: np.ndarray) -> dict:
    """The table's numbers from one run's per-cycle error curve (pre + change + post,)."""
    nominal = float(np.mean(curve[:cfg.pre]))
    changed = curve[cfg.pre:cfg.pre + cfg.change]
    within = np.flatnonzero(changed <= 1.2 * nominal)
    return {"nominal": nominal, "change_first": float(changed[0]),
            "change_last": float(changed[-1]),
            "recover_cycles": float(within[0] + 1 if within.size else cfg.change + 1),
            "undone_first": float(curve[cfg.pre + cfg.change]),
            "undone_last": float(curve[-1]), "curve": [float(v) for v in curve]}


def run_one(cfg: Config, row: Row, seed: int) -> dict:
    return dict(one_of_batch(functools.partial(run_batch, cfg), row, seed))


def build(quick: bool = False, movement: str | None = None, asf: str | None = None,
          dof: int | None = None, signals: str | None = None) -> Experiment:
    """The sweep (paper E exp 5 on the 2D YMCA: ``movement`` etc. are not used);
    ``quick``: 2 runs of 2 training epochs, short phases."""
    cfg = Config(epochs=2, pre=1, change=2, post=1, runs=2) if quick else Config()
    every = tuple(Row(f"{c}-{lr}", {"change": c, "learner": lr})
                  for c in CHANGES for lr in LEARNERS)
    groups = {c: tuple(f"{c}-{lr}" for lr in LEARNERS) for c in CHANGES}
    return Experiment(name=NAME, rows=every, groups=groups,
                      run_one=functools.partial(run_one, cfg), config=cfg, runs=cfg.runs,
                      table_columns=COLUMNS, run_batch=functools.partial(run_batch, cfg))


def report(results: dict, out_dir: Path) -> str:
    """Error over cycles per change (mean ± sd over runs, per learner), the claims."""
    from skinny_mj.plots import learning_curve_png
    from skinny_mj.sweep.stats import load_runs

    out_dir = Path(out_dir)
    cfg = Config(**json.loads((out_dir / "config.json").read_text())["config"])
    runs = load_runs(out_dir)
    lines = []
    for c in CHANGES:
        curves = {lr: np.array([r["metrics"]["curve"] for r in runs if r["row"] == f"{c}-{lr}"
                                and r["status"] == "ok"]) for lr in LEARNERS}
        curves = {k: v for k, v in curves.items() if v.size}
        if curves:
            png = learning_curve_png(
                out_dir / f"curve_{c}.png", curves, f"position NRMSE (K = {cfg.gain:g})",
                xlabel=f"cycle (changed: {cfg.pre + 1}–{cfg.pre + cfg.change})",
                title=f"adaptation to '{c}'", log_y=True)
            lines.append(f"figure: {png.name}")
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
    return "\n".join(lines)
