"""ESN + FEL against deep RL (PPO, SAC) on the same tracking task: test error against env
steps and wall time (needs the ``rl`` extra: ``pip install -e '.[rl]'``).

Rows ``<learner>-<body>-<movement>``: learner ``fel`` (ESN + FEL, paper E's experiment 5:
N = 200, new method β = 0.1 with 3 learning cycles per epoch, 10 epochs, K 1 -> 0),
``ppo`` or ``sac`` (stable-baselines3's defaults, CPU); body ``velocity`` (the velocity
servo) or ``torque`` (the torque twin); movement ``ymca`` or ``md02`` (CMU modern dance
md_02, seconds 3 to 9.26, as long as one YMCA). 2D with Cartesian signals by default
(``--dof 8``: 3D).

The task is the gymnasium env :class:`skinny_mj.gym.env.SkinnyEnv` of the same movement,
full scale and sensor noise (0.01) as the ESN's plant. Observation [sensed(t) |
desired(t) | desired(t+1)] (the ESN's inputs are desired(t+1) and sensed(t)); on the
torque body both learners also get [qd_d(t+1) / v_max; qd(t) / v_max], the torque ESN's
velocity inputs. Action: the normalized joint velocity or torque, in [-1, 1]. Reward
(RL only; FEL learns from the feedback controller's motor error): the env's, minus the
mean absolute tracking error of the noise-free signals after each step,
``-mean |desired(t) - true(t)|``; a diverged simulation ends the episode with the worst
reward (-2) for every step left. An episode is one pass of the movement (T - 1 = 312
steps for both movements).

Every run is tested before training and during it (FEL: after every epoch; RL: every
``budget / evals`` env steps, deterministic policy) on a fresh plant, K = 0, by the
position NRMSE :func:`skinny_mj.training.loop.evaluate` computes
(:mod:`skinny_mj.experiments.rl_vs_fel.runs`). Metrics per run: final and best test error, env
steps used, training wall and CPU time (tests excluded), and for 0.05 and 0.02 the env
steps, wall and CPU time of the first test at or below it. Budgets per run
(:class:`Config`; larger ones with :func:`experiment`): FEL 10 epochs = 15 600 env
steps, PPO the same 15 600, SAC 1 560, chosen for two shared cores; each run's curve
stays in its run file. Groups: ``fel``, ``ppo``, ``sac``, ``velocity``, ``torque``,
``ymca``, ``md02``.
"""

from __future__ import annotations

import functools
import json
from dataclasses import dataclass
from pathlib import Path

from skinny_mj.experiments.rl_vs_fel import runs as runs_mod

from skinny_mj.engine.experiment import Experiment, Row, RunFailed
from skinny_mj.engine.options import config_from_dict
from skinny_mj.training.config import TrainConfig

NAME = "rl-vs-fel"
LEARNERS = ("fel", "ppo", "sac")
BODIES = ("velocity", "torque")
MOVEMENTS = ("ymca", "md02")
#: CPU seconds per env step of each learner, measured on the 2D body (the schedule only).
STEP_COST = {"fel": 1e-3, "ppo": 2e-3, "sac": 2.7e-2}


@dataclass(frozen=True)
class Config:
    """Shared settings; the budgets are env steps per run (FEL: ``epochs``)."""

    dof: int = 4
    signals: str = "cartesian"
    ymca: str = "ymca"
    asf: str | None = None
    clip: str = "md_02.amc@start=3,duration=6.26"
    epochs: int = 10
    ppo_steps: int = 15_600  # FEL's env steps: 10 epochs x (3 + 2) cycles x 312 steps
    sac_steps: int = 1_560  # a tenth of that (SAC costs ~15x PPO's CPU per env step)
    evals: int = 10  # tests per RL run after the one before training
    thresholds: tuple[float, ...] = (0.05, 0.02)
    runs: int = 3
    quick: bool = False  # smaller PPO/SAC batches (a smoke test)

    @classmethod
    def from_dict(cls, d: dict) -> Config:
        return config_from_dict(cls, d)

    def budget(self, learner: str) -> int:
        return {"ppo": self.ppo_steps, "sac": self.sac_steps}[learner]


def all_rows() -> tuple[Row, ...]:
    return tuple(Row(f"{learner}-{body}-{mv}", {"learner": learner, "actuation": body,
                                                "movement": mv})
                 for mv in MOVEMENTS for body in BODIES for learner in LEARNERS)


def groups(every: tuple[Row, ...]) -> dict[str, tuple[str, ...]]:
    out: dict[str, tuple[str, ...]] = {}
    for row in every:
        for key in ("learner", "actuation", "movement"):
            g = row.params[key]
            out[g] = (*out.get(g, ()), row.row_id)
    return out


def train_config(cfg: Config, row: Row) -> TrainConfig:
    """The row's ESN + FEL training; PPO and SAC take its plant and movement."""
    p = row.params
    trajectory, asf = (cfg.ymca, cfg.asf) if p["movement"] == "ymca" else (cfg.clip, None)
    return TrainConfig().override({
        "plant.dof": cfg.dof, "plant.signals": cfg.signals, "actuation": p["actuation"],
        "movement.trajectory": trajectory, "movement.asf": asf, "rule.epochs": cfg.epochs})


#: stable-baselines3's defaults: PPO's rollout steps (``quick``: 128), SAC's replay buffer,
#: the hidden layers of their MlpPolicy (PPO: policy and value net; SAC: the actor, two
#: critics and their target copies).
PPO_N_STEPS, SAC_BUFFER, PPO_HIDDEN, SAC_HIDDEN = 2048, 1_000_000, (64, 64), (256, 256)


def _mlp(n_in: int, n_out: int, hidden: tuple[int, ...]) -> int:
    """Parameters of a fully connected net."""
    sizes = (n_in, *hidden, n_out)
    return sum((a + 1) * b for a, b in zip(sizes[:-1], sizes[1:], strict=True))


def estimate_bytes(cfg: Config, row: Row, runs: int):
    """The memory a PPO or SAC run of ``row`` needs beyond the process's own (torch and
    stable-baselines3 are imported when the sweep is built): the rollout buffer (PPO) or
    the part of the replay buffer the budget fills (SAC: its zeros are not touched
    before), float64 observations, actions and five scalars per step; the networks'
    float32 weights, gradients and Adam's two moments (a target copy: weights only).
    ESN + FEL rows: None (their :func:`train_config` says)."""
    from skinny_mj.memory import Estimate
    from skinny_mj.plant import body

    learner = row.params["learner"]
    if learner == "fel":
        return None
    n_obs = 3 * body.n_signals(cfg.dof, cfg.signals) \
        + (2 * cfg.dof if row.params["actuation"] == "torque" else 0)
    if learner == "ppo":
        steps = 128 if cfg.quick else PPO_N_STEPS
        trained, targets = _mlp(n_obs, cfg.dof, PPO_HIDDEN) + _mlp(n_obs, 1, PPO_HIDDEN), 0
    else:
        steps = min(cfg.budget(learner), SAC_BUFFER)
        critic = _mlp(n_obs + cfg.dof, 1, SAC_HIDDEN)
        trained, targets = _mlp(n_obs, 2 * cfg.dof, SAC_HIDDEN) + 2 * critic, 2 * critic
    return Estimate({"buffer": steps * (2 * n_obs + cfg.dof + 5) * 8,
                     "networks": (4 * trained + targets) * 4},
                    {"buffer": f"{learner} buffer of {steps} steps",
                     "networks": f"{learner}'s networks"})


def run_one(cfg: Config, row: Row, seed: int) -> dict:
    tc = train_config(cfg, row)
    learner = row.params["learner"]
    if learner == "fel":
        points, facts = runs_mod.fel_curve(tc, seed)
    else:
        points, facts = runs_mod.rl_curve(learner, tc, seed, cfg.budget(learner), cfg.evals,
                                          quick=cfg.quick)
    if facts.pop("failed"):
        raise RunFailed("the ESN diverged in training")
    return {**runs_mod.curve_metrics(points, cfg.thresholds), **facts, "curve": points}


def cost(cfg: Config, row: Row) -> float:
    learner = row.params["learner"]
    steps = cfg.epochs * 5 * 312 if learner == "fel" else cfg.budget(learner)
    return steps * STEP_COST[learner] * (2.0 if row.params["actuation"] == "torque" else 1.0)


def table_columns(cfg: Config) -> dict[str, str]:
    cols = {"position_nrmse": "final test NRMSE", "train_cpu_s": "train CPU (s)"}
    for th in cfg.thresholds:
        cols.update({f"steps_to_{th:g}": f"env steps to {th:g}",
                     f"cpu_to_{th:g}": f"CPU (s) to {th:g}"})
    return cols


def build(*, quick: bool = False, movement: str | None = None, asf: str | None = None,
          dof: int | None = None, signals: str | None = None) -> Experiment:
    """The comparison; ``quick``: 1 run per row, FEL 2 epochs, PPO 256 and SAC 100 env
    steps (a smoke test). ``movement`` (+ ``asf``) replaces the YMCA; ``dof`` 8 is the
    3D body; ``signals`` the position signals."""
    runs_mod.require_rl()
    changes: dict = {k: v for k, v in (("dof", dof), ("signals", signals)) if v is not None}
    if movement is not None:
        changes.update(ymca=movement, asf=None if asf is None else str(asf))
    if quick:
        changes.update(epochs=2, ppo_steps=256, sac_steps=100, evals=2, runs=1, quick=True)
    return experiment(Config(**changes))


def experiment(cfg: Config) -> Experiment:
    """The comparison with any :class:`Config`, e.g. larger budgets:
    ``run_sweep(experiment(Config(ppo_steps=1_000_000)), out_dir)``."""
    every = all_rows()
    return Experiment(name=NAME, rows=every, groups=groups(every),
                      run_one=functools.partial(run_one, cfg), config=cfg, runs=cfg.runs,
                      table_columns=table_columns(cfg), cost=functools.partial(cost, cfg))


def report(results: dict, out_dir: Path) -> str:
    """Learning curves (test NRMSE against env steps and against wall time) and the
    comparison table (``comparison.md``)."""
    from skinny_mj.experiments.rl_vs_fel.report import write_report

    out_dir = Path(out_dir)
    cfg = Config.from_dict(json.loads((out_dir / "config.json").read_text())["config"])
    return write_report(out_dir, cfg, all_rows())
